"""Bifurcation diagram: the Poincare section's x along the continued axis, one panel per line,
with the intervals where the period-1 orbit is unstable shaded behind the dots.

Not hvplot: the Poincare samples are thinned per grid value (report/poincare.py) to stay
drawable in matplotlib PNGs; hvplot would draw all of them or rasterize (bokeh only)."""
import numpy as np

from rotorsweep.pipeline import schema
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.branches import hover
from rotorsweep.pipeline.report.cubeinfo import continued_axis, has_attractor, has_down, select, sweep_labels
from rotorsweep.pipeline.report.figures.panels import line_figure, panel_opts
from rotorsweep.pipeline.report.plan import axis_label, line_plan
from rotorsweep.pipeline.report.poincare import THIN_LEVELS, bif_range, sweep_dots
from rotorsweep.pipeline.report.registry import Figure, register
from rotorsweep.pipeline.report.stability import class_colour, class_name, classified, line_segments

HYSTERESIS_COLOUR = "#009E73"
BIF_LABEL = "Poincaré x [µm]"
SHADE_ALPHA = 0.28


def _unstable_spans(ds, where):
    """[(lo, hi, class)] of one line where the period-1 orbit is not stable (refined edges);
    none where the scene did not compute periodic orbits."""
    line = select(ds, where)
    if (line["orbit_status"].values == schema.ORBIT_STATUS.index("not_applicable")).all():
        return []
    return [(lo, hi, c) for lo, hi, c in line_segments(ds, where)[0] if not c == 0]


def _shading(hv, ds, where, backend, keys, x0, ylim):
    """The unstable spans of one line, one element per class; every panel names every shaded
    class (one legend for all panels)."""
    spans = _unstable_spans(ds, where)
    elements = []
    for c in keys:
        rows = [(lo, ylim[0], hi, ylim[1]) for lo, hi, cc in spans
                if cc == c or (np.isnan(c) and np.isnan(cc))] or [(x0, ylim[0], x0, ylim[0])]
        el = hv.Rectangles(rows, label=f"orbit unstable: {class_name(c)}")
        elements.append(el.opts(**style.fill_style(backend, class_colour(c), SHADE_ALPHA), backend=backend))
    return elements


def _bif_panel(hv, ds, where, backend, slot, span_keys):
    x = continued_axis(ds)
    line = select(ds, where)
    grid = line[x].values.astype(float)
    sweeps = [line["poincare_x"].transpose(x, ...).values * 1e6]
    if has_down(line):
        sweeps.append(line["poincare_x" + schema.DOWN_SUFFIX].transpose(x, ...).values * 1e6)
    ylim = bif_range(np.concatenate([v.ravel() for v in sweeps]))
    height = ylim[1] - ylim[0]
    elements = _shading(hv, ds, where, backend, span_keys, float(grid[0]), ylim)
    tooltips = hover((x, "poincare_x"), (axis_label(ds, x), BIF_LABEL))
    elements += sweep_dots(hv, x, grid, sweeps, sweep_labels(ds), backend, height / THIN_LEVELS, tooltips)
    if "hysteresis" in line:
        hs = grid[line["hysteresis"].values == 1]
        mark = style.legend_points(hv, hs, np.full(hs.size, ylim[1] - 0.04 * height), [x, "poincare_x"],
                      "hysteresis (up and down differ)")
        elements.append(mark.opts(**style.marker_style(backend, HYSTERESIS_COLOUR, 7, "v"), backend=backend))
    return hv.Overlay(elements).opts(ylim=ylim, **panel_opts(ds, slot, backend, BIF_LABEL, grid))


def fig_bifurcation(ds, backend="bokeh"):
    """Bifurcation diagram: the Poincare section's x (once per forcing period) along the
    continued axis, one panel per line; intervals where the period-1 orbit is unstable shaded
    behind the dots (refined edges), the down sweep in a second colour, hysteresis marked."""
    ds = classified(ds)
    keys = sorted({c for where in line_plan(ds)["shown"] for _, _, c in _unstable_spans(ds, where)},
                  key=lambda c: (np.isnan(c), c))

    def panel(hv, ds, where, backend, slot):
        return _bif_panel(hv, ds, where, backend, slot, keys)
    return line_figure(ds, backend, "Bifurcation diagram (Poincaré section once per forcing period)", panel)


register(Figure(name="bifurcation", filename="bifurcation.png", title="Bifurcation diagram",
                applies=has_attractor, build=lambda ds, backend, intervals: fig_bifurcation(ds, backend)))

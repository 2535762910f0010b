"""Bifurcation diagram: the Poincare section's x along the continued axis, one panel per line,
with the intervals where the period-1 orbit is unstable shaded behind the dots."""
import numpy as np

from pipeline import schema
from pipeline.report import style
from pipeline.report.cubeinfo import continued_axis, has_attractor, has_down, select, sweep_labels
from pipeline.report.figures.panels import legend_points, line_figure, panel_opts
from pipeline.report.plan import line_plan
from pipeline.report.registry import Figure, register
from pipeline.report.stability import class_colour, class_name, line_segments

# Poincare points per panel of the bifurcation diagram: per grid value the distinct values (at a
# resolution of 1/THIN_LEVELS of the panel's range), evenly thinned to at most budget / values.
# 2401 speeds x 128 samples per line (Bai's Fig. 13) would be 1.5 M points: slow to draw with
# matplotlib and tens of MB in the HTML.
BIF_POINTS = {"matplotlib": 200_000, "bokeh": 40_000}
THIN_LEVELS = 1500
HYSTERESIS_COLOUR = "#009E73"
SHADE_ALPHA = 0.28


def thin_points(grid, values, cap, resolution):
    """(grid value, value) pairs to draw from values[grid, sample]: per grid value the distinct
    finite values at `resolution`, and where there are more than `cap` of them every k-th in
    sorted order (an even thinning that keeps the spread of a chaotic cloud)."""
    values = np.asarray(values, float)
    if not values.size:
        return np.array([]), np.array([])
    q = np.round(values / resolution)
    q = np.where(np.isfinite(q), q, np.inf)
    order = np.argsort(q, axis=1, kind="stable")
    qs = np.take_along_axis(q, order, axis=1)
    vs = np.take_along_axis(values, order, axis=1)
    first = np.ones(qs.shape, bool)
    first[:, 1:] = qs[:, 1:] != qs[:, :-1]
    first &= np.isfinite(qs)
    rank = np.cumsum(first, axis=1) - 1
    stride = np.maximum(1, -(-first.sum(axis=1) // max(int(cap), 1)))
    keep = first & (rank % stride[:, None] == 0)
    at = np.broadcast_to(np.asarray(grid, float)[:, None], values.shape)
    return at[keep], vs[keep]


def _unstable_spans(ds, where):
    """[(lo, hi, class)] of one line where the period-1 orbit is not stable (refined edges);
    none where the scene did not compute periodic orbits."""
    line = select(ds, where)
    if (line["orbit_status"].values == schema.ORBIT_STATUS.index("not_applicable")).all():
        return []
    return [(lo, hi, c) for lo, hi, c in line_segments(ds, where)[0] if not c == 0]


def _bif_range(values):
    finite = values[np.isfinite(values)]
    if not finite.size:
        return -1.0, 1.0
    lo, hi = float(finite.min()), float(finite.max())
    pad = 0.06 * (hi - lo) if hi > lo else max(0.05 * abs(hi), 0.05)
    return lo - pad, hi + pad


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


def _sweep_dots(hv, x, grid, sweeps, labels, backend, resolution):
    """The thinned Poincare points of each sweep, down first: the up sweep is drawn on top."""
    cap = int(np.clip(BIF_POINTS[backend] // max(grid.size * len(sweeps), 1), 4, sweeps[0].shape[1]))
    dot = float(np.clip(300.0 / max(grid.size, 1), 1.0, 5.0))
    elements = []
    for k in reversed(range(len(sweeps))):
        at, val = thin_points(grid, sweeps[k], cap, resolution)
        pts = legend_points(hv, at, val, [x, "poincare_x"], labels[k])
        if backend == "bokeh":
            pts = pts.opts(color=style.SWEEP_COLOURS[k], size=dot + (1 if k else 0), line_width=0,
                           backend=backend)
        else:
            size = float(np.clip(28.0 / np.sqrt(max(grid.size, 1)), 0.55, 3.2)) * (1.3 if k else 1.0)
            pts = pts.opts(color=style.SWEEP_COLOURS[k], s=size ** 2, linewidth=0, backend=backend)
        elements.append(pts)
    return elements


def _bif_panel(hv, ds, where, backend, slot, span_keys):
    x = continued_axis(ds)
    line = select(ds, where)
    grid = line[x].values.astype(float)
    sweeps = [line["poincare_x"].transpose(x, ...).values * 1e6]
    if has_down(line):
        sweeps.append(line["poincare_x" + schema.DOWN_SUFFIX].transpose(x, ...).values * 1e6)
    ylim = _bif_range(np.concatenate([v.ravel() for v in sweeps]))
    height = ylim[1] - ylim[0]
    elements = _shading(hv, ds, where, backend, span_keys, float(grid[0]), ylim)
    elements += _sweep_dots(hv, x, grid, sweeps, sweep_labels(ds), backend, height / THIN_LEVELS)
    if "hysteresis" in line:
        hs = grid[line["hysteresis"].values == 1]
        mark = legend_points(hv, hs, np.full(hs.size, ylim[1] - 0.04 * height), [x, "poincare_x"],
                      "hysteresis (up and down differ)")
        elements.append(mark.opts(**style.marker_style(backend, HYSTERESIS_COLOUR, 7, "v"), backend=backend))
    return hv.Overlay(elements).opts(ylim=ylim, **panel_opts(ds, slot, backend, "Poincaré x [µm]", grid))


def fig_bifurcation(ds, backend="bokeh"):
    """Bifurcation diagram: the Poincare section's x (once per forcing period) along the
    continued axis, one panel per line; intervals where the period-1 orbit is unstable shaded
    behind the dots (refined edges), the down sweep in a second colour, hysteresis marked."""
    keys = sorted({c for where in line_plan(ds)["shown"] for _, _, c in _unstable_spans(ds, where)},
                  key=lambda c: (np.isnan(c), c))

    def panel(hv, ds, where, backend, slot):
        return _bif_panel(hv, ds, where, backend, slot, keys)
    return line_figure(ds, backend, "Bifurcation diagram (Poincaré section once per forcing period)", panel)


register(Figure(name="bifurcation", filename="bifurcation.png", title="Bifurcation diagram",
                applies=has_attractor, build=lambda ds, backend, intervals: fig_bifurcation(ds, backend)))

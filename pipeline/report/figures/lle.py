"""Largest Lyapunov exponent along the continued axis, one panel per line.

Not hvplot: markers by estimation method over a standard-error band (hv.Spread) in one panel."""
import numpy as np

from rotorsweep.pipeline import schema
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.branches import hover
from rotorsweep.pipeline.report.cubeinfo import continued_axis, has_attractor, has_down, select, sweep_labels
from rotorsweep.pipeline.report.figures.panels import line_figure, panel_opts
from rotorsweep.pipeline.report.plan import axis_display, axis_label
from rotorsweep.pipeline.report.registry import Figure, register

LLE_LABEL = "largest Lyapunov exp. [1/s]"
LLE_COLOURS = {"integrated": "#0072B2", "derived": "#999999", "chaotic": "#CC0000", "band": "#56B4E9"}


def _estimates(hv, x, grid, lle, line, backend, tooltips):
    """Integrated and derived estimates as different markers, chaotic points ringed; in bokeh
    with a hover (`tooltips`)."""
    if backend == "bokeh":
        size = float(np.clip(260.0 / max(grid.size, 1), 3.0, 7.0))
    else:
        size = float(np.clip(40.0 / np.sqrt(max(grid.size, 1)), 1.6, 5.0))
    method, ok = line["lle_method"].values, np.isfinite(lle)
    chaotic = line["attractor"].values == schema.ATTRACTOR.index("chaotic")
    groups = (("integrated", method == 0, "o", False, "integrated (Benettin/QR)"),
              ("derived", method == 1, "^", False, "derived ln|λ|/(kT)"),
              ("chaotic", chaotic, "o", True, "chaotic attractor"))
    elements = []
    for key, mask, marker, hollow, label in groups:
        m = mask & ok
        look = style.marker_style(backend, LLE_COLOURS[key], size * (1.9 if hollow else 1.0), marker, hollow)
        if backend == "bokeh":
            look = {**look, "tools": ["hover"], "hover_tooltips": tooltips + [("estimate", label)]}
        elements.append(style.legend_points(hv, grid[m], lle[m], [x, "lle"], label).opts(**look, backend=backend))
    return elements


def _lle_panel(hv, ds, where, backend, slot):
    x = continued_axis(ds)
    line = select(ds, where)
    grid = line[x].values.astype(float)
    lle = line["lle"].values.astype(float)
    err = np.nan_to_num(line["lle_stderr"].values.astype(float), nan=0.0)
    ok = np.isfinite(lle)
    labels = sweep_labels(ds)
    elements = [
        hv.Spread((grid[ok], lle[ok], err[ok]), x, ["lle", "stderr"], label="± standard error")
        .opts(**style.fill_style(backend, LLE_COLOURS["band"], 0.35), backend=backend),
        hv.HLine(0.0).opts(color="#444444", **style.line_style(backend, 1.0, dash=True), backend=backend),
        hv.Curve((grid, lle), x, "lle", label=labels[0])
        .opts(color="#555555", **style.line_style(backend, 0.8), backend=backend),
    ]
    if has_down(line):
        down = line["lle" + schema.DOWN_SUFFIX].values.astype(float)
        elements.append(hv.Curve((grid, down), x, "lle", label=labels[1])
                        .opts(color=style.SWEEP_COLOURS[1], **style.line_style(backend, 1.2, dash=True),
                              backend=backend))
    tooltips = hover((x, "lle"), (axis_label(ds, x), LLE_LABEL))
    elements += _estimates(hv, x, grid, lle, line, backend, tooltips)
    return hv.Overlay(elements).opts(show_grid=True, **panel_opts(ds, slot, backend, LLE_LABEL, grid))


def fig_lle(ds, backend="bokeh"):
    """Largest Lyapunov exponent along the continued axis, one panel per line: ± standard error
    band, zero line, integrated and derived estimates as different markers, chaotic points
    ringed."""
    head = (f"Largest Lyapunov exponent vs {axis_display(ds, continued_axis(ds))[2]} "
            "(shaded: ± standard error)")
    return line_figure(ds, backend, head, _lle_panel)


register(Figure(name="lle", filename="lle.png", title="Largest Lyapunov exponent vs {axis}",
                applies=has_attractor, build=lambda ds, backend, intervals: fig_lle(ds, backend)))

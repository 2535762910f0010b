"""Largest Floquet multiplier modulus along the continued axis, one line per value of the first
other swept axis, the stability limit |lambda| = 1 dashed.

Not hvplot: drawn in the branch style (report/branches.py), which hvplot has no kind for."""
import numpy as np

from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.branches import SPECIAL_LABELS, branch_elements
from rotorsweep.pipeline.report.cubeinfo import continued_axis, has_orbits, select
from rotorsweep.pipeline.report.figures.panels import Sizes, facet_figure, panel_opts
from rotorsweep.pipeline.report.plan import axes_plan, axis_display, axis_label, where_label
from rotorsweep.pipeline.report.registry import Figure, register
from rotorsweep.pipeline.report.stability import refined_boundaries



def _mu_range(ds):
    """(logy, ylim) shared by every panel of the max |multiplier| figure."""
    mu = ds["max_abs_multiplier"].values
    finite = mu[np.isfinite(mu) & (mu > 0)]
    if not finite.size:
        return False, (0.0, 1.5)
    lo, hi = float(finite.min()), float(finite.max())
    if hi > 5.0:        # a diverging orbit would flatten everything else on a linear axis
        return True, (min(lo, 1.0) / 1.3, hi * 1.3)
    return False, (max(0.0, min(lo, 1.0) - 0.05), max(hi, 1.0) + 0.08)


def _mu_panel(hv, ds, where, backend, slot, y):
    """max |multiplier| along the continued axis, one branch per value of y (stable solid,
    unstable dashed, the refined boundaries marked where |lambda| = 1), plus the |lambda| = 1
    line."""
    sub = select(ds, where)
    x = continued_axis(ds)
    grid = sub[x].values
    labels = (axis_label(ds, x), "max |multiplier|")
    elements = []
    for i, v in enumerate(sub[y].values if y else [None]):
        line_where = {**where, y: float(v)} if y else where
        line = sub.sel({y: v}) if y else sub
        specials = [(value, 1.0, SPECIAL_LABELS[kind]) for _, _, value, kind in refined_boundaries(ds, line_where)
                    if kind in SPECIAL_LABELS]
        elements += branch_elements(grid, line["max_abs_multiplier"].values, line["stable"].values == 1,
                                    specials, backend, dims=(x, "max_abs_multiplier"), labels=labels,
                                    colour=style.LINE_COLOURS[i % len(style.LINE_COLOURS)],
                                    name=where_label(ds, {y: v}) if y else "max |λ|", legend_unstable=False)
    ref = hv.Curve(([grid.min(), grid.max()], [1.0, 1.0]), x, "max_abs_multiplier",
                   label="|λ| = 1 (stability limit)")
    elements.append(ref.opts(color="#C00000", **style.line_style(backend, 1.5, dash=True), backend=backend))
    return hv.Overlay(elements).opts(show_grid=True, **panel_opts(ds, slot, backend, labels[1]))


def fig_max_multiplier(ds, backend="bokeh"):
    """max |multiplier| along the continued axis, one line per value of the first other swept
    axis, the stability limit |lambda| = 1 dashed; one panel per facet combination as in the
    stability map."""
    y = axes_plan(ds)["y"]
    logy, ylim = _mu_range(ds)

    def panel(hv, ds, where, backend, slot):
        return _mu_panel(hv, ds, where, backend, slot, y).opts(logy=logy, ylim=ylim, backend=backend)
    # a numeric aspect is a data aspect in holoviews-mpl, wrong on a log axis
    sizes = Sizes(bokeh_one=(1150, 440), bokeh_grid=(560, 300), aspect_one="auto" if logy else 2.4,
                  aspect_grid="auto" if logy else 1.5, inches_one=(11, 4.6), grid_width=9.6)
    head = (f"Largest Floquet multiplier modulus vs {axis_display(ds, continued_axis(ds))[2]} "
            "(solid: stable, dashed: unstable)")
    return facet_figure(ds, backend, head, panel, sizes)


register(Figure(name="max_multiplier", filename="max_multiplier.png",
                title="Largest Floquet multiplier vs {axis}",
                applies=has_orbits, build=lambda ds, backend, intervals: fig_max_multiplier(ds, backend)))

"""Largest Floquet multiplier modulus along the continued axis, one line per value of the first
other swept axis, the stability limit |lambda| = 1 dashed."""
import numpy as np

from pipeline.report.cubeinfo import continued_axis, select
from pipeline.report.figures.panels import Sizes, facet_figure, panel_opts
from pipeline.report.plan import axes_plan, axis_display, where_label
from pipeline.report.registry import Figure, register

# Line colours for the values of the first other axis (Okabe-Ito, then Tol's muted).
LINE_COLOURS = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#D55E00", "#56B4E9", "#000000",
                "#882255", "#117733", "#999933", "#44AA99", "#AA4499")


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
    """Curves of max |multiplier| along the continued axis, one per value of y, plus the
    |lambda| = 1 line."""
    sub = select(ds, where)
    x = continued_axis(ds)
    grid = sub[x].values
    # no explicit alpha (style.line_style): bokeh would then draw unselected lines opaque
    width = {"line_width": 2} if backend == "bokeh" else {"linewidth": 1.8}
    curves = []
    for i, v in enumerate(sub[y].values if y else [None]):
        line = sub.sel({y: v}) if y else sub
        c = hv.Curve((grid, line["max_abs_multiplier"].values), x, "max_abs_multiplier",
                     label=where_label(ds, {y: v}) if y else "max |λ|")
        curves.append(c.opts(color=LINE_COLOURS[i % len(LINE_COLOURS)], backend=backend, **width))
    ref = hv.Curve(([grid.min(), grid.max()], [1.0, 1.0]), x, "max_abs_multiplier",
                   label="|λ| = 1 (stability limit)")
    if backend == "bokeh":
        ref = ref.opts(color="#C00000", line_dash="dashed", line_width=2, backend=backend)
    else:
        ref = ref.opts(color="#C00000", linestyle="--", linewidth=1.5, backend=backend)
    return hv.Overlay(curves + [ref]).opts(show_grid=True, **panel_opts(ds, slot, backend, "max |multiplier|"))


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
    head = f"Largest Floquet multiplier modulus vs {axis_display(ds, continued_axis(ds))[2]}"
    return facet_figure(ds, backend, head, panel, sizes)


register(Figure(name="max_multiplier", filename="max_multiplier.png",
                title="Largest Floquet multiplier vs {axis}",
                build=lambda ds, backend, intervals: fig_max_multiplier(ds, backend)))

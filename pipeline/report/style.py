"""How the report draws: HoloViews backends, fonts, line/marker/fill styles, colours, and the
layout of several panels into one figure. Nothing here knows about cubes."""
import contextlib

import numpy as np

DPI = 120

SWEEP_COLOURS = ("#111111", "#D55E00")       # up (the plain variables), down (_down)
# Line colours for the values of the first other axis (Okabe-Ito, then Tol's muted).
LINE_COLOURS = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#D55E00", "#56B4E9", "#000000",
                "#882255", "#117733", "#999933", "#44AA99", "#AA4499")

_MARKERS = {"o": "circle", "^": "triangle", "s": "square", "v": "inverted_triangle", "D": "diamond"}


def holoviews():
    """holoviews with both plotting backends registered."""
    import holoviews as hv
    import holoviews.plotting.bokeh  # noqa: F401  (registers the renderers)
    import holoviews.plotting.mpl  # noqa: F401
    return hv


@contextlib.contextmanager
def backend(name):
    """Make `name` the current HoloViews backend while figures are built, then restore."""
    hv = holoviews()
    previous = hv.Store.current_backend
    hv.Store.set_current_backend(name)
    try:
        yield hv
    finally:
        hv.Store.set_current_backend(previous)


def fonts(backend):
    if backend == "bokeh":
        return {"title": "12pt", "labels": "11pt", "xticks": "10pt", "yticks": "10pt"}
    return {"title": 12, "labels": 11, "xticks": 9.5, "yticks": 9.5, "legend": 9,
            "cticks": 9.5, "clabel": 10}


_DASHES = {False: ("solid", "-"), True: ("dashed", "--"), "dotted": ("dotted", ":")}


def line_style(backend, width=1.5, dash=False, alpha=1.0):
    """dash: False (solid), True (dashed) or "dotted"."""
    bokeh, mpl = _DASHES[dash]
    if backend == "bokeh":
        return {"line_width": width, "line_dash": bokeh, "alpha": alpha}
    return {"linewidth": width, "linestyle": mpl, "alpha": alpha}


def fill_style(backend, colour, alpha=None):
    """A filled area (rectangles, bands) without an outline."""
    style = {"color": colour, "line_width" if backend == "bokeh" else "linewidth": 0}
    return style if alpha is None else {**style, "alpha": alpha}


def marker_style(backend, colour, size, marker="o", hollow=False, alpha=1.0):
    """size: marker diameter in screen pixels (bokeh) / points (matplotlib)."""
    if backend == "bokeh":
        style = {"color": colour, "size": size, "marker": _MARKERS[marker], "alpha": alpha}
        return {**style, "fill_alpha": 0.0, "line_width": 1.5} if hollow else style
    style = {"s": size ** 2, "marker": marker, "alpha": alpha}
    if hollow:
        return {**style, "facecolors": "none", "edgecolors": colour, "linewidth": 1.1}
    return {**style, "color": colour, "linewidth": 0}


def legend_markers(plot, element):
    """matplotlib hook: legend markers at a readable size even where the dots are tiny."""
    legend = plot.handles["axis"].get_legend()
    if legend is None:
        return
    for handle in getattr(legend, "legend_handles", getattr(legend, "legendHandles", [])):
        if hasattr(handle, "set_sizes"):
            handle.set_sizes([30.0])
        handle.set_alpha(1.0)


def legend_points(hv, x, y, kdims, label):
    """hv.Points that keeps its legend entry when empty (one NaN point, drawn nowhere): the
    matplotlib grids show one legend for all panels, on a panel that may lack the group."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if not x.size:
        x, y = np.array([np.nan]), np.array([np.nan])
    return hv.Points((x, y), kdims, label=label)


def ncols(n):
    """Columns of a grid of n panels."""
    return 1 if n == 1 else 2 if n in (2, 4) else 3


def grid_opts(k, n, backend, columns=None):
    """(show x label, show y label) for panel k of n in a matplotlib grid: x label on the bottom
    row only, y label on the first column only (bokeh panels are separate figures and keep
    both)."""
    columns = columns or ncols(n)
    show_x = backend == "bokeh" or k + columns >= n
    show_y = backend == "bokeh" or k % columns == 0
    return show_x, show_y


def layout(hv, panels, backend, columns, title, fig_inches=None, hspace=0.25):
    """One panel as is, several as a layout with `columns` columns and an overall title; hspace:
    matplotlib's gap between columns (wider where each panel has its own colour bar)."""
    if len(panels) == 1:
        obj = panels[0]
        if backend == "matplotlib" and fig_inches:
            obj = obj.opts(fig_inches=fig_inches, backend=backend)
        return obj
    # bokeh: separate figures in a grid; matplotlib: one figure, one title, no A/B/C labels
    if backend == "bokeh":
        opts = dict(title=title, shared_axes=False)
    else:
        opts = dict(title=title, sublabel_format="", fig_inches=fig_inches, hspace=hspace, vspace=0.35,
                    fontsize={"title": 13})
    # set on an empty layout, which then takes the panels (a clone keeps its options): .opts() on
    # the full layout walks the element tree once per element (the 4-D atlas: 1.1-1.8 s per facet
    # figure and backend; the report 80 -> 77 s, its PNGs and HTML unchanged)
    return hv.Layout([]).opts(backend=backend, **opts).clone(panels).cols(columns)

"""Figures made of one panel per facet or per line: the loop over the plan's panels and their
placement, shared by the figures; each figure supplies the function that draws one panel."""
from typing import NamedTuple

from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.cubeinfo import axis_edges, continued_axis
from rotorsweep.pipeline.report.plan import axes_plan, axis_label, figure_title, line_plan, where_label


class Slot(NamedTuple):
    """Where a panel sits in its figure: its title, whether it shows the legend, x and y label."""
    title: str
    legend: bool
    show_x: bool
    show_y: bool


class Sizes(NamedTuple):
    """Sizes of a facet figure with one panel / a grid of panels."""
    bokeh_one: tuple        # (width, height) in pixels
    bokeh_grid: tuple
    aspect_one: object      # matplotlib aspect of a panel
    aspect_grid: object
    inches_one: tuple       # matplotlib figure size
    grid_width: float       # matplotlib figure width of a grid; 2.7 inches per row


def panel_opts(ds, slot, backend, ylabel, grid=None):
    """Options every panel shares: its title, the legend on the right, the axis labels where the
    slot shows them, fonts; with `grid` (the continued axis) x limits half a step beyond it."""
    opts = {"title": slot.title, "show_legend": slot.legend, "legend_position": "right",
            "xlabel": axis_label(ds, continued_axis(ds)) if slot.show_x else "",
            "ylabel": ylabel if slot.show_y else "", "fontsize": style.fonts(backend), "backend": backend}
    return opts if grid is None else {**opts, "xlim": axis_edges(grid)}


def _draw_panels(ds, backend, plan, title, panel, columns):
    """panel(hv, ds, where, backend, slot) for every shown combination of the plan; a matplotlib
    grid shares one legend (on the first row's last panel) and labels only its outer axes."""
    hv = style.holoviews()
    n = len(plan["shown"])
    panels = []
    for k, where in enumerate(plan["shown"]):
        show_x, show_y = style.grid_opts(k, n, backend, columns)
        slot = Slot(where_label(ds, where) if where else title, backend == "bokeh" or k == columns - 1,
                    show_x, show_y)
        panels.append(panel(hv, ds, where, backend, slot))
    return hv, panels


def facet_figure(ds, backend, head, panel, sizes):
    """One panel per facet combination of axes_plan (at most MAX_PANELS) in a grid."""
    plan = axes_plan(ds)
    title = figure_title(ds, head, plan)
    n = len(plan["shown"])
    columns = style.ncols(n)
    hv, panels = _draw_panels(ds, backend, plan, title, panel, columns)
    one = n == 1
    if backend == "bokeh":
        width, height = sizes.bokeh_one if one else sizes.bokeh_grid
        panels = [p.opts(width=width, height=height, backend=backend) for p in panels]
    else:
        panels = [p.opts(aspect=sizes.aspect_one if one else sizes.aspect_grid, backend=backend)
                  for p in panels]
    inches = sizes.inches_one if one else (sizes.grid_width, 2.7 * -(-n // columns) + 0.8)
    return style.layout(hv, panels, backend, columns, title, fig_inches=inches)


def line_figure(ds, backend, head, panel):
    """One wide panel per line (line_plan), stacked in one column (two beyond six lines); in
    matplotlib with legend markers at a readable size."""
    plan = line_plan(ds)
    title = figure_title(ds, head, plan)
    n = len(plan["shown"])
    columns = 1 if n <= 6 else 2
    hv, panels = _draw_panels(ds, backend, plan, title, panel, columns)
    if backend == "bokeh":
        panels = [p.opts(width=1150 if columns == 1 else 620, height=440 if n == 1 else 300,
                         backend=backend) for p in panels]
    else:
        aspect = 2.6 if n == 1 else 4.6 if columns == 1 else 2.2
        panels = [p.opts(aspect=aspect, hooks=[style.legend_markers], backend=backend) for p in panels]
    height = 2.1 * -(-n // columns) + 0.8
    if backend == "matplotlib" and n > 1:
        return hv.Layout(panels).cols(columns).opts(
            title=title, sublabel_format="", fig_inches=(11, height), hspace=0.15, vspace=0.45,
            fontsize={"title": 13}, backend=backend)
    return style.layout(hv, panels, backend, columns, title, fig_inches=(11, 4.6 if n == 1 else height))

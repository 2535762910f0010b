"""Response curves: the response's half peak-to-peak amplitude of each observable along the
continued axis -- the periodic orbit's, or at a quasi-periodically forced point its torus's
(rotorsweep.pipeline.torus_points) -- one line per value of the first other swept axis (stable
solid, unstable dashed), one panel per observable and facet combination. A point whose torus
failed has no amplitude: it is marked on the axis (amplitude 0) instead.

Not hvplot: drawn in the branch style (report/branches.py), which hvplot has no kind for."""
import numpy as np

from rotorsweep.pipeline import query, schema
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.branches import branch_elements, hover
from rotorsweep.pipeline.report.cubeinfo import branch_values, continued_axis, has_orbits, select, stable_response
from rotorsweep.pipeline.report.figures.panels import Slot, panel_opts
from rotorsweep.pipeline.report.plan import (MAX_PANELS, axes_plan, axis_display, axis_label, figure_title,
                                  unit_display, where_label)
from rotorsweep.pipeline.report.registry import Figure, register
from rotorsweep.pipeline.report.stability import CLASSES, PALETTE

FAILED = "torus failed"
FAILED_COLOUR = PALETTE[CLASSES.index(FAILED)]


def has_tori(ds):
    """Whether any point of the cube is quasi-periodically forced and its torus was attempted."""
    return "torus_status" in ds and bool((ds["torus_status"].values >= 0).any())


def _response_panel(hv, ds, where, backend, slot, observable, y):
    sub = select(ds, where)
    x = continued_axis(ds)
    o = next(o for o in schema.model_of(ds).observables if o.name == observable)
    factor, unit = unit_display(o.unit)
    labels = (axis_label(ds, x), f"amplitude of {o.name} [{unit}]")
    dims = (x, f"amplitude_{o.name}")
    elements = []
    for i, v in enumerate(sub[y].values if y else [None]):
        line = sub.sel({y: v}) if y else sub
        elements += branch_elements(line[x].values, branch_values(line, f"amplitude_{o.name}") * factor,
                                    stable_response(line), (), backend, dims=dims,
                                    labels=labels, colour=style.LINE_COLOURS[i % len(style.LINE_COLOURS)],
                                    name=where_label(ds, {y: v}) if y else o.name, legend_unstable=False)
    elements += _failed_marks(hv, sub, x, backend, dims, labels)
    return hv.Overlay(elements).opts(show_grid=True, **panel_opts(ds, slot, backend, labels[1]))


def _failed_marks(hv, sub, x, backend, dims, labels):
    """The points whose torus failed (query.torus_class_names), on the axis: one marker element
    (none where no torus failed)."""
    failed = query.torus_class_names(sub) == "torus_failed"
    if not failed.any():
        return []
    at = np.broadcast_to(sub[x].values.reshape([-1 if d == x else 1 for d in sub["orbit_status"].dims]),
                         failed.shape)[failed]
    marks = hv.Points((at, np.zeros(at.size)), list(dims), label=FAILED).opts(
        **style.marker_style(backend, FAILED_COLOUR, 9 if backend == "bokeh" else 6, "s", hollow=True), backend=backend)
    if backend == "bokeh":
        marks = marks.opts(tools=["hover"], hover_tooltips=hover(dims[:1], labels[:1]) + [("torus", FAILED)],
                           backend=backend)
    return [marks]


def fig_response(ds, backend="bokeh"):
    """Half peak-to-peak amplitude of each observable along the continued axis, one line per value
    of the first other swept axis; one panel per observable (and facet combination, at most
    MAX_PANELS in all)."""
    hv = style.holoviews()
    plan = axes_plan(ds)
    # two lines: one would widen the PNG past its panels
    head = (f"Response curves: amplitude (half peak-to-peak) vs {axis_display(ds, plan['x'])[2]}\n"
            + ("solid: stable, dashed: unstable (a torus: or undecided), squares at 0: torus failed"
               if has_tori(ds) else "solid: stable, dashed: unstable"))
    title = figure_title(ds, head, plan)
    observables = [o.name for o in schema.model_of(ds).observables]
    cells = [(o, where) for where in plan["shown"] for o in observables][:MAX_PANELS]
    columns = 1 if len(cells) == 1 else 2
    panels = []
    for k, (o, where) in enumerate(cells):
        show_x, _ = style.grid_opts(k, len(cells), backend, columns)
        long_name = next(ob.long_name for ob in schema.model_of(ds).observables if ob.name == o)
        panel_title = f"{o}: {long_name}" + (f" ({where_label(ds, where)})" if where else "")
        slot = Slot(panel_title, backend == "bokeh" or k == columns - 1, show_x, True)
        panel = _response_panel(hv, ds, where, backend, slot, o, plan["y"])
        size = {"width": 1150 if columns == 1 else 570, "height": 380} if backend == "bokeh" else {"aspect": 1.6}
        panels.append(panel.opts(**size, backend=backend))
    return style.layout(hv, panels, backend, columns, title, fig_inches=(11, 4.2 * -(-len(cells) // columns) + 0.6))


register(Figure(name="response", filename="response.png", title="Response curves (amplitude vs {axis})",
                applies=lambda ds: has_orbits(ds) or has_tori(ds),
                build=lambda ds, backend, intervals: fig_response(ds, backend)))

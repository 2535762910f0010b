"""Branch diagram: the periodic orbit along the continued axis, one panel per line, as
continuation tools draw it (stable solid, unstable dashed, the refined stability boundaries
marked LP / PD / NS); where the cube has attractors and the observable is the orbit's Poincare
coordinate, the brute-force attractor diagram (the Poincare samples) lies behind it.

Not hvplot: a line dashed where unstable, joined to its solid part, with labelled special points
(report/branches.py); hvplot draws one style per line (rotorsweep.pipeline.explore.branches: gaps at the
changes)."""
import numpy as np

from rotorsweep.pipeline import schema
from rotorsweep.pipeline.report.branches import SPECIAL_LABELS, branch_elements
from rotorsweep.pipeline.report.cubeinfo import (branch_observables, branch_values, continued_axis,
                                      default_observable, has_attractor, has_down, has_orbits, select,
                                      stable_response, sweep_labels)
from rotorsweep.pipeline.report.figures.panels import line_figure, panel_opts
from rotorsweep.pipeline.report.plan import axis_label, unit_display
from rotorsweep.pipeline.report.poincare import THIN_LEVELS, bif_range, sweep_dots
from rotorsweep.pipeline.report.registry import Figure, register
from rotorsweep.pipeline.report.stability import refined_boundaries

def _attractor_dots(hv, ds, line, observable, factor, backend, tooltips):
    """The Poincare samples of each sweep behind the branch of section_o."""
    x = continued_axis(ds)
    name = "poincare_" + observable[len("section_"):]
    sweeps = [line[name].transpose(x, ...).values * factor]
    if has_down(line):
        sweeps.append(line[name + schema.DOWN_SUFFIX].transpose(x, ...).values * factor)
    lo, hi = bif_range(np.concatenate([v.ravel() for v in sweeps]))
    grid = line[x].values.astype(float)
    return sweep_dots(hv, x, grid, sweeps, sweep_labels(ds), backend, (hi - lo) / THIN_LEVELS, tooltips,
                      ydim=observable)


def _branch_panel(hv, ds, where, backend, slot, observable):
    x = continued_axis(ds)
    line = select(ds, where)
    grid = line[x].values.astype(float)
    label, units = branch_observables(ds)[observable]
    factor, unit = unit_display(units)
    y = branch_values(line, observable) * factor
    labels = (axis_label(ds, x), f"{label} [{unit}]")
    specials = [(value, float(np.interp(value, grid, y)), SPECIAL_LABELS[kind])
                for _, _, value, kind in refined_boundaries(ds, where) if kind in SPECIAL_LABELS]
    elements = []
    if observable.startswith("section_") and has_attractor(line):
        tooltips = [(labels[0], f"@{{{x}}}"), (f"attractor: {labels[1]}", f"@{{{observable}}}")]
        elements += _attractor_dots(hv, ds, line, observable, factor, backend, tooltips)
    elements += branch_elements(grid, y, stable_response(line), specials, backend, dims=(x, observable),
                                labels=labels, colour="#0072B2")
    return hv.Overlay(elements).opts(**panel_opts(ds, slot, backend, labels[1], grid))


def fig_branches(ds, backend="bokeh", observable=None):
    """The periodic orbit's branch along the continued axis, one panel per line: `observable`
    (branch_observables; default: default_observable) stable solid and unstable dashed, the
    refined stability boundaries of the boundary table marked and labelled LP / PD / NS, and
    for section_o in a cube with attractors the Poincare samples behind it."""
    observable = observable or default_observable(ds)
    label = branch_observables(ds)[observable][0]

    def panel(hv, ds, where, backend, slot):
        return _branch_panel(hv, ds, where, backend, slot, observable)
    return line_figure(ds, backend, f"Periodic orbit branch: {label}", panel)


register(Figure(name="branches", filename="branches.png", title="Periodic orbit branches vs {axis}",
                applies=has_orbits, build=lambda ds, backend, intervals: fig_branches(ds, backend)))

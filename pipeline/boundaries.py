"""The boundary table of a cube: every change of stability between neighbouring values of the
continued axis (shaft speed for jeffcott_clearance) on a line, refined far below the grid step,
and stored in the cube along a `boundary` dimension.

Refinement follows the branch of the stable grid point by pseudo-arclength continuation
(rotorkernels.continuation.arclength) towards the unstable one and takes the first event where
a multiplier leaves the unit circle, located by its own test function: a fold (+1), where the
orbit ceases to exist and the unstable grid point's orbit lies on another branch, is located as
accurately as a period doubling or a Neimark-Sacker point. (Brent's method on max|lambda| - 1
between the two grid points cannot locate a fold: there is no continuous function to bracket.)
Only if the branch shows no such event within a grid step beyond the bracket does Brent's
method on the grid's natural continuation (rotorkernels.continuation.events) refine it.
"""
import itertools

import numpy as np

from pipeline import compute, schema
from rotorkernels import continuation, floquet
from rotorkernels.continuation import arclength, events as boundary

XTOL_REL = 1e-8
# The branch is followed at most a grid step beyond the bracket, in steps a fraction of it.
BRANCH_SETTINGS = arclength.Settings(ds=0.1, ds_max=0.25, max_steps=100)
_EVENT_TYPE = {arclength.FOLD: floquet.FOLD, arclength.PERIOD_DOUBLING: floquet.PERIOD_DOUBLING,
               arclength.NEIMARK_SACKER: floquet.NEIMARK_SACKER}


def _others(ds, axis):
    return [a for a in schema.point_axes(ds) if a != axis]


def _lines(ds, axis):
    """(values of the other axes, the cube along `axis`) for each combination of the other axes."""
    others = _others(ds, axis)
    for values in itertools.product(*(ds[a].values for a in others)):
        where = dict(zip(others, (float(v) for v in values)))
        yield where, (ds.sel(where) if where else ds)


def _solver(data, values, axis):
    """solve(value of `axis`, guess) -> the orbit there, the other axes at `values`; and
    family(scale) -> the arclength family along `axis`."""
    model = compute.model_of(data)
    opts = compute.integrator_settings(data)
    newton = compute.newton_settings(model, data["numerics"])
    build = compute.builder(data)

    def params(value):
        return build({**values, axis: value}).p

    def solve(value, guess):
        return continuation.solve_orbit(model, params(value), opts, [guess], **newton)

    def family(scale):
        return arclength.Family(model, params, opts, scale=scale)
    return solve, family


def _crossings(line):
    """Indices i where the orbit is found at i and i+1 and its stability differs."""
    ok = line["orbit_status"].values == 0
    stable = line["stable"].values == 1
    return [i for i in range(len(ok) - 1) if ok[i] and ok[i + 1] and stable[i] != stable[i + 1]]


# What a line's refinement reads: the grid and these variables (a few kB per line, shipped to a
# worker as one task per line).
_LINE_VARS = ("orbit_status", "stable", "orbit_state", "multiplier_real", "multiplier_imag")


def line_rows(data, where, line):
    """One dict per stability change on one line (`where`: values of the other axes; `line`: the
    cube along the continued axis there), refined where possible."""
    axis = schema.continued_axis(line)
    solvers = _solver(data, {**compute.fixed_values(data), **where}, axis)
    grid = line[axis].values
    rows = []
    for i in _crossings(line):
        row = {**{f"boundary_{k}": v for k, v in where.items()},
               "boundary_grid_low": grid[i], "boundary_grid_high": grid[i + 1],
               "boundary_direction": 0 if line["stable"].values[i] == 1 else 1}
        rows.append({**row, **_refine(solvers, line, axis, i)})
    return rows


def line_tasks(ds):
    """(where, line) per line of the cube, each line holding only what line_rows reads."""
    axis = schema.continued_axis(ds)
    keep = ds[[v for v in _LINE_VARS if v in ds]]
    return [(where, line.drop_vars([c for c in line.coords if c not in line.dims and c != axis]))
            for where, line in _lines(keep, axis)]


def boundary_rows(data, ds, map_lines=None):
    """One dict per stability change in the cube, line by line. map_lines(data, tasks) -> the
    rows of each task in order (default: here, one line after the other; a sweep passes one that
    spreads the lines over its Dask workers)."""
    tasks = line_tasks(ds)
    per_line = (map_lines or _serial)(data, tasks)
    return [row for rows in per_line for row in rows]


def _serial(data, tasks):
    return [line_rows(data, where, line) for where, line in tasks]


def _refine(solvers, line, axis, i):
    solve, family = solvers
    a, b = float(line[axis].values[i]), float(line[axis].values[i + 1])
    name = f"boundary_{axis}"
    event = _first_event_on_branch(family(b - a), line, axis, i)
    if event is not None:
        return {name: event.point.lam, "boundary_status": 0, "boundary_type": _EVENT_TYPE[event.kind]}
    try:
        found = boundary.locate_boundary(solve, a, b, line["orbit_state"].values[i],
                                         line["orbit_state"].values[i + 1], xtol_rel=XTOL_REL)
    except boundary.BoundaryError:
        lead = complex(line["multiplier_real"].values[i + 1, 0], line["multiplier_imag"].values[i + 1, 0])
        return {name: np.nan, "boundary_status": 1, "boundary_type": floquet.crossing_type(lead)}
    return {name: found.value, "boundary_status": 0,
            "boundary_type": floquet.crossing_type(found.solution.multipliers[0])}


def _first_event_on_branch(family, line, axis, i):
    """The first stability-losing event on the branch of the stable one of grid points i, i + 1,
    followed towards the other (at most a grid step beyond it); None if there is none."""
    grid = line[axis].values
    k, other = (i, i + 1) if line["stable"].values[i] == 1 else (i + 1, i)
    a, b = float(grid[k]), float(grid[other])
    span = abs(b - a)
    branch = arclength.continue_orbit(family, a, line["orbit_state"].values[k],
                                      (min(a, b) - span, max(a, b) + span), BRANCH_SETTINGS,
                                      direction=1 if b > a else -1)
    return next((e for e in branch.events if e.kind in _EVENT_TYPE), None)


def add_boundary_table(data, ds, map_lines=None):
    """ds with the boundary variables (dimension `boundary`, possibly of length 0); map_lines as
    in boundary_rows."""
    rows = boundary_rows(data, ds, map_lines)
    axis = schema.continued_axis(ds)
    out = ds.copy()
    coord = ds[axis].attrs
    for name, (dtype, attrs) in schema.boundary_variables(axis, coord["units"], coord["long_name"]).items():
        out[name] = ("boundary", np.array([r[name] for r in rows], dtype=dtype), dict(attrs))
    for other in _others(ds, axis):
        attrs = ds[other].attrs
        out[f"boundary_{other}"] = ("boundary", np.array([r[f"boundary_{other}"] for r in rows], float),
                                    {"units": attrs["units"], "long_name": f"{attrs['long_name']} of the boundary"})
    return out


def boundary_frame(ds):
    """The boundary table as a list of dicts (empty when the cube has none)."""
    if "boundary" not in ds.dims:
        return []
    names = [n for n in ds.data_vars if ds[n].dims == ("boundary",)]
    return [{n[len("boundary_"):]: ds[n].values[k].item() for n in names} for k in range(ds.sizes["boundary"])]


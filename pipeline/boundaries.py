"""The boundary table of a cube: every change of stability between neighbouring values of the
continued axis (shaft speed for jeffcott_clearance) on a line, refined by rotorkernels.boundary
(root finding on the continued orbit branch) far below the grid step, and stored in the cube
along a `boundary` dimension."""
import itertools

import numpy as np

from pipeline import compute, schema
from rotorkernels import continuation, floquet
from rotorkernels.continuation import events as boundary

XTOL_REL = 1e-8


def _others(ds, axis):
    return [a for a in schema.point_axes(ds) if a != axis]


def _lines(ds, axis):
    """(values of the other axes, the cube along `axis`) for each combination of the other axes."""
    others = _others(ds, axis)
    for values in itertools.product(*(ds[a].values for a in others)):
        where = dict(zip(others, (float(v) for v in values)))
        yield where, (ds.sel(where) if where else ds)


def _solver(data, values, axis):
    """solve(value of `axis`, guess) -> the orbit there, the other axes at `values`."""
    model = compute.model_of(data)
    opts = compute.integrator_settings(data)
    newton = compute.newton_settings(model, data["numerics"])

    def solve(value, guess):
        params = compute.point_params(data, {**values, axis: value})
        return continuation.solve_orbit(model, params.p, opts, [guess], **newton)
    return solve


def _crossings(line):
    """Indices i where the orbit is found at i and i+1 and its stability differs."""
    ok = line["orbit_status"].values == 0
    stable = line["stable"].values == 1
    return [i for i in range(len(ok) - 1) if ok[i] and ok[i + 1] and stable[i] != stable[i + 1]]


def boundary_rows(data, ds):
    """One dict per stability change in the cube, refined where possible."""
    axis = schema.continued_axis(ds)
    fixed = compute.fixed_values(data)
    rows = []
    for where, line in _lines(ds, axis):
        solve = _solver(data, {**fixed, **where}, axis)
        grid = line[axis].values
        for i in _crossings(line):
            row = {**{f"boundary_{k}": v for k, v in where.items()},
                   "boundary_grid_low": grid[i], "boundary_grid_high": grid[i + 1],
                   "boundary_direction": 0 if line["stable"].values[i] == 1 else 1}
            rows.append({**row, **_refine(solve, line, axis, i)})
    return rows


def _refine(solve, line, axis, i):
    a, b = float(line[axis].values[i]), float(line[axis].values[i + 1])
    name = f"boundary_{axis}"
    try:
        found = boundary.locate_boundary(solve, a, b, line["orbit_state"].values[i],
                                         line["orbit_state"].values[i + 1], xtol_rel=XTOL_REL)
    except boundary.BoundaryError:
        lead = complex(line["multiplier_real"].values[i + 1, 0], line["multiplier_imag"].values[i + 1, 0])
        return {name: np.nan, "boundary_status": 1, "boundary_type": floquet.crossing_type(lead)}
    return {name: found.value, "boundary_status": 0,
            "boundary_type": floquet.crossing_type(found.solution.multipliers[0])}


def add_boundary_table(data, ds):
    """ds with the boundary variables (dimension `boundary`, possibly of length 0)."""
    rows = boundary_rows(data, ds)
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


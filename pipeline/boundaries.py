"""The boundary table of a cube: every change of stability between neighbouring speeds of a line,
refined by rotorkernels.boundary (root finding on the continued orbit branch) far below the
grid step, and stored in the cube along a `boundary` dimension."""
import itertools

import numpy as np

from pipeline import compute, schema
from rotorkernels import boundary, continuation, floquet, models

XTOL_REL = 1e-8


def _lines(ds):
    """(values of the other axes, the cube along speed) for each combination of the other axes."""
    others = [a for a in schema.AXES if a in ds.dims and a != "speed"]
    for values in itertools.product(*(ds[a].values for a in others)):
        where = dict(zip(others, (float(v) for v in values)))
        yield where, (ds.sel(where) if where else ds)


def _point_values(data, where):
    """clearance/contact_angle/preload of a line: swept values, else the scene's fixed ones."""
    fixed = compute.fixed_values(data)
    return {k: where.get(k, fixed[k]) for k in ("clearance", "contact_angle", "preload")}


def _solver(data, values):
    model = compute.MODELS[data["scene"]["model"]]
    num = data["numerics"]
    opts = compute.integrator_settings(num)

    def solve(speed, guess):
        params = compute.point_params(data, speed, values["clearance"], values["contact_angle"],
                                      values["preload"])
        return continuation.solve_orbit(model, params.p, opts, [guess], cold_guess=models.static_guess,
                                        tol=num["newton_tol"], max_iter=num["max_newton_iter"],
                                        transient_periods=num["transient_periods"])
    return solve


def _crossings(line):
    """Indices i where the orbit is found at i and i+1 and its stability differs."""
    ok = line["orbit_status"].values == 0
    stable = line["stable"].values == 1
    return [i for i in range(len(ok) - 1) if ok[i] and ok[i + 1] and stable[i] != stable[i + 1]]


def boundary_rows(data, ds):
    """One dict per stability change in the cube, refined where possible."""
    rows = []
    for where, line in _lines(ds):
        values = _point_values(data, where)
        solve = _solver(data, values)
        speed = line["speed"].values
        for i in _crossings(line):
            row = {**{f"boundary_{k}": v for k, v in where.items()},
                   "boundary_grid_low": speed[i], "boundary_grid_high": speed[i + 1],
                   "boundary_direction": 0 if line["stable"].values[i] == 1 else 1}
            rows.append({**row, **_refine(solve, line, i)})
    return rows


def _refine(solve, line, i):
    a, b = float(line["speed"].values[i]), float(line["speed"].values[i + 1])
    try:
        found = boundary.locate_boundary(solve, a, b, line["orbit_state"].values[i],
                                         line["orbit_state"].values[i + 1], xtol_rel=XTOL_REL)
    except boundary.BoundaryError:
        lead = complex(line["multiplier_real"].values[i + 1, 0], line["multiplier_imag"].values[i + 1, 0])
        return {"boundary_speed": np.nan, "boundary_status": 1, "boundary_type": floquet.crossing_type(lead)}
    return {"boundary_speed": found.value, "boundary_status": 0,
            "boundary_type": floquet.crossing_type(found.solution.multipliers[0])}


def add_boundary_table(data, ds):
    """ds with the boundary variables (dimension `boundary`, possibly of length 0)."""
    rows = boundary_rows(data, ds)
    others = [a for a in schema.AXES if a in ds.dims and a != "speed"]
    out = ds.copy()
    for name, (dtype, attrs) in schema.BOUNDARY_VARIABLES.items():
        out[name] = ("boundary", np.array([r[name] for r in rows], dtype=dtype), dict(attrs))
    for axis in others:
        units, long_name = schema.AXES[axis]
        out[f"boundary_{axis}"] = ("boundary", np.array([r[f"boundary_{axis}"] for r in rows], float),
                                   {"units": units, "long_name": f"{long_name} of the boundary"})
    return out


def boundary_frame(ds):
    """The boundary table as a list of dicts (empty when the cube has none)."""
    if "boundary_speed" not in ds:
        return []
    names = [n for n in ds.data_vars if ds[n].dims == ("boundary",)]
    return [{n[len("boundary_"):]: ds[n].values[k].item() for n in names} for k in range(ds.sizes["boundary"])]


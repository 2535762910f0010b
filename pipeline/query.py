"""Questions asked of a result cube: selections and the unstable speed intervals."""
import itertools

import numpy as np

from pipeline import schema


def _other_axes(ds):
    return [a for a in schema.AXES if a in ds.dims and a != "speed"]


def _runs(mask):
    """(first, last) index pairs of the maximal runs of True in a 1-D boolean array."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1))


def _run_type(line, i0):
    """The instability type of a run: how the orbit lost stability at its first point."""
    if int(line["orbit_status"].values[i0]) != 0:
        return "no_orbit"
    return schema.BIFURCATION[int(line["bifurcation"].values[i0])]


def unstable_intervals(ds):
    """Maximal runs of consecutive speeds whose periodic orbit is not stable (unstable, or not
    found), one list entry per run and per combination of the other swept axes.

    Each entry: the other axes' values, `start`/`end` (Hz, the first and last grid speed of the
    run), `n_points`, `type` (fold / period_doubling / neimark_sacker / no_orbit: the state at the
    run's first point) and the run's largest `max_abs_multiplier`."""
    others = _other_axes(ds)
    speed = ds["speed"].values
    out = []
    for values in itertools.product(*(ds[a].values for a in others)):
        where = dict(zip(others, values))
        line = ds.sel(where) if where else ds
        not_stable = (line["stable"].values != 1) | (line["orbit_status"].values != 0)
        for i0, i1 in _runs(not_stable):
            mu = line["max_abs_multiplier"].values[i0:i1 + 1]
            out.append({
                **{a: float(v) for a, v in where.items()},
                "start": float(speed[i0]),
                "end": float(speed[i1]),
                "n_points": int(i1 - i0 + 1),
                "type": _run_type(line, i0),
                "max_abs_multiplier": float(np.nanmax(mu)) if np.isfinite(mu).any() else float("nan"),
            })
    return out

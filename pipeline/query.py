"""Questions asked of a result cube: selections, flat tables (table/csv/json) and the unstable
speed intervals."""
import itertools
import json
import math

import numpy as np
import pandas as pd

from rotorsweep.pipeline import schema

RTOL = 1e-9                       # a typed value matches a grid value to this relative tolerance
DEFAULT_VARIABLES = ("orbit_status", "max_abs_multiplier", "stable", "bifurcation")
FORMATS = ("table", "csv", "json")


class QueryError(Exception):
    """A selection or output request the cube cannot answer (message for the user)."""


# --- selections -----------------------------------------------------------------------------

def parse_where(items):
    """`AXIS=SEL` strings -> {axis: slice(lo, hi) (inclusive, None: open) or [values]}.
    SEL: "80:120", "80:", ":120" (range), "3.8e-6" (a value) or "0,100" (a list)."""
    where = {}
    for item in items:
        axis, sep, sel = (part.strip() for part in item.partition("="))
        if not sep or not axis or not sel:
            raise QueryError(f"bad selection {item!r}: expected AXIS=SEL, e.g. speed=80:120")
        if axis in where:
            raise QueryError(f"{axis} is selected twice")
        where[axis] = _parse_selector(item, sel)
    return where


def _parse_selector(item, sel):
    if ":" in sel:
        bounds = sel.split(":")
        if len(bounds) != 2:
            raise QueryError(f"bad range in {item!r}: expected LO:HI")
        return slice(*(_number(item, b) if b.strip() else None for b in bounds))
    return [_number(item, v) for v in sel.split(",")]


def _number(item, text):
    try:
        return float(text)
    except ValueError:
        raise QueryError(f"bad number {text.strip()!r} in {item!r}") from None


def select(ds, where):
    """The part of a cube that `where` (from parse_where) selects; swept axes stay dimensions."""
    axes = schema.point_axes(ds)
    index = {}
    for axis, sel in where.items():
        if axis not in axes:
            raise QueryError(f"{axis} is not a swept axis of this cube; its axes are {', '.join(axes)}")
        grid = ds[axis].values
        index[axis] = _range_index(axis, grid, sel) if isinstance(sel, slice) else _value_index(axis, grid, sel)
    return ds.isel(index)


def _range_index(axis, grid, sel):
    keep = np.ones(grid.shape, bool)
    if sel.start is not None:
        keep &= grid >= sel.start - RTOL * abs(sel.start)
    if sel.stop is not None:
        keep &= grid <= sel.stop + RTOL * abs(sel.stop)
    if not keep.any():
        lo, hi = ("" if b is None else f"{b:g}" for b in (sel.start, sel.stop))
        raise QueryError(f"{axis}={lo}:{hi} selects no grid value; the grid spans "
                         f"{grid.min():g} .. {grid.max():g}")
    return np.flatnonzero(keep)


def _value_index(axis, grid, values):
    out = []
    for v in values:
        hits = np.flatnonzero(np.isclose(grid, v, rtol=RTOL, atol=0.0))
        if not hits.size:
            raise QueryError(f"{axis}={v:g} is not on the grid; available: {_sample(grid)}")
        out.append(hits[0])
    return out


def _sample(grid, n=8):
    shown = ", ".join(f"{g:g}" for g in grid[:n])
    return shown + (f", ... ({grid.size} values, up to {grid[-1]:g})" if grid.size > n else "")


# --- tables ---------------------------------------------------------------------------------

def to_table(ds, variables=None, fmt="table"):
    """One row per grid point (the continued axis varying fastest): axis columns, then the variables. Flags
    are shown by meaning; a variable with an extra dimension gives one column per index."""
    variables = list(variables or [v for v in DEFAULT_VARIABLES if v in ds])
    unknown = [v for v in variables if v not in ds.data_vars]
    if unknown:
        raise QueryError(f"unknown variable {unknown[0]!r}; this cube has {', '.join(ds.data_vars)}")
    axes = schema.point_axes(ds)
    along = schema.continued_axis(ds)
    order = [a for a in axes if a != along] + [along]
    grid = np.meshgrid(*(ds[a].values for a in order), indexing="ij")
    columns = {a: grid[order.index(a)].ravel().tolist() for a in axes}
    for name in variables:
        columns.update(_columns(name, ds[name], order))
    return render(columns, fmt)


def _columns(name, var, order):
    """A variable's column, or one per index of its extra dims (multiplier_real_0, ...)."""
    extra = [d for d in var.dims if d not in order]
    n_points = int(np.prod([var.sizes[a] for a in order]))
    values = var.transpose(*order, *extra).values.reshape(n_points, -1)
    suffixes = ("_".join(map(str, k)) for k in np.ndindex(*(var.sizes[d] for d in extra)))
    labels = [f"{name}_{s}" if s else name for s in suffixes]
    shown = _flag_names(var)
    return {label: [shown(x) for x in values[:, j].tolist()] for j, label in enumerate(labels)}


def _flag_names(var):
    """value -> shown value: a flag's meaning (None where unset), else the value itself."""
    if "flag_meanings" not in var.attrs:
        return lambda x: x
    names = dict(zip(np.asarray(var.attrs["flag_values"]).tolist(), var.attrs["flag_meanings"].split()))
    return names.get


def intervals_table(intervals, fmt="table", kind="unstable"):
    """unstable_intervals(ds) (or another `kind` of intervals) in one of FORMATS."""
    if not intervals:
        return {"table": f"no {kind} intervals", "csv": "", "json": "[]"}[_check_format(fmt)]
    return render({k: [row[k] for row in intervals] for k in intervals[0]}, fmt)


def _check_format(fmt):
    if fmt not in FORMATS:
        raise QueryError(f"unknown format {fmt!r}; use one of {', '.join(FORMATS)}")
    return fmt


def render(columns, fmt):
    """Columns {name: values} in one of FORMATS (what every query and the reports' CSV files print)."""
    fmt = _check_format(fmt)
    if fmt == "json":
        rows = [dict(zip(columns, values)) for values in zip(*columns.values())]
        return json.dumps([{k: _json_value(v) for k, v in row.items()} for row in rows], indent=1)
    frame = pd.DataFrame(columns)
    if fmt == "csv":
        return frame.to_csv(index=False, lineterminator="\n").rstrip("\n")
    return frame.to_string(index=False, na_rep="-", float_format=lambda x: f"{x:.7g}")


def _json_value(v):
    return None if isinstance(v, float) and not math.isfinite(v) else v


def _other_axes(ds):
    along = schema.continued_axis(ds)
    return [a for a in schema.point_axes(ds) if a != along]


def _runs(mask):
    """(first, last) index pairs of the maximal runs of True in a 1-D boolean array."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1))


def _run_type(line, i0):
    """The instability type of a run: how the orbit lost stability at its first point."""
    if int(line["orbit_status"].values[i0]) != 0:
        return "no_orbit"
    return schema.BIFURCATION[int(line["bifurcation"].values[i0])]


def _refined_crossings(ds, others):
    """(other axes' values..., unstable grid value next to the crossing) -> (refined value, type)."""
    name = f"boundary_{schema.continued_axis(ds)}"
    if name not in ds:
        return {}
    out = {}
    for k in range(ds.sizes["boundary"]):
        if int(ds["boundary_direction"].values[k]) >= ENTERS_BISTABLE:
            continue        # a jump's fold pair bounds no unstable run
        key = tuple(ds[f"boundary_{a}"].values[k] for a in others)
        losing = int(ds["boundary_direction"].values[k]) == 0
        unstable_side = ds["boundary_grid_high" if losing else "boundary_grid_low"].values[k]
        out[(*key, float(unstable_side))] = (float(ds[name].values[k]),
                                             schema.BIFURCATION[int(ds["boundary_type"].values[k])])
    return out


NOT_APPLICABLE = schema.ORBIT_STATUS.index("not_applicable")
ENTERS_BISTABLE = schema.BOUNDARY_DIRECTION.index("enters_bistable")


def bistable_intervals(ds):
    """The bistable intervals of a cube: one per jump of the sweep (two neighbouring points on
    different branches), between the fold pair its boundary table holds (rotorsweep.pipeline.boundaries).

    Each entry: the other axes' values, `start`/`end` (the lower and upper fold; NaN where the
    pair could not be located), `grid_low`/`grid_high` (the grid points either side of the jump),
    and where the sweep recorded them (boundaries: coexistence.distinct_stable_orbits in the
    middle of the pair), the two coexisting stable orbits: `orbit1_*`, `orbit2_*` (half
    peak-to-peak amplitude of each observable, period in forcing periods, largest |multiplier|)
    and `orbits_at` (where they were computed)."""
    along = schema.continued_axis(ds)
    others = _other_axes(ds)
    name = f"boundary_{along}"
    if name not in ds:
        return []
    pairs = {}
    for k in np.flatnonzero(ds["boundary_direction"].values >= ENTERS_BISTABLE):
        key = (*(float(ds[f"boundary_{a}"].values[k]) for a in others),
               float(ds["boundary_grid_low"].values[k]), float(ds["boundary_grid_high"].values[k]))
        enters = int(ds["boundary_direction"].values[k]) == ENTERS_BISTABLE
        pairs.setdefault(key, {})["start" if enters else "end"] = float(ds[name].values[k])
        pairs[key].update(_coexisting_orbit(ds, k, "orbit1" if enters else "orbit2", along))
    return [{**dict(zip(others, key[:-2])), "start": fold.pop("start", np.nan), "end": fold.pop("end", np.nan),
             "grid_low": key[-2], "grid_high": key[-1], **dict(sorted(fold.items()))}
            for key, fold in sorted(pairs.items())]


def _coexisting_orbit(ds, k, prefix, along):
    """{prefix_amplitude_<observable>, prefix_periods, prefix_max_abs_multiplier, orbits_at} of a
    jump's boundary row k (the boundary table's orbit columns); {} where it has none."""
    if f"boundary_orbit_{along}" not in ds or not np.isfinite(ds[f"boundary_orbit_{along}"].values[k]):
        return {}
    start = "boundary_orbit_amplitude_"
    out = {f"{prefix}_amplitude_{n[len(start):]}": float(ds[n].values[k]) for n in ds.data_vars if n.startswith(start)}
    return {**out, f"{prefix}_periods": int(ds["boundary_orbit_periods"].values[k]),
            f"{prefix}_max_abs_multiplier": float(ds["boundary_orbit_max_abs_multiplier"].values[k]),
            "orbits_at": float(ds[f"boundary_orbit_{along}"].values[k])}


def unstable_intervals(ds):
    """Maximal runs of consecutive values of the continued axis (speed) whose periodic orbit is
    not stable (unstable, or not found), one list entry per run and per combination of the other
    swept axes. Points whose orbit is `not_applicable` (no periodic orbit by design: quasi-periodic
    forcing) belong to no such run; where they have their torus (rotorsweep.pipeline.torus_points),
    the runs of unstable tori and of failed ones are listed too (_torus_runs), in the classes of
    point_classes.

    Each entry: the other axes' values, `start`/`end` (the first and last grid value of the
    run), `onset`/`offset` (the refined crossings of the cube's boundary table just below
    `start` and just above `end`; NaN where there is none, e.g. at a grid edge or next to a point
    without orbit, and for tori), `n_points`, `type` (fold / period_doubling / neimark_sacker /
    no_orbit: how the stable orbit before the run lost stability, from the boundary table where
    the onset is refined -- a fold there although the run's first grid orbit, on another branch,
    may be period-doubled -- else the state at the run's first point; quasi_periodic_unstable /
    torus_failed for a run of tori) and the run's largest `max_abs_multiplier`. A cube with torus
    variables adds to every entry `max_torus_exponent` (the run's largest normal exponent [1/s])
    and `reason` (a failed torus run's torus_status names; "" elsewhere)."""
    others = _other_axes(ds)
    speed = ds[schema.continued_axis(ds)].values
    refined = _refined_crossings(ds, others)
    out = []
    for values in itertools.product(*(ds[a].values for a in others)):
        where = dict(zip(others, values))
        line = ds.sel(where) if where else ds
        status = line["orbit_status"].values
        # a point with no orbit by design (quasi-periodic forcing) lost no stability
        not_stable = ((line["stable"].values != 1) | (status != 0)) & (status != NOT_APPLICABLE)
        runs = []
        for i0, i1 in _runs(not_stable):
            mu = line["max_abs_multiplier"].values[i0:i1 + 1] if "max_abs_multiplier" in line else np.full(1, np.nan)
            runs.append({
                **{a: float(v) for a, v in where.items()},
                "start": float(speed[i0]),
                "end": float(speed[i1]),
                "onset": refined.get((*values, float(speed[i0])), (float("nan"),))[0],
                "offset": refined.get((*values, float(speed[i1])), (float("nan"),))[0],
                "n_points": int(i1 - i0 + 1),
                "type": refined.get((*values, float(speed[i0])), (None, _run_type(line, i0)))[1],
                "max_abs_multiplier": _nanmax(mu),
                **({"max_torus_exponent": float("nan"), "reason": ""} if "torus_status" in ds else {}),
            })
        out += sorted(runs + _torus_runs(line, where, speed), key=lambda run: run["start"])
    return out


def _nanmax(values):
    return float(np.nanmax(values)) if np.isfinite(values).any() else float("nan")


TORUS_UNSTABLE = ("quasi_periodic_unstable", "torus_failed")    # the torus classes `query --unstable` lists


def _torus_runs(line, where, speed):
    """unstable_intervals' entries of one line's runs of tori of one class in TORUS_UNSTABLE
    (torus_class_names); a failed run's `reason`: its points' torus_status names."""
    if "torus_status" not in line:
        return []
    names = torus_class_names(line)
    out = []
    for cls in TORUS_UNSTABLE:
        for i0, i1 in _runs(names == cls):
            status = sorted({schema.TORUS_STATUS[int(k)] for k in line["torus_status"].values[i0:i1 + 1]})
            out.append({**{a: float(v) for a, v in where.items()}, "start": float(speed[i0]), "end": float(speed[i1]),
                        "onset": float("nan"), "offset": float("nan"), "n_points": int(i1 - i0 + 1), "type": cls,
                        "max_abs_multiplier": float("nan"),
                        "max_torus_exponent": _nanmax(line["torus_exponent"].values[i0:i1 + 1]),
                        "reason": ",".join(status) if cls == "torus_failed" else ""})
    return out


def point_classes(ds):
    """The one vocabulary of the stability of grid points (the map, the report's header counts
    and `query --unstable` read it): per point (DataArray over the point dims) "stable" or
    "not_applicable" (no orbit by design) -- what the grid point is -- or, for a point of an
    unstable interval, the interval's `type` (fold / period_doubling / neimark_sacker / no_orbit
    / none): how stability was lost before it (unstable_intervals). A point without orbit is
    "no_orbit" wherever it lies; an unstable orbit in an interval that began without orbit has
    its own bifurcation code's name. A stable point inside a bistable interval
    (bistable_intervals: another stable orbit coexists there) is "bistable". A
    quasi-periodically forced point with its torus is "quasi_periodic_stable" / "_unstable" /
    "_undecided", or "torus_failed" (_torus_classes)."""
    import xarray as xr

    status = ds["orbit_status"]
    names = np.where(status.values == NOT_APPLICABLE, "not_applicable",
                     np.where((status.values == 0) & (ds["stable"].values == 1), "stable", "none")).astype(object)
    cls = xr.DataArray(names, {d: ds[d].values for d in status.dims}, status.dims)
    along = schema.continued_axis(ds)
    for iv in unstable_intervals(ds):
        sel = {a: iv[a] for a in _other_axes(ds)}
        grid = cls[along].values
        inside = (grid >= iv["start"]) & (grid <= iv["end"])
        cls.loc[{**sel, along: grid[inside]}] = iv["type"]
    # a point without orbit is that; an orbit in a run that began without one has no known
    # loss of stability before it: its own code says how it is unstable
    own = np.vectorize(lambda k: schema.BIFURCATION[int(k)] if 0 <= k < len(schema.BIFURCATION) else "none",
                       otypes=[object])(ds["bifurcation"].values)
    values = cls.values
    values[(status.values != 0) & (status.values != NOT_APPLICABLE)] = "no_orbit"
    began_without = (values == "no_orbit") & (status.values == 0)
    values[began_without] = own[began_without]
    for iv in bistable_intervals(ds):
        sel = {a: iv[a] for a in _other_axes(ds)}
        grid = cls[along].values
        inside = grid[(grid >= iv["start"]) & (grid <= iv["end"])]
        line = cls.loc[{**sel, along: inside}]
        cls.loc[{**sel, along: inside}] = np.where(line.values == "stable", "bistable", line.values)
    _torus_classes(ds, cls.values)
    return cls


def class_runs(ds):
    """Maximal runs of grid points of one class (point_classes) along the continued axis, one
    list entry per run and per combination of the other swept axes: the other axes' values,
    `start`/`end` (first and last grid value), `n_points`, `class`. What `info` lists, and what
    the map draws as bands."""
    cls = point_classes(ds)
    along = schema.continued_axis(ds)
    others = _other_axes(ds)
    grid = ds[along].values
    out = []
    for values in itertools.product(*(ds[a].values for a in others)):
        where = dict(zip(others, values))
        names = (cls.sel(where) if where else cls).transpose(along).values
        cuts = np.flatnonzero(names[1:] != names[:-1]) + 1
        for i0, i1 in zip(np.concatenate(([0], cuts)), np.concatenate((cuts, [names.size])) - 1):
            out.append({**{a: float(v) for a, v in where.items()}, "start": float(grid[i0]),
                        "end": float(grid[i1]), "n_points": int(i1 - i0 + 1), "class": str(names[i0])})
    return out


# `info`'s legend of the torus classes (torus_class_names), after the orbit classes' one
TORUS_CLASS_LEGEND = ("quasi_periodic_stable, quasi_periodic_unstable, quasi_periodic_undecided: the point's forcing "
                      "is quasi-periodic (no periodic orbit by design) and its torus is normally stable, unstable, or "
                      "undecided (the largest normal exponent within its error of 0); torus_failed: its torus did not "
                      "converge (torus_status says why)")


def torus_class_names(ds):
    """Per point (array over orbit_status' dims): where the point has no orbit by design and its
    torus was attempted (rotorsweep.pipeline.torus_points) "quasi_periodic_<stable|unstable|undecided>",
    or "torus_failed" where its torus did not converge; None elsewhere (no torus variables: all None)."""
    out = np.full(ds["orbit_status"].shape, None, dtype=object)
    if "torus_status" not in ds:
        return out
    status = ds["torus_status"].transpose(*ds["orbit_status"].dims).values
    stab = ds["torus_stability"].transpose(*ds["orbit_status"].dims).values
    solved = (ds["orbit_status"].values == NOT_APPLICABLE) & (status >= 0)
    names = np.array([f"quasi_periodic_{name}" for name in schema.TORUS_STABILITY] + ["torus_failed"], dtype=object)
    converged = status == schema.TORUS_STATUS.index("converged")
    pick = np.where(converged & (stab >= 0), stab, len(schema.TORUS_STABILITY))
    out[solved] = names[pick[solved]]
    return out


def _torus_classes(ds, values):
    """point_classes' values (in place) at the points with their torus: torus_class_names."""
    names = torus_class_names(ds)
    has = names.astype(bool)
    values[has] = names[has]


def attractor_label(code, k):
    """'period-k', or the class name: 'quasi_periodic', 'chaotic', 'diverged', 'not_settled',
    'integration_failed', 'not_computed'."""
    if code == schema.ATTRACTOR.index("periodic"):
        return f"period-{k}" if k > 0 else "periodic"
    return schema.ATTRACTOR[code] if 0 <= code < len(schema.ATTRACTOR) else "not_computed"


def attractor_intervals(ds, direction="up"):
    """Maximal runs of consecutive values of the continued axis on which the attractor keeps its class and period, per
    combination of the other swept axes (the bifurcation diagram as a table). direction "down"
    reads the down sweep (`*_down`) of a sweep_direction = "both" cube.

    Each entry: the other axes' values, `start`/`end`, `n_points`, `attractor` (see
    attractor_label) and the run's largest exponent `max_lle` [1/s].

    >>> ds = rotorsweep.open_cube(cube_path)
    >>> [(run["start"], run["attractor"]) for run in rotorsweep.attractor_intervals(ds)]
    [(79.0, 'period-1'), (82.0, 'period-2')]
    """
    suffix = schema.DOWN_SUFFIX if direction == "down" else ""
    if "attractor" + suffix not in ds:
        raise ValueError("the cube has no attractor diagnostics"
                         + (" for the down sweep" if suffix and "attractor" in ds else
                            "; run the scene with [analysis] attractor = true"))
    others = _other_axes(ds)
    speed = ds[schema.continued_axis(ds)].values
    out = []
    for values in itertools.product(*(ds[a].values for a in others)):
        where = dict(zip(others, values))
        line = ds.sel(where) if where else ds
        labels = np.array([attractor_label(int(c), int(k)) for c, k in
                           zip(line["attractor" + suffix].values, line["period" + suffix].values)])
        lle = line["lle" + suffix].values
        cuts = np.flatnonzero(labels[1:] != labels[:-1]) + 1
        for i0, i1 in zip(np.concatenate(([0], cuts)), np.concatenate((cuts, [len(labels)])) - 1):
            seg = lle[i0:i1 + 1]
            out.append({
                **{a: float(v) for a, v in where.items()},
                "start": float(speed[i0]),
                "end": float(speed[i1]),
                "n_points": int(i1 - i0 + 1),
                "attractor": str(labels[i0]),
                "max_lle": float(np.nanmax(seg)) if np.isfinite(seg).any() else float("nan"),
            })
    return out


# --- continuation results ---------------------------------------------------------------------

def branch_unstable_stretches(ds):
    """`query --unstable` of a continuation result: the maximal runs of unstable points along each
    distinct branch (in branch order), an orbit branch's (stable 0) and a torus branch's
    (rotorsweep.pipeline.torus_branches: torus_status unstable, "quasi_periodic_unstable" in
    point_classes' vocabulary; an undecided torus is listed by neither, as in a cube).

    Each entry: the line's coordinates, `branch`, `kind` (periodic_orbit / torus), `start`/`end`
    (the parameter at the run's first and last point), `onset`/`offset` (the located fold, period
    doubling, Neimark-Sacker or branch point just before / after the run; on a torus branch the
    located change of normal stability, TS, else the located fold of tori, TF, between the run and
    the nearest decided point outside it (the undecided points next to a crossing lie between);
    NaN where none was located: at a branch end, or a flag kept as a bracket), `n_points`, `type`
    (the onset's event name, "none" without one, or quasi_periodic_unstable), the run's largest
    `max_abs_multiplier` (orbits) and `max_torus_exponent` [1/s] (tori)."""
    from rotorsweep.pipeline import coexistence
    from rotorsweep.kernels import continuation_codes as ev

    tori = ds["branch_kind"].values == 1 if "branch_kind" in ds else np.zeros(ds.sizes["branch"], bool)
    lines = [c for c in ds.coords if ds[c].dims == ("branch",)]
    rows = list(zip(ds["event_branch"].values, ds["event_point"].values, ds["event_parameter"].values,
                    ds["event_type"].values))
    located = {(int(b), int(p)): (float(v), ev.EVENT_TYPES[int(k)]) for b, p, v, k in rows
               if k in (ev.FOLD, ev.PERIOD_DOUBLING, ev.NEIMARK_SACKER, ev.BRANCH_POINT)}
    out = []
    for b in coexistence.distinct_branches(ds):
        n = int(ds["branch_points"].values[b])
        lam = ds["parameter"].values[b, :n]
        torus = bool(tori[b])
        status = ds["torus_status"].values[b, :n] if torus else None
        unstable = (status == 0) if torus else (ds["stable"].values[b, :n] == 0)
        for i0, i1 in _runs(unstable):
            if torus:
                onset, offset = torus_crossings(rows, b, status, i0, i1)
            else:
                onset, offset = located.get((b, i0 - 1), (np.nan, "none")), located.get((b, i1), (np.nan, None))
            out.append({**{c: float(ds[c].values[b]) for c in lines}, "branch": int(b),
                        "kind": "torus" if torus else "periodic_orbit", "start": float(lam[i0]), "end": float(lam[i1]),
                        "onset": onset[0], "offset": offset[0], "n_points": int(i1 - i0 + 1),
                        "type": "quasi_periodic_unstable" if torus else onset[1],
                        "max_abs_multiplier": _nanmax(ds["max_abs_multiplier"].values[b, i0:i1 + 1]),
                        "max_torus_exponent": _nanmax(ds["torus_exponent"].values[b, i0:i1 + 1])
                        if "torus_exponent" in ds else float("nan")})
    return out


def torus_crossings(rows, b, status, i0, i1):
    """((onset, label), (offset, label)) of the unstable run i0..i1 of torus branch b (status: its
    torus_status, 2 undecided): the located TS, else TF, event row (rows: (branch, point,
    parameter, type)) on a step between the run's end and the nearest decided point beyond the
    undecided ones next to it; (NaN, "none") where there is none."""
    from rotorsweep.kernels import continuation_codes as ev

    def crossing(lo, hi):
        """The event on the steps lo .. hi (a step k: points k to k + 1)."""
        for code in (ev.TORUS_STABILITY, ev.TORUS_FOLD):
            hits = [v for eb, p, v, k in rows if eb == b and k == code and lo <= p <= hi and np.isfinite(v)]
            if hits:
                return float(hits[0]), ev.EVENT_TYPES[code]
        return np.nan, "none"
    before, after = i0 - 1, i1 + 1
    while before > 0 and status[before] == 2:
        before -= 1
    while after < len(status) - 1 and status[after] == 2:
        after += 1
    return crossing(max(before, 0), i0 - 1), crossing(i1, after - 1)

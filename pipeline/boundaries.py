"""The boundary table of a cube: every change of stability between neighbouring values of the
continued axis (shaft speed for jeffcott_clearance) on a line, refined far below the grid step,
and stored in the cube along a `boundary` dimension.

Refinement follows the branch of the stable grid point by pseudo-arclength continuation
(rotorsweep.kernels.continuation.arclength) towards the unstable one and takes the first event where
a multiplier leaves the unit circle, located by its own test function: a fold (+1), where the
orbit ceases to exist and the unstable grid point's orbit lies on another branch, is located as
accurately as a period doubling or a Neimark-Sacker point. (Brent's method on max|lambda| - 1
between the two grid points cannot locate a fold: there is no continuous function to bracket.)
Only if the branch shows no such event within a grid step beyond the bracket does Brent's
method on the grid's natural continuation (rotorsweep.kernels.continuation.events) refine it.

A jump (hysteresis) is a pair of neighbouring points, both stable or both unstable, that lie on
different branches (`jump_brackets` says how it is told from a steep smooth branch): the branch of
the point next to the fold is followed through a window around the gap until it has turned at
both folds of the pair, and both become rows typed fold, with the directions enters_bistable /
leaves_bistable (the bistable interval lies between them).
"""
import itertools
from collections import namedtuple

import numpy as np

from rotorsweep.pipeline import coexistence, compute, schema
from rotorsweep.kernels import continuation, extrema, floquet
from rotorsweep.kernels.continuation import arclength, events as boundary

XTOL_REL = 1e-8
# The branch is followed at most a grid step beyond the bracket, in steps a fraction of it.
BRANCH_SETTINGS = arclength.Settings(ds=0.1, ds_max=0.25, max_steps=100)
_EVENT_TYPE = {arclength.FOLD: floquet.FOLD, arclength.PERIOD_DOUBLING: floquet.PERIOD_DOUBLING,
               arclength.NEIMARK_SACKER: floquet.NEIMARK_SACKER}


def _others(ds, axis):
    return [a for a in schema.point_axes(ds) if a != axis]


def axis_solver(scene, values, axis):
    """solve(value of `axis`, guess) -> the orbit there, the other axes at `values`;
    family(scale) -> the arclength family along `axis`; and half_pp(value, state, periods) -> the
    half peak-to-peak amplitude of each observable over the orbit (SI, exact: rotorsweep.kernels.extrema)
    (scene: rotorsweep.pipeline.scene.Scene)."""
    model = scene.model
    opts = scene.integrator
    newton = scene.newton.solve_orbit_args(model)
    build = compute.builder(scene)

    def params(value):
        return build({**values, axis: value}).p

    def solve(value, guess):
        return continuation.solve_orbit(model, params(value), opts, [guess], **newton)

    def family(scale):
        return arclength.Family(model, params, opts, scale=scale)

    def half_pp(value, state, periods):
        built = build({**values, axis: value})
        return extrema.amplitudes(model, state, built.p, periods, opts, built.period)[1]
    return solve, family, half_pp


# One stability change between grid points i and i + 1 of a line (`line`: the other axes' grid
# indices): what its refinement reads, a few hundred bytes (shipped to the workers as is).
# jump: None for a stability change; for a jump, the side (0: grid[0], 1: grid[1]) whose multiplier
# lies nearest +1, where the branch through the fold pair is started.
Bracket = namedtuple("Bracket", "line i grid stable states lead jump", defaults=(None,))


def brackets(line, grid, status, stable, states, lead, candidates=None):
    """The Brackets of one line from its per-point arrays (status, stable: ints; states (n, n_state);
    lead: the leading multiplier), where the orbit is found at i and i + 1 and its stability
    differs; `candidates`: the i to test (default: all)."""
    i = np.arange(len(grid) - 1) if candidates is None else np.asarray(candidates, int)
    ok = (status[i] == 0) & (status[i + 1] == 0)
    change = ok & ((stable[i] == 1) != (stable[i + 1] == 1))
    return [Bracket(line, int(k), (float(grid[k]), float(grid[k + 1])),
                    (int(stable[k]), int(stable[k + 1])), (states[k], states[k + 1]), complex(lead[k + 1]))
            for k in i[change]]


def _lead(real, imag):
    return real[..., 0] + 1j * imag[..., 0]


def _near_one(real, imag):
    """Per point, the distance of the multiplier nearest +1 from +1."""
    return np.min(np.abs(real + 1j * imag - 1.0), axis=-1)


# The jump criterion. Between grid points i and i + 1 of one branch the state moves by about the
# tangent-predicted step |x'| h, which varies smoothly: the neighbouring steps (i - 1 -> i and
# i + 1 -> i + 2) predict it. Where the state moves more than JUMP_RATIO times the larger of them,
# the two points are not on one branch. The steepest smooth case is a branch that ends in a fold
# x ~ sqrt(lambda_f - lambda) exactly at a grid point: its last step is (sqrt(2) - 1)^-1 = 2.41
# times the one before, below 3. A jump over a fold also has a multiplier approaching +1 on the
# side that ends there: at least one of the two points has a multiplier within NEAR_ONE of +1 (the
# Bai rotor's jumps with 0.05 Hz steps: 0.14 at 7.6 um, 0.02 at 15.2 um, and their jumps are
# 7.7 and 4.0 times the larger neighbouring step). Both conditions read arrays the chunk holds.
JUMP_RATIO = 3.0
NEAR_ONE = 0.5
# The fold pair is looked for this many grid steps either side of the gap, in continuation steps
# of a fraction of the grid step; the branch is started at the near-fold side.
JUMP_WINDOW = 10
JUMP_SETTINGS = arclength.Settings(ds=0.1, ds_max=0.5, max_steps=300)


def jump_brackets(line, grid, pos, status, stable, states, near):
    """The jump Brackets of one line from the per-point arrays of its points at grid indices
    `pos` (increasing; gaps allowed): a pair of neighbours on the grid is tested where the steps
    before and after it are known too."""
    pos = np.asarray(pos, int)
    step = np.linalg.norm(np.diff(states, axis=0), axis=1)
    adjacent = (np.diff(pos) == 1) & (status[:-1] == 0) & (status[1:] == 0)
    step = np.where(adjacent, step, np.nan)
    pad = np.array([np.nan])
    # both neighbouring steps are needed: a chunk tests only the pairs inside it that the whole
    # line would test alike (its edge pairs are left to the driver), so chunking changes nothing
    predicted = np.maximum(np.concatenate((pad, step[:-1])), np.concatenate((step[1:], pad)))
    with np.errstate(invalid="ignore"):
        hit = ((step > JUMP_RATIO * predicted) & (stable[:-1] == stable[1:])
               & (np.minimum(near[:-1], near[1:]) < NEAR_ONE))
    return [Bracket(line, int(pos[j]), (float(grid[pos[j]]), float(grid[pos[j] + 1])),
                    (int(stable[j]), int(stable[j + 1])), (states[j], states[j + 1]), complex(np.nan),
                    0 if near[j] <= near[j + 1] else 1)
            for j in np.flatnonzero(hit)]


# What the brackets of a cube are built from.
_LINE_VARS = ("orbit_status", "stable", "orbit_state", "multiplier_real", "multiplier_imag")


def cube_brackets(ds, axis):
    """(where, Bracket) of every stability change in a cube, lines in grid order."""
    others = _others(ds, axis)
    grid = ds[axis].values
    keep = ds[[v for v in _LINE_VARS if v in ds]].transpose(*others, axis, ...)
    arrays = {v: keep[v].values for v in keep.data_vars}
    lead = _lead(arrays["multiplier_real"], arrays["multiplier_imag"])
    near = _near_one(arrays["multiplier_real"], arrays["multiplier_imag"])
    out = []
    for line in itertools.product(*(range(ds.sizes[a]) for a in others)):
        where = {a: float(ds[a].values[k]) for a, k in zip(others, line)}
        status, stable, states = arrays["orbit_status"][line], arrays["stable"][line], arrays["orbit_state"][line]
        out += [(where, b) for b in brackets(line, grid, status, stable, states, lead[line])]
        out += [(where, b) for b in jump_brackets(line, grid, np.arange(len(grid)), status, stable, states,
                                                  near[line])]
    return out


def chunk_jumps(axes, axis, index, results):
    """(where, Bracket) of the jumps between neighbouring points of one chunk (grid `index`)."""
    names = list(axes)
    at, others = names.index(axis), [k for k, a in enumerate(names) if a != axis]
    index = np.asarray(index)
    near = _near_one(results["multiplier_real"], results["multiplier_imag"])
    found = []
    for key in sorted({tuple(int(v) for v in row) for row in index[:, others]}):
        rows = np.flatnonzero(np.all(index[:, others] == key, axis=1)) if others else np.arange(len(index))
        rows = rows[np.argsort(index[rows, at])]
        where = {names[k]: float(axes[names[k]][v]) for k, v in zip(others, key)}
        found += [(where, b) for b in jump_brackets(key, np.asarray(axes[axis], float), index[rows, at],
                                                    results["orbit_status"][rows], results["stable"][rows],
                                                    results["orbit_state"][rows], near[rows])]
    return found


def key_of(bracket, k=0):
    """A refined row's key: (line, i) for a stability change, (line, i, k) for the k-th fold of a
    jump's pair."""
    return (bracket.line, bracket.i) if bracket.jump is None else (bracket.line, bracket.i, k)


def entries(bracket, refined):
    """[(key, row)] of a refined bracket (refine_brackets' row, or a jump's list of two)."""
    if bracket.jump is None:
        return [(key_of(bracket), refined)]
    return [(key_of(bracket, k), row) for k, row in enumerate(refined)]


def refine_brackets(scene, axis, items):
    """The refined row of each (where, Bracket) in items (one solver per line), for a jump the
    list of its two fold rows: a worker task."""
    solvers = {}
    rows = []
    for where, bracket in items:
        key = tuple(sorted(where.items()))
        if key not in solvers:
            solvers[key] = axis_solver(scene, {**scene.fixed, **where}, axis)
        refine = _refine if bracket.jump is None else _refine_jump
        rows.append(refine(solvers[key], axis, bracket))
    return rows


def refine_within(scene, index, results):
    """[[line, i, row], ...]: the refined stability changes along the scene's continued axis
    between two points of one chunk (its grid `index` and `results`), in plain JSON types: a
    chunk's task refines them with its points, and its part file keeps them, so a resumed sweep
    does not refine them again."""
    axes, axis = scene.axes, scene.along
    found = Tracker(axes, axis).add(index, results)
    found += chunk_jumps(axes, axis, index, results)
    rows = refine_brackets(scene, axis, found)
    return [[list(key[0]), *key[1:], {k: v.item() if isinstance(v, np.generic) else v for k, v in row.items()}]
            for (_, b), refined in zip(found, rows) for key, row in entries(b, refined)]


def keyed(items):
    """refine_within's entries ([line, i, row], or [line, i, k, row] for a jump's k-th fold) as
    {(line, i[, k]): row}, boundary_rows' `done`."""
    return {(tuple(e[0]), *(int(v) for v in e[1:-1])): e[-1] for e in items}


def boundary_rows(scene, ds, map_tasks=None, done=None):
    """One dict per stability change in the cube, in grid order. done: {(line, i): row} refined
    already (a sweep refines brackets while it computes); the others are refined one task per
    line by map_tasks(scene, axis, tasks) -> the rows of each task in order (default: here, one
    after the other; a sweep passes one that spreads them over its Dask workers)."""
    axis = schema.continued_axis(ds)
    done = dict(done or {})
    todo = {}
    for where, b in cube_brackets(ds, axis):
        if key_of(b) not in done:
            todo.setdefault(b.line, []).append((where, b))
    tasks = list(todo.values())
    for task, rows in zip(tasks, (map_tasks or refine_serially)(scene, axis, tasks)):
        for (_, b), refined in zip(task, rows):
            done.update(entries(b, refined))
    others = _others(ds, axis)
    return [{**{f"boundary_{a}": float(ds[a].values[k]) for a, k in zip(others, key[0])}, **done[key]}
            for key in sorted(done)]


def refine_serially(scene, axis, tasks):
    """refine_brackets of each task in this process (the map_tasks of boundary_rows without a cluster)."""
    return [refine_brackets(scene, axis, task) for task in tasks]


def _refine(solvers, axis, bracket):
    solve, family, _ = solvers
    (a, b), (s_low, _), (u_low, u_high) = bracket.grid, bracket.stable, bracket.states
    name = f"boundary_{axis}"
    row = {"boundary_grid_low": a, "boundary_grid_high": b, "boundary_direction": 0 if s_low == 1 else 1}
    event = _first_event_on_branch(family(b - a), bracket)
    if event is not None:
        return {**row, name: event.point.lam, "boundary_status": 0, "boundary_type": _EVENT_TYPE[event.kind]}
    try:
        found = boundary.locate_boundary(solve, a, b, u_low, u_high, xtol_rel=XTOL_REL)
    except boundary.BoundaryError:
        return {**row, name: np.nan, "boundary_status": 1, "boundary_type": floquet.crossing_type(bracket.lead)}
    return {**row, name: found.value, "boundary_status": 0,
            "boundary_type": floquet.crossing_type(found.solution.multipliers[0])}


def _refine_jump(solvers, axis, bracket):
    """The two fold rows of a jump: the branch of its near-fold side followed towards the other
    side through the window, its first two folds (not refined, NaN, where it has not both)."""
    _, family, half_pp = solvers
    (a, b), k = bracket.grid, bracket.jump
    span = b - a
    branch = arclength.continue_orbit(family(span), bracket.grid[k], bracket.states[k],
                                      (a - JUMP_WINDOW * span, b + JUMP_WINDOW * span), JUMP_SETTINGS,
                                      direction=1 if k == 0 else -1)
    folds = sorted([e.point.lam for e in branch.events if e.kind == arclength.FOLD][:2])
    status = 0 if len(folds) == 2 else 1
    folds = folds if status == 0 else [np.nan, np.nan]
    orbits = [{}, {}]
    if status == 0:     # the start's own branch reaches the middle only when followed the other way
        back = arclength.continue_orbit(family(span), bracket.grid[k], bracket.states[k], (min(folds), max(folds)),
                                        JUMP_SETTINGS, direction=-1 if k == 0 else 1)
        orbits = _coexisting(family(span), (branch, back), half_pp, folds)
    return [{"boundary_grid_low": a, "boundary_grid_high": b, f"boundary_{axis}": value,
             "boundary_status": status, "boundary_type": floquet.FOLD,
             "boundary_direction": schema.BOUNDARY_DIRECTION.index(direction), **orbit}
            for value, direction, orbit in zip(folds, ("enters_bistable", "leaves_bistable"), orbits)]


def _coexisting(family, branches, half_pp, folds):
    """The two stable orbits that coexist in the middle of a jump's fold pair, as the extra
    columns of its two rows (`_orbit_columns`; the smaller amplitude of the first observable in
    the first row): coexistence.distinct_stable_orbits on the branches (through the folds, and
    the start's followed the other way). Empty dicts where it does not find two."""
    records = [{"parameter": np.array([p.lam for p in b.points]), "state": np.array([p.state for p in b.points]),
                "multipliers": np.array([p.multipliers for p in b.points]).reshape(len(b.points), -1),
                "periods": b.periods} for b in branches]
    middle = 0.5 * (folds[0] + folds[1])
    found = coexistence.distinct_stable_orbits(family, records, JUMP_SETTINGS, middle)
    if len(found) != 2:
        return [{}, {}]
    rows = [{"boundary_orbit_half_pp": [float(v) for v in half_pp(middle, point.state, records[b]["periods"])],
             "boundary_orbit_max_abs_multiplier": float(np.abs(point.multipliers).max()),
             "boundary_orbit_periods": float(records[b]["periods"]), "boundary_orbit_at": middle} for b, point in found]
    return sorted(rows, key=lambda row: row["boundary_orbit_half_pp"][0])


def _first_event_on_branch(family, bracket):
    """The first stability-losing event on the branch of the stable end of the bracket, followed
    towards the other (at most a grid step beyond it); None if there is none."""
    k = 0 if bracket.stable[0] == 1 else 1
    a, b = bracket.grid[k], bracket.grid[1 - k]
    span = abs(b - a)
    branch = arclength.continue_orbit(family, a, bracket.states[k], (min(a, b) - span, max(a, b) + span),
                                      BRANCH_SETTINGS, direction=1 if b > a else -1)
    return next((e for e in branch.events if e.kind in _EVENT_TYPE), None)


class Tracker:
    """The Brackets of a sweep as its chunks finish: add(index, results) -> the (where, Bracket)
    whose two grid points have both become known, so that each is found once, in whatever order
    the chunks finish. A line is dropped once all its points are known."""

    def __init__(self, axes, axis):
        names = list(axes)
        self.axes, self.at = axes, names.index(axis)
        self.other_names = [a for a in names if a != axis]
        self.others = [names.index(a) for a in self.other_names]
        self.grid = np.asarray(axes[axis], float)
        self.lines = {}

    def _line(self, key, n_state):
        if key not in self.lines:
            n = len(self.grid)
            self.lines[key] = {"known": np.zeros(n, bool), "orbit_status": np.zeros(n, int),
                               "stable": np.zeros(n, int), "orbit_state": np.zeros((n, n_state)),
                               "lead": np.zeros(n, complex)}
        return self.lines[key]

    def add(self, index, results):
        index = np.asarray(index)
        values = {**{k: results[k] for k in ("orbit_status", "stable", "orbit_state")},
                  "lead": _lead(results["multiplier_real"], results["multiplier_imag"])}
        # lines by flat index: np.unique(axis=0) compares structured rows, and numpy reports a
        # KeyboardInterrupt raised in that comparison as a TypeError
        shape = [len(self.axes[a]) for a in self.other_names]
        flat = np.ravel_multi_index(tuple(index[:, self.others].T), shape) if shape else np.zeros(len(index), int)
        keys, which = np.unique(flat, return_inverse=True)
        found = []
        for j, key in enumerate(tuple(int(v) for v in np.unravel_index(k, shape)) for k in keys):
            rows = np.flatnonzero(which == j)
            pos = index[rows, self.at]
            line = self._line(key, values["orbit_state"].shape[1])
            line["known"][pos] = True
            for name, v in values.items():
                line[name][pos] = v[rows]
            cand = np.unique(np.concatenate([pos - 1, pos]))
            cand = cand[(cand >= 0) & (cand < len(self.grid) - 1)]
            cand = cand[line["known"][cand] & line["known"][cand + 1]]
            where = {a: float(self.axes[a][k]) for a, k in zip(self.other_names, key)}
            found += [(where, b) for b in brackets(key, self.grid, line["orbit_status"], line["stable"],
                                                   line["orbit_state"], line["lead"], cand)]
            if line["known"].all():
                del self.lines[key]
        return found


def add_boundary_table(scene, ds, map_tasks=None, done=None):
    """ds with the boundary variables (dimension `boundary`, possibly of length 0); map_tasks and
    done as in boundary_rows."""
    rows = boundary_rows(scene, ds, map_tasks, done)
    axis = schema.continued_axis(ds)
    coord = ds[axis].attrs
    table = {name: ("boundary", np.array([r[name] for r in rows], dtype=dtype), dict(attrs))
             for name, (dtype, attrs) in schema.boundary_variables(axis, coord["units"], coord["long_name"]).items()}
    for other in _others(ds, axis):
        attrs = ds[other].attrs
        table[f"boundary_{other}"] = ("boundary", np.array([r[f"boundary_{other}"] for r in rows], float),
                                      {"units": attrs["units"], "long_name": f"{attrs['long_name']} of the boundary"})
    if any("boundary_orbit_half_pp" in r for r in rows):
        table.update(_orbit_columns(scene, ds, rows, axis))
    return ds.assign(table)     # one merge, not one per variable


def _orbit_columns(scene, ds, rows, axis):
    """The boundary table's columns of the coexisting orbits of jumps (`_coexisting`; NaN on the
    other rows): per observable the half peak-to-peak amplitude, the largest |multiplier|, the
    orbit's period in forcing periods, and where along `axis` they were computed."""
    def column(get):
        return np.array([get(r) if "boundary_orbit_half_pp" in r else np.nan for r in rows], float)
    coord = ds[axis].attrs
    out = {}
    for k, obs in enumerate(scene.model.observables):
        unit = ds[f"amplitude_{obs.name}"].attrs.get("units", "") if f"amplitude_{obs.name}" in ds else ""
        out[f"boundary_orbit_amplitude_{obs.name}"] = ("boundary", column(lambda r: r["boundary_orbit_half_pp"][k]), {
            "units": unit, "long_name": f"half peak-to-peak {obs.name} of a stable orbit coexisting in a jump's interval"})
    out["boundary_orbit_max_abs_multiplier"] = ("boundary", column(lambda r: r["boundary_orbit_max_abs_multiplier"]),
                                                {"units": "1", "long_name": "largest |Floquet multiplier| of that orbit"})
    out["boundary_orbit_periods"] = ("boundary", column(lambda r: r["boundary_orbit_periods"]),
                                     {"units": "1", "long_name": "that orbit's period in forcing periods"})
    out[f"boundary_orbit_{axis}"] = ("boundary", column(lambda r: r["boundary_orbit_at"]), {
        "units": coord["units"], "long_name": f"{coord['long_name']} where the coexisting orbits were computed"})
    return out


def boundary_frame(ds):
    """The boundary table as a list of dicts (empty when the cube has none)."""
    if "boundary" not in ds.dims:
        return []
    names = [n for n in ds.data_vars if ds[n].dims == ("boundary",)]
    return [{n[len("boundary_"):]: ds[n].values[k].item() for n in names} for k in range(ds.sizes["boundary"])]


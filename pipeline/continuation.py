"""`rotorsweep continue`: pseudo-arclength branches of a scene (rotorsweep.kernels.continuation.arclength)
on a Dask cluster, into a netCDF *continuation result*.

The config's [continuation] section names the continued parameter (any float parameter of the
scene's model: a sweep axis such as speed or clearance, or a section value such as the damping)
and its range (default: the sweep's values of it). Every combination of the other swept axes is
one *line*, one Dask task: the orbit is solved at the start, followed through folds to the end
of the range, and each period doubling met spawns the period-2k branch (branch switching) up to
`period_doubling_switches` deep. Every branch of every line is one entry of the `branch`
dimension (its points along `point`, padded with NaN / INT_FILL), its located fold / period
doubling / Neimark-Sacker points entries of the `event` dimension.
"""
import functools
import itertools
import json
import math
import sys
from dataclasses import dataclass

import numpy as np

from rotorsweep.pipeline import cluster, compute, plainnc, result_kinds, results, schema, torus_branches
from rotorsweep.pipeline.coexistence import line_coexistence, mark_copies
from rotorsweep.pipeline.config import ConfigError, range_text, settings_problems
from rotorsweep.kernels import extrema
from rotorsweep.kernels.continuation import arclength as al, solve_orbit, twoparam


@dataclass(frozen=True)
class Plan:
    parameter: str
    start: float
    stop: float
    lines: tuple            # dicts {other swept axis: value}
    settings: al.Settings
    periods: int
    switches: int
    second: str = ""        # boundary curves in this swept axis ("": none)
    marks: tuple = ()       # its grid values (curve points are solved there)

    @property
    def range(self):
        return (min(self.start, self.stop), max(self.start, self.stop))


def plan(scene):
    """The continuation a scene (rotorsweep.pipeline.scene.Scene) asks for; raises ConfigError naming every
    key that cannot work (before any work starts)."""
    spec = scene.model
    compute.require_forced(spec, "continue")
    sec = scene.continuation
    name = sec.parameter or scene.along
    floats = [p.name for p in spec.parameters if p.kind == "float"]
    if name not in floats:
        raise ConfigError(f"continuation.parameter: {name!r} is not a float parameter of model {spec.name} "
                          f"(continuable: {', '.join(floats)})")
    par = spec.parameter(name)
    sweep = scene.axes
    errors = []
    start, stop = sec.start, sec.stop
    for key, value in (("start", start), ("stop", stop)):
        if value is None and name not in sweep:
            errors.append(f"continuation.{key}: required ({name} is not swept, so the sweep gives no range)")
    if errors:
        raise ConfigError("\n".join(errors))
    start = float(sweep[name][0]) if start is None else float(start)
    stop = float(sweep[name][-1]) if stop is None else float(stop)
    if start == stop:
        errors.append(f"continuation.start and continuation.stop: both {start!r}; the range is empty")
    for key, value in (("start", start), ("stop", stop)):
        if not _within(value, par):
            errors.append(f"continuation.{key}: {value!r} is outside the allowed values of {name}: "
                          f"must be {range_text(par)}")
    settings = al.Settings(ds=sec.ds, ds_min=sec.ds_min, ds_max=sec.ds_max, max_steps=sec.max_steps,
                           max_angle=sec.max_angle, tol=scene.newton.tol)
    errors += settings_problems(settings.problems(), "continuation", vars(sec))
    if errors:
        raise ConfigError("\n".join(errors))
    second = sec.curves_in
    if second and (second == name or len(sweep.get(second, ())) < 2):
        raise ConfigError(f"continuation.curves_in: {second!r} must be another axis the sweep gives at least two "
                          f"values (the box of the curves and the grid they are checked on); swept: "
                          f"{', '.join(a for a in sweep if a != name and len(sweep[a]) > 1) or 'none'}")
    others = [a for a in sweep if a != name]
    lines = tuple(dict(zip(others, map(float, combo))) for combo in itertools.product(*(sweep[a] for a in others)))
    problem = "" if torus_branches.is_torus_line(scene, name, start, lines[0]) else \
        _period_problem(scene, name, start, stop, lines[0])
    if problem:
        raise ConfigError(f"continuation.parameter: {problem}")
    if scene.report.frequency_unit == "omega_l" and par.unit != "Hz":
        raise ConfigError(f"report.frequency_unit: omega_l scales frequencies; the continued parameter {name} is in "
                          f"{par.unit or 'no unit'} (use Hz)")
    return Plan(name, start, stop, lines, settings, sec.periods, sec.period_doubling_switches, second,
                tuple(float(v) for v in sweep.get(second, ())))


# The shooting period must be a continuous function of the continued parameter. Probed at the
# start and PERIOD_PROBE x the range width away: a continuous period moves by about that much
# relative to itself (far below PERIOD_JUMP_RTOL for any range narrower than 10^3 x its start),
# two forcings whose ratio the parameter changes become aperiodic there or jump in period by O(1).
PERIOD_PROBE = 1e-7
PERIOD_JUMP_RTOL = 1e-4


def _period_problem(scene, name, start, stop, line):
    """Why the forcing period is not continuous in the parameter near its start ("": it is)."""
    build = compute.builder(scene)
    values = {**scene.fixed, **line}
    near = start + PERIOD_PROBE * (stop - start)
    a, b = (build({**values, name: lam}) for lam in (start, near))
    if a.periodic and b.periodic and abs(b.period / a.period - 1.0) <= PERIOD_JUMP_RTOL:
        return ""
    what = "is not periodic" if not (a.periodic and b.periodic) else f"has period {b.period:.6g} s (not {a.period:.6g} s)"
    return (f"continuing {name} is ill-posed: at {name} = {near!r} the forcing {what}, so no periodic orbit is "
            f"continuous in {name} (two forcings whose frequency ratio {name} changes are periodic only at "
            "rational ratios, with a common period that jumps); continue with one forcing on (rigid_preloaded: "
            "forcing.eccentricity = 0 or forcing.support_acceleration = 0)")


def _within(value, par):
    above = value > par.lo if par.lo_open else value >= par.lo
    below = value < par.hi if par.hi_open else value <= par.hi
    return above and below


# Kernel inputs kept per line (about 1 kB each): a branch point asks for those of one parameter
# value several times (its corrector's last iterate, its amplitudes, its record)
BUILT_KEPT = 4096


def line_family(scene, pl, where):
    """(arclength Family along the parameter at the line `where`, lambda -> Built, each value's
    built once while among the BUILT_KEPT latest)."""
    build = compute.builder(scene)
    values = {**scene.fixed, **where}

    @functools.lru_cache(maxsize=BUILT_KEPT)
    def built_signed(lam, sign):
        return build({**values, pl.parameter: lam})

    def built(lam):      # keyed with the sign: 0.0 == -0.0, but a build may tell them apart
        return built_signed(lam, math.copysign(1.0, lam))
    model = scene.model
    # the observables read positions, so their weights do not depend on the forcing period
    weights = extrema.observable_weights(model, built(pl.start).period)
    family = al.Family(model, lambda lam: built(lam).p, scene.integrator,
                       scale=pl.range[1] - pl.range[0], periods=float(pl.periods), weights=weights,
                       peak=_plotted(model, scene.report))
    return family, built


def _plotted(model, report):
    """The index of the observable the report ([report] keys) plots (its half peak-to-peak peaks are events)."""
    names = [o.name for o in model.observables]
    return names.index(report.observable) if report.observable in names else 0


def continue_line(scene, where):
    """The branches of one line (a Dask task): a list of dicts of numpy arrays (branch_record)."""
    pl = plan(scene)
    if torus_branches.is_torus_line(scene, pl.parameter, pl.start, where):
        return torus_branches.continue_torus_line(scene, pl, where)
    family, built = line_family(scene, pl, where)
    model = family.model
    # the start's orbit only: no samples (their kernel would load for nothing in a small run)
    sol = solve_orbit(model, family.params(pl.start), family.opts, periods=pl.periods, n_samples=0,
                      **scene.newton.solve_orbit_args(model))
    if sol.status != 0:
        empty = al.Branch([], [], al.START_FAILED, f"no periodic orbit converged at {pl.parameter} = {pl.start!r}",
                          family.periods, sol.n_rhs)
        return [branch_record(family, built, empty, -1)]
    first = al.continue_orbit(family, pl.start, sol.state, pl.range, pl.settings,
                              direction=1 if pl.stop > pl.start else -1)
    records = [branch_record(family, built, first, -1)]
    if pl.second:
        records[0]["curves"] = line_curves(scene, pl, where, first)
    queue = [(first, 0, 0)]
    while queue:
        branch, depth, index = queue.pop(0)
        if depth == pl.switches:
            continue
        parent = family.with_periods(branch.periods)
        for event in (e for e in branch.events if e.kind == al.PERIOD_DOUBLING):
            child = al.switch_period_doubling(parent, event, pl.range, pl.settings)
            records.append(branch_record(family, built, child, index))
            queue.append((child, depth + 1, len(records) - 1))
    records = mark_copies(family, records, pl.settings)
    records[0]["coexistence"] = line_coexistence(family, records, pl.settings, pl.range)
    return records


def line_curves(scene, pl, where, branch):
    """Boundary curves in (parameter, second axis) through the located fold / PD / NS points of
    a line's period-1 branch: each followed both ways from the event (once if it closes), curve
    points solved at the second axis's grid values."""
    build = compute.builder(scene)
    values = {**scene.fixed, **where}
    lo2, hi2 = min(pl.marks), max(pl.marks)
    plane = twoparam.Plane(scene.model, lambda lam, nu: build({**values, pl.parameter: lam, pl.second: nu}).p,
                           scene.integrator, lam_scale=pl.range[1] - pl.range[0],
                           nu_scale=hi2 - lo2, periods=float(pl.periods))
    settings = twoparam.Settings(**{k: getattr(pl.settings, k) for k in ("ds", "ds_min", "ds_max", "max_steps",
                                                                        "max_angle", "tol")})
    out = []
    for event in (e for e in branch.events if e.kind in twoparam.KINDS):
        for direction in (1, -1):
            curve = twoparam.continue_bifurcation(plane, event, where[pl.second], (pl.range, (lo2, hi2)), settings,
                                                  direction, pl.marks)
            out.append(curve_record(curve, event, where[pl.second]))
            if curve.end == twoparam.CLOSED:
                break
    return out


def curve_record(curve, event, nu0):
    return {"kind": int(curve.kind), "parameter": np.array([p.lam for p in curve.points]),
            "second": np.array([p.nu for p in curve.points]),
            "critical": np.array([p.critical for p in curve.points], complex),
            "end": int(curve.end), "detail": curve.detail, "start": (float(event.point.lam), float(nu0)),
            "marked": [(float(p.nu), float(p.lam)) for p in curve.marked]}


def branch_record(family, built, branch, parent):
    """One branch as plain arrays (what a Dask task returns)."""
    model = family.model
    fam = family.with_periods(branch.periods)
    pts = branch.points
    X = np.array([p.X for p in pts]).reshape(len(pts), model.n_state + 1)
    steps = np.linalg.norm(np.diff(X, axis=0), axis=1) if len(pts) > 1 else np.zeros(0)
    amp = np.array([_amplitudes(fam, built, p) for p in pts]).reshape(len(pts), 2, len(model.observables))
    ev = branch.events
    ev_amp = np.array([_amplitudes(fam, built, e.point) for e in ev]).reshape(len(ev), 2, len(model.observables))
    return {
        "parameter": np.array([p.lam for p in pts]),
        "arclength": np.concatenate(([0.0], np.cumsum(steps)))[:len(pts)],
        "state": X[:, :-1] if len(pts) else np.zeros((0, model.n_state)),
        "multipliers": np.array([p.multipliers for p in pts]).reshape(len(pts), model.n_state),
        "amplitude_max": amp[:, 0], "amplitude_half_pp": amp[:, 1],
        "period": np.array([branch.periods * built(p.lam).period for p in pts]),
        "periods": int(branch.periods), "parent": int(parent), "end": int(branch.end), "detail": branch.detail,
        "n_rhs": int(branch.n_rhs),
        "event_type": np.array([e.kind for e in ev], int),
        "event_parameter": np.array([e.point.lam for e in ev]),
        "event_parameter_error": np.array([e.lam_error for e in ev], float),
        "event_index": np.array([e.index for e in ev], int),
        "event_state": np.array([e.point.state for e in ev]).reshape(len(ev), model.n_state),
        "event_multipliers": np.array([e.point.multipliers for e in ev]).reshape(len(ev), model.n_state),
        "event_amplitude_max": ev_amp[:, 0], "event_amplitude_half_pp": ev_amp[:, 1],
    }


def _amplitudes(family, built, point):
    """(max |o|, half peak-to-peak of o) over the orbit for each observable o, in SI, exact
    (rotorsweep.kernels.extrema): those the point recorded (what its events read) where it did."""
    if point.amplitudes is not None:
        return point.amplitudes
    return extrema.amplitudes(family.model, point.state, family.params(point.lam), family.periods, family.opts,
                              built(point.lam).period)


# --- the result file -----------------------------------------------------------------------------

def _parameter_attrs(spec, name):
    par = spec.parameter(name)
    return {"units": par.unit, "long_name": par.long_name or par.help or name}


# An event lies on a curve already found from another line when the curve's point at the event's
# value of the second axis (equal up to round-off: nu = eta * scale) is within this (relative) of
# the event's parameter: far above the
# curves' and events' own accuracy (~1e-9), far below the distance between distinct curves.
SAME_CURVE_RTOL = 1e-6


def distinct_curves(curves):
    """The curves, without those whose starting event lies on a curve kept from another event
    (the same boundary found again from another line)."""
    kept = []
    for c in curves:
        lam, nu = c["start"]
        found_again = any(k["kind"] == c["kind"] and k["start"] != c["start"] and
                          any(abs(m_nu - nu) <= 1e-12 * abs(nu) and abs(m_lam - lam) <= SAME_CURVE_RTOL * max(1.0, abs(lam))
                              for m_nu, m_lam in k["marked"]) for k in kept)
        if not found_again:
            kept.append(c)
    return kept


def _curve_variables(spec, pl, curves, par_attrs):
    """(values, run-time attrs) of the boundary curves (dimensions curve x curve_point)."""
    curves = distinct_curves(curves)
    n = max([len(c["parameter"]) for c in curves] + [1])

    def pad(key, dtype=float):
        out = np.full((len(curves), n), np.nan, dtype)
        for i, c in enumerate(curves):
            out[i, :len(c[key])] = c[key]
        return out
    critical = pad("critical", complex)
    second = spec.parameter(pl.second)
    values = {"curve_parameter": pad("parameter"), "curve_second": pad("second"),
              "curve_critical_real": critical.real, "curve_critical_imag": critical.imag,
              "curve_type": np.array([c["kind"] for c in curves], "int8"),
              "curve_points": np.array([len(c["parameter"]) for c in curves], "int32"),
              "curve_end": np.array([c["end"] for c in curves], "int8"),
              "curve_detail": np.array([c["detail"] for c in curves], object)}
    attrs = {"curve_parameter": {**par_attrs, "comment": f"{pl.parameter} along the boundary curve"},
             "curve_second": {"units": second.unit, "long_name": second.long_name or pl.second,
                              "comment": f"{pl.second} along the boundary curve"},
             "curve_type": schema.flag_attrs(al.EVENT_TYPES), "curve_end": schema.flag_attrs(twoparam.END_REASONS)}
    return values, attrs


def _torus_variables(records, stable):
    """(values, run-time attrs) of the torus branches (rotorsweep.pipeline.torus_branches): their points'
    error estimate, normal stability and largest exponent; `stable` is 1 where a torus is stable."""
    def pad(key, fill, dtype):
        out = np.full(stable.shape, fill, dtype)
        for b, (_, r) in enumerate(records):
            out[b, :len(r.get(key, ()))] = r.get(key, ())
        return out
    status = pad("torus_status", -1, "int8")
    torus = status >= 0
    return ({"branch_kind": np.array([int("torus_status" in r) for _, r in records], "int8"),
             "torus_status": status, "torus_error": pad("torus_error", np.nan, float),
             "torus_exponent": pad("torus_exponent", np.nan, float), "torus_modes": pad("torus_modes", -1, "int16"),
             "torus_nodes": _torus_nodes(records, stable.shape),
             "event_note": np.array([note for _, r in records for note in r.get("event_note", [""] * len(r["event_type"]))],
                                    object),
             "event_periods": np.array([k for _, r in records
                                        for k in r.get("event_periods", [r["periods"]] * len(r["event_type"]))], "int32"),
             "stable": np.where(torus, status == torus_branches.TORUS_STATUS["stable"], stable).astype("int8")}, {})


def _torus_nodes(records, shape):
    """(branch, point, torus_node, state) node values of the tori's circles, NaN-padded (each
    torus point's own node count: torus_modes; orbit branches hold NaN)."""
    held = [r["torus_nodes"] for _, r in records if "torus_nodes" in r]
    n_nodes = max([h.shape[1] for h in held] + [1])
    out = np.full(shape + (n_nodes, held[0].shape[2] if held else 1), np.nan)
    for b, (_, r) in enumerate(records):
        if "torus_nodes" in r:
            out[b, :len(r["torus_nodes"]), :r["torus_nodes"].shape[1]] = r["torus_nodes"]
    return out


def _omega_l_variables(scene, pl, values):
    """(values, run-time attrs) of the continued frequency and the events' over omega_l
    (rotorsweep.pipeline.modes.omega_l): the paper's nondimensional frequency, a coordinate the report draws
    its axes in."""
    from rotorsweep.pipeline import modes

    wl = modes.omega_l(scene)
    attrs = {"long_name": f"{pl.parameter} / omega_l", "omega_l": wl,
             "comment": f"omega_l = {wl:.10g} Hz: the lowest linear natural frequency with the 15 deg bearing"}
    return ({"parameter_over_omega_l": values["parameter"] / wl, "event_parameter_over_omega_l": values["event_parameter"] / wl},
            {"parameter_over_omega_l": attrs, "event_parameter_over_omega_l": attrs})


def _global_parents(lines, key="parent"):
    """Parent (or copy_of) branch indices over the whole result (a line's records number them
    locally; -1: none)."""
    out, offset = [], 0
    for _, recs in lines:
        out += [r.get(key, -1) + offset if r.get(key, -1) >= 0 else -1 for r in recs]
        offset += len(recs)
    return np.array(out, "int32")


def _global_records(lines, pl):
    """(event_copy_of, coexistence pieces) over the whole result from the lines' local indices
    (mark_copies, line_coexistence; a line without them: each event its own first record, no
    stable orbit)."""
    events, pieces, b0 = [], {"piece_lo": [], "piece_hi": [], "piece_line": [], "piece_branches": []}, 0
    for _, recs in lines:
        e_line = len(events)
        for r in recs:
            own = range(len(events) - e_line, len(events) - e_line + len(r["event_type"]))
            events += [e_line + int(j) for j in r.get("event_copy_of", own)]
        for lo, hi, orbits in recs[0].get("coexistence", [(*pl.range, [])]):
            for key, value in zip(pieces, (lo, hi, b0, " ".join(str(b0 + b) for b in orbits))):
                pieces[key].append(value)
        b0 += len(recs)
    return np.array(events, "int32"), {k: np.array(v, {"piece_line": "int32", "piece_branches": object}.get(k, float))
                                          for k, v in pieces.items()}


def to_dataset(scene, pl, lines, provenance):
    """The continuation result as an xarray.Dataset (to_result's variables; imports xarray)."""
    return to_result(scene, pl, lines, provenance).to_xarray()


def to_result(scene, pl, lines, provenance):
    """The continuation result's plain variables (plainnc.Plain; schema:
    result_kinds.CONTINUATION_VARIABLES) of a scene: lines = [(where, [branch records])] in plan order."""
    spec = scene.model
    records = [(where, r) for where, recs in lines for r in recs]
    n_branch, n_pt = len(records), max([len(r["parameter"]) for _, r in records] + [1])
    n, n_obs = spec.n_state, len(spec.observables)

    def pad(key, tail=(), fill=np.nan):
        out = np.full((n_branch, n_pt) + tail, fill)
        for b, (_, r) in enumerate(records):
            out[b, :len(r[key])] = r[key]
        return out
    mult = np.full((n_branch, n_pt, n), np.nan + 0j)
    for b, (_, r) in enumerate(records):
        mult[b, :len(r["multipliers"])] = r["multipliers"]
    absmax = np.abs(mult).max(axis=2)
    present = ~np.isnan(absmax)
    ev = [(b, r, k) for b, (_, r) in enumerate(records) for k in range(len(r["event_type"]))]
    ev_mult = np.array([r["event_multipliers"][k] for _, r, k in ev]).reshape(len(ev), n)

    copies = _global_records(lines, pl)

    def per_event(key, dtype=float, tail=()):
        return np.array([r[key][k] for _, r, k in ev], dtype).reshape((len(ev),) + tail)
    values = {
        "parameter": pad("parameter"), "arclength": pad("arclength"), "orbit_state": pad("state", (n,)),
        "amplitude_max": pad("amplitude_max", (n_obs,)), "amplitude_half_pp": pad("amplitude_half_pp", (n_obs,)),
        "orbit_period": pad("period"), "multiplier_real": mult.real, "multiplier_imag": mult.imag,
        "max_abs_multiplier": absmax, "stable": np.where(present, absmax < 1.0, -1).astype("int8"),
        "branch_points": np.array([len(r["parameter"]) for _, r in records], "int32"),
        "branch_periods": np.array([r["periods"] for _, r in records], "int32"),
        "branch_parent": _global_parents(lines), "branch_copy_of": _global_parents(lines, "copy_of"),
        "event_copy_of": copies[0], **copies[1],
        "branch_end": np.array([r["end"] for _, r in records], "int8"),
        "branch_detail": np.array([r["detail"] for _, r in records], object),
        "event_type": per_event("event_type", "int8"), "event_branch": np.array([b for b, _, _ in ev], "int32"),
        "event_point": per_event("event_index", "int32"), "event_parameter": per_event("event_parameter"),
        "event_parameter_error": np.array([r.get("event_parameter_error", np.full(len(r["event_type"]), np.nan))[k]
                                           for _, r, k in ev], float),
        "event_multiplier_real": ev_mult.real, "event_multiplier_imag": ev_mult.imag,
        "event_state": per_event("event_state", tail=(n,)),
        "event_amplitude_max": per_event("event_amplitude_max", tail=(n_obs,)),
        "event_amplitude_half_pp": per_event("event_amplitude_half_pp", tail=(n_obs,)),
    }
    par_attrs = _parameter_attrs(spec, pl.parameter)
    obs_units = [o.unit for o in spec.observables]
    amp = {"units": obs_units[0] if len(set(obs_units)) == 1 else "various"}
    attrs = {"parameter": {**par_attrs, "comment": f"the continued parameter: {pl.parameter}"},
             "event_parameter": par_attrs, "event_parameter_error": par_attrs, "branch_end": schema.flag_attrs(al.END_REASONS),
             "event_type": schema.flag_attrs(al.EVENT_TYPES),
             **{name: amp for name in ("amplitude_max", "amplitude_half_pp", "event_amplitude_max",
                                       "event_amplitude_half_pp")}}
    rep = scene.report
    tori = any("torus_status" in r for _, r in records)
    extras = ([_torus_variables(records, values["stable"])] if tori else []) + (
        [_omega_l_variables(scene, pl, values)] if rep.frequency_unit == "omega_l" else []) + (
        [_curve_variables(spec, pl, [c for _, r in records for c in r.get("curves", [])], par_attrs)] if pl.second else [])
    for more_values, more_attrs in extras:
        values.update(more_values)
        attrs.update(more_attrs)
    coords = {"observable": ("observable", [o.name for o in spec.observables], {"long_name": "observable (units: " + ", ".join(obs_units) + ")"})}
    for axis in (pl.lines[0] if pl.lines else {}):
        axis_attrs = spec.parameter(axis)
        coords[axis] = ("branch", np.array([w[axis] for w, _ in records]), {"units": axis_attrs.unit, "long_name": axis_attrs.long_name or axis})
    global_attrs = {**provenance, "result_kind": result_kinds.CONTINUATION, "parameter": pl.parameter,
                    "curves_in": pl.second, "report_observable": rep.observable or spec.observables[0].name,
                    "range": json.dumps(list(pl.range)), "Conventions": "CF-1.10"}
    return plainnc.Plain(result_kinds.variables(result_kinds.CONTINUATION, values, attrs), coords, global_attrs)


# --- running -------------------------------------------------------------------------------------

def run(cfg, output, workers=None, scheduler=None, overwrite=False, stream=sys.stderr, resume=False):
    """Run the continuation a config asks for into a netCDF result at `output`; returns its path.
    Line by line, each kept as a part file until the result is written (`resume`: see results.run_result)."""
    pl = plan(cfg.scene)

    def dataset(parts):
        lines = _run_lines(cfg, pl, workers, scheduler, stream, parts)
        return to_result(cfg.scene, pl, lines, cluster.provenance(cfg, result_kinds.CONTINUATION))
    return results.run_result(cfg, result_kinds.CONTINUATION, output, dataset, stream, overwrite, scheduler, resume)


def _run_lines(cfg, pl, workers, scheduler, stream, parts):
    results.say(stream, f"continuing {pl.parameter} from {pl.start:g} to {pl.stop:g} on {len(pl.lines)} line(s)")
    with torus_branches.progress_on(stream):
        done = results.run_lines(cfg, continue_line, pl.lines, workers, scheduler, stream, _line_summary, parts)
    return list(zip(pl.lines, done))


def _line_summary(records):
    counts = {}
    for r in records:
        for kind in r["event_type"]:
            counts[al.EVENT_LABELS[kind]] = counts.get(al.EVENT_LABELS[kind], 0) + 1
    events = ", ".join(f"{n} {label}" for label, n in counts.items()) or "no events"
    ends = ", ".join(sorted({al.END_REASONS[r["end"]] for r in records}))
    return f"{len(records)} branch(es), {sum(len(r['parameter']) for r in records)} points, {events}; ended: {ends}"

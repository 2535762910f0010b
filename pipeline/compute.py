"""From a scene (rotorsweep.pipeline.scene.Scene) to kernel inputs, and from kernel outputs to cube variables.

A *segment* is a run of consecutive values of the continued axis (shaft speed for
jeffcott_clearance) at fixed values of the other axes: the orbit is continued along it, each
point starting from its neighbours. Segments are fixed by the config (numerics.segment_length),
so results never depend on how they are scheduled. The model is reached only through its
`ModelSpec` (rotorsweep.kernels.models).
"""
import time
from dataclasses import replace

import numpy as np

from rotorsweep.pipeline import schema, torus_points
from rotorsweep.kernels import attractor, continuation, extrema, integrators, shooting


def require_forced(spec, command):
    """ConfigError unless the model `spec` is forced: `run`, `continue` and `point` shoot orbits
    over a forcing period, which a conservative model (symmetric4, asymmetric5) has not."""
    if not spec.forced:
        from rotorsweep.pipeline.config import ConfigError
        raise ConfigError(f"scene.model: {spec.name} is conservative (no damping, no forcing): `rotorsweep {command}` "
                          "needs a forced model; its nonlinear normal modes and backbones: `rotorsweep backbone`")


def builder(scene):
    """point {axis: value} -> Built kernel inputs (p, period, derived values) of a scene
    (rotorsweep.pipeline.scene.Scene), its values gathered once (a segment builds many points)."""
    spec, values = scene.model, scene.values
    return lambda point: spec.build({**values, **point})


def point_params(scene, point):
    """Built kernel inputs (p, period, derived values) at one grid point {axis: value}."""
    return builder(scene)(point)


def point_values(cfg, given):
    """A point {axis: value} of the scene's model from `given` (None: not given) and the scene's
    fixed values; raises config.ConfigError naming what is missing or out of range."""
    from rotorsweep.pipeline import config, point_input

    require_forced(cfg.model, "point")
    spec = cfg.model
    values = {**cfg.scene.fixed, **{k: v for k, v in given.items() if v is not None}}
    unknown = sorted(set(values) - set(spec.axes))
    missing = [a for a in spec.axes if a not in values]
    problems = [f"{name}: not an axis of model {spec.name} (axes: {', '.join(spec.axes)})" for name in unknown]
    problems += [f"{name}: required (an axis of model {spec.name} that the scene does not fix)" for name in missing]
    if problems:
        raise config.ConfigError("\n".join(problems))
    point_input.check_point(values, cfg.data)
    return values


def solve_segment(scene, points):
    """Solve a continuation segment of a scene (rotorsweep.pipeline.scene.Scene). points: list of dicts
    {axis: value} (SI, angles in degrees). Returns schema variables, one row per point: the
    periodic orbit ([analysis] floquet; at a quasi-periodically forced point its torus,
    rotorsweep.pipeline.torus_points) and the attractor ([analysis] attractor)."""
    model = scene.model
    ana = scene.analysis
    opts = scene.integrator
    params, seconds, sols = [], [], []
    build = builder(scene)
    for pt in points:
        start = time.perf_counter()
        params.append(build(pt))
        seconds.append(time.perf_counter() - start)
    if ana.floquet:
        sols = _orbit_chain(model, params, opts, scene.newton, seconds)
    else:
        sols = [_no_orbit(model, "not_requested")] * len(points)
    rows = []
    for i, (sol, par) in enumerate(zip(sols, params)):
        start = time.perf_counter()
        rows.append(point_variables(model, sol, par, 0.0, opts))
        seconds[i] += time.perf_counter() - start
    if ana.floquet:
        for i, sec in enumerate(torus_points.segment_rows(model, params, rows, opts, scene.newton.tol)):
            seconds[i] += sec
    if ana.attractor:
        settings = ana.settings
        for direction, suffix in _directions(ana.sweep_direction):
            order = range(len(points)) if direction == "up" else range(len(points) - 1, -1, -1)
            for i, att in _attractor_chain(model, params, sols, opts, settings, order, seconds):
                rows[i].update({name + suffix: v for name, v in attractor_variables(model, att, params[i].period).items()})
        if ana.sweep_direction == "both":
            for row in rows:
                row["hysteresis"] = _differs(model, row, schema.DOWN_SUFFIX)
    for row, sec in zip(rows, seconds):
        row["compute_time"] = sec
    return {name: np.array([r[name] for r in rows]) for name in rows[0]}


def _orbit_chain(model, params, opts, newton, seconds):
    """Periodic orbits along the segment by natural continuation, timed per point; each run of
    periodically forced points is one chain (a quasi-periodically forced point has no orbit)."""
    sols = [None] * len(params)
    for run in _periodic_runs(params):
        chain = continuation.natural(model, [params[i].p for i in run], opts, n_samples=0,
                                     **newton.solve_orbit_args(model))
        start = time.perf_counter()
        for i, sol in zip(run, chain):
            sols[i] = sol
            now = time.perf_counter()
            seconds[i] += now - start
            start = now
    return [_no_orbit(model, "quasi_periodic_forcing") if sol is None else sol for sol in sols]


def _periodic_runs(params):
    """Index runs of consecutive points with periodic forcing."""
    runs, run = [], []
    for i, par in enumerate(params):
        if par.periodic:
            run.append(i)
        elif run:
            runs.append(run)
            run = []
    return runs + [run] if run else runs


def _no_orbit(model, reason):
    nan = np.full(model.n_state, np.nan)
    return continuation.PointSolution(schema.ORBIT_STATUS.index("not_applicable"),
                                      schema.ORBIT_REASON.index(reason), 0, np.nan,
                                      nan * (1 + 1j), np.nan, False, 0, nan, None, 0)


def _directions(option):
    """(direction, variable suffix) pairs: the first direction fills the plain variables."""
    if option == "both":
        return (("up", ""), ("down", schema.DOWN_SUFFIX))
    return ((option, ""),)


def _attractor_chain(model, params, sols, opts, settings, order, seconds):
    """Continuation of the attractor: each speed (in `order`) starts from the previous one's end
    state; the first from its periodic orbit when one was found, else near static equilibrium."""
    state, k_prev = None, 0
    for i in order:
        start = time.perf_counter()
        par, sol = params[i], sols[i]
        found = sol.status == shooting.CONVERGED
        if state is None:
            state = sol.state if found else model.cold_guess(par.p)
        stable_orbit = (sol.state, sol.multipliers) if found and sol.stable else None
        att = attractor.diagnose(model, state, par.p, par.period, opts, settings, stable_orbit=stable_orbit,
                                 continued_period=k_prev, periodic=par.periodic)
        # a diverged run leaves no attractor to continue from: the next speed starts afresh
        state = att.end_state if att.code not in (attractor.DIVERGED, attractor.INTEGRATION_FAILED) else None
        k_prev = att.period if att.code == attractor.PERIODIC else 0
        seconds[i] += time.perf_counter() - start
        yield i, att


def point_variables(model, sol, params, seconds, opts=None):
    """Cube variables (schema.VARIABLES) of one solved point, SI units (opts: the integrator
    settings the orbit was solved with, default integrators.settings())."""
    lam = np.asarray(sol.multipliers, complex)
    out = {
        "orbit_status": sol.status,
        "orbit_reason": sol.reason,
        "newton_iterations": sol.iterations,
        "residual": sol.residual if np.isfinite(sol.residual) else np.nan,
        "multiplier_real": lam.real,
        "multiplier_imag": lam.imag,
        "max_abs_multiplier": sol.max_abs,
        "stable": int(sol.stable) if sol.status == shooting.CONVERGED else schema.INT_FILL,
        "bifurcation": sol.bifurcation if sol.status == shooting.CONVERGED else schema.INT_FILL,
        "forcing_period": params.period,
        **params.derived,
        "orbit_state": sol.state if sol.status == shooting.CONVERGED else np.full(len(lam), np.nan),
        "compute_time": seconds,
    }
    out.update(_orbit_extent(model, sol, params, integrators.settings() if opts is None else opts))
    return out


def _orbit_extent(model, sol, params, opts):
    """Mean and half peak-to-peak of each observable over the orbit (SI), from one integration
    (rotorsweep.kernels.extrema.orbit_extent: exact extrema, the mean by a Hermite rule on the steps)."""
    names = [o.name for o in model.observables]
    if sol.status != shooting.CONVERGED:
        return {k: np.nan for name in names for k in (f"{name}_mean", f"amplitude_{name}")}
    hi, lo, mean, _, _ = extrema.extent(model, sol.state, params.p, 1.0, opts, params.period)
    out = {}
    for k, name in enumerate(names):
        out[f"{name}_mean"] = mean[k]
        out[f"amplitude_{name}"] = 0.5 * (hi[k] - lo[k])
    return out


def point_detail(scene, point, start_state=None, periods=256, steps_per_period=32):
    """What `report --point` draws at one point: the cube variables of the point (orbit and
    attractor; a dict of numpy values), a trajectory on the attractor over `periods` forcing
    periods, and the power spectrum of its first observable.

    start_state: a state on the attractor (a cube's attractor_state) to start from instead of
    diagnosing the point afresh from its periodic orbit -- where attractors coexist, this picks
    the one the sweep found. Returns dict(row, time [s], one array per observable (SI; x and y
    for jeffcott_clearance), frequency [Hz], power [unit^2], spectrum_of: the observable's name)."""
    scene = replace(scene, analysis=replace(scene.analysis, attractor=True, sweep_direction="up"))
    row = {k: v[0] for k, v in solve_segment(scene, [point]).items()}
    model = scene.model
    par = point_params(scene, point)
    state = np.asarray(row["attractor_state"] if start_state is None else start_state, float)
    n = int(periods) * int(steps_per_period)
    traj = np.full((n, model.n_state), np.nan)
    if np.all(np.isfinite(state)):
        traj = shooting.sample_orbit(model.kernel, state, par.p, float(periods), n, scene.integrator)
    dt = par.period / steps_per_period
    values = model.observe(traj, par.period)
    ok = np.all(np.isfinite(values), axis=1)
    freq, power = attractor.power_spectrum(values[ok, 0], dt) if ok.sum() > 8 else (np.array([]), np.array([]))
    observed = {o.name: values[:, k] for k, o in enumerate(model.observables)}
    return {"row": row, "time": np.arange(n) * dt, **observed, "frequency": freq, "power": power,
            "spectrum_of": model.observables[0].name}


def attractor_variables(model, att, period):
    """Cube variables (schema.ATTRACTOR_VARIABLES and the Poincare samples of the model's
    observables) of one diagnosed point, SI units."""
    lam = np.asarray(att.multipliers, complex)
    section = model.observe(att.samples, period)
    integrated = att.periods_used > 0
    has_lle = np.isfinite(att.lle)
    return {
        "attractor": att.code,
        "period": att.period,
        "lle": att.lle,
        "lle_stderr": att.lle_stderr,
        "lle_method": (schema.LLE_METHOD.index("derived") if att.derived else
                       schema.LLE_METHOD.index("integrated") if has_lle and integrated else schema.INT_FILL),
        "lyapunov_exponents": np.asarray(att.exponents, float),
        **{f"poincare_{o.name}": section[:, k] for k, o in enumerate(model.observables)},
        "attractor_multiplier_real": lam.real,
        "attractor_multiplier_imag": lam.imag,
        "lyapunov_periods": att.periods_used,
        "attractor_state": np.asarray(att.end_state, float),
    }


# Two periodic attractors of one class and period are distinct orbits when a Poincare point of one
# lies this far (relative to the section's size) from every point of the other.
SAME_ORBIT_RTOL = 1e-3


def _differs(model, row, suffix):
    """1 where the up and down sweeps ended on different attractors: class or period differ, or
    two periodic ones are different orbits (e.g. two coexisting stable period-1 orbits). A
    not_settled attractor (period unresolved: still settling, as next to a bifurcation) cannot
    be compared: 0."""
    unresolved = [row["attractor" + s] == attractor.NOT_SETTLED for s in ("", suffix)]
    if any(unresolved):
        return 0
    if row["attractor"] != row["attractor" + suffix] or row["period"] != row["period" + suffix]:
        return 1
    if row["attractor"] != attractor.PERIODIC:
        return 0
    names = [f"poincare_{o.name}" for o in model.observables]
    up = np.stack([row[name] for name in names], axis=1)
    down = np.array([row[name + suffix][-1] for name in names])
    scale = SAME_ORBIT_RTOL * max(np.abs(up).max(), model.length_scale)
    return int(np.abs(up - down).max(axis=1).min() > scale)

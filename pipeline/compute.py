"""From a validated scene to kernel inputs, and from kernel outputs to cube variables.

A *segment* is a run of consecutive speeds at fixed (clearance, contact angle, preload): the
orbit is continued along it, each point starting from its neighbours. Segments are fixed by the
config (numerics.segment_length), so results never depend on how they are scheduled.
"""
import time
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from pipeline import schema
from rotorkernels import attractor, bearing, continuation, integrators, models, shooting

MODELS = {"jeffcott_clearance": models.JEFFCOTT_CLEARANCE}


@dataclass(frozen=True)
class PointParams:
    p: np.ndarray           # kernel parameter vector
    period: float           # forcing period T [s]
    contact_angle: float    # angle used in the force law [rad]


@lru_cache(maxsize=8)
def _geometry(preset, nominal_angle):
    return bearing.preset(preset, nominal_angle)


def _free_angle(geom, clearance, contact_angle_deg):
    """The unloaded contact angle: the user's, else from the clearance (Bai eq. 6), else nominal."""
    if contact_angle_deg is not None and np.isfinite(contact_angle_deg):
        return np.radians(contact_angle_deg)
    if clearance > 0:
        return bearing.free_contact_angle(geom, clearance)
    return geom.nominal_contact_angle


def _stiffness(option, geom, alpha):
    if option == "hertz":
        return bearing.hertz_constant(geom, alpha)
    if option == "bai2006":
        return bearing.BAI2006_CONTACT_CONSTANT
    return float(option)


def point_params(data, speed, clearance, contact_angle, preload):
    """Kernel parameters at one grid point. contact_angle in degrees (None/NaN: not given)."""
    b, rotor = data["bearing"], data["rotor"]
    geom = _geometry(b["preset"], b.get("nominal_angle"))
    alpha0 = _free_angle(geom, clearance, contact_angle)
    stiffness = _stiffness(b["stiffness"], geom, alpha0)
    alpha, approach = alpha0, 0.0
    if preload > 0:
        state = bearing.preload_state(geom, preload, clearance=clearance, free_angle=alpha0,
                                      stiffness=stiffness, constant=b["preload_constant"])
        alpha, approach, stiffness = state.contact_angle, state.axial_approach, state.contact_constant
    load = rotor["mass"] * rotor["gravity"] if rotor["radial_load"] == "gravity" else rotor["radial_load"]
    p, period = models.jeffcott_params(
        speed=speed, stiffness=stiffness, clearance=clearance, contact_angle=alpha,
        axial_approach=approach, mass=rotor["mass"], damping=rotor["damping"], radial_load=load,
        n_balls=geom.n_balls, ball_diameter=geom.ball_diameter, pitch_diameter=geom.pitch_diameter,
        cage_rotation=b["cage_rotation"])
    return PointParams(p, period, alpha)


def integrator_settings(numerics):
    return integrators.settings(numerics["integrator"], rtol=numerics["rtol"], atol=numerics["atol"],
                                steps_per_unit=numerics["rk4_steps"],
                                amplitude_limit=numerics["amplitude_limit"] / models.LENGTH_SCALE)


def fixed_values(data):
    """Values of the parameters a scene does not sweep (contact angle None: from clearance)."""
    b = data["bearing"]
    return {"clearance": b.get("clearance") or 0.0, "contact_angle": b.get("contact_angle"),
            "preload": b.get("preload") or 0.0}


def solve_segment(data, points):
    """Solve a continuation segment. points: list of dicts with keys speed, clearance,
    contact_angle, preload (SI, angle in degrees). Returns schema variables, one row per point:
    the periodic orbit ([analysis] floquet) and the attractor ([analysis] attractor)."""
    model = MODELS[data["scene"]["model"]]
    ana = data["analysis"]
    opts = integrator_settings(data["numerics"])
    params, seconds, sols = [], [], []
    for pt in points:
        start = time.perf_counter()
        params.append(point_params(data, pt["speed"], pt["clearance"], pt["contact_angle"], pt["preload"]))
        seconds.append(time.perf_counter() - start)
    if ana["floquet"]:
        sols = _orbit_chain(model, params, opts, data["numerics"], seconds)
    else:
        sols = [_not_requested(model)] * len(points)
    rows = [point_variables(sol, par, 0.0) for sol, par in zip(sols, params)]
    if ana["attractor"]:
        for direction, suffix in _directions(ana["sweep_direction"]):
            order = range(len(points)) if direction == "up" else range(len(points) - 1, -1, -1)
            for i, att in _attractor_chain(model, params, sols, opts, ana, order, seconds):
                rows[i].update({name + suffix: v for name, v in attractor_variables(att).items()})
        if ana["sweep_direction"] == "both":
            for row in rows:
                row["hysteresis"] = _differs(row, schema.DOWN_SUFFIX)
    for row, sec in zip(rows, seconds):
        row["compute_time"] = sec
    return {name: np.array([r[name] for r in rows]) for name in rows[0]}


def _orbit_chain(model, params, opts, num, seconds):
    """Periodic orbits along the segment, each started from its neighbours (continuation)."""
    history, sols = [], []
    for i, par in enumerate(params):
        start = time.perf_counter()
        sol = continuation.solve_orbit(
            model, par.p, opts, history[-2:], cold_guess=models.static_guess,
            tol=num["newton_tol"], max_iter=num["max_newton_iter"],
            transient_periods=num["transient_periods"])
        if sol.status == shooting.CONVERGED:
            history.append(sol.state)
        else:
            history.clear()
        sols.append(sol)
        seconds[i] += time.perf_counter() - start
    return sols


def _not_requested(model):
    nan = np.full(model.n_state, np.nan)
    return continuation.PointSolution(schema.ORBIT_STATUS.index("not_applicable"),
                                      schema.ORBIT_REASON.index("not_requested"), 0, np.nan,
                                      nan + 0j, np.nan, False, 0, nan, None, 0)


def _directions(option):
    """(direction, variable suffix) pairs: the first direction fills the plain variables."""
    if option == "both":
        return (("up", ""), ("down", schema.DOWN_SUFFIX))
    return ((option, ""),)


# A Lyapunov run measures at least this many forcing periods before its 2 % standard-error stop:
# with two multipliers of nearly equal modulus (a gap of ~0.02 per period is common here) the
# tangent frame aligns slowly, and 100 periods left the exponent off by several standard errors
# (Fig. 13 at 1 Hz: 6 of 1032 stable points; 300 periods: none beyond 3 standard errors).
LYAPUNOV_MIN_PERIODS = 300


def _attractor_chain(model, params, sols, opts, ana, order, seconds):
    """Continuation of the attractor: each speed (in `order`) starts from the previous one's end
    state; the first from its periodic orbit when one was found, else near static equilibrium."""
    state = None
    for i in order:
        start = time.perf_counter()
        par, sol = params[i], sols[i]
        found = sol.status == shooting.CONVERGED
        if state is None:
            state = sol.state if found else models.static_guess(par.p)
        stable_orbit = (sol.state, sol.multipliers) if found and sol.stable and ana["derive_when_stable"] else None
        att = attractor.diagnose(
            model, state, par.p, par.period, opts, n_transient=ana["transient_periods"],
            n_samples=ana["poincare_samples"], max_period=ana["max_period"],
            lyapunov_always=not ana["derive_when_stable"], stable_orbit=stable_orbit,
            max_periods=ana["lyapunov_max_periods"],
            min_periods=min(LYAPUNOV_MIN_PERIODS, ana["lyapunov_max_periods"]))
        # a diverged run leaves no attractor to continue from: the next speed starts afresh
        state = att.end_state if att.code != attractor.DIVERGED else None
        seconds[i] += time.perf_counter() - start
        yield i, att


def point_variables(sol, params, seconds):
    """Cube variables (schema.VARIABLES) of one solved point, SI units."""
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
        "contact_angle_used": np.degrees(params.contact_angle),
        "orbit_state": sol.state if sol.status == shooting.CONVERGED else np.full(len(lam), np.nan),
        "compute_time": seconds,
    }
    out.update(_orbit_extent(sol.samples))
    return out


def _orbit_extent(samples):
    """Mean and half peak-to-peak of the journal displacement over the orbit [m]."""
    if samples is None:
        return {k: np.nan for k in ("x_mean", "y_mean", "amplitude_x", "amplitude_y")}
    xy = samples[:, :2] * models.LENGTH_SCALE
    half = 0.5 * (xy.max(axis=0) - xy.min(axis=0))
    mean = xy.mean(axis=0)
    return {"x_mean": mean[0], "y_mean": mean[1], "amplitude_x": half[0], "amplitude_y": half[1]}


def point_detail(data, point, start_state=None, periods=256, steps_per_period=32):
    """What `report --point` draws at one point: the cube variables of the point (orbit and
    attractor; a dict of numpy values), a trajectory on the attractor over `periods` forcing
    periods, and the power spectrum of its horizontal displacement.

    start_state: a state on the attractor (a cube's attractor_state) to start from instead of
    diagnosing the point afresh from its periodic orbit -- where attractors coexist, this picks
    the one the sweep found. Returns dict(row, time [s], x, y [m], frequency [Hz], power [m^2])."""
    data = {**data, "analysis": {**data["analysis"], "attractor": True, "sweep_direction": "up"}}
    row = {k: v[0] for k, v in solve_segment(data, [point]).items()}
    model = MODELS[data["scene"]["model"]]
    par = point_params(data, point["speed"], point["clearance"], point["contact_angle"], point["preload"])
    state = np.asarray(row["attractor_state"] if start_state is None else start_state, float)
    n = int(periods) * int(steps_per_period)
    traj = np.full((n, model.n_state), np.nan)
    if np.all(np.isfinite(state)):
        traj = shooting.sample_orbit(model.id, state, par.p, model.n_state, model.n_position,
                                     float(periods), n, integrator_settings(data["numerics"]))
    dt = par.period / steps_per_period
    xy = traj[:, :2] * models.LENGTH_SCALE
    ok = np.all(np.isfinite(xy), axis=1)
    freq, power = attractor.power_spectrum(xy[ok, 0], dt) if ok.sum() > 8 else (np.array([]), np.array([]))
    return {"row": row, "time": np.arange(n) * dt, "x": xy[:, 0], "y": xy[:, 1],
            "frequency": freq, "power": power}


def attractor_variables(att):
    """Cube variables (schema.ATTRACTOR_VARIABLES) of one diagnosed point, SI units."""
    lam = np.asarray(att.multipliers, complex)
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
        "poincare_x": att.samples[:, 0] * models.LENGTH_SCALE,
        "poincare_y": att.samples[:, 1] * models.LENGTH_SCALE,
        "attractor_multiplier_real": lam.real,
        "attractor_multiplier_imag": lam.imag,
        "lyapunov_periods": att.periods_used,
        "attractor_state": np.asarray(att.end_state, float),
    }


# Two periodic attractors of one class and period are distinct orbits when a Poincare point of one
# lies this far (relative to the section's size) from every point of the other.
SAME_ORBIT_RTOL = 1e-3


def _differs(row, suffix):
    """1 where the up and down sweeps ended on different attractors: class or period differ, or
    two periodic ones are different orbits (e.g. two coexisting stable period-1 orbits). A
    periodic attractor whose period was not resolved (k = 0: still settling, as next to a
    bifurcation) cannot be compared: 0."""
    unresolved = [row["attractor" + s] == attractor.PERIODIC and row["period" + s] <= 0 for s in ("", suffix)]
    if any(unresolved):
        return 0
    if row["attractor"] != row["attractor" + suffix] or row["period"] != row["period" + suffix]:
        return 1
    if row["attractor"] != attractor.PERIODIC:
        return 0
    up = np.stack([row["poincare_x"], row["poincare_y"]], axis=1)
    down = np.array([row["poincare_x" + suffix][-1], row["poincare_y" + suffix][-1]])
    scale = SAME_ORBIT_RTOL * max(np.abs(up).max(), models.LENGTH_SCALE)
    return int(np.abs(up - down).max(axis=1).min() > scale)

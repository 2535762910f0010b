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
from rotorkernels import bearing, continuation, integrators, models, shooting

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
    contact_angle, preload (SI, angle in degrees). Returns schema variables, one row per point."""
    model = MODELS[data["scene"]["model"]]
    num = data["numerics"]
    opts = integrator_settings(num)
    rows = []
    history = []
    for pt in points:
        start = time.perf_counter()
        params = point_params(data, pt["speed"], pt["clearance"], pt["contact_angle"], pt["preload"])
        sol = continuation.solve_orbit(
            model, params.p, opts, history[-2:], cold_guess=models.static_guess,
            tol=num["newton_tol"], max_iter=num["max_newton_iter"],
            transient_periods=num["transient_periods"])
        if sol.status == shooting.CONVERGED:
            history.append(sol.state)
        else:
            history.clear()
        rows.append(point_variables(sol, params, time.perf_counter() - start))
    return {name: np.array([r[name] for r in rows]) for name in rows[0]}


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

"""Rotor models: right-hand sides and analytic Jacobians in scaled form.

Scaling, for conditioning and so that one orbit serves as the Newton start of its neighbour
along the speed axis: time tau = t / T (T the forcing period, so the basic periodic orbit has
period 1 whatever the speed), displacements in units of the length scale L (1 um by default).
The state of `jeffcott_clearance` is u = (x/L, y/L, dx/dtau / L, dy/dtau / L).

A model is (name, id, n_state, n_position) with a right-hand side f(tau, u, p, du), an analytic
Jacobian J(tau, u, p, J) and both from one evaluation, (f, J)(tau, u, p, du, J), over a float64
parameter vector p built by the model's `*_params` function. u and du may be longer than
n_state (the integrators pass the augmented variational vector): only the first n_state entries
are read and written. The integrators and the shooting solver reach every model through `rhs`,
`jac` and `rhs_jac`, which dispatch on the model id: Numba caches functions of plain arguments on
disk, whereas a jitted function passed as an argument would be recompiled in every process
(~25 s each).

Every model here is in velocity form, u = (q, q') with dq/dtau = q' (n_state = 2 n_position), so
its Jacobian is [[0, I], [A, B]]; `velocity_form` tells the integrators, which then form J Phi
from the lower block rows only. The per-model functions and the dispatchers are inlined into
their callers (`inline="always"`): a compiled call with array arguments costs more than the
9-ball force sum it would wrap.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from rotorkernels.contact import ring_force, ring_load

Model = namedtuple("Model", "name id n_state n_position")

LENGTH_SCALE = 1e-6  # m: bearing clearances and vibration amplitudes are micrometres

# Parameter vector of jeffcott_clearance (indices).
P_DAMP, P_GAIN, P_OFFSET, P_LOAD, P_COS_A, P_SIN_A, P_NBALLS, P_PHI0, P_CAGE, P_COS_D, P_SIN_D = range(11)
N_PARAMS = 11


@njit(cache=True, nogil=True, inline="always")
def _velocity_form_jac(jac, a00, a01, a10, a11, b00, b01, b10, b11):
    """jac = [[0, I], [A, B]] of a 2-DOF model in velocity form, every entry written."""
    jac[0, 0] = 0.0
    jac[0, 1] = 0.0
    jac[0, 2] = 1.0
    jac[0, 3] = 0.0
    jac[1, 0] = 0.0
    jac[1, 1] = 0.0
    jac[1, 2] = 0.0
    jac[1, 3] = 1.0
    jac[2, 0] = a00
    jac[2, 1] = a01
    jac[2, 2] = b00
    jac[2, 3] = b01
    jac[3, 0] = a10
    jac[3, 1] = a11
    jac[3, 2] = b10
    jac[3, 3] = b11


@njit(cache=True, nogil=True, inline="always")
def _ball_phase(tau, p):
    """Angle of the first ball: the cage turns 2 pi / N per forcing period (tau = 1)."""
    # np.divide: the same IEEE division as `/`, without Python's zero-division check, whose
    # exception path keeps Numba from pruning reference counts in an inlining caller
    theta = p[P_PHI0] + np.divide(p[P_CAGE] * 2.0 * np.pi * tau, p[P_NBALLS])
    return np.cos(theta), np.sin(theta)


@njit(cache=True, nogil=True, inline="always")
def _jeffcott_force(tau, u, p):
    cos_t, sin_t = _ball_phase(tau, p)
    return ring_force(u[0], u[1], 0.0, p[P_OFFSET], p[P_COS_A], p[P_SIN_A], int(p[P_NBALLS]),
                      cos_t, sin_t, p[P_COS_D], p[P_SIN_D])


@njit(cache=True, nogil=True, inline="always")
def _jeffcott_load(tau, u, p):
    cos_t, sin_t = _ball_phase(tau, p)
    return ring_load(u[0], u[1], 0.0, p[P_OFFSET], p[P_COS_A], p[P_SIN_A], int(p[P_NBALLS]),
                     cos_t, sin_t, p[P_COS_D], p[P_SIN_D])


@njit(cache=True, nogil=True, inline="always")
def _jeffcott_du(u, p, fx, fy, du):
    a = p[P_DAMP]
    g = p[P_GAIN]
    du[0] = u[2]
    du[1] = u[3]
    du[2] = -a * u[2] - g * fx
    du[3] = -a * u[3] - g * fy - p[P_LOAD]


@njit(cache=True, nogil=True, inline="always")
def jeffcott_rhs(tau, u, p, du):
    """M x'' + D x' + K sum [delta]^{3/2} cos(phi) cos(a) = 0, likewise for y with the load -W."""
    fx, fy, _ = _jeffcott_force(tau, u, p)
    _jeffcott_du(u, p, fx, fy, du)


@njit(cache=True, nogil=True, inline="always")
def jeffcott_jac(tau, u, p, jac):
    _, _, _, kxx, kxy, kyy, _, _, _ = _jeffcott_load(tau, u, p)
    g = p[P_GAIN]
    a = p[P_DAMP]
    _velocity_form_jac(jac, -g * kxx, -g * kxy, -g * kxy, -g * kyy, -a, 0.0, 0.0, -a)


@njit(cache=True, nogil=True, inline="always")
def jeffcott_rhs_jac(tau, u, p, du, jac):
    """jeffcott_rhs and jeffcott_jac from one ball sum."""
    fx, fy, _, kxx, kxy, kyy, _, _, _ = _jeffcott_load(tau, u, p)
    _jeffcott_du(u, p, fx, fy, du)
    g = p[P_GAIN]
    a = p[P_DAMP]
    _velocity_form_jac(jac, -g * kxx, -g * kxy, -g * kxy, -g * kyy, -a, 0.0, 0.0, -a)


@njit(cache=True, nogil=True, inline="always")
def linear_rhs(tau, u, p, du):
    """Validation model: u'' + C u' + K u = 0, K = [[p0, p1], [p1, p2]], C = diag(p3, p4)."""
    du[0] = u[2]
    du[1] = u[3]
    du[2] = -p[0] * u[0] - p[1] * u[1] - p[3] * u[2]
    du[3] = -p[1] * u[0] - p[2] * u[1] - p[4] * u[3]


@njit(cache=True, nogil=True, inline="always")
def linear_jac(tau, u, p, jac):
    _velocity_form_jac(jac, -p[0], -p[1], -p[1], -p[2], -p[3], 0.0, 0.0, -p[4])


@njit(cache=True, nogil=True, inline="always")
def linear_rhs_jac(tau, u, p, du, jac):
    linear_rhs(tau, u, p, du)
    linear_jac(tau, u, p, jac)


@njit(cache=True, nogil=True, inline="always")
def _mathieu_stiffness(tau, p):
    return p[1] + p[2] * np.cos(2 * np.pi * tau)


@njit(cache=True, nogil=True, inline="always")
def _mathieu_du(u, p, k, du):
    du[0] = u[2]
    du[1] = u[3]
    du[2] = -2 * p[0] * u[2] - k * u[0]
    du[3] = -2 * p[0] * u[3] - k * u[1]


@njit(cache=True, nogil=True, inline="always")
def mathieu_rhs(tau, u, p, du):
    """Validation model: x'' + 2 zeta x' + (delta + eps cos 2 pi tau) x = 0, twice (uncoupled),
    p = (zeta, delta, eps)."""
    _mathieu_du(u, p, _mathieu_stiffness(tau, p), du)


@njit(cache=True, nogil=True, inline="always")
def mathieu_jac(tau, u, p, jac):
    k = _mathieu_stiffness(tau, p)
    _velocity_form_jac(jac, -k, 0.0, 0.0, -k, -2 * p[0], 0.0, 0.0, -2 * p[0])


@njit(cache=True, nogil=True, inline="always")
def mathieu_rhs_jac(tau, u, p, du, jac):
    k = _mathieu_stiffness(tau, p)
    _mathieu_du(u, p, k, du)
    _velocity_form_jac(jac, -k, 0.0, 0.0, -k, -2 * p[0], 0.0, 0.0, -2 * p[0])


JEFFCOTT_CLEARANCE = Model("jeffcott_clearance", 0, 4, 2)
LINEAR_OSCILLATOR = Model("linear_oscillator", 1, 4, 2)
DAMPED_MATHIEU = Model("damped_mathieu", 2, 4, 2)


@njit(cache=True, nogil=True, inline="always")
def rhs(model, tau, u, p, du):
    """du = f(tau, u) of model id `model`."""
    if model == 0:
        jeffcott_rhs(tau, u, p, du)
    elif model == 1:
        linear_rhs(tau, u, p, du)
    else:
        mathieu_rhs(tau, u, p, du)


@njit(cache=True, nogil=True, inline="always")
def jac(model, tau, u, p, out):
    """out = df/du(tau, u) of model id `model`."""
    if model == 0:
        jeffcott_jac(tau, u, p, out)
    elif model == 1:
        linear_jac(tau, u, p, out)
    else:
        mathieu_jac(tau, u, p, out)


@njit(cache=True, nogil=True, inline="always")
def rhs_jac(model, tau, u, p, du, out):
    """du = f(tau, u) and out = df/du(tau, u) of model id `model` from one evaluation (one ball
    sum for the bearing models): what the variational equations need at every stage."""
    if model == 0:
        jeffcott_rhs_jac(tau, u, p, du, out)
    elif model == 1:
        linear_rhs_jac(tau, u, p, du, out)
    else:
        mathieu_rhs_jac(tau, u, p, du, out)


@njit(cache=True, nogil=True, inline="always")
def velocity_form(model):
    """True when model `model` has u = (q, q'), dq/dtau = q' (n_state = 2 n_position): its
    Jacobian is [[0, I], [A, B]] and J Phi needs only the lower block rows. All models here."""
    return model == 0 or model == 1 or model == 2


def cage_speed_ratio(ball_diameter, pitch_diameter, contact_angle):
    """omega_cage / omega_shaft for an outer ring at rest: (1 - (D_b / D_m) cos a) / 2."""
    return 0.5 * (1.0 - ball_diameter / pitch_diameter * np.cos(contact_angle))


def forcing_period(speed_hz, n_balls, ball_diameter, pitch_diameter, contact_angle):
    """Ball-passage period T = 2 pi / (N omega_cage) [s]."""
    omega_cage = 2.0 * np.pi * speed_hz * cage_speed_ratio(ball_diameter, pitch_diameter, contact_angle)
    return 2.0 * np.pi / (n_balls * omega_cage)


def jeffcott_params(*, speed, stiffness, clearance, contact_angle, axial_approach, mass, damping,
                    radial_load, n_balls, ball_diameter, pitch_diameter, cage_rotation=True,
                    phase=0.0, length_scale=LENGTH_SCALE):
    """Parameter vector of `jeffcott_clearance` and the forcing period T [s], from SI inputs.

    speed [Hz], stiffness K [N/m^1.5], clearance c [m], contact_angle [rad], axial_approach s0
    [m] (0 without preload), mass [kg], damping [N s/m], radial_load W [N] acting in -y."""
    period = forcing_period(speed, n_balls, ball_diameter, pitch_diameter, contact_angle)
    L = length_scale
    p = np.empty(N_PARAMS)
    p[P_DAMP] = damping * period / mass
    p[P_GAIN] = period ** 2 * stiffness * np.sqrt(L) / mass
    p[P_OFFSET] = (axial_approach * np.sin(contact_angle) - clearance) / L
    p[P_LOAD] = period ** 2 * radial_load / (mass * L)
    p[P_COS_A] = np.cos(contact_angle)
    p[P_SIN_A] = np.sin(contact_angle)
    p[P_NBALLS] = n_balls
    p[P_PHI0] = phase
    p[P_CAGE] = 1.0 if cage_rotation else 0.0
    p[P_COS_D] = np.cos(2.0 * np.pi / n_balls)
    p[P_SIN_D] = np.sin(2.0 * np.pi / n_balls)
    return p, period


def to_physical(u, period, length_scale=LENGTH_SCALE):
    """Scaled state(s) (..., 4) -> (x, y, x', y') in m and m/s."""
    u = np.asarray(u, float)
    scale = np.array([length_scale, length_scale, length_scale / period, length_scale / period])
    return u * scale


def static_guess(p):
    """A state near static equilibrium: the lowest ball carries the radial load.

    Used to start the transient of a cold solve; Newton takes over from where it settles."""
    g = p[P_GAIN]
    depth = (p[P_LOAD] / g) ** (2.0 / 3.0) if g > 0 else 0.0
    y = -(depth - p[P_OFFSET]) / p[P_COS_A]
    return np.array([0.0, y, 0.0, 0.0])

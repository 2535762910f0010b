"""The njit equations of the model `jeffcott_clearance` (its spec and parameter vector: models.jeffcott_clearance)."""
import numpy as np
from numba import njit

from rotorsweep.kernels.contact import ring_force, ring_load
from rotorsweep.kernels.models.jeffcott_clearance import (P_CAGE, P_COS_A, P_COS_D, P_DAMP, P_GAIN, P_LOAD, P_NBALLS,
                                                         P_OFFSET, P_PHI0, P_SIN_A, P_SIN_D)
from rotorsweep.kernels.models.velocity import upper_rows


@njit(cache=True, nogil=True, inline="always")
def _lower_rows(out, kxx, kxy, kyy, damp):
    """out = [[0, I], [A, B]] with A = [[kxx, kxy], [kxy, kyy]], B = damp I."""
    upper_rows(out, 2)
    out[2, 0] = kxx
    out[2, 1] = kxy
    out[2, 2] = damp
    out[2, 3] = 0.0
    out[3, 0] = kxy
    out[3, 1] = kyy
    out[3, 2] = 0.0
    out[3, 3] = damp


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
def rhs(tau, u, p, du):
    """M x'' + D x' + K sum [delta]^{3/2} cos(phi) cos(a) = 0, likewise for y with the load -W."""
    fx, fy, _ = _jeffcott_force(tau, u, p)
    _jeffcott_du(u, p, fx, fy, du)


@njit(cache=True, nogil=True, inline="always")
def jac(tau, u, p, out):
    _, _, _, kxx, kxy, kyy, _, _, _ = _jeffcott_load(tau, u, p)
    g = p[P_GAIN]
    a = p[P_DAMP]
    _lower_rows(out, -g * kxx, -g * kxy, -g * kyy, -a)


@njit(cache=True, nogil=True, inline="always")
def rhs_jac(tau, u, p, du, out):
    """rhs and jac from one ball sum."""
    fx, fy, _, kxx, kxy, kyy, _, _, _ = _jeffcott_load(tau, u, p)
    _jeffcott_du(u, p, fx, fy, du)
    g = p[P_GAIN]
    a = p[P_DAMP]
    _lower_rows(out, -g * kxx, -g * kxy, -g * kyy, -a)

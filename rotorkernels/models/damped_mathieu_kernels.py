"""The njit equations of the validation model `damped_mathieu` (its spec: models.damped_mathieu)."""
import numpy as np
from numba import njit

from rotorsweep.kernels.models.velocity import upper_rows, velocity_rows


@njit(cache=True, nogil=True, inline="always")
def _stiffness(tau, p):
    return p[1] + p[2] * np.cos(2 * np.pi * tau)


@njit(cache=True, nogil=True, inline="always")
def _lower(u, p, k, du):
    velocity_rows(u, du, 2)
    du[2] = -2 * p[0] * u[2] - k * u[0]
    du[3] = -2 * p[0] * u[3] - k * u[1]


@njit(cache=True, nogil=True, inline="always")
def _jac(k, p, out):
    upper_rows(out, 2)
    out[2, 0] = -k
    out[2, 1] = 0.0
    out[2, 2] = -2 * p[0]
    out[2, 3] = 0.0
    out[3, 0] = 0.0
    out[3, 1] = -k
    out[3, 2] = 0.0
    out[3, 3] = -2 * p[0]


@njit(cache=True, nogil=True, inline="always")
def rhs(tau, u, p, du):
    _lower(u, p, _stiffness(tau, p), du)


@njit(cache=True, nogil=True, inline="always")
def jac(tau, u, p, out):
    _jac(_stiffness(tau, p), p, out)


@njit(cache=True, nogil=True, inline="always")
def rhs_jac(tau, u, p, du, out):
    k = _stiffness(tau, p)
    _lower(u, p, k, du)
    _jac(k, p, out)

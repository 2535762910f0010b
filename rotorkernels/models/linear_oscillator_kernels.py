"""The njit equations of the validation model `linear_oscillator` (its spec: models.linear_oscillator)."""
from numba import njit

from rotorsweep.kernels.models.velocity import upper_rows, velocity_rows


@njit(cache=True, nogil=True, inline="always")
def rhs(tau, u, p, du):
    velocity_rows(u, du, 2)
    du[2] = -p[0] * u[0] - p[1] * u[1] - p[3] * u[2]
    du[3] = -p[1] * u[0] - p[2] * u[1] - p[4] * u[3]


@njit(cache=True, nogil=True, inline="always")
def jac(tau, u, p, out):
    upper_rows(out, 2)
    out[2, 0] = -p[0]
    out[2, 1] = -p[1]
    out[2, 2] = -p[3]
    out[2, 3] = 0.0
    out[3, 0] = -p[1]
    out[3, 1] = -p[2]
    out[3, 2] = 0.0
    out[3, 3] = -p[4]


@njit(cache=True, nogil=True, inline="always")
def rhs_jac(tau, u, p, du, out):
    rhs(tau, u, p, du)
    jac(tau, u, p, out)

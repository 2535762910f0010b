"""The njit equations of the model `duffing` (its spec: models.duffing)."""
import numpy as np
from numba import njit

from rotorsweep.kernels.models.duffing import P_DAMP, P_FORCE, P_GAMMA, P_T2
from rotorsweep.kernels.models.velocity import upper_rows, velocity_rows


@njit(cache=True, nogil=True, inline="always")
def rhs(tau, u, p, du):
    velocity_rows(u, du, 1)
    x = u[0]
    du[1] = p[P_T2] * (p[P_FORCE] * np.cos(2.0 * np.pi * tau) - x - p[P_GAMMA] * x * x * x) - p[P_DAMP] * u[1]


@njit(cache=True, nogil=True, inline="always")
def jac(tau, u, p, out):
    upper_rows(out, 1)
    out[1, 0] = -p[P_T2] * (1.0 + 3.0 * p[P_GAMMA] * u[0] * u[0])
    out[1, 1] = -p[P_DAMP]


@njit(cache=True, nogil=True, inline="always")
def rhs_jac(tau, u, p, du, out):
    rhs(tau, u, p, du)
    jac(tau, u, p, out)

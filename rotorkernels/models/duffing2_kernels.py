"""The njit equations of the model `duffing2` (its spec: models.duffing2)."""
import numpy as np
from numba import njit

from rotorsweep.kernels.models.duffing2 import P_C, P_F1, P_F2, P_GAMMA, P_K, P_PHASE, P_W2
from rotorsweep.kernels.models.velocity import upper_rows, velocity_rows


@njit(cache=True, nogil=True, inline="always")
def rhs(tau, u, p, du):
    velocity_rows(u, du, 1)
    x = u[0]
    du[1] = (p[P_F1] * np.cos(2.0 * np.pi * tau) + p[P_F2] * np.cos(p[P_W2] * tau + p[P_PHASE])
             - p[P_K] * x - p[P_GAMMA] * x * x * x - p[P_C] * u[1])


@njit(cache=True, nogil=True, inline="always")
def jac(tau, u, p, out):
    upper_rows(out, 1)
    out[1, 0] = -p[P_K] - 3.0 * p[P_GAMMA] * u[0] * u[0]
    out[1, 1] = -p[P_C]


@njit(cache=True, nogil=True, inline="always")
def rhs_jac(tau, u, p, du, out):
    rhs(tau, u, p, du)
    jac(tau, u, p, out)

"""The njit equations of the model `rigid_preloaded` (its spec, parameter vector and SI model:
models.rigid_preloaded)."""
import numpy as np
from numba import njit

from rotorsweep.kernels.contact import ring_force, ring_load
from rotorsweep.kernels.cubic_law_kernels import cubic_load
from rotorsweep.kernels.models.rigid_preloaded import (
    N_POS, P_ARR, P_CA, P_CONST, P_COS_A, P_COS_D, P_CR, P_DAMP, P_GAIN, P_LAW, P_NBALLS, P_OFFSET, P_PHASE, P_SIN_A,
    P_SIN_D, P_SUP, P_TAN2, P_UCOS, P_USIN, P_WS, P_WU, P_Z0)
from rotorsweep.kernels.models.velocity import upper_rows, velocity_rows


@njit(cache=True, nogil=True, inline="always")
def _accelerations(tau, u, p, fxa, fya, fxb, fyb, fz, du):
    """du[5:] = -gain F - damp q' + gravity + unbalance + support, F the ball-sum forces."""
    cu = np.cos(p[P_WU] * tau)
    su = np.sin(p[P_WU] * tau)
    ss = np.sin(p[P_WS] * tau + p[P_PHASE])
    for i in range(N_POS):
        g = P_GAIN + N_POS * i
        d = P_DAMP + N_POS * i
        acc = -(p[g] * fxa + p[g + 1] * fya + p[g + 2] * fxb + p[g + 3] * fyb + p[g + 4] * fz)
        for j in range(N_POS):
            acc -= p[d + j] * u[N_POS + j]
        du[N_POS + i] = (acc + p[P_CONST + i] + p[P_UCOS + i] * cu + p[P_USIN + i] * su
                         + p[P_SUP + i] * ss)


@njit(cache=True, nogil=True, inline="always")
def _stiffness_column(out, p, j, k0, k1, k2, k3, k4):
    """Column j of the lower-left block: -gain . (column j of the bearing stiffness dP/dq)."""
    for i in range(N_POS):
        g = P_GAIN + N_POS * i
        out[N_POS + i, j] = -(p[g] * k0 + p[g + 1] * k1 + p[g + 2] * k2 + p[g + 3] * k3 + p[g + 4] * k4)


@njit(cache=True, nogil=True, inline="always")
def jacobian(out, p, a, b):
    """[[0, I], [-gain dP/dq, -damp]] from the ring loads a (bearing A, shift s z) and b (B, -s z),
    s = p[P_ARR] = +-1: A's cross terms with z carry s, B's -s, and kzz = kzz_A + kzz_B (s^2 = 1)."""
    s = p[P_ARR]
    upper_rows(out, N_POS)
    _stiffness_column(out, p, 0, a[3], a[4], 0.0, 0.0, s * a[6])
    _stiffness_column(out, p, 1, a[4], a[5], 0.0, 0.0, s * a[7])
    _stiffness_column(out, p, 2, 0.0, 0.0, b[3], b[4], -s * b[6])
    _stiffness_column(out, p, 3, 0.0, 0.0, b[4], b[5], -s * b[7])
    _stiffness_column(out, p, 4, s * a[6], s * a[7], -s * b[6], -s * b[7], a[8] + b[8])
    for i in range(N_POS):
        for j in range(N_POS):
            out[N_POS + i, N_POS + j] = -p[P_DAMP + N_POS * i + j]


# `load` and `_force` run once per bearing (A and B) in each kernel: `forceinline` lowers the
# ball sum once and lets LLVM inline both calls, where `inline="always"` lowered it at each call
# (rhs_jac's first compile 2.4 -> 1.3 s CPU, rhs 1.9 -> 0.7 s; the same machine code speed).
@njit(cache=True, nogil=True, forceinline=True)
def load(x, y, z, p):
    """One bearing's forces and stiffness (`ring_load` layout): the ball sum, or the cubic series."""
    if p[P_LAW] > 0.0:
        return cubic_load(x, y, z, p[P_CR], p[P_CA], p[P_Z0], p[P_TAN2])
    return ring_load(x, y, z, p[P_OFFSET], p[P_COS_A], p[P_SIN_A], int(p[P_NBALLS]),
                     1.0, 0.0, p[P_COS_D], p[P_SIN_D])


@njit(cache=True, nogil=True, forceinline=True)
def _force(x, y, z, p):
    """One bearing's forces only (the ball sum skips its stiffness)."""
    if p[P_LAW] > 0.0:
        c = cubic_load(x, y, z, p[P_CR], p[P_CA], p[P_Z0], p[P_TAN2])
        return c[0], c[1], c[2]
    return ring_force(x, y, z, p[P_OFFSET], p[P_COS_A], p[P_SIN_A], int(p[P_NBALLS]),
                      1.0, 0.0, p[P_COS_D], p[P_SIN_D])


@njit(cache=True, nogil=True)
def rhs(tau, u, p, du):
    velocity_rows(u, du, N_POS)
    z = p[P_ARR] * u[4]
    fxa, fya, fza = _force(u[0], u[1], z, p)
    fxb, fyb, fzb = _force(u[2], u[3], -z, p)
    _accelerations(tau, u, p, fxa, fya, fxb, fyb, p[P_ARR] * (fza - fzb), du)


@njit(cache=True, nogil=True)
def jac(tau, u, p, out):
    z = p[P_ARR] * u[4]
    jacobian(out, p, load(u[0], u[1], z, p), load(u[2], u[3], -z, p))


@njit(cache=True, nogil=True)
def rhs_jac(tau, u, p, du, out):
    """rhs and jac from one ball sum per bearing."""
    z = p[P_ARR] * u[4]
    a = load(u[0], u[1], z, p)
    b = load(u[2], u[3], -z, p)
    velocity_rows(u, du, N_POS)
    _accelerations(tau, u, p, a[0], a[1], b[0], b[1], p[P_ARR] * (a[2] - b[2]), du)
    jacobian(out, p, a, b)

"""The njit bearing loads, accelerations and Jacobian that the kernels of `symmetric4` and
`asymmetric5` share (conventions and scaling: `series_rotor`)."""
from numba import njit

from rotorsweep.kernels.cubic_law_kernels import cubic_load
from rotorsweep.kernels.models.velocity import upper_rows, velocity_rows

# The models' `rhs` (symmetric4, asymmetric5) are `forceinline=True`: Numba compiles each once and
# marks it LLVM `alwaysinline`, so LLVM inlines it into the step loops, where a call (23 arguments,
# 17 of them on the stack, and a status check) cost symmetric4 a few ns against ~10 ns of
# arithmetic. Numba's `inline="always"` gives the same code but types and lowers the body again at
# every call site: the first backbone's compile 15.3 -> 23.6 s CPU, against no change with
# `forceinline` (docs/benchmarks/compile.md; revision 28c7349 is the `inline="always"` variant).
# `error_model="numpy"` (all three kernels): a division by zero (z0 = 0, which no valid config
# gives) makes inf/NaN and an integrator failure status instead of an exception, and costs no
# check and exception branch in every evaluation.

@njit(cache=True, nogil=True, inline="always")
def bearing_loads(u, p, n):
    """The series loads of bearings A (shift s z) and B (-s z), scaled units (z = 0 when n = 4)."""
    law = 2 * n * n
    z = p[law + 4] * u[4] if n == 5 else 0.0
    a = cubic_load(u[0], u[1], z, p[law], p[law + 1], p[law + 2], p[law + 3])
    b = cubic_load(u[2], u[3], -z, p[law], p[law + 1], p[law + 2], p[law + 3])
    return a, b


@njit(cache=True, nogil=True, inline="always")
def accelerations(u, p, n, a, b, du):
    """du[n:] = -gain P(q) - gyro q', P = (P_xA, P_yA, P_xB, P_yB[, P_zA - P_zB]), summed term by
    term as the C floor (workflows/bench/peers/rotor_rhs.c) does: the same operations, the same
    rounding."""
    velocity_rows(u, du, n)
    load = (a[0], a[1], b[0], b[1], p[2 * n * n + 4] * (a[2] - b[2]))
    gyro = n * n
    for i in range(n):
        g = n * i
        acc = 0.0
        for j in range(n):
            acc -= p[g + j] * load[j] + p[gyro + g + j] * u[n + j]
        du[n + i] = acc


@njit(cache=True, nogil=True, inline="always")
def _stiffness_column(out, p, n, j, k0, k1, k2, k3, k4):
    """Column j of the lower-left block: -gain . (column j of dP/dq)."""
    for i in range(n):
        g = n * i
        v = p[g] * k0 + p[g + 1] * k1 + p[g + 2] * k2 + p[g + 3] * k3
        if n == 5:
            v += p[g + 4] * k4
        out[n + i, j] = -v


@njit(cache=True, nogil=True, inline="always")
def jacobian(out, p, n, a, b):
    """[[0, I], [-gain dP/dq, -gyro]]; z enters A as s z and B as -s z (their cross terms with z
    carry s and -s; kzz does not)."""
    s = p[2 * n * n + 4]
    upper_rows(out, n)
    _stiffness_column(out, p, n, 0, a[3], a[4], 0.0, 0.0, s * a[6])
    _stiffness_column(out, p, n, 1, a[4], a[5], 0.0, 0.0, s * a[7])
    _stiffness_column(out, p, n, 2, 0.0, 0.0, b[3], b[4], -s * b[6])
    _stiffness_column(out, p, n, 3, 0.0, 0.0, b[4], b[5], -s * b[7])
    if n == 5:
        _stiffness_column(out, p, n, 4, s * a[6], s * a[7], -s * b[6], -s * b[7], a[8] + b[8])
    gyro = n * n
    for i in range(n):
        for j in range(n):
            out[n + i, n + j] = -p[gyro + n * i + j]

"""The conservative polynomial system shared by the models and the nonlinear-normal-mode code
(`models.spec.PolynomialSystem`, which a model's `polynomial(values)` returns): its checks, its
linear part and its right-hand side for scipy.
"""
import numpy as np

from rotorsweep.kernels import modal
from rotorsweep.kernels.models.spec import PolynomialSystem  # noqa: F401 (the package's API)

# M symmetric and G skew to this relative accuracy (the models assemble them in floating point).
SYMMETRY_RTOL = 1e-10


def _asymmetry(a, sign):
    """|a - sign a^T| relative to |a| (0 for a zero matrix)."""
    scale = np.abs(a).max()
    return 0.0 if scale == 0 else float(np.abs(a - sign * a.T).max() / scale)


def validate(system):
    """Raise ValueError unless the matrices have consistent shapes, M and K are symmetric, M is
    positive definite and G is skew (the conservative gyroscopic systems the method assumes)."""
    n = len(system.coordinates)
    shapes = {"M": (n, n), "G": (n, n), "K": (n, n), "Q2": (n,) * 3, "Q3": (n,) * 4}
    for name, shape in shapes.items():
        if np.shape(getattr(system, name)) != shape:
            raise ValueError(f"{name} has shape {np.shape(getattr(system, name))}, expected {shape} "
                             f"for {n} coordinates")
    if len(system.units) != n:
        raise ValueError(f"{len(system.units)} units for {n} coordinates")
    for name, sign, what in (("M", 1, "symmetric"), ("K", 1, "symmetric"), ("G", -1, "skew")):
        error = _asymmetry(np.asarray(getattr(system, name), float), sign)
        if error > SYMMETRY_RTOL:
            raise ValueError(f"{name} is not {what} (relative error {error:.1e}): "
                             "the system is not conservative gyroscopic")
    if np.linalg.eigvalsh(system.M).min() <= 0:
        raise ValueError("M is not positive definite")


def state_matrix(system):
    """A of the linear part of x' = A x + ..., x = (q, q')."""
    return modal.first_order(system.M, system.G, system.K)


def rhs(system):
    """f(t, x) of the full first-order system, for scipy's solve_ivp (x = (q, q'), SI)."""
    n = len(system.coordinates)
    m_inv = np.linalg.inv(system.M)

    def f(t, x):
        q, v = x[:n], x[n:]
        force = system.G @ v + system.K @ q + np.einsum("ijk,j,k->i", system.Q2, q, q) \
            + np.einsum("ijkl,j,k,l->i", system.Q3, q, q, q)
        return np.concatenate([v, -m_inv @ force])
    return f

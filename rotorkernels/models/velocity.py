"""Helpers for models in velocity form, u = (q, q') with dq/dtau = q', for any number of positions."""
from numba import njit


@njit(cache=True, nogil=True, inline="always")
def upper_rows(out, n_position):
    """The upper block rows [0, I] of the Jacobian [[0, I], [A, B]]; the model writes A and B."""
    for i in range(n_position):
        for j in range(2 * n_position):
            out[i, j] = 0.0
        out[i, n_position + i] = 1.0


@njit(cache=True, nogil=True, inline="always")
def velocity_rows(u, du, n_position):
    """dq/dtau = q': the upper half of the right-hand side."""
    for i in range(n_position):
        du[i] = u[n_position + i]

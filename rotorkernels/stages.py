"""Stage arithmetic shared by the integrators, written for any state size; the generated
`models.dispatch` calls it with the registered models' sizes as constants (which the compiler
unrolls) and with the runtime size otherwise."""
from numba import njit


@njit(cache=True, nogil=True, inline="always")
def tangent_product(velocity_form, z, n, jac, dz):
    """dz[n:] = J Phi with Phi = z[n:] (n x n, row-major) and J = jac.

    For a model in velocity form (J = [[0, I], [A, B]]) the upper half of J Phi is the lower half
    of Phi and only the lower block rows are multiplied: half the dense product's work."""
    h = n // 2 if velocity_form else 0
    for i in range(h):
        for j in range(n):
            dz[n + i * n + j] = z[n + (h + i) * n + j]
    for i in range(h, n):
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += jac[i, k] * z[n + k * n + j]
            dz[n + i * n + j] = acc


@njit(cache=True, nogil=True, inline="always")
def combine(K, coef, n_terms, z, step, out, m):
    """out = z + step * sum_{j < n_terms} coef[j] K[j] over the first m entries (coef[0] != 0
    and coef[n_terms - 1] != 0).

    Row by row over K (contiguous, vectorised), each component summed in the order j = 0, 1, ...
    as a per-component dot product would; terms with a zero coefficient are skipped (a quarter
    of the Dormand-Prince tableau). One pass over `out` per term: the first assigns, the last
    adds z."""
    c = coef[0]
    if n_terms == 1:
        for i in range(m):
            out[i] = z[i] + step * (c * K[0, i])
        return
    for i in range(m):
        out[i] = c * K[0, i]
    for j in range(1, n_terms - 1):
        c = coef[j]
        if c != 0.0:
            for i in range(m):
                out[i] += c * K[j, i]
    c = coef[n_terms - 1]
    for i in range(m):
        out[i] = z[i] + step * (out[i] + c * K[n_terms - 1, i])

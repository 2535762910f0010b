"""The njit equations of the model `asymmetric5` (its spec: models.asymmetric5; the shared pieces:
models.series_rotor_kernels)."""
from numba import njit

from rotorsweep.kernels.models import series_rotor_kernels as sr
from rotorsweep.kernels.models.asymmetric5 import N_POS


@njit(cache=True, nogil=True, forceinline=True, error_model="numpy")
def rhs(tau, u, p, du):
    a, b = sr.bearing_loads(u, p, N_POS)
    sr.accelerations(u, p, N_POS, a, b, du)


@njit(cache=True, nogil=True, error_model="numpy")
def jac(tau, u, p, out):
    a, b = sr.bearing_loads(u, p, N_POS)
    sr.jacobian(out, p, N_POS, a, b)


@njit(cache=True, nogil=True, error_model="numpy")
def rhs_jac(tau, u, p, du, out):
    a, b = sr.bearing_loads(u, p, N_POS)
    sr.accelerations(u, p, N_POS, a, b, du)
    sr.jacobian(out, p, N_POS, a, b)

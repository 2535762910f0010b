"""The njit evaluation of the cubic series law (`cubic_law`: its derivation, coefficients and
potential), for the models' kernels; kept apart so that the coefficients need no Numba."""
from numba import njit


@njit(cache=True, nogil=True, inline="always")
def cubic_load(x, y, z, radial, axial, approach, tan2):
    """The series' forces and stiffness as a tuple in `contact.ring_load`'s layout:
    (fx, fy, fz, kxx, kxy, kyy, kxz, kyz, kzz), k = df/d(x, y, z) symmetric. Units: the
    coefficients' (c [force/length], z0 and x, y, z in one length unit)."""
    h = 0.5 / approach
    e = 0.125 / (approach * approach)
    a = e / (4.0 * tan2)
    r2 = x * x + y * y
    radial_factor = 1.0 + h * z - a * r2 - e * z * z
    fx = radial * x * radial_factor
    fy = radial * y * radial_factor
    fz = (axial * (approach / 1.5 + z + 0.5 * h * z * z - e * z * z * z / 3.0)
          + radial * r2 * (0.5 * h - e * z))
    kxx = radial * (radial_factor - 2.0 * a * x * x)
    kyy = radial * (radial_factor - 2.0 * a * y * y)
    kxy = -2.0 * radial * a * x * y
    kxz = radial * x * (h - 2.0 * e * z)
    kyz = radial * y * (h - 2.0 * e * z)
    kzz = axial * (1.0 + h * z - e * z * z) - radial * r2 * e
    return fx, fy, fz, kxx, kxy, kyy, kxz, kyz, kzz

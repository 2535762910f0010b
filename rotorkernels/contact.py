"""The one ball-bearing force law of rotorsweep, in scaled units.

Ball j sits at angle phi_j = theta + 2 pi j / N. Its elastic deformation along the contact line is

    delta_j = (x cos phi_j + y sin phi_j) cos(alpha) + z sin(alpha) + e,    e = (s0 sin(alpha) - c) / L

with x, y, z the journal displacements in units of the length scale L, s0 the axial approach
from preload (0 without preload) and c the radial clearance. Only balls with delta_j > 0 carry
load, Q_j = delta_j^{3/2} (the caller multiplies by K L^{3/2}); a ball out of contact carries
nothing. With s0 = 0 this is the clearance law of Bai 2006; with c = 0, s0 = z0 it is the
preloaded law of the Filipkovsky papers.

`ring_force` (forces only, for the right-hand side) and `ring_load` (forces and stiffness, for
the Jacobian) share the per-ball geometry below. All are inlined into their callers at the Numba
IR level (`inline="always"`): the integrators evaluate the force law millions of times, and a
separate compiled function costs more in call overhead than the ball sum itself.
"""
import numpy as np
from numba import njit


@njit(cache=True, nogil=True, inline="always")
def _deformation(x, y, z, e, cos_a, sin_a, c, s):
    """delta of the ball at angle (c, s) = (cos phi, sin phi)."""
    return (x * c + y * s) * cos_a + z * sin_a + e


@njit(cache=True, nogil=True, inline="always")
def _next_ball(c, s, cos_d, sin_d):
    """(cos, sin) of the next ball's angle: rotation by the ball spacing."""
    return c * cos_d - s * sin_d, s * cos_d + c * sin_d


@njit(cache=True, nogil=True, inline="always")
def ring_force(x, y, z, e, cos_a, sin_a, n_balls, cos_t, sin_t, cos_d, sin_d):
    """Summed ball loads (fx, fy, fz) of one bearing: the first three entries of `ring_load`,
    without the stiffness work."""
    fx = fy = fz = 0.0
    c = cos_t
    s = sin_t
    for _ in range(n_balls):
        delta = _deformation(x, y, z, e, cos_a, sin_a, c, s)
        if delta > 0.0:
            q = delta * np.sqrt(delta)
            fx += q * (c * cos_a)
            fy += q * (s * cos_a)
            fz += q * sin_a
        c, s = _next_ball(c, s, cos_d, sin_d)
    return fx, fy, fz


@njit(cache=True, nogil=True, inline="always")
def ring_load(x, y, z, e, cos_a, sin_a, n_balls, cos_t, sin_t, cos_d, sin_d):
    """Summed ball loads of one bearing and their derivatives, as a tuple (no allocation):

    (fx, fy, fz, kxx, kxy, kyy, kxz, kyz, kzz) with f = sum_j delta_j^{3/2} (cos phi_j cos a,
    sin phi_j cos a, sin a) over loaded balls and k = df/d(x, y, z) (symmetric).
    (cos_t, sin_t) is the first ball's angle and (cos_d, sin_d) the ball spacing 2 pi / N: the
    other balls follow by rotation, two trig calls per evaluation instead of 2 N."""
    fx = fy = fz = 0.0
    kxx = kxy = kyy = kxz = kyz = kzz = 0.0
    c = cos_t
    s = sin_t
    for _ in range(n_balls):
        delta = _deformation(x, y, z, e, cos_a, sin_a, c, s)
        if delta > 0.0:
            root = np.sqrt(delta)
            q = delta * root
            dq = 1.5 * root
            ux = c * cos_a
            uy = s * cos_a
            fx += q * ux
            fy += q * uy
            fz += q * sin_a
            kxx += dq * ux * ux
            kxy += dq * ux * uy
            kyy += dq * uy * uy
            kxz += dq * ux * sin_a
            kyz += dq * uy * sin_a
            kzz += dq * sin_a * sin_a
        c, s = _next_ball(c, s, cos_d, sin_d)
    return fx, fy, fz, kxx, kxy, kyy, kxz, kyz, kzz

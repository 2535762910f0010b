"""The cubic power-series law of a preloaded angular-contact bearing (Filipkovsky 2010: symmetric
paper eq. 14, axial paper eq. 2), the small-amplitude alternative to the exact ball sum of
`contact.ring_load`.

With c_r = (3/4) N K z0^{1/2} sin^{1/2}(a) cos^2(a) and c_a = 2 c_r tan^2(a), r^2 = x^2 + y^2:

    P_x = c_r x [1 + z / (2 z0) - r^2 / (32 z0^2 tan^2 a) - z^2 / (8 z0^2)]       (P_y likewise)
    P_z = c_a [2 z0 / 3 + z + z^2 / (4 z0) - z^3 / (24 z0^2)] + c_r r^2 [1 / (4 z0) - z / (8 z0^2)]

the gradient of the potential `potential_monomials`. This is exactly the Taylor expansion to
third order of the ball sum K sum_k delta_k^{3/2} (cos a cos b_k, cos a sin b_k, sin a),
delta_k = (x cos b_k + y sin b_k) cos a + (z0 + z) sin a, for N >= 5 balls: its terms are
trigonometric polynomials in b_k of degree <= 4, whose sums over N >= 5 equally spaced balls equal
N times their average over a continuous ring, so the series is isotropic (the paper's "N ->
continuous" reading and the discrete sum agree to this order).

Two misprints of the symmetric paper's eq. 14 are corrected as its axial companion (eq. 2) and
the potential require: P_z's term is -c_r z x^2 / (8 z0^2), not -c_r x z^2 / (8 z0^2).

z0 is the axial approach under the preload (`bearing.PreloadState.axial_approach`: the elastic
part, delta_k = z0 sin a at rest) and K the constant of the chosen normalization: "hertz"
(`bearing` constant "consistent": the static axial force 2 c_a z0 / 3 = N K (z0 sin a)^{3/2} sin a
equals the preload P0) or "paper" (the papers' K = 3 P0 / (2 N) z0^{-3/2} sin^{-5/2} a, static
force 1.5 P0, SPEC 1 note).
"""
import itertools
import math
from typing import NamedTuple

import numpy as np


class CubicCoefficients(NamedTuple):
    radial: float       # c_r [N/m]
    axial: float        # c_a [N/m]
    approach: float     # z0 [m] (or the length unit the displacements are given in)
    tan2: float         # tan^2(alpha)

    @property
    def static_force(self):
        """The axial force of the bearing at rest, 2 c_a z0 / 3 [N]."""
        return 2.0 * self.axial * self.approach / 3.0


def cubic_coefficients(contact_constant, axial_approach, contact_angle, n_balls):
    """c_r, c_a, z0, tan^2 a of the series from K [N/m^1.5], z0 [m], alpha [rad] and N."""
    s, c = math.sin(contact_angle), math.cos(contact_angle)
    radial = 0.75 * n_balls * contact_constant * math.sqrt(axial_approach * s) * c * c
    return CubicCoefficients(radial, 2.0 * radial * (s / c) ** 2, axial_approach, (s / c) ** 2)


def potential_monomials(k):
    """The bearing's potential V(x, y, z) (P = dV/d(x, y, z)) as {(i, j, l): coefficient of
    x^i y^j z^l}, degrees 1 to 4."""
    cr, ca, z0 = k.radial, k.axial, k.approach
    a = cr / (128.0 * z0 * z0 * k.tan2)    # (r^2)^2 coefficient, r^2 = x^2 + y^2
    e = cr / (16.0 * z0 * z0)              # r^2 z^2 coefficient
    return {
        (0, 0, 1): k.static_force,
        (2, 0, 0): cr / 2, (0, 2, 0): cr / 2, (0, 0, 2): ca / 2,
        (2, 0, 1): cr / (4 * z0), (0, 2, 1): cr / (4 * z0), (0, 0, 3): ca / (12 * z0),
        (4, 0, 0): -a, (2, 2, 0): -2 * a, (0, 4, 0): -a,
        (2, 0, 2): -e, (0, 2, 2): -e, (0, 0, 4): -ca / (96 * z0 * z0),
    }


def derivative_tensor(monomials, degree, n=3):
    """The symmetric tensor T[i1..im] = d^m V_m / dq_i1..dq_im of the degree-m part of a
    polynomial given as {exponents: coefficient} (exact: c prod(e_i!) at every index ordering)."""
    t = np.zeros((n,) * degree)
    for exps, coef in monomials.items():
        if sum(exps) != degree:
            continue
        indices = [i for i, e in enumerate(exps) for _ in range(e)]
        value = coef * math.prod(math.factorial(e) for e in exps)
        for order in set(itertools.permutations(indices)):
            t[order] = value
    return t

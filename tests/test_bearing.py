"""Tests of rotorsweep.kernels.bearing: Hertz constants, contact angles, preload state, presets."""
import dataclasses
import math

import numpy as np
import pytest

from rotorsweep.kernels.bearing import (
    BAI2006_CONTACT_CONSTANT,
    _elliptic_integrals,
    PRESETS,
    as_printed_state,
    BearingGeometry,
    ball_contacts,
    contact_constant,
    free_contact_angle,
    groove_free_angle,
    hertz_constant,
    preload_state,
    preload_with_approach,
    preset,
    raceway_curvatures,
    table_geometry,
)

ANGLES = (12, 15, 26, 36, 40)
STEEL_E, STEEL_NU = 2.08e11, 0.3


def e_star(e=STEEL_E, nu=STEEL_NU):
    """Hertz's contact modulus for two bodies of one material: 1/E* = 2 (1 - nu^2) / E."""
    return e / (2.0 * (1.0 - nu ** 2))


# ---------------------------------------------------------------- 1. circular-contact limit

@pytest.mark.parametrize("r1, r2", [(6.35e-3, math.inf), (6.35e-3, 10e-3), (5e-3, -20e-3)])
def test_circular_contact_matches_hertz_sphere(r1, r2):
    """Sphere on a flat / sphere / spherical cup: kappa = 1 and K = (4/3) E* sqrt(R_eff)."""
    c2 = 0.0 if math.isinf(r2) else 1.0 / r2
    cc = contact_constant((1 / r1, 1 / r1), (c2, c2), STEEL_E, STEEL_NU)
    r_eff = 1.0 / (1.0 / r1 + c2)
    assert cc.ellipticity == 1.0
    assert cc.ellip_k == pytest.approx(math.pi / 2, rel=1e-12)
    assert cc.ellip_e == pytest.approx(math.pi / 2, rel=1e-12)
    assert cc.stiffness == pytest.approx(4.0 / 3.0 * e_star() * math.sqrt(r_eff), rel=1e-8)


def test_nearly_circular_contact_is_continuous():
    """The elliptic branch (kappa solved by Brent's method) must join the circular closed form."""
    r = 6.35e-3
    circ = contact_constant((1 / r, 1 / r), (0.0, 0.0), STEEL_E, STEEL_NU)
    near = contact_constant((1 / r, 1 / r), (1e-4 / r, 0.0), STEEL_E, STEEL_NU)
    assert 1.0 < near.ellipticity < 1.001
    assert near.stiffness == pytest.approx(circ.stiffness, rel=1e-4)


LOG_KAPPAS = np.concatenate([[0.0], np.logspace(-10.0, 1.2, 200)])     # kappa = 1 to 1.6e5
EPS = np.finfo(float).eps


def test_elliptic_integrals_match_scipy():
    """The AGM's K and E against scipy.special (ellipkm1 at p = 1/kappa^2, ellipe): K to a few
    ulp (one rounding per AGM step, 5-6 steps); E = K (1 - sum) loses the relative precision of
    the sum (~6 ulp) times K / E, the cancellation in 1 - sum as m -> 1."""
    from scipy.special import ellipe, ellipkm1

    for log_kappa in LOG_KAPPAS:
        k, e = _elliptic_integrals(log_kappa)
        k_ref = float(ellipkm1(math.exp(-2.0 * log_kappa)))
        e_ref = float(ellipe(-math.expm1(-2.0 * log_kappa)))
        assert abs(k / k_ref - 1.0) <= 8 * EPS, log_kappa
        assert abs(e / e_ref - 1.0) <= (4.0 + 8.0 * k_ref / e_ref) * EPS, log_kappa


def test_elliptic_integrals_satisfy_legendres_relation():
    """E K' + E' K - K K' = pi / 2, K' and E' at the complementary parameter 1 - m: with
    m = 1 - 1/kappa^2, 1 - m = 1/kappa'^2 for ln kappa' = -ln(m) / 2. No reference library;
    each product is below ~30, rounded to a few ulp."""
    for log_kappa in LOG_KAPPAS[LOG_KAPPAS > 1e-6]:
        m = -math.expm1(-2.0 * log_kappa)
        k, e = _elliptic_integrals(log_kappa)
        kc, ec = _elliptic_integrals(-0.5 * math.log(m))
        assert e * kc + ec * k - k * kc == pytest.approx(math.pi / 2, abs=1e-12), log_kappa


# ---------------------------------------------------------------- 2. Hamrock-Brewe approximations

def hamrock_brewe(curv_1, curv_2, e, nu):
    """Hamrock & Brewe (1983) curve fits: kappa ~ 1.0339 (R_y/R_x)^0.636,
    E ~ 1.0003 + 0.5968 R_x/R_y, K ~ 1.5277 + 0.6023 ln(R_y/R_x), and the exact Hertz
    delta = K [9/(2 E R) (Q/(pi kappa E'))^2]^{1/3} solved for Q = k delta^{3/2}."""
    rx = 1.0 / (curv_1[0] + curv_2[0])
    ry = 1.0 / (curv_1[1] + curv_2[1])
    r = 1.0 / (1.0 / rx + 1.0 / ry)
    ratio = ry / rx
    kappa = 1.0339 * ratio ** 0.636
    ell_e = 1.0003 + 0.5968 / ratio
    ell_k = 1.5277 + 0.6023 * math.log(ratio)
    e_prime = e / (1.0 - nu ** 2)
    # delta^{3/2} = K^{3/2} (9/(2ER))^{1/2} Q / (pi kappa E')
    k = math.pi * kappa * e_prime / (ell_k ** 1.5 * math.sqrt(9.0 / (2.0 * ell_e * r)))
    return k, kappa, ell_k, ell_e


@pytest.mark.parametrize("which", [0, 1])
def test_209_contacts_agree_with_hamrock_brewe(which):
    """Independent curve fits (a few % accuracy) vs the elliptic-integral solution, 209 bearing."""
    geom = preset("209")
    ball, inner, outer = raceway_curvatures(geom)
    race = (inner, outer)[which]
    exact = contact_constant(ball, race, geom.youngs_modulus, geom.poisson_ratio)
    k, kappa, ell_k, ell_e = hamrock_brewe(ball, race, geom.youngs_modulus, geom.poisson_ratio)
    assert exact.ellipticity == pytest.approx(kappa, rel=0.03)
    assert exact.ellip_k == pytest.approx(ell_k, rel=0.02)
    assert exact.ellip_e == pytest.approx(ell_e, rel=0.02)
    assert exact.stiffness == pytest.approx(k, rel=0.03)


def test_209_curvatures():
    """Harris's curvature sums for a ball on the 209 races, gamma = D cos(a) / d_m."""
    geom = preset("209")
    d, gamma = 12.7e-3, 12.7 / 65.0
    inner, outer = ball_contacts(geom)
    assert inner.curvature_sum == pytest.approx((4 - d / 6.6e-3 + 2 * gamma / (1 - gamma)) / d, rel=1e-12)
    assert outer.curvature_sum == pytest.approx((4 - d / 6.6e-3 - 2 * gamma / (1 + gamma)) / d, rel=1e-12)


# ---------------------------------------------------------------- 3. named bearing

def test_209_hertz_constant_matches_spec_value():
    """209 deep-groove bearing (D_b = 12.7 mm, D_m = 65 mm, r_i = r_o = 6.6 mm, E = 2.08e11 Pa,
    nu = 0.3). Reference: /work/shared/SPEC.md section 2.1, "The Hertz value computed from the 209
    geometry (E = 2.08e11 Pa, Poisson 0.3) is about 1.18e10 N/m^1.5". Harris's worked 209 example is
    not used: its book value could not be verified here, so none is cited."""
    geom = preset("209")
    k = hertz_constant(geom)
    assert k == pytest.approx(1.18e10, rel=0.02)
    inner, outer = ball_contacts(geom)
    assert k < min(inner.stiffness, outer.stiffness)  # series is softer than either contact
    assert k == pytest.approx((inner.stiffness ** (-2 / 3) + outer.stiffness ** (-2 / 3)) ** -1.5, rel=1e-12)
    # The paper's constant is ~4x softer than Hertz; keep the two apart.
    assert BAI2006_CONTACT_CONSTANT == 2.883e9
    assert k / BAI2006_CONTACT_CONSTANT > 3.5


def test_hertz_constant_uses_contact_angle():
    """Larger angle -> smaller gamma -> inner race flatter, outer less concave; K changes a little."""
    geom = preset("angular_contact_medium", 26)
    assert hertz_constant(geom) == hertz_constant(geom, math.radians(26))
    assert hertz_constant(geom, 0.0) != pytest.approx(hertz_constant(geom, math.radians(40)), rel=1e-4)


# ---------------------------------------------------------------- 4. free contact angle

@pytest.mark.parametrize("c_um", [3.8, 7.6, 11.4, 15.2, 19.0])
def test_free_contact_angle_bai_eq6(c_um):
    geom = preset("209")
    a = 6.6 + 6.6 - 12.7  # mm, r_i + r_o - D_b
    expected = math.acos(1.0 - c_um * 1e-3 / a)
    assert free_contact_angle(geom, c_um * 1e-6) == pytest.approx(expected, rel=1e-12)


def test_free_contact_angle_limits():
    geom = preset("209")
    assert free_contact_angle(geom, 0.0) == 0.0
    assert free_contact_angle(geom, 0.5e-3) == pytest.approx(math.pi / 2, rel=1e-12)
    with pytest.raises(ValueError, match=r"-1e-06.*allowed range"):
        free_contact_angle(geom, -1e-6)
    with pytest.raises(ValueError, match="allowed range"):
        free_contact_angle(geom, 0.6e-3)  # angle past 90 deg
    with pytest.raises(ValueError, match="allowed range"):
        free_contact_angle(geom, 1.2e-3)  # cosine below -1


# ---------------------------------------------------------------- 5. preload state

def summed_force(k, alpha, s0, c, n, x=0.0):
    """Ball-load sum of one bearing, sum_j K [delta_j]_+^{3/2} (cos phi cos a, sin a), phi_j = 2 pi j/N."""
    phi = 2 * np.pi * np.arange(n) / n
    delta = x * np.cos(phi) * np.cos(alpha) + s0 * np.sin(alpha) - c
    q = k * np.where(delta > 0, delta, 0.0) ** 1.5
    return np.sum(q * np.cos(phi)) * np.cos(alpha), np.sum(q) * np.sin(alpha)


BEARINGS = [("209", None), ("angular_contact_medium", 12), ("angular_contact_medium", 26),
            ("angular_contact_medium", 40)]


@pytest.mark.parametrize("name, angle", BEARINGS)
@pytest.mark.parametrize("p0", [10.0, 100.0, 300.0, 2000.0])
def test_preload_static_equilibrium(name, angle, p0):
    geom = preset(name, angle)
    st = preload_state(geom, p0)
    n = geom.n_balls
    assert n * st.ball_load * math.sin(st.contact_angle) == pytest.approx(p0, rel=1e-10)
    # the force law at x = y = 0 reproduces the preload
    _, fz = summed_force(st.contact_constant, st.contact_angle, st.axial_approach, 0.0, n)
    assert fz == pytest.approx(p0, rel=1e-10)
    # loaded geometry: delta_n = A (cos a0 / cos a - 1) and K is the Hertz value at the loaded angle
    a = geom.groove_center_distance
    expected = a * (math.cos(geom.nominal_contact_angle) / math.cos(st.contact_angle) - 1)
    assert st.normal_approach == pytest.approx(expected, rel=1e-10)
    assert st.contact_constant == pytest.approx(hertz_constant(geom, st.contact_angle), rel=1e-12)


@pytest.mark.parametrize("name, angle", BEARINGS)
def test_preload_angle_grows_with_load(name, angle):
    geom = preset(name, angle)
    alphas = [preload_state(geom, p).contact_angle for p in (1e-6, 1.0, 10.0, 100.0, 1000.0, 2000.0)]
    assert np.all(np.diff(alphas) > 0)
    assert alphas[0] > geom.nominal_contact_angle
    assert alphas[0] == pytest.approx(geom.nominal_contact_angle, abs=2e-3)


def test_preload_zero_load():
    geom = preset("angular_contact_medium", 26)
    st = preload_state(geom, 0.0)
    assert st.contact_angle == geom.nominal_contact_angle
    assert (st.normal_approach, st.ball_load, st.radial_stiffness, st.axial_stiffness) == (0, 0, 0, 0)
    assert st.axial_approach == 0.0
    g209 = preset("209")
    st = preload_state(g209, 0.0, clearance=7.6e-6)
    assert st.contact_angle == free_contact_angle(g209, 7.6e-6)
    assert st.axial_approach * math.sin(st.contact_angle) == pytest.approx(7.6e-6, rel=1e-12)
    assert preload_state(g209, 0.0).axial_approach == 0.0


@pytest.mark.parametrize("name, angle, clearance", [("209", None, 0.0), ("209", None, 11.4e-6),
                                                    ("angular_contact_medium", 15, 0.0),
                                                    ("angular_contact_medium", 40, 0.0)])
def test_linear_stiffness_matches_finite_difference(name, angle, clearance):
    geom = preset(name, angle)
    st = preload_state(geom, 300.0, clearance=clearance)
    assert st.axial_approach * math.sin(st.contact_angle) - clearance == pytest.approx(
        st.normal_approach, rel=1e-9)
    args = (st.contact_constant, st.contact_angle, st.axial_approach, clearance, geom.n_balls)
    h = 1e-3 * st.normal_approach
    kr = (summed_force(*args, x=h)[0] - summed_force(*args, x=-h)[0]) / (2 * h)
    assert st.radial_stiffness == pytest.approx(kr, rel=1e-5)
    # axial: shift s0 with alpha frozen, as in the force law
    k, a, s0, c, n = args
    ka = (summed_force(k, a, s0 + h, c, n)[1] - summed_force(k, a, s0 - h, c, n)[1]) / (2 * h)
    assert st.axial_stiffness == pytest.approx(ka, rel=1e-5)


def test_preload_with_given_constant_and_free_angle():
    """Bai's constant and an explicit free angle are honoured; equilibrium still holds."""
    geom = preset("209")
    alpha0 = free_contact_angle(geom, 3.8e-6)
    st = preload_state(geom, 50.0, clearance=3.8e-6, stiffness=BAI2006_CONTACT_CONSTANT)
    assert st.contact_constant == BAI2006_CONTACT_CONSTANT
    assert st.contact_angle > alpha0
    _, fz = summed_force(st.contact_constant, st.contact_angle, st.axial_approach, 3.8e-6, 9)
    assert fz == pytest.approx(50.0, rel=1e-10)
    ac = preset("angular_contact_medium", 15)
    free = groove_free_angle(ac)
    st = preload_state(ac, 300.0, free_angle=free)
    assert st.normal_approach == pytest.approx(
        ac.groove_center_distance * (math.cos(free) / math.cos(st.contact_angle) - 1), rel=1e-10)


# The 2016 table as printed, typed here from the paper (not read from the code under test):
# R1 = 16.0, R_K = 5.930, d = 11.510 mm; R2 per nominal angle; N = 7.
R1_MM, RK_MM, D_MM = 16.0, 5.930, 11.510
R2_MM = {12: 27.5125, 15: 27.5167, 26: 27.5399, 36: 27.5709, 40: 27.5858}


@pytest.mark.parametrize("angle", ANGLES)
def test_table_free_angle_is_the_closed_form_of_eq_10_at_zero_load(angle):
    """(2 R_K - d) cos(a0) = R1 + 2 R_K - R2 (2010 papers, eq. 10 with w = 0); the nominal angle
    is only a label (the 15 deg row's free angle is 11.23 deg). Both sides are a few flops on
    numbers of 1e-2: 1e-12 relative."""
    geom = table_geometry("filipkovsky2016", angle)
    closed = math.acos((R1_MM + 2 * RK_MM - R2_MM[angle]) / (2 * RK_MM - D_MM))
    assert geom.nominal_contact_angle == pytest.approx(closed, rel=1e-12)
    assert geom.inner_race_radius == 16.0e-3 and geom.outer_race_radius == pytest.approx(R2_MM[angle] * 1e-3, rel=1e-15)
    g2010 = table_geometry("filipkovsky2010")
    assert g2010.youngs_modulus == 2e11 and g2010.outer_race_radius == 27.53e-3
    assert math.degrees(g2010.nominal_contact_angle) == pytest.approx(
        math.degrees(math.acos((16.00 + 2 * 5.93 - 27.53) / (2 * 5.93 - 11.51))), rel=1e-12)


def test_table_overrides_replace_the_printed_values():
    geom = table_geometry("filipkovsky2016", 15, youngs_modulus=2e11, outer_race_radius=27.53e-3)
    assert (geom.youngs_modulus, geom.outer_race_radius, geom.ball_diameter) == (2e11, 27.53e-3, 11.510e-3)
    with pytest.raises(ValueError, match="nominal_angle"):
        table_geometry("filipkovsky2016", 20)
    with pytest.raises(ValueError, match="outside"):
        table_geometry("filipkovsky2016", 15, outer_race_radius=28.5e-3)


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("p0", [100.0, 400.0])
def test_loaded_angle_is_an_independent_scalar_root_of_eq_10(angle, p0):
    """Eq. 10, (A + w(a)) cos(a) = R1 + 2 R_K - R2, with eqs. 8-9's w = (P_k / K_h(a))^{2/3},
    P_k = P0 / (N sin a), solved for a by scipy's brentq on [a0, 80 deg] (the code solves for
    the stretch in log space). Both to ~1e-15 in their variables: 1e-10 relative."""
    from scipy.optimize import brentq

    geom = table_geometry("filipkovsky2016", angle)
    big_a, rhs = (2 * RK_MM - D_MM) * 1e-3, (R1_MM + 2 * RK_MM - R2_MM[angle]) * 1e-3

    def residual(a):
        w = (p0 / (7 * math.sin(a) * hertz_constant(geom, a))) ** (2 / 3)
        return (big_a + w) * math.cos(a) - rhs

    alpha = brentq(residual, geom.nominal_contact_angle, math.radians(80), xtol=1e-15, rtol=1e-15)
    st = as_printed_state(geom, p0, geom.nominal_contact_angle)
    assert st.contact_angle == pytest.approx(alpha, rel=1e-10)
    assert preload_state(geom, p0, free_angle=geom.nominal_contact_angle).contact_angle == st.contact_angle


@pytest.mark.parametrize("angle", [12, 40])
def test_hertz_coefficient_of_eq_11_is_the_contact_constant(angle):
    """2010 papers' eq. 11, b = (3/2) F1 cbrt(sum K k^2 (Theta1 + Theta2)^2 / (3 E1)), with
    Theta = (1 - sigma^2) / (pi E), k = 1 / kappa and F1, E1 the complete elliptic integrals of
    modulus k1^2 = 1 - k^2 (scipy), gives w = b P^{2/3}: b = k_contact^{-2/3} for each contact of
    the loaded ball (the ellipticity from the code's solve of eq. 12). Rounding: 1e-12."""
    from scipy.special import ellipe, ellipk

    geom = table_geometry("filipkovsky2016", angle)
    theta = (1 - geom.poisson_ratio ** 2) / (math.pi * geom.youngs_modulus)
    for cc in ball_contacts(geom, math.radians(angle + 2.0)):
        k = 1.0 / cc.ellipticity
        f1, e1 = ellipk(1 - k * k), ellipe(1 - k * k)
        b = 1.5 * f1 * (cc.curvature_sum * k * k * (2 * theta) ** 2 / (3 * e1)) ** (1 / 3)
        assert b == pytest.approx(cc.stiffness ** (-2 / 3), rel=1e-12)


def printed_ball_sum(k, alpha, z0, x, y, z, n=7):
    """Eq. 5 (2016: eq. 1) as printed, numpy: P = K sum [x cos a cos b + y cos a sin b +
    (z + z0) sin a]_+^{3/2} (cos a cos b, cos a sin b, sin a), b = 2 pi v / N; and its analytic
    stiffness dP/d(x, y, z) = K sum 1.5 [.]_+^{1/2} u u^T."""
    beta = 2 * np.pi * np.arange(n) / n
    u = np.stack([np.cos(alpha) * np.cos(beta), np.cos(alpha) * np.sin(beta), np.full(n, np.sin(alpha))])
    delta = np.maximum(x * u[0] + y * u[1] + (z + z0) * np.sin(alpha), 0.0)
    return k * u @ delta ** 1.5, k * 1.5 * (u * np.sqrt(delta)) @ u.T


@pytest.mark.parametrize("angle", ANGLES)
def test_as_printed_state_follows_eqs_6_to_10(angle):
    """z0 from eq. 7, K from eq. 6 (both computed here from the loaded angle and w), eq. 10 holds,
    and its static thrust at rest is 1.5 P0 (closed form: N K (z0 sin a)^{3/2} sin a with eq. 6's
    K is (3/2) P0 for every z0 and a). Rounding only: 1e-12."""
    geom = table_geometry("filipkovsky2016", angle)
    p0, n = 300.0, 7
    st = as_printed_state(geom, p0, geom.nominal_contact_angle)
    a, big_a = st.contact_angle, (2 * RK_MM - D_MM) * 1e-3
    w = (p0 / (n * math.sin(a) * hertz_constant(geom, a))) ** (2 / 3)       # eqs. 8, 9
    assert st.hertz_approach == pytest.approx(w, rel=1e-12)
    assert (big_a + w) * math.cos(a) == pytest.approx((R1_MM + 2 * RK_MM - R2_MM[angle]) * 1e-3, rel=1e-12)
    z0 = (big_a + w) * math.sin(a)                                            # eq. 7
    k = 3 * p0 / (2 * n) * z0 ** -1.5 * math.sin(a) ** -2.5                   # eq. 6
    assert st.axial_approach == pytest.approx(z0, rel=1e-12)
    assert st.contact_constant == pytest.approx(k, rel=1e-12)
    force, _ = printed_ball_sum(k, a, z0, 0.0, 0.0, 0.0)
    assert force[2] == pytest.approx(1.5 * p0, rel=1e-12) and st.static_thrust == pytest.approx(1.5 * p0, rel=1e-12)
    assert np.abs(force[:2]).max() < 1e-12 * p0
    # the linear stiffnesses are those of the printed sum at rest
    _, stiff = printed_ball_sum(k, a, z0, 0.0, 0.0, 0.0)
    assert st.radial_stiffness == pytest.approx(stiff[0, 0], rel=1e-12)
    assert st.axial_stiffness == pytest.approx(stiff[2, 2], rel=1e-12)


def test_as_printed_at_400_n_and_15_deg_is_the_issue_s_numbers():
    """The issue's estimate: eq. 7 gives z0 of about 97 um, K about 2.4e9 N/m^1.5 (against 24 um
    and 1.9e10 of the old Hertz-approach reading)."""
    st = as_printed_state(table_geometry("filipkovsky2016", 15), 400.0, table_geometry("filipkovsky2016", 15)
                          .nominal_contact_angle)
    assert st.axial_approach == pytest.approx(97e-6, rel=0.01)
    assert st.contact_constant == pytest.approx(2.4e9, rel=0.02)


def test_as_printed_values_given_replace_the_derived_ones():
    geom = table_geometry("filipkovsky2016", 15)
    a0 = geom.nominal_contact_angle
    st = as_printed_state(geom, 300.0, a0, contact_angle=math.radians(15.0))
    assert st.contact_angle == math.radians(15.0)
    w = (300.0 / (7 * math.sin(st.contact_angle) * hertz_constant(geom, st.contact_angle))) ** (2 / 3)
    assert st.axial_approach == pytest.approx(((2 * RK_MM - D_MM) * 1e-3 + w) * math.sin(math.radians(15)), rel=1e-12)
    st = as_printed_state(geom, 300.0, a0, stiffness=3e9, axial_approach=80e-6)
    assert (st.contact_constant, st.axial_approach) == (3e9, 80e-6)
    assert st.normal_approach == pytest.approx(80e-6 * math.sin(st.contact_angle), rel=1e-15)


def test_consistent_model_with_z0_given_carries_the_preload():
    geom = table_geometry("filipkovsky2016", 15)
    st = preload_with_approach(geom, 300.0, math.radians(17.0), 20e-6)
    force, _ = printed_ball_sum(st.contact_constant, st.contact_angle, 20e-6, 0.0, 0.0, 0.0)
    assert force[2] == pytest.approx(300.0, rel=1e-12) and st.static_thrust == pytest.approx(300.0, rel=1e-12)


def test_preload_state_rejects_bad_input():
    geom = preset("angular_contact_medium")
    with pytest.raises(ValueError, match="preload"):
        preload_state(geom, -1.0)
    with pytest.raises(ValueError, match="clearance"):
        preload_state(geom, 100.0, clearance=-1e-6)
    with pytest.raises(ValueError, match="free contact angle"):
        preload_state(geom, 100.0, free_angle=math.pi / 2)
    with pytest.raises(ValueError, match="preload must be a finite force > 0"):
        as_printed_state(geom, 0.0, 0.2)


# ---------------------------------------------------------------- 6. presets

def test_presets_listed():
    assert {"209", "angular_contact_medium"} <= set(PRESETS)
    g = preset("209")
    assert (g.ball_diameter, g.pitch_diameter, g.n_balls, g.youngs_modulus) == (12.7e-3, 65.0e-3, 9, 2.08e11)
    assert g.nominal_contact_angle == 0.0
    ac = preset("angular_contact_medium")
    assert ac.nominal_contact_angle == pytest.approx(math.radians(26))
    assert ac.outer_race_radius == pytest.approx(27.5399e-3)
    assert ac.pitch_diameter == pytest.approx(16.0e-3 + 27.5399e-3)


def test_preset_rejects_unknown_name():
    with pytest.raises(ValueError, match=r"'6205'.*209.*angular_contact_medium"):
        preset("6205")


@pytest.mark.parametrize("bad", [20, 26.5, -12, "26"])
def test_preset_rejects_bad_nominal_angle(bad):
    with pytest.raises(ValueError, match=r"\[12, 15, 26, 36, 40\]"):
        preset("angular_contact_medium", bad)
    with pytest.raises(ValueError, match="209"):
        preset("209", 15)


@pytest.mark.parametrize("angle", ANGLES)
def test_angular_contact_radii_encode_the_angle(angle):
    """Finding (see the comment at _ANGULAR_R2_MM): with the printed R_K and ball, eq. 10 at zero
    load does not give the nominal angle, but all five R2 follow R2 = 27.85048 - 0.34555 cos(a) mm
    to their 0.1 um rounding."""
    geom = preset("angular_contact_medium", angle)
    r2_mm = geom.outer_race_radius * 1e3
    assert r2_mm == pytest.approx(27.85048 - 0.34555 * math.cos(math.radians(angle)), abs=5e-5)
    cos_a0 = (16.0 + 2 * 5.93 - r2_mm) / (2 * 5.93 - 11.51)
    assert groove_free_angle(geom) == pytest.approx(math.acos(cos_a0), rel=1e-9)
    assert math.degrees(groove_free_angle(geom)) < angle - 1.5


@pytest.mark.parametrize("angle", ANGLES)
def test_an_angular_preset_takes_its_free_angle_from_the_groove_geometry_when_asked(angle):
    """free_angle="geometry": eq. 10 at zero load on the radii typed here from the 2016 table
    (cos a0 = (R1 + 2 R_K - R2) / (2 R_K - d); rounding of the sums: 1e-9), as table_geometry and
    rigid_preloaded's default have it; the default keeps the label; the preload starts from it."""
    geom = preset("angular_contact_medium", angle, free_angle="geometry")
    closed_form = math.acos((R1_MM + 2 * RK_MM - R2_MM[angle]) / (2 * RK_MM - D_MM))
    assert geom.nominal_contact_angle == pytest.approx(closed_form, rel=1e-9)
    assert geom == dataclasses.replace(table_geometry("filipkovsky2016", angle), name=geom.name)
    assert preset("angular_contact_medium", angle).nominal_contact_angle == math.radians(angle)
    assert preload_state(geom, 0.0).contact_angle == geom.nominal_contact_angle
    with pytest.raises(ValueError, match="free_angle must be one of"):
        preset("angular_contact_medium", angle, free_angle="label")


def test_geometry_validation():
    with pytest.raises(ValueError, match="n_balls"):
        BearingGeometry("x", 12.7e-3, 65e-3, 6.6e-3, 6.6e-3, 2, 2e11, 0.3)
    with pytest.raises(ValueError, match="ball radius"):
        BearingGeometry("x", 12.7e-3, 65e-3, 6.0e-3, 6.6e-3, 9, 2e11, 0.3)

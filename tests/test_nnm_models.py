"""The cubic series bearing law (rotorsweep.kernels.cubic_law) against the exact Hertz ball sum, and the
Filipkovsky 2010 models symmetric4 / asymmetric5: kernel = polynomial form, f = dV/dq, M and G
from the papers' kinetic energy (sympy), linear frequencies, config errors. All numpy-level or
single kernel calls (no integration): about 10 s once the model kernels are compiled."""
import itertools
import math

import numpy as np
import pytest
import sympy as sp

from rotorsweep.pipeline import config
from rotorsweep.kernels import models
from rotorsweep.kernels.contact import ring_load
from rotorsweep.kernels.cubic_law import cubic_coefficients, derivative_tensor, potential_monomials
from rotorsweep.kernels.cubic_law_kernels import cubic_load
from rotorsweep.kernels.models import rigid_preloaded as rp, series_rotor as sr

MODELS = ("symmetric4", "asymmetric5")


def values(spec, **over):
    v = {p.name: (p.unset if p.axis else p.default) for p in spec.parameters}
    v.update(over)
    return v


def ring_units(nominal_angle=15, stiffness="hertz"):
    """(offset e, alpha, N, series coefficients) in ring_load's units (lengths in um, K = 1)."""
    state = rp.preload_of(nominal_angle, 300.0, stiffness)
    alpha, n = state.contact_angle, rp.geometry(nominal_angle).n_balls
    z0 = state.axial_approach / 1e-6
    return z0 * math.sin(alpha), alpha, n, cubic_coefficients(1.0, z0, alpha, n)


def exact(q, e, alpha, n):
    return np.array(ring_load(q[0], q[1], q[2], e, math.cos(alpha), math.sin(alpha), n, 1.0, 0.0,
                              math.cos(2 * math.pi / n), math.sin(2 * math.pi / n)))


# --- the series is the ball sum's Taylor expansion ---------------------------------------------

@pytest.mark.parametrize("nominal_angle", [12, 26])
def test_series_coefficients_are_the_taylor_coefficients_of_the_ball_sum(nominal_angle):
    """Force and stiffness of ring_load at 0 are the series' T1 and T2 exactly (to rounding); the
    third and fourth derivatives of the potential are central differences of ring_load's analytic
    stiffness with step h = 1e-3 delta0: truncation O((h / delta0)^2) = 1e-6 relative, rounding
    eps / h^2 * delta0^2 ~ 1e-10, so 1e-5 relative to the tensor's largest entry is an honest bound.
    With N = 7 > 4 balls the discrete sum has exactly the continuous ring's (isotropic) series."""
    e, alpha, n, coef = ring_units(nominal_angle)
    mono = potential_monomials(coef)
    h = 1e-3 * e

    def stiffness(q):
        f = exact(q, e, alpha, n)
        return np.array([[f[3], f[4], f[6]], [f[4], f[5], f[7]], [f[6], f[7], f[8]]])

    f0 = exact(np.zeros(3), e, alpha, n)
    np.testing.assert_allclose(f0[:3], derivative_tensor(mono, 1), atol=1e-13 * f0[2])
    np.testing.assert_allclose(stiffness(np.zeros(3)), derivative_tensor(mono, 2), rtol=1e-13, atol=1e-13 * coef.radial)
    eye = np.eye(3) * h
    t3 = np.stack([(stiffness(eye[l]) - stiffness(-eye[l])) / (2 * h) for l in range(3)], axis=-1)
    t4 = np.stack([np.stack([(stiffness(eye[l] + eye[m]) - stiffness(eye[l] - eye[m]) - stiffness(-eye[l] + eye[m])
                              + stiffness(-eye[l] - eye[m])) / (4 * h * h) for m in range(3)], axis=-1)
                   for l in range(3)], axis=-2)
    for numeric, degree in ((t3, 3), (t4, 4)):
        series = derivative_tensor(mono, degree)
        np.testing.assert_allclose(numeric, series, atol=1e-5 * np.abs(series).max())


@pytest.mark.parametrize("preload_law, ratio", [("hertz", 1.0), ("as_printed", 1.5)])
def test_static_force_of_the_series_is_the_preload_or_the_papers_1_5_p0(preload_law, ratio):
    state = rp.preload_of(15, 300.0, preload_law)
    coef = cubic_coefficients(state.contact_constant, state.axial_approach, state.contact_angle, 7)
    assert coef.static_force == pytest.approx(ratio * 300.0, rel=1e-12)
    assert coef.radial == pytest.approx(state.radial_stiffness, rel=1e-12)
    assert 2 * coef.axial == pytest.approx(2 * state.axial_stiffness, rel=1e-12)


def test_njit_loads_are_the_gradient_and_hessian_of_the_potential():
    """cubic_load (kernels) and potential_monomials (polynomial form) are two writings of the
    series: equal to rounding at random points."""
    _, _, _, coef = ring_units()
    mono = potential_monomials(coef)
    t = [derivative_tensor(mono, m) for m in (1, 2, 3, 4)]
    rng = np.random.default_rng(1)
    for q in rng.normal(size=(5, 3)):
        f = t[0] + t[1] @ q + np.einsum("ijk,j,k", t[2], q, q) / 2 + np.einsum("ijkl,j,k,l", t[3], q, q, q) / 6
        k = t[1] + np.einsum("ijk,k", t[2], q) + np.einsum("ijkl,k,l", t[3], q, q) / 2
        got = np.array(cubic_load(*q, *coef))
        np.testing.assert_allclose(got[:3], f, rtol=1e-13, atol=1e-13 * np.abs(f).max())
        np.testing.assert_allclose(got[[3, 4, 5, 6, 7, 8]], k[[0, 0, 1, 0, 1, 2], [0, 1, 1, 2, 2, 2]],
                                   rtol=1e-13, atol=1e-13 * np.abs(k).max())


def series_error(h, e, alpha, n, coef, direction=(1.0, 0.5, 0.7)):
    """max |P_series - P_exact| / P0 at displacement h (um) along a generic direction."""
    q = h * np.asarray(direction) / np.linalg.norm(direction)
    return np.abs(np.array(cubic_load(*q, *coef))[:3] - exact(q, e, alpha, n)[:3]).max() / coef.static_force


def test_series_error_is_fourth_order_in_amplitude_over_z0():
    """The first omitted term is quartic in q / z0 (a generic direction: along x alone the quartic
    term of P_x vanishes by the ring's symmetry): the log-log slope over a decade of amplitude,
    3e-3 to 3e-2 z0, is 4 within 0.05 (the quintic term shifts it by ~(q / z0) ~ 0.03 at the top;
    rounding is 1e-16 against errors above 1e-11)."""
    e, alpha, n, coef = ring_units()
    h = np.array([3e-3, 3e-2]) * coef.approach
    err = [series_error(x, e, alpha, n, coef) for x in h]
    assert np.log(err[1] / err[0]) / np.log(10.0) == pytest.approx(4.0, abs=0.05)


def test_series_parts_from_the_ball_sum_by_one_percent_near_a_fifth_of_z0():
    """The amplitude where the series' force error reaches 1 % of the preload force (README: about
    0.2 z0 at the papers' bearing) -- recorded as a number with its bracket."""
    e, alpha, n, coef = ring_units()
    from scipy.optimize import brentq
    h1 = brentq(lambda h: series_error(h, e, alpha, n, coef) - 0.01, 1e-3 * coef.approach, 0.9 * coef.approach)
    assert 0.1 < h1 / coef.approach < 0.5


# --- the models ---------------------------------------------------------------------------------

@pytest.mark.parametrize("arrangement", ["back_to_back", "face_to_face"])
@pytest.mark.parametrize("name", MODELS)
def test_kernel_rhs_is_the_polynomial_form(name, arrangement):
    """At random scaled states: du/dtau of the kernel = the PolynomialSystem's acceleration in SI
    scaled by T^2 / L (rounding: 1e-12 of the largest term), in both bearing arrangements."""
    spec = models.get(name)
    v = values(spec, arrangement=arrangement)
    built, system = spec.build(v), spec.polynomial(v)
    n, el, t = spec.n_position, spec.length_scale, built.period
    module = __import__(spec.module, fromlist=["rhs"])
    for u in np.random.default_rng(2).normal(scale=3.0, size=(4, 2 * n)):
        du = np.empty(2 * n)
        module.rhs(0.0, u, built.p, du)
        q, qd = u[:n] * el, u[n:] * el / t
        f = system.K @ q + np.einsum("ijk,j,k", system.Q2, q, q) + np.einsum("ijkl,j,k,l", system.Q3, q, q, q)
        acc = -np.linalg.solve(system.M, system.G @ qd + f) * t * t / el
        np.testing.assert_allclose(du[n:], acc, atol=1e-12 * np.abs(acc).max())
        np.testing.assert_array_equal(du[:n], u[n:])


@pytest.mark.parametrize("name", MODELS)
def test_polynomial_forces_are_the_gradient_of_a_potential(name):
    """K, Q2, Q3 fully symmetric (then f = dV/dq with V = qKq/2 + Q2qqq/3 + Q3qqqq/4), checked
    also by a central difference of V (step 1e-4 of |q|: error 1e-8 relative); G skew, M symmetric."""
    spec = models.get(name)
    s = spec.polynomial(values(spec))
    for t in (s.K, s.Q2, s.Q3):
        for perm in itertools.permutations(range(t.ndim)):
            np.testing.assert_allclose(t, t.transpose(perm), atol=1e-14 * np.abs(t).max())
    np.testing.assert_allclose(s.G, -s.G.T, atol=0)
    np.testing.assert_array_equal(s.M, s.M.T)
    from rotorsweep.kernels.continuation.backbone import energy
    q = np.random.default_rng(3).normal(scale=2e-6, size=s.M.shape[0])
    h = 1e-4 * np.abs(q).max()
    zero = np.zeros_like(q)
    grad = [(energy(s, q + h * d, zero) - energy(s, q - h * d, zero)) / (2 * h) for d in np.eye(q.size)]
    f = s.K @ q + np.einsum("ijk,j,k", s.Q2, q, q) + np.einsum("ijkl,j,k,l", s.Q3, q, q, q)
    np.testing.assert_allclose(grad, f, atol=1e-8 * np.abs(f).max())


def _papers_lagrangian(n):
    """M and G (per unit Omega) of the papers' T_B + T_D with x1 at support A (series_rotor)."""
    t, zc = sp.symbols("t zc")
    l, l1, rho, area, inertia, m0, i1, i0, om = sp.symbols("l l1 rho S I m0 I1 I0 Omega", positive=True)
    q = [sp.Function(c)(t) for c in sr.COORDINATES[:n]]
    x1, y1, x2, y2 = q[:4]
    d = sp.diff
    th1, th2 = -(y2 - y1) / l, (x2 - x1) / l
    ux = x1 * (l - zc) / l + x2 * zc / l
    uy = y1 * (l - zc) / l + y2 * zc / l
    kin_b = (rho * inertia / 2 * l * (d(th1, t) ** 2 + d(th2, t) ** 2) - 2 * rho * inertia * om * l * d(th2, t) * th1
             + rho * area / 2 * sp.integrate(d(ux, t) ** 2 + d(uy, t) ** 2, (zc, 0, l)))
    kin_d = (i1 / 2 * (d(th2, t) ** 2 + d(th1, t) ** 2) - i0 * om * d(th2, t) * th1
             + m0 / 2 * (d(ux, t) ** 2 + d(uy, t) ** 2).subs(zc, l1))
    kin = kin_b + kin_d + ((rho * area * l + m0) / 2 * d(q[4], t) ** 2 if n == 5 else 0)
    eqs = [sp.expand(d(sp.diff(kin, d(c, t)), t) - sp.diff(kin, c)) for c in q]
    mass = sp.Matrix([[e.coeff(d(c, t, 2)) for c in q] for e in eqs])
    gyro = sp.Matrix([[e.coeff(d(c, t)) / om for c in q] for e in eqs])
    return (l, l1, rho, area, inertia, m0, i1, i0), mass, gyro


@pytest.mark.parametrize("name", MODELS)
def test_mass_and_gyroscopic_matrices_equal_the_sympy_derivation_from_the_papers_energy(name):
    """Entry by entry to rounding (1e-14 relative: a few float operations on the same inputs)."""
    spec = models.get(name)
    v = values(spec)
    s = spec.polynomial(v)
    n = spec.n_position
    syms, mass, gyro = _papers_lagrangian(n)
    d = v["shaft_diameter"]
    l1 = v["length"] / 2 if name == "symmetric4" else v["disk_position"]
    subs = dict(zip(syms, (v["length"], l1, v["shaft_density"], math.pi * d * d / 4, math.pi * d ** 4 / 64,
                           v["disk_mass"], v["disk_diametral"], v["disk_polar"])))
    m_sym = np.array(mass.subs(subs).evalf(), float)
    g_sym = np.array(gyro.subs(subs).evalf(), float) * 2 * math.pi * v["speed"]
    np.testing.assert_allclose(s.M, m_sym, rtol=1e-14, atol=1e-14 * np.abs(m_sym).max())
    np.testing.assert_allclose(s.G, g_sym, rtol=1e-14, atol=1e-14 * np.abs(g_sym).max())


def test_symmetric4_has_a_double_first_frequency_and_asymmetric5_an_axial_first_mode():
    """The papers: symmetric rotor's first frequency double (two planes); asymmetric rotor's first
    mode mainly axial (axial stiffness below radial). The papers print no frequency values (only
    figures). Double: equal to 1e-12 (the x and y blocks are identical). Axial: z carries more
    than 99 % of the mode's kinetic energy (measured: 100 %, z decouples linearly)."""
    s4 = models.get("symmetric4")
    w = sr.linear_frequencies(s4.polynomial(values(s4)))
    assert w[1] == pytest.approx(w[0], rel=1e-12) and w[2] > 1.5 * w[0]
    s5 = models.get("asymmetric5")
    sys5 = s5.polynomial(values(s5))
    m_inv = np.linalg.inv(sys5.M)
    lam, vec = np.linalg.eig(np.block([[np.zeros((5, 5)), np.eye(5)], [-m_inv @ sys5.K, -m_inv @ sys5.G]]))
    k = np.argmin(np.where(lam.imag > 0, lam.imag, np.inf))
    qd = vec[5:, k]
    kinetic = np.real(np.conj(qd) * (sys5.M @ qd))
    assert kinetic[4] / kinetic.sum() > 0.99
    assert lam[k].imag == pytest.approx(sr.linear_frequencies(sys5)[0])


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("toml, key", [
    ("[bearing]\npreload = 0.0", "bearing.preload"),
    ("[bearing]\npreload = -300.0", "bearing.preload"),
    ("[bearing]\ncontact_angle = 90.0", "bearing.contact_angle"),
    ("[bearing]\ncontact_angle = 0.0", "bearing.contact_angle"),
    ("[bearing]\nnominal_angle = 20.0", "bearing.nominal_angle"),
])
def test_invalid_bearing_input_is_a_config_error_naming_the_key_and_range(name, toml, key):
    text = f'[scene]\nname = "bad"\nmodel = "{name}"\n{toml}\n[sweep]\nspeed = [100.0]\n'
    with pytest.raises(config.ConfigError) as exc:
        config.parse_config(text)
    assert key in str(exc.value)


@pytest.mark.parametrize("path", ["configs/filipkovsky2010_symmetric.toml", "configs/filipkovsky2010_axial.toml"])
def test_paper_scene_configs_validate(path):
    cfg = config.load_config(path)
    assert cfg.data["bearing"]["preload"] == 300.0

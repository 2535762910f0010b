"""Nonlinear normal modes (rotorsweep.kernels.nnm): Shaw-Pierre manifold to cubic order, reduced
oscillator and backbone, against closed forms and against periodic orbits of the full system
computed here independently (solve_ivp shooting, Newton with the monodromy matrix)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from rotorsweep.kernels import nnm
from rotorsweep.kernels.nnm import shaw_pierre

TWO_PI = 2 * np.pi


def one_dof(w, cubic=0.0, quadratic=0.0):
    """u'' + w^2 u + quadratic u^2 + cubic u^3 = 0."""
    return nnm.PolynomialSystem(np.eye(1), np.zeros((1, 1)), np.array([[w * w]]), np.full((1, 1, 1), quadratic),
                                np.full((1, 1, 1, 1), cubic), ("x",), ("m",))


def isotropic_cubic(gamma):
    """gamma (x^2 + y^2) (x, y): the force of the potential gamma (x^2 + y^2)^2 / 4."""
    q3 = np.zeros((2,) * 4)
    q3[0, 0, 0, 0] = q3[1, 1, 1, 1] = q3[0, 0, 1, 1] = q3[1, 1, 0, 0] = gamma
    return q3


def tilting_rotor(gyro=300.0, kx=4e6, ky=5e6, gamma=1e15, beta=2e10):
    """Journal B (x, y) of a rigid rotor pivoted at A: M = (I_d / l^2) 1, G = (I_p Omega / l^2) J
    (the shaft turns from +x to +y), an anisotropic bearing, a cubic isotropic spring and a
    quadratic beta x^2 in x (potential beta x^3 / 3)."""
    q2 = np.zeros((2,) * 3)
    q2[0, 0, 0] = beta
    return nnm.PolynomialSystem(np.eye(2), gyro * np.array([[0.0, 1.0], [-1.0, 0.0]]), np.diag([kx, ky]), q2,
                                isotropic_cubic(gamma), ("xB", "yB"), ("m", "m"))


def rigid_rotor(spin, disk=0.4, l=0.5, mass=10.0, i_d=0.1, i_p=0.2, k=1e7, gamma=0.0):
    """Rigid rotor on two journals (x1, y1, x2, y2) at 0 and l, disk at disk * l, spin [rad/s],
    two identical isotropic bearings of stiffness k with a cubic isotropic force gamma each
    (potential gamma (x^2 + y^2)^2 / 4 per journal): rotationally symmetric (SO(2)) for any spin."""
    translation = np.array([[1 - disk, 0, disk, 0], [0, 1 - disk, 0, disk]])
    tilt = np.array([[0, 1, 0, -1], [-1, 0, 1, 0]]) / l             # (theta_x, theta_y)
    m = mass * translation.T @ translation + i_d * tilt.T @ tilt
    g = i_p * spin * tilt.T @ np.array([[0.0, 1.0], [-1.0, 0.0]]) @ tilt
    q3 = np.zeros((4,) * 4)
    q3[:2, :2, :2, :2] = q3[2:, 2:, 2:, 2:] = isotropic_cubic(gamma)
    return nnm.PolynomialSystem(m, g, k * np.eye(4), np.zeros((4,) * 3), q3, ("x1", "y1", "x2", "y2"), ("m",) * 4)


def slope(x, y):
    return np.polyfit(np.log(x), np.log(y), 1)[0]


# ---- the independent reference: periodic orbits of the full system by shooting ----

def _full_rhs(s):
    m_inv = np.linalg.inv(s.M)
    n = len(s.M)

    def f(t, x):
        q, v = x[:n], x[n:]
        force = s.G @ v + s.K @ q + np.einsum("ijk,j,k->i", s.Q2, q, q) + np.einsum("ijkl,j,k,l->i", s.Q3, q, q, q)
        return np.concatenate([v, -m_inv @ force])
    return f


def _flow(f, x0, period, t_eval=None):
    return solve_ivp(f, (0, period), x0, method="DOP853", rtol=1e-13, atol=1e-13 * np.abs(x0).max(),
                     t_eval=t_eval)


def _variational_rhs(s, size):
    """(x, S)' for x' = f(x) and its scaled sensitivity S = diag(1 / size) dx(t)/dx(0) diag(size)."""
    m_inv, n, f = np.linalg.inv(s.M), len(s.M), _full_rhs(s)
    q2 = s.Q2 + s.Q2.transpose(0, 2, 1)                                   # d(Q2 q q)/dq = q2 q
    q3 = s.Q3 + s.Q3.transpose(0, 2, 1, 3) + s.Q3.transpose(0, 3, 2, 1)  # d(Q3 q q q)/dq = q3 q q
    ratio = size[None, :] / size[:, None]

    def rhs(t, y):
        x, sens = y[:2 * n], y[2 * n:].reshape(2 * n, 2 * n)
        q = x[:n]
        stiffness = s.K + np.einsum("ijk,k->ij", q2, q) + np.einsum("ijkl,k,l->ij", q3, q, q)
        a = np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv @ stiffness, -m_inv @ s.G]])
        return np.concatenate([f(t, x), ((a * ratio) @ sens).ravel()])
    return rhs


def periodic_orbit(s, master, turning, guess_state, guess_period, samples=256):
    """The orbit with the master at a turning point (velocity 0: the phase condition) at
    displacement `turning`; unknowns: the other state components and the period; equations:
    phi(T) - x0 without the master's displacement row (redundant by energy conservation), solved
    by Newton's method with the exact Jacobian (the monodromy matrix, integrated with the orbit).
    Returns (omega [rad/s], first-harmonic amplitude of the master, half peak-to-peak of each q)."""
    f, n = _full_rhs(s), len(s.M)
    others = [i for i in range(2 * n) if i not in (master, n + master)]
    # Residuals and steps scaled to O(1): lengths by the turning displacement, velocities by it
    # times the frequency, the period relative.
    size = np.where(np.arange(2 * n) < n, turning, turning * TWO_PI / guess_period)
    rhs = _variational_rhs(s, size)
    atol = 1e-13 * np.concatenate([size, np.ones(4 * n * n)])
    x0, period = np.array(guess_state, float), float(guess_period)
    x0[master], x0[n + master] = turning, 0.0
    for _ in range(20):
        y0 = np.concatenate([x0, np.eye(2 * n).ravel()])
        y = solve_ivp(rhs, (0, period), y0, method="DOP853", rtol=1e-13, atol=atol).y[:, -1]
        xt, sens = y[:2 * n], y[2 * n:].reshape(2 * n, 2 * n)
        residual = np.delete((xt - x0) / size, master)
        if np.abs(residual).max() <= 1e-12:
            break
        jacobian = np.delete(np.column_stack([(sens - np.eye(2 * n))[:, others], f(0, xt) / size * period]),
                             master, axis=0)
        step = np.linalg.solve(jacobian, -residual)
        x0[others] += step[:-1] * size[others]
        period *= 1 + step[-1]
    # Converged to the integration's noise (rtol 1e-13).
    assert np.abs(residual).max() <= 1e-10, residual
    x = _flow(f, x0, period, t_eval=period * np.arange(samples) / samples).y
    first = 2 * abs(np.mean(x[master] * np.exp(-2j * np.pi * np.arange(samples) / samples)))
    return TWO_PI / period, first, (x[:n].max(axis=1) - x[:n].min(axis=1)) / 2


# ---- one degree of freedom: closed forms ----

def test_duffing_backbone_is_the_cubic_lindstedt_result_and_converges_to_the_elliptic_period_like_a4():
    w, g = TWO_PI * 100.0, 1e12
    m = nnm.manifold(one_dof(w, cubic=g), 0)
    amplitudes = np.logspace(-5, -4, 5)                         # g A^2 / w^2 from 2.5e-4 to 2.5e-2
    np.testing.assert_allclose(nnm.backbone(m, amplitudes), w * (1 + 3 * g * amplitudes ** 2 / (8 * w ** 2)) / TWO_PI,
                               rtol=1e-13)
    # Exact: x = a cn(W t, k^2), W^2 = w^2 + g a^2, k^2 = g a^2 / (2 W^2), period 4 K / W; its first
    # harmonic is a 2 pi sqrt(nome) / (k K (1 + nome)) (the backbone's amplitude).
    peaks = amplitudes
    big_w = np.sqrt(w ** 2 + g * peaks ** 2)
    k2 = g * peaks ** 2 / (2 * big_w ** 2)
    kk = ellipk(k2)
    nome = np.exp(-np.pi * ellipk(1 - k2) / kk)
    first = peaks * 2 * np.pi * np.sqrt(nome) / (np.sqrt(k2) * kk * (1 + nome))
    error = np.abs(nnm.backbone(m, first) - big_w / (4 * kk))
    # Error O(A^4); the next term is O(A^6), g A^2 / w^2 <= 2.5e-2 of it: the fitted slope is
    # within 4 * 2.5e-2 of 4 (and a wrong A^2 coefficient would give 2).
    assert slope(first, error) == pytest.approx(4.0, abs=0.1)


def test_quadratic_oscillator_backbone_is_nayfehs_and_matches_shooting_to_a4():
    w, a = TWO_PI * 100.0, 1e8
    s = one_dof(w, quadratic=a)
    m = nnm.manifold(s, 0)
    assert nnm.frequency_coefficient(m) == pytest.approx(-5 * a ** 2 / (12 * w ** 3), rel=1e-12)
    errors, firsts = [], []
    for turning in (1e-4, 2e-4, 4e-4):                        # a A / w^2 from 0.025 to 0.1
        omega, first, _ = periodic_orbit(s, 0, turning, np.zeros(2), TWO_PI / w)
        errors.append(abs(nnm.angular_frequency(m, first) - omega) / w)
        firsts.append(first)
    # O(A^4) error (omega is even in A); the O(A^6) term is (a A / w^2)^2 <= 1e-2 of it.
    assert slope(firsts, errors) == pytest.approx(4.0, abs=0.2)


# ---- several degrees of freedom ----

def test_decoupled_invariant_subspace_gives_vanishing_slave_coefficients():
    """Potential g1 x^4/4 + c x^2 y^2/2 + g2 y^4/4: y = 0 is invariant, so the x mode's slaves
    (y, y') vanish identically and its backbone is the Duffing one."""
    w1, w2, g1, c = TWO_PI * 100, TWO_PI * 170, 1e12, 3e12
    q3 = np.zeros((2,) * 4)
    q3[0, 0, 0, 0], q3[1, 1, 1, 1] = g1, 2e12
    q3[0, 0, 1, 1] = q3[1, 1, 0, 0] = c
    s = nnm.PolynomialSystem(np.eye(2), np.zeros((2, 2)), np.diag([w1 ** 2, w2 ** 2]), np.zeros((2,) * 3), q3,
                             ("x", "y"), ("m", "m"))
    m = nnm.manifold(s, 0)
    assert m.master == 0
    # Rows y, y' (1, 3): the right-hand side of every degree is exactly zero there.
    assert np.abs(m.coefficients[[1, 3]]).max() <= 1e-12 * np.abs(m.coefficients).max()
    assert nnm.frequency_coefficient(m) == pytest.approx(3 * g1 / (8 * w1), rel=1e-12)


def test_invariance_pde_holds_to_cubic_order():
    """The matched-power equations are solved: the residual of the invariance PDE vanishes at
    degrees 1-3, relative to the size of its terms (rounding only)."""
    s = tilting_rotor()
    for k in range(2):
        m = nnm.manifold(s, k)
        state = np.zeros((4, 10))
        state[:, 1:] = m.coefficients
        residual = shaw_pierre.invariance_residual(s, state, m.master)
        terms = np.abs(shaw_pierre.field(s, state))
        for degree in (1, 2, 3):
            cols = shaw_pierre.DEGREE == degree
            assert np.abs(residual[:, cols]).max() <= 1e-9 * terms[:, cols].max()


@pytest.mark.parametrize("mode", [0, 1])
def test_gyroscopic_backbone_against_shooting_of_the_full_system(mode):
    """Anisotropic tilting rotor with gyroscopic coupling, cubic isotropic and quadratic springs:
    both whirl modes. The manifold's backbone error shrinks like A^4 (its error term) and the
    reduced flow is a centre (growth coefficient ~ 0)."""
    s = tilting_rotor()
    m = nnm.manifold(s, mode)
    w = m.omega
    # The reduced flow of a conservative system is a centre: sigma A^2 / (kappa A^2) is rounding.
    assert abs(nnm.growth_coefficient(m)) <= 1e-8 * abs(nnm.frequency_coefficient(m))
    errors, firsts, amplitude_errors = [], [], []
    for turning in (2e-6, 4e-6, 8e-6):                         # kappa A^2 / w from 1e-4 to 4e-3
        guess = m.slaves(turning, 0.0)
        omega, first, amplitudes = periodic_orbit(s, m.master, turning, guess,
                                                  TWO_PI / nnm.angular_frequency(m, turning))
        errors.append(abs(nnm.angular_frequency(m, first) - omega) / w)
        firsts.append(first)
        predicted = nnm.coordinate_amplitudes(m, first)[0, :2]
        amplitude_errors.append(np.abs(predicted - amplitudes).max() / first)
    # O(A^4) backbone error; the next term, O(A^5) relative A beta / k ~ 0.04 smaller at the top
    # amplitude, moves the fitted slope by less than 0.2.
    assert slope(firsts, errors) == pytest.approx(4.0, abs=0.2)
    assert errors[0] <= 1e-6
    # Coordinate amplitudes come from the second-order orbit: error O(A^3), relative O(A^2); the
    # fitted slope over a factor 4 is pre-asymptotic (1.7 and 2.05 for the two modes), hence 0.4.
    assert slope(firsts, amplitude_errors) == pytest.approx(2.0, abs=0.4)


@pytest.mark.parametrize("mode", range(4))
def test_whirl_modes_of_a_rotationally_symmetric_rotor_match_shooting_to_a4(mode):
    """Off-centre disk (cylindrical and conical coupled), spin 250 Hz, cubic isotropic bearings:
    every mode is a circular whirl (cylindrical backward/forward 217/221 Hz, conical 381/877 Hz).
    Their degree-3 operators are regular (eigenvalues i omega (a - b) - lambda_s at least 0.02
    omega from 0, the nearest pair being the cylindrical one), so no resonance may be reported and
    the manifold's backbone must converge to the full system's periodic orbits like A^4. (A solver
    that truncated the regular operator as singular gave kappa wrong by 7 % to 220 %, an O(A^2)
    error: slopes 1.8-2.0 here.)"""
    s = rigid_rotor(TWO_PI * 250, gamma=1e15)
    m = nnm.manifold(s, mode)
    assert m.mode.whirl in ("backward", "forward")
    assert not any("internal resonance" in note for note in m.notes), m.notes
    assert abs(nnm.growth_coefficient(m)) <= 1e-8 * abs(nnm.frequency_coefficient(m))
    errors, firsts = [], []
    for turning in (5e-6, 1e-5, 2e-5):                         # kappa A^2 / w from 6e-4 to 2.3e-2
        omega, first, _ = periodic_orbit(s, m.master, turning, m.slaves(turning, 0.0),
                                         TWO_PI / nnm.angular_frequency(m, turning))
        errors.append(abs(nnm.angular_frequency(m, first) - omega) / m.omega)
        firsts.append(first)
    # Error O(A^4), ~ (kappa A^2 / w)^2: 3e-7 to 1e-6 at the smallest amplitude, 1e5 above the
    # shooting's accuracy (rtol 1e-13). The next term is O(A^6), relative kappa A^2 / w <= 2.3e-2
    # smaller: the fitted slope is within 0.1 of 4 (measured 3.96-4.01); a wrong kappa gives 2.
    assert slope(firsts, errors) == pytest.approx(4.0, abs=0.2)
    assert errors[0] <= 3e-6


def test_degenerate_planar_pair_of_a_spinning_rotor_gives_both_planar_modes():
    """Centred disk, spinning: the cylindrical modes do not tilt, so the spin leaves them a
    degenerate pair (as symmetric4's), returned as the x-plane and the y-plane mode. Each is an
    exact 1:1 resonance with the other, singular but consistent: the isotropic forces keep planar
    motion planar, the right-hand side of the other plane's rows cancels to rounding (x1 = x2
    exactly), and the consistency test must measure the residual against the size of the forces,
    not against that rounding. Both planes give the same planar Duffing backbone,
    kappa = 3 (2 gamma) / (8 m w), w^2 = 2 k / m."""
    mass, k, gamma = 10.0, 1e7, 1e15
    s = rigid_rotor(TWO_PI * 250, disk=0.5, mass=mass, k=k, gamma=gamma)
    w = np.sqrt(2 * k / mass)
    for mode, plane in ((0, [0, 2]), (1, [1, 3])):
        m = nnm.manifold(s, mode)
        assert m.mode.label == "cylindrical" and m.mode.whirl == "none"
        assert m.master in plane and any("1:1 internal resonance" in note for note in m.notes)
        # The other plane stays at rest: on the amplitude-A linear orbit (gamma A^2 / k = 1e-2, the
        # cubic terms' relative size), its displacements below 1e-9 A and velocities below 1e-9 A w.
        a, theta = 1e-5, np.linspace(0, TWO_PI, 16)
        state = m.slaves(a * np.cos(theta), -a * w * np.sin(theta))
        other = [i for i in range(4) if i not in plane]
        assert np.abs(state[:, other]).max() <= 1e-9 * a
        assert np.abs(state[:, [4 + i for i in other]]).max() <= 1e-9 * a * w
        assert m.omega == pytest.approx(w, rel=1e-12)
        assert nnm.frequency_coefficient(m) == pytest.approx(3 * gamma / (4 * mass * w), rel=1e-9)


def test_isotropic_gyroscopic_rotor_backbone_matches_the_circular_whirl_closed_form():
    """kx = ky, no quadratic term: the modes are circular whirls, m w^2 -+ g w = k + gamma A^2
    (forward -, backward +), so d omega / d(A^2) = gamma / (2 m w -+ g) at A = 0."""
    gyro, k, gamma = 300.0, 4e6, 1e15
    s = tilting_rotor(gyro=gyro, kx=k, ky=k, beta=0.0, gamma=gamma)
    for mode in nnm.linear_modes(s):
        assert mode.whirl in ("forward", "backward")
    for index in range(2):
        m = nnm.manifold(s, index)
        sign = -1 if m.mode.whirl == "forward" else 1
        closed = (-sign * gyro + np.sqrt(gyro ** 2 + 4 * k)) / 2
        assert m.omega == pytest.approx(closed, rel=1e-12)
        assert nnm.frequency_coefficient(m) == pytest.approx(gamma / (2 * closed + sign * gyro), rel=1e-9)


def test_linear_limit_is_the_eigenvalue_frequency():
    """The reduced oscillator's linear stiffness B_p = omega^2, computed through the manifold's
    linear part and the master's equation, against the eigenvalues of the quadratic pencil."""
    s = rigid_rotor(spin=TWO_PI * 250)
    pencil = np.block([[np.zeros((4, 4)), np.eye(4)], [-np.linalg.solve(s.M, s.K), -np.linalg.solve(s.M, s.G)]])
    expected = np.sort(np.linalg.eigvals(pencil).imag)[4:]
    for index, w in enumerate(expected):
        m = nnm.manifold(s, index)
        assert np.sqrt(m.reduced["p"]) == pytest.approx(w, rel=1e-12)
        assert abs(m.reduced["r"]) <= 1e-12 * w
        assert nnm.backbone(m, 0.0) == pytest.approx(w / TWO_PI, rel=1e-12)


def test_orbit_from_the_manifold_stays_on_it_and_the_distance_shrinks_like_a4():
    """The papers' check: integrate the full system from a manifold point for ten periods. A cubic
    manifold leaves an O(A^4) invariance error (a linear one would leave O(A^2))."""
    s = tilting_rotor()
    m = nnm.manifold(s, 0)
    amplitudes = np.array([1e-6, 2e-6, 4e-6])
    distance = np.array([nnm.invariance_error(s, m, a) for a in amplitudes])
    # Next term O(A^5), relative A beta / k <= 0.02: slope within 0.25 of 4.
    assert slope(amplitudes, distance) == pytest.approx(4.0, abs=0.25)
    assert distance[0] <= 1e-5 * amplitudes[0]


def test_labels_and_whirl_of_a_rigid_rotor():
    """Off-centre disk: a cylindrical and a conical pair, each split by the spin into a backward
    (lower, falling with spin) and a forward (higher, rising) whirl; at rest the pairs are
    degenerate and come as planar modes."""
    slow, fast = nnm.linear_modes(rigid_rotor(TWO_PI * 100)), nnm.linear_modes(rigid_rotor(TWO_PI * 300))
    for modes in (slow, fast):
        assert [m.label for m in modes] == ["cylindrical", "cylindrical", "conical", "conical"]
        assert [m.whirl for m in modes] == ["backward", "forward", "backward", "forward"]
    for a, b in zip(slow, fast):
        assert (b.frequency > a.frequency) == (a.whirl == "forward")
    rest = nnm.linear_modes(rigid_rotor(0.0))
    assert [m.whirl for m in rest] == ["none"] * 4
    assert [m.label for m in rest] == ["cylindrical", "cylindrical", "conical", "conical"]
    assert np.abs(rest[0].shape[[1, 3]]).max() <= 1e-12         # x plane first
    assert np.abs(rest[1].shape[[0, 2]]).max() <= 1e-12


def test_axial_label_from_kinds():
    s = nnm.PolynomialSystem(np.eye(3), np.zeros((3, 3)), np.diag([1e6, 2e6, 0.5e6]), np.zeros((3,) * 3),
                             np.zeros((3,) * 4), ("a", "b", "c"), ("m",) * 3)
    kinds = (("x", "A"), ("y", "A"), ("z", None))
    assert [m.label for m in nnm.linear_modes(s, kinds)] == ["axial", "transverse", "transverse"]
    assert [m.label for m in nnm.linear_modes(s)] == ["unknown"] * 3


def test_degenerate_pair_gives_a_planar_mode_with_a_consistent_1_1_resonance():
    """Isotropic, no spin: the x-plane mode's partner (the y-plane mode, same frequency) is a 1:1
    resonance, singular but consistent (the isotropic force keeps planar motion planar); the
    planar backbone is Duffing's."""
    w, gamma = TWO_PI * 100, 1e12
    s = nnm.PolynomialSystem(np.eye(2), np.zeros((2, 2)), w ** 2 * np.eye(2), np.zeros((2,) * 3),
                             isotropic_cubic(gamma), ("x1", "y1"), ("m", "m"))
    m = nnm.manifold(s, 0)
    assert m.names[m.master] == "x1" and any("1:1" in note for note in m.notes)
    assert np.abs(m.coefficients[[1, 3]]).max() <= 1e-9 * np.abs(m.coefficients).max()
    assert nnm.frequency_coefficient(m) == pytest.approx(3 * gamma / (8 * w), rel=1e-9)


def test_inconsistent_3_1_resonance_is_named():
    """w2 = 3 w1 and the potential c x^3 y: the x^3 term drives y at its own frequency."""
    w, c = TWO_PI * 100, 1e12
    q3 = np.zeros((2,) * 4)
    q3[0, 0, 0, 1], q3[1, 0, 0, 0] = 3 * c, c
    s = nnm.PolynomialSystem(np.eye(2), np.zeros((2, 2)), np.diag([w ** 2, 9 * w ** 2]), np.zeros((2,) * 3), q3,
                             ("x", "y"), ("m", "m"))
    with pytest.raises(ValueError, match="3:1 internal resonance"):
        nnm.manifold(s, 0)


@pytest.mark.parametrize("change, message", [
    (lambda s: s._replace(M=s.M + np.triu(np.ones((2, 2)), 1)), "M is not symmetric"),
    (lambda s: s._replace(G=np.abs(s.G)), "G is not skew"),
    (lambda s: s._replace(Q3=np.zeros((2, 2, 2))), "Q3 has shape"),
])
def test_bad_systems_are_rejected(change, message):
    with pytest.raises(ValueError, match=message):
        nnm.manifold(change(tilting_rotor()), 0)


def test_bad_indices_are_rejected():
    with pytest.raises(ValueError, match="mode index 2 out of range"):
        nnm.manifold(tilting_rotor(), 2)
    with pytest.raises(ValueError, match="does not move"):
        nnm.manifold(rigid_rotor(0.0), 0, master=1)               # the x-plane mode has no y1


def test_figure_data():
    s = tilting_rotor()
    m = nnm.manifold(s, 0)
    p, r, value = nnm.surface(m, "yB'", (-1e-6, 1e-6), (-2e-3, 2e-3), n=5)
    assert value.shape == (5, 5)
    np.testing.assert_allclose(value, m.slaves(p, r)[..., 3])
    orbit = nnm.orbit_on_manifold(s, m, 1e-6, periods=2)
    assert orbit.state.shape == orbit.manifold_state.shape == (len(orbit.t), 4)
    assert "p^3" in m.table()

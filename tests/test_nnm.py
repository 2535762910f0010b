"""Nonlinear normal modes (rotorkernels.nnm): Shaw-Pierre manifold to cubic order, reduced
oscillator and backbone, against closed forms and against periodic orbits of the full system
computed here independently (solve_ivp + fsolve shooting)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve
from scipy.special import ellipk

from rotorkernels import nnm
from rotorkernels.nnm import shaw_pierre

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


def rigid_rotor(spin, disk=0.4, l=0.5, mass=10.0, i_d=0.1, i_p=0.2, k=1e7):
    """Rigid rotor on two journals (x1, y1, x2, y2) at 0 and l, disk at disk * l, spin [rad/s]."""
    translation = np.array([[1 - disk, 0, disk, 0], [0, 1 - disk, 0, disk]])
    tilt = np.array([[0, 1, 0, -1], [-1, 0, 1, 0]]) / l             # (theta_x, theta_y)
    m = mass * translation.T @ translation + i_d * tilt.T @ tilt
    g = i_p * spin * tilt.T @ np.array([[0.0, 1.0], [-1.0, 0.0]]) @ tilt
    return nnm.PolynomialSystem(m, g, k * np.eye(4), np.zeros((4,) * 3), np.zeros((4,) * 4),
                                ("x1", "y1", "x2", "y2"), ("m",) * 4)


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


def periodic_orbit(s, master, turning, guess_state, guess_period, samples=256):
    """The orbit with the master at a turning point (velocity 0: the phase condition) at
    displacement `turning`; unknowns: the other state components and the period; equations:
    phi(T) - x0 without the master's displacement row (redundant by energy conservation).
    Returns (omega [rad/s], first-harmonic amplitude of the master, half peak-to-peak of each q)."""
    f, n = _full_rhs(s), len(s.M)
    others = [i for i in range(2 * n) if i not in (master, n + master)]

    def start(z):
        x0 = np.zeros(2 * n)
        x0[others], x0[master] = z[:-1], turning
        return x0

    def residual(z):
        x0 = start(z)
        return np.delete(_flow(f, x0, z[-1]).y[:, -1] - x0, master)

    z, info, ok, msg = fsolve(residual, np.append(guess_state[others], guess_period), xtol=1e-11, full_output=True)
    # Converged to the integration's noise (rtol 1e-13), whatever fsolve's stopping reason.
    assert np.abs(info["fvec"]).max() <= 1e-10 * abs(turning) * TWO_PI / guess_period, msg
    t = z[-1] * np.arange(samples) / samples
    x = _flow(f, start(z), z[-1], t_eval=t).y
    first = 2 * abs(np.mean(x[master] * np.exp(-2j * np.pi * np.arange(samples) / samples)))
    return TWO_PI / z[-1], first, (x[:n].max(axis=1) - x[:n].min(axis=1)) / 2


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

"""Invariant tori under two-frequency forcing (rotorsweep.kernels.torus) against independent values:
the closed-form response of the linear oscillator, a long scipy DOP853 run of the nonlinear one,
and the shooting solver's periodic orbit at a rational frequency ratio."""
import numpy as np
import pytest

from rotorsweep.kernels import integrators as ig, shooting, torus
from rotorsweep.kernels.models import duffing2, get
from tests.reference import duffing2_strobe

MODEL = get("duffing2")
OPTS = ig.settings(rtol=1e-11, atol=1e-13)
GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0
PHASE = duffing2.P_PHASE


def params(w2, k=2.0, c=0.1, gamma=0.0, f1=1.0, f2=0.5):
    return np.array([k, c, gamma, f1, f2, w2, 0.0])


def solve(p, n_nodes=7, **kw):
    return torus.solve_torus(MODEL.kernel, np.zeros((n_nodes, 2)), p, PHASE, p[duffing2.P_W2], OPTS, **kw)


def linear_response(p, theta):
    """The linear oscillator's steady response at tau = 0, second forcing phase theta: the sum of
    the two forcings' periodic responses F / (k - w^2 + i c w) (position, velocity)."""
    k, c, _, f1, f2, w2, _ = p
    w1 = 2.0 * np.pi
    a1 = f1 / (k - w1 ** 2 + 1j * c * w1)
    a2 = f2 * np.exp(1j * np.asarray(theta)) / (k - w2 ** 2 + 1j * c * w2)
    return np.stack([np.real(a1 + a2), np.real(1j * w1 * a1 + 1j * w2 * a2)], axis=-1)


def test_linear_torus_is_the_sum_of_two_periodic_responses():
    p = params(2.0 * np.pi * GOLDEN * 1.3)
    tor = solve(p)
    assert tor.status == torus.CONVERGED
    theta = np.linspace(0.0, 2.0 * np.pi, 61)
    # integration at rtol 1e-11 over one period, amplified by ||J^-1|| ~ 1 / (1 - e^{-c/2}) ~ 40
    assert np.abs(tor.at(theta) - linear_response(p, theta)).max() < 1e-10
    assert tor.error < 1e-10


def test_nonlinear_torus_holds_a_long_independent_run():
    """10^4 stroboscopic iterates of scipy's DOP853 (rtol 1e-12) from a point of the circle stay
    on the circle within the solver's error estimate, at the imposed rotation theta + n rho."""
    p = params(2.0 * np.pi * GOLDEN, gamma=0.5)
    tor = solve(p)
    assert tor.status == torus.CONVERGED and tor.error < 1e-8
    n = 10_000
    states = duffing2_strobe(p, tor.nodes[0], n)
    on_circle = tor.at(np.fmod(p[duffing2.P_W2] * np.arange(1, n + 1), 2.0 * np.pi))
    assert np.abs(states - on_circle).max() <= tor.error


def test_at_a_rational_ratio_the_torus_holds_the_periodic_orbit():
    """omega / Omega = 3/5: the forcing has period 5 and the torus through theta = 0 contains the
    orbit the shooting solver finds over 5 periods (both to the integration error)."""
    p = params(2.0 * np.pi * 3.0 / 5.0, gamma=0.5)
    tor = solve(p)
    assert tor.status == torus.CONVERGED
    orbit = shooting.periodic_orbit(MODEL, np.zeros(2), p, OPTS, periods=5, tol=1e-12)
    assert orbit.status == shooting.CONVERGED
    assert np.abs(tor.at(0.0)[0] - orbit.state).max() < 1e-8


@pytest.mark.parametrize("c", [0.1, -0.1])
def test_linear_torus_stability_has_the_closed_form_exponents(c):
    """Linear: M(theta) = expm(A), the exponents are Re eig(A) = -c/2 (a pair: underdamped, k = 2);
    their sum is log det M = -c exactly, each one converges like 1/n_steps (the complex pair's
    rotation), hence 1e-3. Negative damping: the torus repels (unstable)."""
    tor = solve(params(2.0 * np.pi * GOLDEN * 1.3, c=c))
    st = torus.stability(tor)
    assert np.abs(st.exponents + c / 2).max() < 1e-3
    assert abs(st.exponents.sum() + c) < 1e-9
    assert st.status == (torus.STABLE if c > 0 else torus.UNSTABLE)


def test_nonlinear_torus_attracts_and_is_stable():
    """A transient from a perturbed point of the circle returns to it, and the exponents say
    stable."""
    p = params(2.0 * np.pi * GOLDEN, gamma=0.5)
    tor = solve(p)
    assert torus.stability(tor).status == torus.STABLE
    states = duffing2_strobe(p, tor.nodes[0] + np.array([0.3, -0.2]), 300)
    assert np.abs(states[-1] - tor.at(300 * p[duffing2.P_W2])[0]).max() < 1e-4


def test_failures_are_statuses():
    p = params(2.0 * np.pi * GOLDEN, gamma=0.5)
    assert solve(p, max_nodes=7).status == torus.FOURIER_DECAY_FAILED
    blowup = torus.solve_torus(MODEL.kernel, np.zeros((7, 2)), params(1.0, f1=1e5), PHASE, 1.0,
                               ig.settings(amplitude_limit=1.0))
    assert blowup.status == torus.INTEGRATION_FAILED
    assert torus.stability(blowup).status == torus.UNDECIDED
    with pytest.raises(ValueError, match="N odd"):
        solve(p, n_nodes=6)


def test_saddle_torus_of_a_resonant_duffing_is_unstable():
    """Hardening Duffing above resonance (omega_n = 2 pi / sqrt 1.3) with three periodic responses
    (harmonic balance, a^2 = 1.13, 9.05, 14.1): the middle one is a saddle; under a weak second
    forcing its torus is a saddle torus, whose exponents are near the orbit's log|multipliers|
    (the second forcing, 1% of the first, perturbs them at O(1e-2)) with the exact sum log det M =
    -c, and a transient started next to it leaves it."""
    w = 2.0 * np.pi
    k, c, gamma, f1 = w ** 2 / 1.3, 0.3, 1.0, 9.0
    p = params(w * GOLDEN, k=k, c=c, gamma=gamma, f1=f1, f2=0.0)
    a2 = 9.04946491
    phi = np.arctan2(c * w, k - w ** 2 + 0.75 * gamma * a2)      # x = a cos(w tau - phi)
    guess = np.sqrt(a2) * np.array([np.cos(phi), w * np.sin(phi)])
    orbit = shooting.periodic_orbit(MODEL, guess, p, OPTS, tol=1e-11, staged=False)
    logs = np.sort(np.log(np.abs(np.linalg.eigvals(orbit.monodromy))))[::-1]
    assert orbit.status == shooting.CONVERGED and logs[0] > 0.1
    p[duffing2.P_F2] = 0.09
    tor = torus.solve_torus(MODEL.kernel, torus.periodic_guess(orbit.state, 7), p, PHASE, p[duffing2.P_W2], OPTS)
    st = torus.stability(tor)
    assert st.status == torus.UNSTABLE
    assert np.abs(st.exponents - logs).max() < 2e-2
    assert abs(st.exponents.sum() + c) < 1e-8
    gap = np.abs(duffing2_strobe(p, tor.nodes[0] + 1e-6, 60) - tor.at(np.fmod(p[duffing2.P_W2] * np.arange(1, 61), 2 * np.pi)))
    assert gap.max(axis=1)[-1] > 1e3 * 1e-6


def test_the_sampled_torus_has_the_linear_half_swing():
    """Linear: x(tau, theta) = Re(a1 e^{i 2 pi tau} + a2 e^{i (w2 tau + theta)}) with independent
    phases, so its half swing over the torus is |a1| + |a2|; sampled on a grid of n phases and n
    times each phase lies within pi / n of the maximizing one: the sampled max is below the true
    one by at most (|a1| + |a2|)(1 - cos(pi / n)) (both phases off by up to pi / n), the min above
    the true min by as much."""
    p = params(2.0 * np.pi * GOLDEN * 1.3)
    tor = solve(p)
    n = 64
    x = torus.surface_samples(MODEL.kernel, tor, p, PHASE, OPTS, n, n)[..., 0]
    k, c, _, f1, f2, w2, _ = p
    exact = abs(f1 / (k - 4 * np.pi ** 2 + 2j * np.pi * c)) + abs(f2 / (k - w2 ** 2 + 1j * c * w2))
    half = (x.max() - x.min()) / 2.0
    assert exact * np.cos(np.pi / n) <= half <= exact + 1e-10


def test_coarsened_keeps_the_fewest_nodes_that_resolve_the_circle():
    """A trigonometric polynomial of degree 4 on 63 nodes: 15 nodes (K = 7) hold it exactly (tail
    at rounding), 7 (K = 3) alias its fourth mode onto the third (tail 1e-3): it comes down to 15,
    and there it is the same circle; with min_nodes 31 it stops at 31."""
    theta = torus.node_phases(63)[:, None]
    nodes = np.hstack([np.sin(theta) + 1e-3 * np.sin(4 * theta), np.cos(theta)])
    small = torus.coarsened(nodes, 1e-9, 7)
    assert small.shape == (15, 2)
    assert np.abs(torus.resample(small, 63) - nodes).max() < 1e-13     # two resamplings: ~N eps each
    assert torus.coarsened(nodes, 1e-9, 31).shape == (31, 2)

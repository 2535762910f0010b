"""The preloaded rotor's torus at the quasi-periodic point of Filipkovsky 2016, Figs. 5-6 (15 deg,
f_Omega = 250 Hz, support vibration at 627.3 Hz: no ratio of small integers): solved from a
transient's stroboscopic points, attracting, and holding a long run at a tighter tolerance."""
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import compute, config
from rotorsweep.kernels import integrators as ig, torus as tr
from rotorsweep.kernels.models import rigid_preloaded as rp

FIG5 = Path(__file__).resolve().parents[1] / "configs" / "filipkovsky2016_fig5.toml"

OPTS = ig.settings(rtol=1e-10, atol=1e-12)
FINE = ig.settings(rtol=1e-12, atol=1e-14)


def strobe(kernel, p, u, first, n, opts):
    """Stroboscopic iterates n = first + 1 .. first + n, each period shot from tau = 0 at its
    support phase (n rho mod 2 pi, as the circle is read: see tests/test_torus.py)."""
    pj, rho, h = p.copy(), p[rp.P_WS], 0.0
    out = np.empty((n, u.size))
    for i in range(n):
        pj[rp.P_PHASE] = np.fmod((first + i) * rho, 2.0 * np.pi)
        u, status, _, h = ig.flow(kernel, 0.0, 1.0, u, pj, False, opts, h)
        assert status == ig.STATUS_OK
        out[i] = u
    return out


@pytest.fixture(scope="module")
def point():
    data = config.load_config(FIG5).scene
    built = compute.builder(data)({**data.fixed, "speed": 250.0, "support_frequency": 627.3,
                                   "nominal_angle": 15.0})
    assert not built.periodic
    kernel = data.model.kernel
    transient, n_fit = 300, 60
    samples = strobe(kernel, built.p, np.zeros(kernel.n_state), 0, transient + n_fit, OPTS)[transient - 1:-1]
    phases = np.fmod(np.arange(transient, transient + n_fit) * built.p[rp.P_WS], 2.0 * np.pi)
    guess = tr.fitted_guess(samples, phases, 15)
    tor = tr.solve_torus(kernel, guess, built.p, rp.P_PHASE, built.p[rp.P_WS], OPTS, decay_tol=1e-9)
    return kernel, built, tor


def test_preloaded_torus_holds_a_long_run_at_a_tighter_tolerance(point):
    """10^4 stroboscopic iterates (rtol 1e-12, 100x the solver's) from a point of the circle stay
    within the solver's error estimate of it, at the imposed rotation."""
    kernel, built, tor = point
    assert tor.status == tr.CONVERGED
    n = 10_000
    states = strobe(kernel, built.p, tor.nodes[0], 0, n, FINE)
    on_circle = tor.at(np.fmod(built.p[rp.P_WS] * np.arange(1, n + 1), 2.0 * np.pi))
    assert np.abs(states - on_circle).max() <= tor.error


def test_preloaded_torus_is_the_attractor_and_stable(point):
    """The transient diagnostics' attractor (a closed Poincare curve, tests/test_filipkovsky_scenes.py)
    is this torus: the transient's later points approach it, and its normal exponents say stable."""
    kernel, built, tor = point
    assert tr.stability(tor, n_steps=2000).status == tr.STABLE
    late = strobe(kernel, built.p, tor.nodes[0] + 0.01 * np.abs(tor.nodes).max(), 0, 200, OPTS)
    gap = np.abs(late - tor.at(np.fmod(built.p[rp.P_WS] * np.arange(1, 201), 2.0 * np.pi))).max(axis=1)
    assert gap[-1] < 1e-3 * gap[0]

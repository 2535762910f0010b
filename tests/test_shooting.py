"""Staged (inexact) Newton shooting against plain Newton, the kernel benchmark's references and
the failure statuses."""
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from rotorsweep.kernels import floquet, integrators as ig, models, shooting
from rotorsweep.kernels.models import jeffcott_clearance as jc

JEFF = models.get("jeffcott_clearance")
REFS = json.loads((Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "reference_points.json").read_text())
RTOL = 1e-10
OPTS = ig.settings(rtol=RTOL, atol=RTOL / 100)
TOL = RTOL / 10         # the benchmark's Newton tolerance: below the map's own error, so the last
                        # two iterates must both be on the configured map
# Multipliers: a single DOP853 monodromy at rtol 1e-10 errs by up to 7e-8 (heavy tail over step
# placements and starts, docs/benchmarks/README.md); one from the early map (rtol 1e-6) by ~1e-6.
MULT_TOL = 1e-7


def match(a, b):
    """Largest distance between two multiplier sets after optimal pairing."""
    cost = np.abs(np.subtract.outer(a, b))
    rows, cols = linear_sum_assignment(cost)
    return cost[rows, cols].max()


def configured_map(kernel, state, p, opts, periods=1.0):
    """(residual norm, monodromy) of the configured map at `state`, from the integrator's own first
    step: how the staged Newton integrates every configured-map iterate."""
    n = kernel.n_state
    z, status, _, _ = ig.flow(kernel, 0.0, periods, ig.initial_state(state, n, True), p, True, opts, 0.0)
    assert status == ig.STATUS_OK
    res = np.abs(z[:n] - state).max() / max(1.0, np.abs(state).max())
    return res, z[n:].reshape(n, n)


def state_bound(state, lam, rtol):
    """Orbit error allowed at `rtol`: the map's global error (~0.4 rtol max|s| measured in the
    benchmark; 10 rtol here) through (M - I)^-1, whose norm ~ 1 / min|lambda - 1|."""
    return 10 * rtol * max(1.0, np.abs(state).max()) / np.abs(lam - 1).min()


@pytest.mark.parametrize("ref", REFS["points"], ids=lambda e: e["name"])
@pytest.mark.parametrize("pattern", [(1, -1, 1, -1), (-1, 1, 1, -1)])
def test_staged_newton_returns_plain_newtons_orbit_and_the_references(ref, pattern):
    p, s_ref = np.array(ref["p"]), np.array(ref["state"])
    lam_ref = np.array([complex(re, im) for re, im in ref["multipliers"]])
    guess = s_ref * (1 + 0.01 * np.array(pattern, float))      # the benchmark's +-1 % starts
    plain = shooting.periodic_orbit(JEFF, guess, p, OPTS, tol=TOL, staged=False)
    staged = shooting.periodic_orbit(JEFF, guess, p, OPTS, tol=TOL)
    assert plain.status == staged.status == shooting.CONVERGED
    assert staged.n_rhs < 0.8 * plain.n_rhs            # the early iterations did run on the early map
    # the returned residual and monodromy are the configured map's at the returned state
    res, mono = configured_map(JEFF.kernel, staged.state, p, OPTS)
    assert staged.residual == res <= TOL
    np.testing.assert_array_equal(staged.monodromy, mono)
    bound = state_bound(s_ref, lam_ref, RTOL)
    assert np.abs(staged.state - s_ref).max() < bound
    assert np.abs(staged.state - plain.state).max() < 2 * bound
    lam = floquet.multipliers(staged.monodromy)
    assert match(lam, lam_ref) < MULT_TOL
    assert match(lam, floquet.multipliers(plain.monodromy)) < 2 * MULT_TOL


def test_staged_newton_reports_failures_as_statuses():
    p, _ = jc.jeffcott_params(speed=190.0, stiffness=2.883e9, clearance=19e-6,
                              contact_angle=np.arccos(1 - 19e-6 / 0.5e-3), axial_approach=0.0, mass=2.0,
                              damping=300.0, radial_load=19.6, n_balls=9, ball_diameter=12.7e-3,
                              pitch_diameter=65e-3)
    cold = jc.static_guess(p)
    for staged in (False, True):
        nan = shooting.periodic_orbit(JEFF, np.full(4, np.nan), p, OPTS, staged=staged)
        assert (nan.status, nan.reason, nan.iterations) == (shooting.DIVERGED, shooting.R_NAN, 0)
        tiny = ig.settings(rtol=1e-11, atol=1e-13, amplitude_limit=1e-3)     # 1 nm: 'diverged'
        out = shooting.periodic_orbit(JEFF, cold, p, tiny, staged=staged)
        assert (out.status, out.reason) == (shooting.DIVERGED, shooting.R_AMPLITUDE)
        # out of iterations on the early map: the state is handed to the configured map, whose
        # residual is the one reported
        out = shooting.periodic_orbit(JEFF, cold, p, OPTS, tol=1e-14, max_iter=1, staged=staged)
        assert out.status == shooting.NOT_CONVERGED and out.reason in (shooting.R_MAX_ITER, shooting.R_LINE_SEARCH)
        if staged:
            assert out.residual == configured_map(JEFF.kernel, out.state, p, OPTS)[0] > 1e-14
    duffing = models.get("duffing")
    unknown = duffing.kernel._replace(tag=type(duffing.kernel.tag)(99))
    opts = ig.settings()
    out = shooting.shoot_staged(unknown, np.zeros(2), np.zeros(4), 1.0, opts, shooting.early_settings(opts), 1e-9, 5)
    assert out[2] == shooting.NOT_CONVERGED and out[3] == shooting.R_UNKNOWN_MODEL


def test_rk4_has_no_early_map_and_staged_equals_plain():
    rk4 = ig.settings("rk4", steps_per_unit=256)
    assert shooting.early_settings(rk4) is rk4
    loose = shooting.early_settings(OPTS)
    assert loose.rtol == shooting.EARLY_RTOL and loose.atol / loose.rtol == pytest.approx(OPTS.atol / OPTS.rtol)
    assert shooting.early_settings(loose) is loose       # already as loose: plain Newton
    ref = REFS["points"][0]
    p, guess = np.array(ref["p"]), np.array(ref["state"]) * 1.01
    a = shooting.periodic_orbit(JEFF, guess, p, rk4, tol=1e-12)
    b = shooting.periodic_orbit(JEFF, guess, p, rk4, tol=1e-12, staged=False)
    assert a.n_rhs == b.n_rhs and np.array_equal(a.state, b.state) and np.array_equal(a.monodromy, b.monodromy)

"""The hard cases of SPEC section 5: each asserts the right status and accuracy."""
import numpy as np
import pytest

from rotorkernels import boundary, continuation, floquet, integrators as ig, models, shooting
from tests.reference import BaiPoint
from tests.test_kernels import JEFF, bai_params, match

OPTS = ig.settings(rtol=1e-11, atol=1e-13)


def solve(point, opts=OPTS, history=(), **overrides):
    p, period = bai_params(point, **overrides)
    sol = continuation.solve_orbit(JEFF, p, opts, history, cold_guess=models.static_guess, tol=1e-10,
                                   transient_periods=100)
    return sol, p, period


def liouville(point, period):
    return np.exp(-point.damping * period / point.mass) ** 2


def loaded_balls(state_samples, p):
    """Number of loaded balls at each orbit sample."""
    counts = []
    for k, (x, y) in enumerate(state_samples[:, :2]):
        theta = 2 * np.pi * (k / len(state_samples)) / p[models.P_NBALLS]
        phi = theta + 2 * np.pi * np.arange(int(p[models.P_NBALLS])) / p[models.P_NBALLS]
        delta = (x * np.cos(phi) + y * np.sin(phi)) * p[models.P_COS_A] + p[models.P_OFFSET]
        counts.append(int((delta > 0).sum()))
    return np.array(counts)


def test_large_clearance_with_most_balls_unloaded():
    point = BaiPoint(30.0, 19.0e-6)
    sol, p, period = solve(point)
    assert sol.status == shooting.CONVERGED
    assert loaded_balls(sol.samples, p).max() <= 3          # 9 balls, at most 3 carry load
    assert abs(np.prod(sol.multipliers).real - liouville(point, period)) < 1e-9
    ref_state, ref_mono, _ = point.periodic_orbit(models.to_physical(sol.state, period), iterations=1)
    assert match(sol.multipliers, np.linalg.eigvals(ref_mono)) < 1e-6


def test_grazing_contact_every_ball_passage():
    """A ball enters and leaves contact within every forcing period (the force is only C^1)."""
    point = BaiPoint(100.0, 7.6e-6)
    sol, p, _ = solve(point)
    counts = loaded_balls(sol.samples, p)
    assert sol.status == shooting.CONVERGED and counts.min() < counts.max()


@pytest.mark.parametrize("clearance", [5e-8, 1e-9])
def test_very_small_clearance_is_stiff_but_solved(clearance):
    point = BaiPoint(150.0, clearance)
    sol, _, period = solve(point)
    assert sol.status == shooting.CONVERGED
    assert abs(np.prod(sol.multipliers).real - liouville(point, period)) < 1e-9


def test_zero_damping_keeps_multipliers_on_the_unit_circle():
    point = BaiPoint(60.0, 7.6e-6)
    point.damping = 0.0
    sol, _, _ = solve(point, damping=0.0)
    assert sol.status == shooting.CONVERGED
    np.testing.assert_allclose(np.abs(sol.multipliers), 1.0, atol=1e-7)
    assert abs(np.prod(sol.multipliers).real - 1.0) < 1e-9


def test_multiplier_within_1e_3_of_minus_one_is_resolved():
    """Near period doubling Newton still converges (M - I stays regular at lambda = -1) and the
    multiplier is as accurate as anywhere else."""
    clearance = 7.6e-6

    def at(speed, guess):
        return continuation.solve_orbit(JEFF, bai_params(BaiPoint(speed, clearance))[0], OPTS, [guess],
                                        cold_guess=models.static_guess, tol=1e-10)

    lo, _, _ = solve(BaiPoint(76.0, clearance))
    hi = at(84.0, lo.state)
    assert lo.max_abs < 1 < hi.max_abs
    crossing = boundary.locate_boundary(at, 76.0, 84.0, lo.state, hi.state, xtol_rel=1e-6)
    speed = crossing.value * (1 + 2e-5)
    sol = at(speed, crossing.solution.state)
    lead = sol.multipliers[0]
    assert sol.status == shooting.CONVERGED and abs(lead + 1) < 1e-3
    point = BaiPoint(speed, clearance)
    _, ref_mono, _ = point.periodic_orbit(models.to_physical(sol.state, bai_params(point)[1]), iterations=1)
    assert match(sol.multipliers, np.linalg.eigvals(ref_mono)) < 1e-7


def test_nonconvergence_is_reported_as_data():
    point = BaiPoint(190.0, 19.0e-6)
    p, _ = bai_params(point)
    orbit = shooting.periodic_orbit(JEFF, models.static_guess(p), p, OPTS, tol=1e-14, max_iter=1)
    assert orbit.status == shooting.NOT_CONVERGED
    assert orbit.reason in (shooting.R_MAX_ITER, shooting.R_LINE_SEARCH)
    tiny = ig.settings(rtol=1e-11, atol=1e-13, amplitude_limit=1e-3)   # 1 nm limit: 'diverged'
    orbit = shooting.periodic_orbit(JEFF, models.static_guess(p), p, tiny)
    assert orbit.status == shooting.DIVERGED and orbit.reason == shooting.R_AMPLITUDE
    nan_guess = np.full(4, np.nan)
    orbit = shooting.periodic_orbit(JEFF, nan_guess, p, OPTS)
    assert orbit.status == shooting.DIVERGED and orbit.reason == shooting.R_NAN

"""The continuation engine (rotorsweep.kernels.continuation.engine) on a problem with a closed-form
branch, written against the problem contract alone: the unit circle x^2 + y^2 = 1 continued in y.
The loop closes, an edge is solved exactly, a user event (x = 0, the top and bottom of the circle)
is located by Brent on the arclength and a level event (y = 1/2) is solved where it is crossed;
a corrector that fails ends the branch as a status. No orbits: a fraction of a second."""
from typing import NamedTuple

import numpy as np
import pytest

from rotorsweep.kernels.continuation import engine, events as ev

SETTINGS = engine.Settings(ds=0.1, ds_max=0.3, tol=1e-14, locate_xtol=1e-12)


class Point(NamedTuple):
    X: np.ndarray
    tangent: np.ndarray
    iterations: int


class Circle(NamedTuple):
    """x^2 + y^2 = 1, the continued parameter y (X[1]); `wall`: the corrector fails above it."""
    wall: float = np.inf
    parameters = (("y", 1, 1.0),)

    def correct(self, X0, c, target, at, settings, counter):
        X = X0.copy()
        for it in range(settings.max_newton + 1):
            counter.n += 1
            F = np.array([X @ X - 1.0, c @ X - target])
            if X[1] > self.wall:
                return None, engine.NEWTON_FAILED
            if np.abs(F).max() <= settings.tol:
                return Point(X, None, it), None
            X = X - np.linalg.solve(np.vstack([2.0 * X, c]), F)
        return None, engine.NEWTON_FAILED

    def point(self, sol, at, settings, counter):
        return sol._replace(tangent=engine.tangent(np.vstack([2.0 * sol.X, at.tangent])))

    def where(self, point):
        return f"y = {point.X[1]!r}"

    def solves_edge(self, k, edge):
        return True


class Top(ev.Zero):
    """A user event: x = 0 (the extremes of y on the circle)."""
    label = "top"

    def value(self, solution):
        return solution.X[0]


FIRST = Point(np.array([1.0, 0.0]), np.array([0.0, 1.0]), 0)


def test_the_circle_closes_with_its_events_located():
    """Brent's tolerance 1e-12 on the arclength puts x = 0 within 1e-12 (|dx/dsigma| <= 1 there,
    the chord's projection on t_a scales sigma by cos(step angle) > 0.95); the level point is solved
    by Newton to 1e-14, so x = +-sqrt(3)/2 to 1e-13."""
    run = engine.follow(Circle(), FIRST, [(-2.0, 2.0)], SETTINGS, (Top(), ev.Level(0.5)))
    assert run.end == engine.CLOSED_LOOP, run.detail
    points = np.array([p.X for p in run.points])
    np.testing.assert_allclose(np.hypot(*points.T), 1.0, atol=1e-13)
    tops = [f.point.X for f in run.found if isinstance(f.event, Top)]
    np.testing.assert_allclose(tops, [[0.0, 1.0], [0.0, -1.0]], atol=1e-12)
    levels = [f.point.X for f in run.found if isinstance(f.event, ev.Level)]
    np.testing.assert_allclose(levels, [[np.sqrt(0.75), 0.5], [-np.sqrt(0.75), 0.5]], atol=1e-13)
    assert [f.index for f in run.found] == sorted(f.index for f in run.found)


def test_an_edge_is_solved_exactly_and_failures_are_statuses():
    run = engine.follow(Circle(), FIRST, [(-0.5, 0.5)], SETTINGS)
    assert run.end == engine.LEFT_RANGE and run.detail == "y left [-0.5, 0.5] at 0.5"
    np.testing.assert_allclose(run.points[-1].X, [np.sqrt(0.75), 0.5], atol=1e-13)
    walled = engine.follow(Circle(wall=0.3), FIRST, [(-2.0, 2.0)], SETTINGS)
    assert walled.end == engine.NEWTON_FAILED and "minimum step" in walled.detail
    # the step halves down to ds_min before giving up: the last point lies within ~ds_min of the wall
    assert max(p.X[1] for p in walled.points) == pytest.approx(0.3, abs=2 * SETTINGS.ds_min)
    budget = engine.follow(Circle(), FIRST, [(-2.0, 2.0)], engine.Settings(max_steps=3))
    assert budget.end == engine.STEP_BUDGET and len(budget.points) == 4

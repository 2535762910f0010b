"""rotorsweep.kernels.roots.brent_root against analytic roots and scipy.optimize.brentq (an independent
implementation of the same method)."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rotorsweep.kernels.roots import RTOL_MIN, NotConverged, brent_root

DOTTIE = 0.7390851332151607      # the root of cos(x) = x (OEIS A003957)

# (f, a, b, exact root): smooth, steep, flat (a triple root: bisection's pace), a root at the
# bracket's far end, and a kink
CASES = [
    (lambda x: x ** 3 - 2.0, 0.0, 2.0, 2.0 ** (1.0 / 3.0)),
    (lambda x: math.cos(x) - x, 0.0, 1.0, DOTTIE),
    (lambda x: math.exp(x) - 10.0, -5.0, 10.0, math.log(10.0)),
    (lambda x: math.exp(40.0 * (x - 0.5)) - 1.0, 0.0, 1.0, 0.5),
    (lambda x: (x - 0.3) ** 3, 0.0, 1.0, 0.3),
    (lambda x: abs(x - 1e-3) - 1e-3, 1e-3, 5.0, 2e-3),
    (lambda x: x * (x - 4.0), 1.0, 4.0, 4.0),
]
IDS = ["cubic", "dottie", "exp", "steep", "triple", "kink", "end"]


@pytest.mark.parametrize("xtol", [1e-3, 1e-8, 1e-15])
@pytest.mark.parametrize("f, a, b, root", CASES, ids=IDS)
def test_the_root_is_within_the_promised_tolerance(f, a, b, root, xtol):
    """|x - x*| <= xtol + rtol |x|: the bracket [b, c] the method stops on holds the root and is
    at most that wide. The exact roots' own rounding (~1 ulp) sits well inside RTOL_MIN |x|."""
    x = brent_root(f, a, b, xtol=xtol, maxiter=200)
    assert abs(x - root) <= xtol + RTOL_MIN * abs(x)
    # and from the other end of the bracket
    assert abs(brent_root(f, b, a, xtol=xtol, maxiter=200) - root) <= xtol + RTOL_MIN * abs(root)


@pytest.mark.parametrize("f, a, b, root", CASES, ids=IDS)
def test_agrees_with_scipy_brentq_and_needs_no_more_evaluations(f, a, b, root):
    """Both meet the same tolerance, so they agree to twice it; the evaluation counts compare
    the methods' pace (bisection alone needs ~log2(width / xtol) = 50-55 here, the triple root
    ~120 with either: interpolation crawls towards a multiple root): within 3 of scipy's, which
    differs only in its extrapolation formula."""
    calls = []

    def counted(x):
        calls.append(x)
        return f(x)

    x = brent_root(counted, a, b, xtol=1e-14, maxiter=200)
    ref, info = brentq(f, a, b, xtol=1e-14, maxiter=200, full_output=True)
    assert abs(x - ref) <= 2 * (1e-14 + RTOL_MIN * abs(ref))
    assert len(calls) <= info.function_calls + 3


def test_superlinear_on_a_smooth_root():
    """cos(x) - x to 1e-15 in at most 10 evaluations (bisection: 50): the interpolation steps,
    not bisection, do the work."""
    calls = []
    brent_root(lambda x: calls.append(x) or math.cos(x) - x, 0.0, 1.0, xtol=1e-15)
    assert len(calls) <= 10


def test_a_zero_at_an_end_is_returned_without_iterating():
    assert brent_root(lambda x: x - 1.0, 1.0, 3.0, xtol=1e-12) == 1.0
    assert brent_root(lambda x: x - 3.0, 1.0, 3.0, xtol=1e-12) == 3.0


@pytest.mark.parametrize("f", [lambda x: x * x + 1.0, lambda x: float("nan")], ids=["same-sign", "nan"])
def test_no_sign_change_is_a_value_error_that_shows_the_bracket(f):
    with pytest.raises(ValueError, match=r"opposite signs: f\(-1.0\) = .*, f\(2.0\) = "):
        brent_root(f, -1.0, 2.0, xtol=1e-12)


@pytest.mark.parametrize("kwargs", [dict(xtol=0.0), dict(xtol=1e-12, rtol=1e-17), dict(xtol=1e-12, maxiter=0)])
def test_bad_tolerances_are_refused(kwargs):
    with pytest.raises(ValueError, match="brent_root needs xtol > 0"):
        brent_root(lambda x: x, -1.0, 1.0, **kwargs)


def test_too_few_steps_raise_not_converged_with_a_bracket_that_holds_the_root():
    with pytest.raises(NotConverged, match=r"no convergence in 3 steps; bracket \[") as info:
        brent_root(lambda x: (x - 0.3) ** 3, 0.0, 1.0, xtol=1e-15, maxiter=3)
    low, high = sorted(info.value.bracket)
    assert low <= 0.3 <= high and high - low < 1.0
    assert isinstance(info.value, RuntimeError)        # as scipy's brentq raised


def test_a_boundary_brent_cannot_locate_is_a_boundary_error_not_a_crash(monkeypatch):
    """A crossing Brent does not locate within its steps (a multiple root or a rough max|mu|)
    becomes the locator's BoundaryError, the boundary table's 'unrefined' status."""
    from collections import namedtuple

    from rotorsweep.kernels.continuation import events

    sol = namedtuple("Sol", "status state max_abs")

    def solve(v, guess):
        return sol(0, guess, 0.5 + v)

    simple = events.locate_boundary(solve, 0.0, 1.0, state_a=0.0, state_b=0.0)
    assert abs(simple.value - 0.5) <= 1e-8

    def not_converging(f, a, b, xtol):
        f(0.5)
        raise NotConverged("no convergence", (0.49, 0.51))
    monkeypatch.setattr(events, "brent_root", not_converging)
    with pytest.raises(events.BoundaryError, match=r"not located to 1e-08 in 3 orbit solves; it lies in \(0.49, 0.51\)"):
        events.locate_boundary(solve, 0.0, 1.0, state_a=0.0, state_b=0.0)


def test_random_smooth_functions_match_scipy():
    """Cubics with one real root in the bracket, coefficients drawn at random (seeded): every
    root agrees with scipy's to the sum of the two tolerances."""
    rng = np.random.default_rng(7)
    for _ in range(200):
        r = rng.uniform(-3.0, 3.0)
        k, m = rng.uniform(0.1, 5.0, size=2)

        def f(x, r=r, k=k, m=m):
            return (x - r) * (k + m * (x - r) ** 2)      # one real root, at r
        a, b = r - rng.uniform(0.01, 4.0), r + rng.uniform(0.01, 4.0)
        x = brent_root(f, a, b, xtol=1e-12)
        assert abs(x - brentq(f, a, b, xtol=1e-12)) <= 2 * (1e-12 + RTOL_MIN * 3.0)
        assert abs(x - r) <= 1e-12 + RTOL_MIN * abs(x)

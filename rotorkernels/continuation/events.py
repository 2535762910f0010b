"""Events on a branch, the one home of the concept.

On a grid (natural continuation): `locate_boundary`, the parameter value where max |multiplier|
crosses 1 (a stability boundary), by root finding (Brent) on g(v) = max|lambda|(v) - 1 between
two bracketing grid values, with the periodic orbit continued from the nearest value already
solved, so each evaluation is a short Newton solve and the branch followed is the one the grid saw.

On a pseudo-arclength branch (`engine.follow(..., events)`): event objects, `BranchEvent` and its
kinds. `Zero` events are sign changes of a test function located by Brent's method on the
arclength (`engine.locate_zero`): fold / branch point, prod(mu_i - 1); period doubling,
prod(mu_i + 1); Neimark-Sacker, prod_{i<j}(mu_i mu_j - 1) (the bialternate product: it vanishes
when a complex pair crosses |mu| = 1 and does not change sign when a pair turns real off the
circle), with overflow-safe signs of the products. A sign change of prod(mu_i - 1) with a turning
parameter (the tangent's parameter component changes sign) is a fold, without one a branch point.
`Level` events are the points where a continued parameter takes a given value (solved exactly
there); `Flag` events are detected between two points and not located (codimension-2 flags).
A user event is one subclass of `Zero` with `detect` and `value`: `Peak`, a local maximum of a
point's plotted amplitude along the branch (its `slope`, the amplitude's derivative along the
unit tangent, turns from positive to negative), located like a fold.
"""
from collections import namedtuple

import numpy as np

from rotorsweep.kernels import floquet
from rotorsweep.kernels.continuation import engine
from rotorsweep.kernels.roots import NotConverged, brent_root

from rotorsweep.kernels.continuation_codes import (  # noqa: F401 (the event codes; the names events has always offered)
    BRANCH_POINT, EVENT_LABELS, EVENT_TYPES, FOLD, LOCKED, NEIMARK_SACKER, PEAK, PERIOD_DOUBLING, TORUS_FOLD,
    TORUS_STABILITY)

Boundary = namedtuple("Boundary", "value solution evaluations")


class BoundaryError(RuntimeError):
    """The orbit could not be followed between the bracketing values."""


def locate_boundary(solve, a, b, state_a, state_b=None, xtol_rel=1e-8):
    """Refine a stability boundary between parameter values a and b.

    solve(value, guess) -> a continuation.PointSolution; the solutions at a and b must lie on
    opposite sides of max|lambda| = 1. Returns Boundary(value, solution nearest the crossing,
    number of orbit solves). The crossing is located to xtol_rel relative to max(|a|, |b|)."""
    known = [(a, state_a)] + ([(b, state_b)] if state_b is not None else [])
    solutions = {}

    def g(v):
        guess = min(known, key=lambda item: abs(item[0] - v))[1]
        sol = solve(v, guess)
        if sol.status != 0:
            raise BoundaryError(f"no periodic orbit at {v!r} while refining the boundary in [{a}, {b}]")
        known.append((v, sol.state))
        solutions[v] = sol
        return sol.max_abs - 1.0

    ga, gb = g(a), g(b)
    if np.sign(ga) == np.sign(gb):
        raise BoundaryError(f"max|multiplier| - 1 has the same sign at {a} and {b}: no crossing bracketed")
    xtol = xtol_rel * max(abs(a), abs(b))
    try:
        value = brent_root(g, a, b, xtol=xtol)
    except NotConverged as exc:
        raise BoundaryError(f"the crossing in [{a}, {b}] was not located to {xtol:.3g} in "
                            f"{len(solutions)} orbit solves; it lies in {exc.bracket}") from None
    nearest = min(solutions, key=lambda v: abs(v - value))
    return Boundary(value, solutions[nearest], len(solutions))


class BranchEvent:
    """An event on a pseudo-arclength branch; the extension contract of `engine.follow`'s events.

    label       short text for details ("LP", "PD", ...)
    code        what the problem's result records for it (e.g. EVENT_TYPES index)
    locates     True: `locate` finds its point; False: a flag between two points
    end         an engine.END_REASONS code to end the branch where it is detected, or None
    detect(problem, a, b) -> bool           met on the step from point a to point b
    locate(problem, a, b, settings, counter) -> (point, correctors spent) or None (not located)
    end_detail(problem, point, a, b) -> str  the end in words (point: the located one or None)
    """
    label, code, locates, end = "", None, True, None

    def detect(self, problem, a, b):
        raise NotImplementedError

    def locate(self, problem, a, b, settings, counter):
        return None

    def end_detail(self, problem, point, a, b):
        return f"{self.label} {at_or_between(problem, point, a, b)}"


def at_or_between(problem, point, a, b):
    """Where an event lies in words: at its located point, else between the step's ends."""
    return f"at {problem.where(point)}" if point is not None else f"between {problem.where(a)} and {problem.where(b)}"


class Zero(BranchEvent):
    """A sign change of a test function `value` (of a point or a corrector's solution, continuous
    through its zero), located by Brent's method on the arclength (`root`: the root finder)."""

    def __init__(self, root=brent_root):
        self.root = root

    def value(self, solution):
        raise NotImplementedError

    def detect(self, problem, a, b):
        return (self.value(a) < 0) != (self.value(b) < 0)

    def locate(self, problem, a, b, settings, counter):
        return engine.locate_zero(problem, a, b, self.value, settings, counter, self.root)


def signs(lams):
    """Signs of the three multiplier test functions (fold/branch point, period doubling,
    Neimark-Sacker)."""
    def sign(values):
        size = np.abs(values)
        phase = np.prod(np.where(size > 0, values / np.where(size > 0, size, 1.0), 1.0))
        return 1.0 if phase.real >= 0 else -1.0
    i, j = np.triu_indices(lams.size, 1)
    return sign(lams - 1.0), sign(lams + 1.0), sign(lams[i] * lams[j] - 1.0)


def test_value(lams, which):
    """A multiplier test function continuous through its zero: the sign of the product times the
    distance of the nearest factor from zero."""
    i, j = np.triu_indices(lams.size, 1)
    factors = (lams - 1.0, lams + 1.0, lams[i] * lams[j] - 1.0)[which]
    return signs(lams)[which] * float(np.abs(factors).min())


class RecentSigns:
    """`signs` of the last two multiplier arrays asked for, by identity: on a branch each point's
    signs serve four events on two steps, computed once (they cost as much as the step's linear
    algebra on a small model)."""

    def __init__(self):
        self.recent = []

    def __call__(self, lams):
        for known, values in self.recent:
            if known is lams:
                return values
        values = signs(lams)
        self.recent = [(lams, values)] + self.recent[:1]
        return values


class Multiplier(Zero):
    """A multiplier test function (`which`: 0 fold/branch point, 1 period doubling, 2
    Neimark-Sacker) of points with `.multipliers`; `signs`: the function of their signs, shared by
    the events of one branch (RecentSigns)."""
    which = 0

    def __init__(self, root=brent_root, signs=signs):
        super().__init__(root)
        self.signs = signs

    def value(self, solution):
        return test_value(solution.multipliers, self.which)

    def detect(self, problem, a, b):
        return self.signs(a.multipliers)[self.which] != self.signs(b.multipliers)[self.which]


def _turns(problem, a, b):
    """The first continued parameter's tangent component changes sign from a to b."""
    index = problem.parameters[0][1]
    return a.tangent[index] * b.tangent[index] < 0


class Fold(Multiplier):
    label, code = EVENT_LABELS[FOLD], FOLD

    def detect(self, problem, a, b):
        return super().detect(problem, a, b) and _turns(problem, a, b)


class BranchPoint(Multiplier):
    label, code = EVENT_LABELS[BRANCH_POINT], BRANCH_POINT

    def detect(self, problem, a, b):
        return super().detect(problem, a, b) and not _turns(problem, a, b)


class PeriodDoubling(Multiplier):
    label, code, which = EVENT_LABELS[PERIOD_DOUBLING], PERIOD_DOUBLING, 1


class NeimarkSacker(Multiplier):
    label, code, which = EVENT_LABELS[NEIMARK_SACKER], NEIMARK_SACKER, 2

    def detect(self, problem, a, b):
        return super().detect(problem, a, b) and _has_complex_critical(a, b)


def _has_complex_critical(a, b):
    """A bialternate sign change is a Neimark-Sacker point only if the pair crossing |mu| = 1 is
    complex (a real pair with mu_i mu_j = 1 is a neutral saddle, no bifurcation)."""
    def near_circle_complex(lams):
        cplx = lams[np.abs(lams.imag) > floquet.REAL_TOL * np.abs(lams)]
        return cplx.size and np.abs(np.abs(cplx) - 1.0).min()
    return bool(near_circle_complex(a.multipliers)) and bool(near_circle_complex(b.multipliers))


def orbit_events(root=brent_root, branch_point=BranchPoint):
    """The bifurcations of orbits located on a branch (with `root` as root finder), in the order
    they are detected; `branch_point`: the class of its branch points (a subclass may end the
    branch there)."""
    recent = RecentSigns()
    return tuple(kind(root, recent) for kind in (Fold, branch_point, PeriodDoubling, NeimarkSacker))


class Peak(Zero):
    """A local maximum of the plotted amplitude along the branch: points carry `.slope`, the
    amplitude's derivative along their unit tangent (oriented along the travel), which turns from
    positive to negative. Located by Brent's method on the arclength like a fold, each corrector's
    solution made a point (its tangent and slope) by the problem. Only smooth maxima: the
    amplitude (half peak-to-peak) is the largest local maximum of the signal minus the smallest
    local minimum, so where two local maxima exchange which is the largest (a kink, on period-k
    orbits) it is the larger of two smooth curves, a corner opening upward, never a maximum. The
    problem checks the located zero is smooth and estimates its error (arclength.Family.peak_error)."""
    label, code = EVENT_LABELS[PEAK], PEAK

    def value(self, point):
        return point.slope

    def detect(self, problem, a, b):
        return a.slope > 0.0 and b.slope <= 0.0

    def locate(self, problem, a, b, settings, counter):
        def slope(solution):
            point = solution if hasattr(solution, "slope") else problem.point(solution, a, settings, counter)
            if point is None:
                raise ValueError("no tangent at a corrector's solution")
            return point.slope
        return engine.locate_zero(problem, a, b, slope, settings, counter, self.root)


def same_value(level, value):
    """value is the level up to round-off (a point solved at X[index] = level / scale)."""
    return abs(value - level) <= 1e-12 * abs(level)


class Level(BranchEvent):
    """Where the continued parameter k takes the value `level` (physical units): the point solved
    exactly there (the step's end point itself when it lies on the level)."""

    def __init__(self, level, k=0):
        self.level, self.k = level, k
        self.label = f"level {level!r}"

    def detect(self, problem, a, b):
        m, va, vb = self.level, engine.parameter_value(problem, a, self.k), engine.parameter_value(problem, b, self.k)
        return not same_value(m, va) and ((va - m) * (vb - m) < 0 or same_value(m, vb))

    def locate(self, problem, a, b, settings, counter):
        if same_value(self.level, engine.parameter_value(problem, b, self.k)):
            return b, 0
        _, index, scale = problem.parameters[self.k]
        point = engine.solve_at(problem, a, b, index, self.level / scale, settings, counter)
        return None if point is None else (point, 1)


class Flag(BranchEvent):
    """Detected between two points, not located."""
    locates = False

    def __init__(self, code, label=""):
        self.code, self.label = code, label


class Cusp(Flag):
    """The branch's projection on the plane of its two parameters reverses (both parameter
    components of the tangent, the unknowns' last two, change sign together)."""

    def detect(self, problem, a, b):
        return a.tangent[-2:] @ b.tangent[-2:] < 0


class OtherMultiplierCrosses(Flag):
    """A real multiplier other than the point's `critical` one crosses `value`."""

    def __init__(self, code, value, label=""):
        super().__init__(code, label)
        self.value = value

    def detect(self, problem, a, b):
        def sign(point):
            lams = np.delete(point.multipliers, np.argmin(np.abs(point.multipliers - point.critical)))
            return np.prod((lams - self.value) / np.abs(lams - self.value)).real >= 0
        return sign(a) != sign(b)


class KappaCrosses(Flag):
    """kappa = cos(theta) of a Neimark-Sacker pair (the unknown after the state) reaches `kappa`."""

    def __init__(self, code, kappa, label=""):
        super().__init__(code, label)
        self.kappa = kappa

    def detect(self, problem, a, b):
        n = a.monodromy.shape[0]
        return (a.X[n] - self.kappa) * (b.X[n] - self.kappa) <= 0

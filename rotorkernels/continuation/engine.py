"""The pseudo-arclength engine: one loop, written once, that follows any continuation problem.

`follow(problem, first, bounds, settings, events)` owns the predictor (a step ds along the unit
tangent), the call of the problem's corrector on the arclength hyperplane t_a . (X - X_a) = ds,
step control, edges, end reasons, closed-loop detection and event location. The problems
(BifurcationKit's split of problem and algorithm) own their unknowns and equations:
`arclength.Family` (forced orbits along one parameter), `backbone.Shooting` (autonomous orbits
along their amplitude) and `twoparam.BifurcationCurve` (fold / PD / NS points along two
parameters).

The problem contract (what `follow` calls; a new problem class implements these):

    parameters                      tuple of (name, index, scale): the continued parameters, each
                                    the unknowns' component X[index] = value / scale (for bounds,
                                    edges and level events)
    correct(X0, c, target, at, settings, counter) -> (solution, None) or (None, failure)
                                    Newton (or Gauss-Newton) on [F(X) = 0, c . X = target] from X0,
                                    failure an END_REASONS code (NEWTON_FAILED,
                                    INTEGRATION_FAILED); `at` is the point the step starts from
                                    (its tangent orients the new one; a problem may carry data on
                                    its points, as the bifurcation curves' borders); the solution
                                    has `.X` and what the problem's events read (`.multipliers`)
    point(solution, at, settings, counter) -> point or None
                                    the converged solution made a point: its unit tangent oriented
                                    like at.tangent and what a point records (None: the tangent
                                    could not be had, counted as INTEGRATION_FAILED)
    where(point) -> str             the point's position in words, for end details
    solves_edge(k, edge) -> bool    whether the edge of parameter k at `edge` is solved exactly
                                    (the backbone's zero amplitude is the trivial orbit: not solved)

Points have `.X` (the unknowns), `.tangent` (unit) and `.iterations` (the corrector's). The
settings are `Settings`; a counter counts right-hand-side evaluations (`Counter.n`). The events
(`events.BranchEvent`) are detected on each accepted step and located by their own method
(`events` module). A branch that stops early is data: `Run.end` and `Run.detail`, never an
exception.

Step control: the step grows after a corrector that converged in few iterations (fast_newton)
and halves after one that failed, needed nearly all its iterations or turned the tangent by more
than `max_angle`: with both bounded the corrector stays on the branch it started from.
"""
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from rotorsweep.kernels.roots import NotConverged, brent_root

from rotorsweep.kernels.continuation_codes import (  # noqa: F401 (how a branch ended; the names engine has always offered)
    CLOSED_LOOP, END_REASONS, INTEGRATION_FAILED, LEFT_RANGE, NEWTON_FAILED, REJOINED, START_FAILED, STEP_BUDGET,
    TORUS_BREAKDOWN)

# The first point is solved at a fixed parameter from a guess that may be rough (a settled transient).
START_NEWTON = 30


@dataclass(frozen=True)
class Settings:
    ds: float = 0.02            # first step (normalized units of X)
    ds_min: float = 1e-6
    ds_max: float = 0.1
    max_steps: int = 400
    max_angle: float = 0.25     # rad between successive tangents
    max_newton: int = 8
    fast_newton: int = 3        # a corrector this quick lets the step grow
    grow: float = 1.5
    tol: float = 1e-10          # corrector: relative residual (orbits: max|phi - s| / max(1, max|s|))
    fd_step: float = 1e-5       # step of the problems' central differences in a scaled parameter
    locate_xtol: float = 1e-11  # arclength tolerance of event location (normalized units)

    def problems(self):
        """Messages for settings that cannot work (checked before any work starts)."""
        out = []
        for name in ("ds", "ds_min", "ds_max", "max_angle", "tol", "fd_step", "locate_xtol"):
            if not getattr(self, name) > 0:
                out.append(f"{name} = {getattr(self, name)!r}: must be > 0")
        if self.ds_min > self.ds or self.ds > self.ds_max:
            out.append(f"steps must satisfy ds_min <= ds <= ds_max, got {self.ds_min}, {self.ds}, {self.ds_max}")
        for name in ("max_steps", "max_newton", "fast_newton"):
            if int(getattr(self, name)) < 1:
                out.append(f"{name} = {getattr(self, name)!r}: must be an integer >= 1")
        if not self.grow > 1:
            out.append(f"grow = {self.grow!r}: must be > 1")
        if not self.max_angle < np.pi / 2:
            out.append(f"max_angle = {self.max_angle!r}: must be below pi/2")
        return out


class Counter:
    """Right-hand-side evaluations spent on one branch."""
    def __init__(self):
        self.n = 0


class Seed(NamedTuple):
    """A stand-in for the point a first corrector starts from: its tangent orients the new one."""
    tangent: np.ndarray


class Found(NamedTuple):
    """An event met between points[index] and points[index + 1]."""
    event: object           # the events.BranchEvent
    point: object           # the located point (None for a flag, which is not located)
    index: int
    evaluations: int        # correctors spent locating it


class Run(NamedTuple):
    points: list            # in the order of travel
    found: list             # Found, in the order met
    end: int                # END_REASONS index
    detail: str             # the end in words, and the events detected but not located


def tangent(bordered):
    """The unit null vector of J oriented like t_prev, from bordered = [J; t_prev] (J with one row
    fewer than columns): the solution of bordered t = e_last (so t . t_prev > 0)."""
    rhs = np.zeros(bordered.shape[1])
    rhs[-1] = 1.0
    t = np.linalg.solve(bordered, rhs)
    return t / np.linalg.norm(t)


def angle(t1, t2):
    return float(np.arccos(np.clip(t1 @ t2, -1.0, 1.0)))


def rejected(a, b, settings):
    """A converged step a -> b is still refused when its corrector needed nearly all its
    iterations or the tangent turned by more than max_angle (the step is halved and retried)."""
    return b.iterations > settings.max_newton - 2 or angle(a.tangent, b.tangent) > settings.max_angle


def on_arclength(problem, a, sigma, settings, counter, near=None):
    """The corrector's solution on the hyperplane t_a . (X - X_a) = sigma, predicted along t_a from
    a, or from `near` = (sigma', solution there) when given."""
    start, at = (a.X, 0.0) if near is None else (near[1].X, near[0])
    return problem.correct(start + (sigma - at) * a.tangent, a.tangent, a.tangent @ a.X + sigma, a, settings, counter)


def _nearest(found, sigma):
    """(sigma', solution) of the found solutions nearest sigma (None if none): Brent's late
    evaluations lie close together, and a predictor from the nearest one needs fewer Newton
    iterations than one from the step's first point (the Bai 7.6 um line's six events: 61 Newton
    iterations in 125 evaluations instead of 286 in 129)."""
    if not found:
        return None
    near = min(found, key=lambda s: abs(s - sigma))
    return near, found[near]


class _Lost(Exception):
    """The corrector failed while locating an event."""


def locate_zero(problem, a, b, value, settings, counter, root=brent_root):
    """The point between a and b where value(solution) = 0, by Brent's method on the arclength
    sigma from a (sigma -> the corrected solution on t_a . (X - X_a) = sigma). Returns (point,
    correctors spent) or None when the branch cannot be followed between them, value has the same
    sign at both ends, or Brent's 100 steps do not locate it. `root`: the root finder, called as
    brent_root."""
    sigma_b = float(a.tangent @ (b.X - a.X))
    found = {}

    def g(sigma):
        sol, failure = on_arclength(problem, a, sigma, settings, counter, _nearest(found, sigma))
        if failure is not None:
            raise _Lost
        found[sigma] = sol
        return value(sol)

    try:
        if value(a) * value(b) > 0:
            return None
        sigma = root(g, 0.0, sigma_b, xtol=settings.locate_xtol)
    except (_Lost, ValueError, NotConverged):
        return None
    sol = found[sigma] if sigma in found else found[min(found, key=lambda s: abs(s - sigma))]
    p = problem.point(sol, a, settings, counter)
    return None if p is None else (p, len(found))


def _step(problem, a, ds, settings, counter):
    """One predictor-corrector step of length ds from a: (point, None) or (None, failure). Its
    corrector stops after max_newton - 2 iterations: a step that needs more is refused (`rejected`)
    whether or not it converges (the Bai 7.6 um line's ten diverging correctors: 2 iterations less)."""
    quick = replace(settings, max_newton=max(0, settings.max_newton - 2))
    sol, failure = on_arclength(problem, a, ds, quick, counter)
    if failure is not None:
        return None, failure
    b = problem.point(sol, a, settings, counter)
    return (b, None) if b is not None else (None, INTEGRATION_FAILED)


def solve_at(problem, a, b, index, value, settings, counter):
    """The point between a and b where X[index] = value (an edge, a level), predicted on the
    chord; None if the corrector fails."""
    frac = (value - a.X[index]) / (b.X[index] - a.X[index])
    c = np.zeros(a.X.size)
    c[index] = 1.0
    sol, failure = problem.correct(a.X + frac * (b.X - a.X), c, value, a, settings, counter)
    return None if failure is not None else problem.point(sol, a, settings, counter)


def parameter_value(problem, point, k):
    """The value of the continued parameter k at a point (problem.parameters' units)."""
    _, index, scale = problem.parameters[k]
    return float(point.X[index] * scale)


def _exit(problem, bounds, a, b):
    """(fraction of the step, k, edge) of the first edge crossed from a (inside) to b, or None
    when b is inside."""
    crossings = []
    for k, (lo, hi) in enumerate(bounds):
        va, vb = parameter_value(problem, a, k), parameter_value(problem, b, k)
        crossings += [((edge - va) / (vb - va), k, edge) for edge, beyond in ((lo, vb < lo), (hi, vb > hi)) if beyond]
    return min(crossings) if crossings else None


def _closes(first, a, b):
    """The step a -> b passes the first point again, heading the same way: a closed branch. (The
    first point projects inside the chord a -> b and lies near it: the chord's sagitta on a branch
    turning by at most max_angle is below a tenth of its length.)"""
    chord = b.X - a.X
    along = (first.X - a.X) @ chord / (chord @ chord)
    off = np.linalg.norm(first.X - a.X - along * chord)
    return 0.0 < along <= 1.0 and off < 0.1 * np.linalg.norm(chord) and chord @ first.tangent > 0


def _events_between(problem, events, a, b, index, settings, counter):
    """(found, missed notes, detected events) for the events detected from a to b: located ones
    ordered along the step, flags in the order of `events`."""
    found, missed = [], []
    detected = [event for event in events if event.detect(problem, a, b)]
    for event in detected:
        if not event.locates:
            found.append(Found(event, None, index, 0))
            continue
        located = event.locate(problem, a, b, settings, counter)
        if located is None:
            missed.append(f"; {event.label} not located between points {index} and {index + 1} "
                          f"({problem.where(a)} and {problem.where(b)})")
        else:
            found.append(Found(event, located[0], index, located[1]))
    found.sort(key=lambda f: np.inf if f.point is None else float(f.point.X @ a.tangent))
    return found, missed, detected


def follow(problem, first, bounds, settings=Settings(), events=(), counter=None):
    """Pseudo-arclength continuation of `problem` from its point `first` (whose tangent gives the
    direction) until a continued parameter leaves bounds (one (lo, hi) per problem.parameters;
    the edge point is solved exactly), the branch closes on its first point, an event with an
    `end` code is met, the step budget is spent or the corrector fails at the minimum step."""
    counter = counter or Counter()
    points, found, missed = [first], [], []
    ds = settings.ds
    end, detail = STEP_BUDGET, f"{settings.max_steps} steps"

    def record(a, b):
        new, notes, detected = _events_between(problem, events, a, b, len(points) - 1, settings, counter)
        found.extend(f for f in new if f.point is not first)
        missed.extend(notes)
        return new, detected

    while len(points) <= settings.max_steps:
        a = points[-1]
        b, failure = _step(problem, a, ds, settings, counter)
        if b is not None and rejected(a, b, settings):
            b, failure = None, NEWTON_FAILED
        if b is None:
            if ds <= settings.ds_min * 1.000001:
                end = failure
                detail = f"{END_REASONS[failure]} at the minimum step {settings.ds_min} after {problem.where(a)}"
                break
            ds = max(settings.ds_min, ds / 2.0)
            continue
        crossing = _exit(problem, bounds, a, b)
        if crossing is not None:
            end, detail = LEFT_RANGE, _left(problem, bounds, *crossing[1:])
            edge = _edge(problem, a, b, *crossing[1:], settings, counter)
            if edge is not None:
                record(a, edge)
                points.append(edge)
            break
        if len(points) > 2 and _closes(first, a, b):
            record(a, first)
            end, detail = CLOSED_LOOP, f"back at its first point after {len(points)} points"
            break
        new, detected = record(a, b)
        points.append(b)
        stop = next((event for event in detected if event.end is not None), None)
        if stop is not None:
            located = next((f.point for f in new if f.event is stop), None)
            end, detail = stop.end, stop.end_detail(problem, located, a, b)
            break
        if b.iterations <= settings.fast_newton:
            ds = min(settings.ds_max, ds * settings.grow)
    return Run(points, found, end, detail + "".join(missed))


def _left(problem, bounds, k, edge):
    lo, hi = bounds[k]
    return f"{problem.parameters[k][0]} left [{lo!r}, {hi!r}] at {edge!r}"


def _edge(problem, a, b, k, edge, settings, counter):
    """The point at the edge of parameter k (None if the problem does not solve it there)."""
    if not problem.solves_edge(k, edge):
        return None
    _, index, scale = problem.parameters[k]
    return solve_at(problem, a, b, index, edge / scale, settings, counter)

"""Pseudo-arclength continuation of periodic orbits of forced-orbit problems in any scalar
parameter lambda (shaft speed, a clearance, a preload, a forcing amplitude, ...), through folds.

Unknowns X = (s, mu): the orbit's scaled initial state s and mu = lambda / scale (`scale`, e.g.
the width of the parameter range, makes both parts O(1) so the arclength weighs them alike).
Equations: phi(s, lambda) - s = 0 (phi: the flow over the orbit's period, `periods` forcing
periods) and one scalar condition c . X = target: the arclength condition t . (X - X_k) = ds on
a step, mu = bound to end on the range's edge, t_a . (X - X_a) = sigma when locating an event.

Bordered Newton: [[M - I, dphi/dmu], [c]] dX = -[phi - s, c . X - target], with M the monodromy
from the variational equations (exact to the integrator's tolerance) and dphi/dmu by differences
of plain integrations in mu (the models are not differentiated in their parameters; step 1e-5):
at the first iterate a forward one, one integration at mu + 1e-5 less the variational one's phi
(truncation and the two integrations' different steps ~1e-5 to 1e-3 relative: the predictor's
error dominates that step anyway), at the later ones a central one (two integrations; truncation
O(1e-10), noise rtol / 1e-5 ~ 1e-5): forward at every iterate slowed Newton on the Bai rotor's
period-4 branches into 4-6 iterations and 20 % more points (forward at the first two, one of them
ended at a spurious branch point).
dphi/dmu enters only the Newton matrix and the tangent, never the residual, so its error slows
Newton a little and tilts the predictor, but the converged orbits are exact to the Newton
tolerance. It is recomputed at every Newton iterate: it depends strongly on s (a chord column
from the previous point made Newton linear with rate ~0.1-0.4 on the Duffing resonance; fresh
columns converge quadratically, in 2-3 iterations).

A point's tangent, where the family has no peak to locate, comes from a forward difference at the
converged orbit (one plain integration, its phi - s that of the last Newton iterate); a peak
family's from the parameter pass (`parameter_pass`: the orbit with its derivative in mu on its
own steps), as exact as its orbit, at every point: the slope its peaks are detected and located
by is taken along it (a 1e-5 tilt moves the Bai rotor's flat period-4 peak by 1e-4 Hz), and the
same pass gives the extremes' derivative in mu, so that the slope takes one more pass along the
state part alone (extrema.amplitudes_and_slope). The last Newton iterate's column is no tangent:
taken one iterate before convergence, it tilted period-4 tangents by up to 0.27 rad.

The family is a problem of the continuation engine (`Family`, engine's contract): `engine.follow`
owns the predictor, step control, edges, end reasons and closed loops; the events are
`events.orbit_events()` (fold, branch point, period doubling, Neimark-Sacker: sign changes of
test functions of the multipliers, each located by Brent's method on the arclength from the
point before it, each evaluation a corrector on the branch).
"""
from dataclasses import replace
from typing import Callable, NamedTuple

import numpy as np

from rotorsweep.kernels import extrema, floquet, integrators as ig
from rotorsweep.kernels.continuation import engine, events as ev
from rotorsweep.kernels.continuation.engine import (  # noqa: F401 (the names this module has always offered)
    CLOSED_LOOP, END_REASONS, INTEGRATION_FAILED, LEFT_RANGE, NEWTON_FAILED, REJOINED, START_FAILED, START_NEWTON,
    STEP_BUDGET, Counter, Settings)
from rotorsweep.kernels.continuation.events import (  # noqa: F401
    BRANCH_POINT, EVENT_LABELS, EVENT_TYPES, FOLD, NEIMARK_SACKER, PEAK, PERIOD_DOUBLING)
from rotorsweep.kernels.orbits import ForcedOrbitProblem
from rotorsweep.kernels.roots import brent_root


class Solution(NamedTuple):
    """A corrector's converged solution (a Point without tangent)."""
    X: np.ndarray
    monodromy: np.ndarray
    iterations: int
    residual: float
    r: np.ndarray = None        # phi(s, lam) - s at X (a forward difference's base)

    @property
    def multipliers(self):
        return floquet.multipliers(self.monodromy)


class Point(NamedTuple):
    """A converged point of a branch."""
    X: np.ndarray           # (s, mu)
    lam: float
    monodromy: np.ndarray
    multipliers: np.ndarray
    tangent: np.ndarray     # unit, oriented along the branch's direction of travel
    dphi: np.ndarray        # dphi/dmu at X
    iterations: int
    residual: float
    amplitudes: np.ndarray = None   # (max |o|, half peak-to-peak of o) per observable (Family.weights)
    slope: float = np.nan           # d(half peak-to-peak of the peak observable) / d(arclength)

    @property
    def state(self):
        return self.X[:-1]


# The step in mu of `Family.parameter_pass`'s parameter term (extrema.tangent_params: a central
# difference of the right-hand side at a fixed state, smooth in the parameters): truncation
# ~step^2, round-off ~1e-16 / step, both ~1e-10 here.
LOCKED_STEP = 1e-6

# A located peak's error (Family.peak_error) is what its slope changes by when the point is
# re-solved with the integrator's tolerances and the corrector's this many times tighter (the
# reference; its own error is far smaller: on the Bai rotor's flat period-4 peak the re-solves at
# 1/100 and 1/1000 of the tolerances agree to 3e-7 Hz where the default solves are up to 1e-5 off).
REFINE = 100.0
# The orbits' error is not smooth in the tolerance (a C^1 contact force: each step sequence leaves
# its own), so one solve's slope error can be small by accident (the Bai rotor's period-4 peak at
# 15.2 um: 2e-8 Hz from one solve where the peak lies 2e-6 Hz away); its size is taken as the
# largest over the located solve and re-solves at these factors times the tolerances (more
# realizations of the same error level).
TOLERANCE_SPREAD = (0.5, 2.0)
# A peak is a smooth zero of the slope (Family.peak_error's `smooth`) when the located point's
# |slope| is within this factor of what the location's tolerance and the slope's error explain;
# at a jump of the slope (a corner opening downward, a jump of the amplitude) Brent shrinks the
# bracket onto the jump and |slope| there stays at the jump's size, orders of magnitude above.
KINK_MARGIN = 100.0


class Family(NamedTuple):
    """The forced-orbit problems of `model` along lambda: params(lambda) -> kernel vector p. An
    engine problem (engine's contract): unknowns X = (s, mu), bordered Newton corrector.

    weights: observables o = weights @ u[:m] whose exact extrema every point records
    (`Point.amplitudes`, rotorsweep.kernels.extrema); peak: the row of weights whose half peak-to-peak
    amplitude's local maxima are `events.Peak` events (-1: none), its slope along the tangent
    from the tangent-linear solution at the extremes' times (extrema.amplitudes_and_slope: no
    step-size noise, a peak located like a fold)."""
    model: object
    params: Callable
    opts: np.ndarray
    scale: float = 1.0
    periods: float = 1.0
    weights: np.ndarray = None
    peak: int = -1

    @property
    def parameters(self):
        return (("lambda", -1, self.scale),)

    def lam(self, X):
        return float(X[-1] * self.scale)

    def problem(self, lam):
        return ForcedOrbitProblem(self.model, self.params(lam), self.opts, self.periods)

    def return_map(self, s, lam, variational):
        """(phi(s, lam) - s, monodromy or None, flow status, n_rhs)."""
        kernel = self.model.kernel
        n = kernel.n_state
        z, status, n_rhs, _ = ig.flow(kernel, 0.0, float(self.periods), ig.initial_state(s, n, variational),
                                      self.params(lam), variational, self.opts, 0.0)
        mono = z[n:].reshape((n, n)) if variational else None
        return z[:n] - s, mono, status, n_rhs

    def dphi_dmu(self, X, fd_step, r=None):
        """Difference of phi in mu: (column, flow status, n_rhs); forward from r = phi - s at X
        where given (one plain integration), else central (two)."""
        s, h = X[:-1], self.scale
        step = fd_step * max(1.0, abs(X[-1]))
        plus = self.return_map(s, (X[-1] + step) * h, False)
        if r is not None:
            return (plus[0] - r) / step, plus[2], plus[3]
        minus = self.return_map(s, (X[-1] - step) * h, False)
        bad = next((r[2] for r in (plus, minus) if r[2] != ig.STATUS_OK), ig.STATUS_OK)
        return (plus[0] - minus[0]) / (2.0 * step), bad, plus[3] + minus[3]

    def parameter_pass(self, X):
        """(dphi/dmu, along, status, n_rhs) from one pass of the orbit at X with its derivative in mu
        on its own steps (extrema.parameter_pass, its parameter term of step LOCKED_STEP: no
        rtol / fd_step noise): the tangent the peaks' slope is taken along, as exact as the orbit
        where `dphi_dmu`'s is good to ~1e-5 (a 1e-5 tilt moves the Bai rotor's flat period-4 peak
        by 1e-4 Hz); along = the observables' extremes and their derivatives in mu, the slope's
        parameter part (extrema.amplitudes_and_slope)."""
        step = LOCKED_STEP * max(1.0, abs(X[-1]))
        (hi, lo, d_hi, d_lo), dphi, status, n_rhs = extrema.parameter_pass(
            self.model.kernel, X[:-1], self.params, self.lam(X), step * self.scale, float(self.periods),
            np.ascontiguousarray(self.weights), self.opts)
        return dphi * self.scale, (hi, lo, d_hi * self.scale, d_lo * self.scale), status, n_rhs

    def refined(self, settings, factor):
        """(family, settings) with the integrator's error and the corrector's tolerance `factor`
        times theirs (fixed-step RK4: factor^(-1/4) times the steps, its error ~ h^4)."""
        if type(self.opts) is ig.Dop853Settings:
            opts = self.opts._replace(rtol=self.opts.rtol * factor, atol=self.opts.atol * factor)
        else:
            opts = self.opts._replace(steps_per_unit=self.opts.steps_per_unit * factor ** -0.25)
        return self._replace(opts=opts), replace(settings, tol=settings.tol * factor)

    def resolved(self, point, a, settings, factor, counter):
        """`point` re-solved on its own hyperplane at `factor` times the tolerances (`refined`): a
        Point, or None where it fails."""
        family, changed = self.refined(settings, factor)
        sol, failure = family.correct(point.X, point.tangent, point.tangent @ point.X, a, changed, counter)
        again = None if failure is not None else family.point(sol, a, changed, counter)
        return again if again is not None and np.isfinite(again.slope) else None

    def peak_error(self, point, a, b, settings, counter):
        """(lambda error estimate, smooth) of a peak located at `point` between the steps' points a
        and b: the slope's error over d slope / d sigma (the slope's secant over the step; the peak
        a smooth maximum, its slope near linear there), plus the location's tolerance, both along
        the tangent's lambda component, plus the reference's own move in lambda. The slope's
        error: the largest difference from the reference (the point re-solved at 1 / REFINE times
        the tolerances) of its slope and of the point's re-solved at the TOLERANCE_SPREAD factors
        (`resolved`). smooth: the located |slope| is within KINK_MARGIN of what they explain (else
        a jump of the slope, no maximum). inf and True where a re-solve fails."""
        others = [self.resolved(point, a, settings, f, counter) for f in (1.0 / REFINE,) + TOLERANCE_SPREAD]
        if any(p is None for p in others):
            return np.inf, True
        reference = others[0]
        curvature = (a.slope - b.slope) / float(a.tangent @ (b.X - a.X))
        d_slope = max(abs(p.slope - reference.slope) for p in [point] + others[1:])
        sigma_error = d_slope / curvature + settings.locate_xtol
        error = self.scale * abs(point.tangent[-1]) * sigma_error + abs(reference.lam - point.lam)
        return float(error), abs(point.slope) <= KINK_MARGIN * curvature * sigma_error

    def with_periods(self, periods):
        return self._replace(periods=float(periods))

    def correct(self, X0, c, target, at, settings, counter):
        """Newton on [phi(s, lam) - s = 0, c . X = target] from X0: (Solution, None) or (None,
        failure), failure NEWTON_FAILED or INTEGRATION_FAILED."""
        X = X0.copy()
        for it in range(settings.max_newton + 1):
            r, mono, status, n_rhs = self.return_map(X[:-1], self.lam(X), True)
            counter.n += n_rhs
            if status != ig.STATUS_OK:
                return None, INTEGRATION_FAILED
            res = np.abs(r).max() / max(1.0, np.abs(X[:-1]).max())
            if res <= settings.tol:
                return Solution(X, mono, it, res, r), None
            if it == settings.max_newton:
                break
            dphi, status, n_rhs = self.dphi_dmu(X, settings.fd_step, r if it == 0 else None)
            counter.n += n_rhs
            if status != ig.STATUS_OK:
                return None, INTEGRATION_FAILED
            try:
                X = X + np.linalg.solve(_bordered(mono, dphi, c), np.append(-r, target - c @ X))
            except np.linalg.LinAlgError:
                break
        return None, NEWTON_FAILED

    def point(self, sol, at, settings, counter):
        """The Point of a converged solution (dphi/dmu and tangent there); None if the flow failed."""
        along = None
        if self.peak >= 0:
            dphi, along, status, n_rhs = self.parameter_pass(sol.X)
        else:
            dphi, status, n_rhs = self.dphi_dmu(sol.X, settings.fd_step, sol.r)
        counter.n += n_rhs
        if status != ig.STATUS_OK:
            return None
        try:
            t = engine.tangent(_bordered(sol.monodromy, dphi, at.tangent))
        except np.linalg.LinAlgError:
            return None
        amplitudes, slope, n_rhs = self.measures(sol.X, t, along)
        counter.n += n_rhs
        return Point(sol.X, self.lam(sol.X), sol.monodromy, sol.multipliers, t, dphi, sol.iterations, sol.residual,
                     amplitudes, slope)

    def extremes(self, X, rows):
        """(highest, lowest, n_rhs) of the observables weights[rows] over the orbit from X's state."""
        hi, lo, _, _, _, n_rhs = extrema.orbit_extent(self.model.kernel, X[:-1], self.params(self.lam(X)),
                                                      float(self.periods), np.ascontiguousarray(self.weights[rows]),
                                                      self.opts, False)
        return hi, lo, n_rhs

    def measures(self, X, t, along=None):
        """(amplitudes, slope, n_rhs) of a point at X with tangent t (None, NaN, 0 without weights);
        along: its `parameter_pass` extremes where the point has them (else taken here)."""
        if self.weights is None:
            return None, np.nan, 0
        if self.peak < 0:
            hi, lo, n_rhs = self.extremes(X, slice(None))
            return np.array([np.maximum(hi, -lo), 0.5 * (hi - lo)]), np.nan, n_rhs
        spent = 0
        if along is None:
            _, along, _, spent = self.parameter_pass(X)
        amplitudes, slope, n_rhs = extrema.amplitudes_and_slope(
            self.model.kernel, X, t, self.params(self.lam(X)), float(self.periods), np.ascontiguousarray(self.weights),
            self.peak, self.opts, along)
        return amplitudes, slope, n_rhs + spent

    def where(self, point):
        return f"lambda = {point.lam!r}"

    def solves_edge(self, k, edge):
        return True


def _bordered(mono, dphi, c):
    """[[M - I, dphi/dmu], [c]]: the Jacobian of phi(s, lam) - s in X bordered by the row c."""
    n = dphi.size
    A = np.empty((n + 1, n + 1))
    A[:n, :n] = mono - np.eye(n)
    A[:n, n] = dphi
    A[n] = c
    return A


class Event(NamedTuple):
    kind: int               # EVENT_TYPES index
    point: Point            # the located point
    index: int              # the branch point before it
    evaluations: int        # correctors spent locating it
    lam_error: float = np.nan   # the located lambda's error estimate (peaks: Family.peak_error; NaN: not estimated)


class Branch(NamedTuple):
    points: list            # Point, in the order of travel
    events: list            # Event
    end: int                # END_REASONS index
    detail: str             # human-readable detail of the end
    periods: float
    n_rhs: int


def start(family, lam0, guess, direction=1, settings=Settings(), counter=None):
    """The first point: Newton shooting at fixed lam0 from `guess` (a state near the orbit, e.g.
    from natural continuation or a settled transient), tangent pointing to increasing lambda
    for direction = +1, decreasing for -1. Returns a Point or None."""
    counter = counter or Counter()
    X = np.append(np.asarray(guess, float), lam0 / family.scale)
    c = np.zeros(X.size)
    c[-1] = 1.0
    patient = replace(settings, max_newton=max(settings.max_newton, START_NEWTON))
    seed = engine.Seed(direction * c)
    sol, failure = family.correct(X, c, X[-1], seed, patient, counter)
    if failure is not None:
        return None
    return family.point(sol, seed, settings, counter)


class Rejoin(ev.BranchPoint):
    """A branch point on a switched period-2k branch: it met its period-k parent; the branch ends."""
    end = REJOINED

    def end_detail(self, family, point, a, b):
        return f"met the period-{family.periods / 2:g} branch {ev.at_or_between(family, point, a, b)}"


def follow_branch(family, first, lam_range, settings=Settings(), stop_at_branch_point=False, counter=None):
    """Pseudo-arclength continuation from the Point `first` (its tangent gives the direction)
    until lambda leaves lam_range = (lo, hi), the branch closes, the step budget is spent, or the
    corrector fails at the minimum step (engine.follow). Events are located as they are passed. A
    switched period-2k branch (stop_at_branch_point) ends where it meets its period-k parent (a
    branch point)."""
    counter = counter or Counter()
    # located with this module's root finder, looked up at each call (it can be replaced)
    events = ev.orbit_events(brent_root, Rejoin if stop_at_branch_point else ev.BranchPoint)
    events += (ev.Peak(brent_root),) if family.peak >= 0 else ()
    run = engine.follow(family, first, [lam_range], settings, events, counter)
    located = [_with_error(family, run.points, Event(f.event.code, f.point, f.index, f.evaluations), settings,
                           counter) for f in run.found]
    return Branch(run.points, [e for e in located if e is not None], run.end, run.detail, family.periods, counter.n)


def _with_error(family, points, event, settings, counter):
    """A located peak with its error estimate (Family.peak_error), None where it is no smooth
    maximum (dropped); other events as they are."""
    if event.kind != PEAK or event.point is None:
        return event
    b = points[event.index + 1] if event.index + 1 < len(points) else points[0]   # a closed loop's last step
    error, smooth = family.peak_error(event.point, points[event.index], b, settings, counter)
    return event._replace(lam_error=error) if smooth else None


def continue_orbit(family, lam0, guess, lam_range, settings=Settings(), direction=1):
    """Start at lam0 from `guess` and follow the branch in `direction` (+1: increasing lambda).
    Settings that cannot work raise ValueError before any work."""
    problems = settings.problems()
    if problems:
        raise ValueError("continuation settings: " + "; ".join(problems))
    counter = Counter()
    first = start(family, lam0, guess, direction, settings, counter)
    if first is None:
        return Branch([], [], START_FAILED, f"no periodic orbit converged at lambda = {lam0!r}",
                      family.periods, counter.n)
    return follow_branch(family, first, lam_range, settings, counter=counter)


def switch_period_doubling(family, event, lam_range, settings=Settings()):
    """Follow the period-2k branch born at a located period-doubling event of a period-k branch.

    The critical eigenvector v (M v = -v) spans the new branch's direction in state space: the
    first point is corrected on the hyperplane d . (X - X_pd) = ds, with d the part of (v, 0)
    orthogonal to the period-k tangent, so the period-k branch (which meets that hyperplane only
    O(sqrt(ds)) away) is not where Newton lands. The period-2k problem is then continued from
    there, away from the event, until it meets its parent again or leaves the range."""
    counter = Counter()
    pd = event.point
    doubled = family.with_periods(2 * family.periods)
    lams, vecs = np.linalg.eig(pd.monodromy)
    v = np.real(vecs[:, np.argmin(np.abs(lams + 1.0))])
    d = np.append(v / np.linalg.norm(v), 0.0)
    d -= (d @ pd.tangent) * pd.tangent
    d /= np.linalg.norm(d)
    ds = settings.ds
    while ds >= settings.ds_min:
        sol, failure = doubled.correct(pd.X + ds * d, d, d @ pd.X + ds, engine.Seed(d), settings, counter)
        if failure is None and _is_new_orbit(family, sol.X, settings):
            first = doubled.point(sol, engine.Seed(d), settings, counter)
            if first is not None:
                turn = 1.0 if first.tangent @ (sol.X - pd.X) >= 0 else -1.0
                first = first._replace(tangent=turn * first.tangent, slope=turn * first.slope)
                return follow_branch(doubled, first, lam_range, settings, True, counter)
        ds /= 2.0
    return Branch([], [], START_FAILED, f"no period-{2 * family.periods:g} orbit found next to the period "
                  f"doubling at lambda = {pd.lam!r}", doubled.periods, counter.n)


def _is_new_orbit(family, X, settings):
    """The corrected orbit is not the period-k orbit traversed twice: phi_k(s) != s."""
    r, _, status, _ = family.return_map(X[:-1], family.lam(X), False)
    return status == ig.STATUS_OK and np.abs(r).max() > 1e3 * settings.tol * max(1.0, np.abs(X[:-1]).max())


def orbit_samples(family, point, n_per_period=64):
    """States along the orbit of a point (n_per_period per forcing period)."""
    return family.problem(point.lam).samples(point.state, n_per_period)


def summary(branch):
    """Short text: points, events with their parameter values, how it ended."""
    lines = [f"{len(branch.points)} points, period {branch.periods:g}, ended: {END_REASONS[branch.end]} ({branch.detail})"]
    lines += [f"  {EVENT_LABELS[e.kind]} at lambda = {e.point.lam!r}" for e in branch.events]
    return "\n".join(lines)

"""Pseudo-arclength continuation of invariant tori under two-frequency forcing (a problem class of
`engine.follow`) along one parameter lambda, e.g. the second forcing's frequency omega.

Unknowns X = (U / sqrt(N), mu): the torus's node values U (N x n, rotorsweep.kernels.torus) weighted
by 1 / sqrt(N) (`TorusFamily.weight`), and mu = lambda / scale. The weight makes the engine's
Euclidean arclength count the circle like one orbit's state: |dX|^2 = the nodes' mean square change
+ dmu^2, the circle's mean square over its phase where N resolves it (Parseval), the same at every
node count (unweighted, a circle on 63 nodes counted sqrt(63) times one state: a step's meaning
changed with N). The scale then sets how a step splits between the parameter and the circle.
Equations: the collocation residual R(U, lambda) = 0 (the rotation rho(lambda) and the kernel
vector p(lambda) both follow lambda) and one scalar condition c . X = target. Bordered chord Newton
(TorusFamily.correct: the matrix kept while it converges fast) with dR/dX from the nodes'
monodromies and the shift operator (over the weight), dR/dmu by a difference of plain collocation
residuals (forward in the corrector, central for the tangent; as arclength.Family's dphi/dmu it
enters only the Newton matrix and the tangent, never the residual).

The imposed forcing phase is the torus coordinate, so a rational ratio omega / Omega = p / q is
no special point: there the circle is the union of the q-periodic orbits' stroboscopic points
over the forcing phases, and the branch passes through it.

The node count N adapts to the circle's spectral decay (`follow_tori`): N is fixed within a run of
the engine (X keeps its size), and a run ends where an accepted point's N no longer fits its circle
(`Resolution`): its Fourier tail exceeds the decay tolerance (N -> 2N + 1), or the tail the next
coarser count would have (the circle resampled there) is below torus.COARSEN times it (N -> (N -
1) / 2, odd): the gap of 1/COARSEN (1e3) between the two thresholds is the hysteresis that keeps N
from oscillating. The point is then solved again at the new count at its lambda (its circle
re-interpolated, i.e. its Fourier coefficients zero-padded or truncated, its tangent likewise) and
the next run goes on from it. At the top count (2N + 1 beyond max_nodes) the tail may rise to the
family's breakdown_tol (default: the decay tolerance) before the branch ends with
`torus_breakdown` (as does a growth whose re-solve fails) (the circle is losing smoothness: no N within the
bounds resolves it); a coarser count whose re-solve misses the tolerance is not tried again on that
branch. Default bounds min_nodes = max_nodes = the family's n_nodes: a fixed count.

The branch flags a change of normal stability (`TS`: the largest normal Lyapunov exponent changes
sign) and a fold of tori (`TF`: the branch turns back in lambda), each located after the engine's
run on the corrected points between the step's two (`locate_flags`: Brent on the arclength, TF at
the zero of d mu / ds, TS at the zero of the exponent to the arclength its own error estimate
allows, kept as a bracket with the reason where that error hides the sign), and solves the torus exactly
where the rotation is 2 pi p / q with small q (`Locked`: there the circle consists of q-periodic
points, which the caller links to the periodic-orbit solver's orbits).
"""
import warnings
from dataclasses import replace
from typing import Callable, NamedTuple

import numpy as np

from rotorsweep.kernels import torus as tr
from rotorsweep.kernels.continuation import engine, events as ev
from rotorsweep.kernels.continuation.engine import INTEGRATION_FAILED, NEWTON_FAILED, START_NEWTON, TORUS_BREAKDOWN
from rotorsweep.kernels.roots import brent_root


CONTRACTION = 0.1   # a chord step must cut the residual this much to keep its matrix (TorusFamily.correct)


class Solution(NamedTuple):
    X: np.ndarray
    jacobian: np.ndarray    # dR/dU at X
    monodromies: np.ndarray
    iterations: int
    residual: float


class Point(NamedTuple):
    X: np.ndarray           # (U.ravel() / sqrt(N), mu): TorusFamily.unknowns
    lam: float
    tangent: np.ndarray
    iterations: int
    residual: float
    tail: float             # the circle's Fourier tail (torus.fourier_tail)
    stability: tr.Stability
    monodromies: np.ndarray


class TorusFamily(NamedTuple):
    """Tori of `kernel` along lambda: params(lambda) -> kernel vector p, rotation(lambda) -> rho.
    An engine problem (engine's contract)."""
    kernel: object
    params: Callable
    rotation: Callable
    phase_index: int
    opts: object
    n_nodes: int            # the current node count (follow_tori's runs: each run's own)
    scale: float = 1.0
    period: float = 1.0
    decay_tol: float = 1e-8
    min_nodes: int = 0      # bounds of the adaptive node count (0: n_nodes, a fixed count)
    max_nodes: int = 0
    breakdown_tol: float = 0.0  # the tail that ends the branch at max_nodes (0: decay_tol)
    on_point: Callable = None   # called with each point solved (a caller's progress; None: none)

    @property
    def node_bounds(self):
        return (self.min_nodes or self.n_nodes, self.max_nodes or self.n_nodes)

    @property
    def parameters(self):
        return (("lambda", -1, self.scale),)

    def lam(self, X):
        return float(X[-1] * self.scale)

    def weight(self, n_nodes):
        """The node values' weight in the unknowns at n_nodes nodes: 1 / sqrt(N) (module docstring)."""
        return 1.0 / np.sqrt(n_nodes)

    def node_weight(self, X):
        """The weight of X's node part (N from X's size)."""
        return self.weight((X.size - 1) // self.kernel.n_state)

    def nodes(self, X):
        """U (N, n) of unknowns X, N from X's size (points of one branch may differ in N)."""
        return X[:-1].reshape(-1, self.kernel.n_state) / self.node_weight(X)

    def unknowns(self, nodes, lam):
        """X of node values U (N, n) at lambda (the inverse of nodes and lam)."""
        nodes = np.asarray(nodes, float)
        return np.append(nodes.ravel() * self.weight(nodes.shape[0]), lam / self.scale)

    def torus(self, point):
        """The point's circle as a `torus.Torus` (its error estimate not computed: nan)."""
        lam = self.lam(point.X)
        return tr.Torus(self.nodes(point.X), float(self.rotation(lam)), self.period, tr.CONVERGED,
                        point.iterations, point.residual, point.tail, np.nan, point.monodromies, 0)

    def residual(self, X, variational):
        """torus.collocation's (R, Jacobian, monodromies, ok, n_rhs) at X, the Jacobian dR/dX
        (in the unknowns: dR/dU / node_weight; `circle_jacobian` undoes it)."""
        lam = self.lam(X)
        r, jac, monos, ok, n_rhs = tr.collocation(self.kernel, self.nodes(X), self.params(lam), self.phase_index,
                                                  self.rotation(lam), self.period, self.opts, variational)
        return r, (None if jac is None else jac / self.node_weight(X)), monos, ok, n_rhs

    def circle_jacobian(self, X, jacobian):
        """dR/dU (torus.error_estimate's) of residual's dR/dX at X."""
        return jacobian * self.node_weight(X)

    def dr_dmu(self, X, fd_step, r=None):
        """dR/dmu by a difference of plain collocation residuals: central, or forward from r = R(X)
        where given (one residual instead of two; its O(fd_step) error, ~1e-5 relative, only slows
        the chord corrector, whose frozen matrix is O(ds) off anyway, and never moves its
        solution, which is judged on R alone): (column or None, n_rhs)."""
        step = fd_step * max(1.0, abs(X[-1]))
        cols, n_rhs = [], 0
        for sign in (1.0,) if r is not None else (1.0, -1.0):
            Y = X.copy()
            Y[-1] += sign * step
            ry, _, _, ok, nr = self.residual(Y, False)
            n_rhs += nr
            if not ok:
                return None, n_rhs
            cols.append(ry.ravel())
        if r is not None:
            return (cols[0] - r.ravel()) / step, n_rhs
        return (cols[0] - cols[1]) / (2.0 * step), n_rhs

    def shifted_jacobian(self, at, X):
        """dR/dX (dR/dU over the node weight) at X from the monodromies of `at` (a point of X's node count; None for a Seed or
        another count) and the shift operator at X's rotation: the chord's first matrix."""
        monos = getattr(at, "monodromies", None)
        n_nodes = self.nodes(X).shape[0]
        if monos is None or monos.shape[0] != n_nodes or not np.isfinite(monos).all():
            return None
        phases = tr.node_phases(n_nodes) + self.rotation(self.lam(X))
        return tr.collocation_jacobian(monos, tr.interpolation_matrix(n_nodes, phases)) / self.node_weight(X)

    def correct(self, X0, c, target, at, settings, counter):
        """Chord Newton on [R(U, lambda) = 0, c . X = target]: (Solution, None) or (None, failure).

        The bordered matrix is factored once and kept while each step cuts the residual at least
        1 / CONTRACTION-fold: first from the monodromies of `at` (the last point; shifted_jacobian),
        else and wherever a step falls short from the variational equations where the corrector
        stands. Its steps need only plain collocations (a variational one costs ~8 at n = 10);
        convergence is judged on R, then confirmed by one variational collocation at the
        solution, whose monodromies are the point's (stability, tangent): the solution meets the
        same tolerance as a full Newton's, and differs from it by at most that residual times
        ||dR/dX^-1|| (tests/test_tori_corrector.py)."""
        X, res, solve = X0.copy(), np.inf, None
        jac = self.shifted_jacobian(at, X0)
        for it in range(settings.max_newton + 1):
            r, _, _, ok, n_rhs = self.residual(X, False)
            counter.n += n_rhs
            if not ok:
                return None, INTEGRATION_FAILED
            last, res, base = res, _relative(r, self.nodes(X)), r
            stale = solve is None or res > CONTRACTION * last
            if res <= settings.tol or (stale and jac is None):
                r, jac, monos, ok, n_rhs = self.residual(X, True)
                counter.n += n_rhs
                if not ok:
                    return None, INTEGRATION_FAILED
                res = _relative(r, self.nodes(X))
                if res <= settings.tol:
                    return Solution(X, jac, monos, it, res), None
                stale = True
            if it == settings.max_newton:
                break
            if stale:
                col, n_rhs = self.dr_dmu(X, settings.fd_step, base)
                counter.n += n_rhs
                solve, jac = (None if col is None else _factored(_bordered(jac, col, c))), None
                if solve is None:
                    return (None, INTEGRATION_FAILED) if col is None else (None, NEWTON_FAILED)
            X = X + solve(np.append(-r.ravel(), target - c @ X))
        return None, NEWTON_FAILED

    def point(self, sol, at, settings, counter):
        col, n_rhs = self.dr_dmu(sol.X, settings.fd_step)
        counter.n += n_rhs
        if col is None:
            return None
        try:
            t = engine.tangent(_bordered(sol.jacobian, col, at.tangent))
        except np.linalg.LinAlgError:
            return None
        lam = self.lam(sol.X)
        nodes = self.nodes(sol.X)
        circle = tr.Torus(nodes, float(self.rotation(lam)), self.period, tr.CONVERGED, sol.iterations,
                          sol.residual, 0.0, np.nan, sol.monodromies, 0)
        point = Point(sol.X, lam, t, sol.iterations, sol.residual, tr.fourier_tail(nodes),
                      tr.stability(circle), sol.monodromies)
        if self.on_point is not None:
            self.on_point(point)
        return point

    def where(self, point):
        return f"lambda = {point.lam!r}"

    def solves_edge(self, k, edge):
        return True


def polish(family, point, tol, max_iter=3):
    """(point, jacobian): the point with its circle refined by Newton at its fixed lambda until
    max |R| <= tol max(1, max |U|) (at most max_iter steps; where a step cannot be solved, the
    point as far as it got), and dR/dX (family.residual's) at the returned circle, None where its
    shots failed. The corrector stops at the continuation's tolerance, relative to the largest
    node value, so its absolute residual varies from point to point by orders of magnitude
    (quadratic convergence lands anywhere below it), and the circle's distance from the invariant
    one is that residual times ||dR/dU^-1||. Each iterate is judged on a variational collocation
    (the point's monodromies do not serve the first: with the variational equations the
    integrator controls the error of every component, so its u, and R, differ from a plain
    collocation's by the integration error, ~1e-9 here); the last one's Jacobian is returned, the
    error estimate's (torus.error_estimate) at the polished circle."""
    X = point.X.copy()
    for it in range(max_iter + 1):
        r, jac, _, ok, _ = family.residual(X, True)
        if not ok or it == max_iter or np.abs(r).max() <= tol * max(1.0, np.abs(family.nodes(X)).max()):
            break
        try:
            X[:-1] += np.linalg.solve(jac, -r.ravel())
        except np.linalg.LinAlgError:
            break
    return point._replace(X=X, tail=tr.fourier_tail(family.nodes(X))), (jac if ok else None)


def _relative(r, nodes):
    """max |R| relative to max(1, max |U|) (U the node values, unweighted): the corrector's measure."""
    return np.abs(r).max() / max(1.0, np.abs(nodes).max())


def _factored(matrix):
    """b -> matrix^-1 b by the LU factors of a bordered matrix (scipy.linalg, imported here: a
    command that follows no torus does not load it), None where it is singular or not finite."""
    import scipy.linalg
    if not np.isfinite(matrix).all():
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
        lu = scipy.linalg.lu_factor(matrix)
    if not np.all(np.diag(lu[0]) != 0.0):
        return None
    return lambda b: scipy.linalg.lu_solve(lu, b)


def _bordered(jac, col, c):
    m = col.size
    A = np.empty((m + 1, m + 1))
    A[:m, :m] = jac
    A[:m, m] = col
    A[m] = c
    return A


def acceptable_tail(family, n_nodes):
    """The largest tail a circle on n_nodes nodes may keep: the decay tolerance while the count can
    still grow within max_nodes, the breakdown tolerance at the top of the ladder."""
    top = 2 * n_nodes + 1 > family.node_bounds[1]
    return (family.breakdown_tol or family.decay_tol) if top else family.decay_tol


def wanted_nodes(family, point):
    """The node count the point's circle asks for: 2N + 1 where its tail exceeds the acceptable one
    (even beyond max_nodes: the caller ends the branch there), the coarser count
    where the circle resampled there keeps its tail below COARSEN times the tolerance (not below
    min_nodes; torus.coarser_tail, as torus.coarsened's), else its own N."""
    nodes = family.nodes(point.X)
    n_nodes = nodes.shape[0]
    if point.tail > acceptable_tail(family, n_nodes):
        return 2 * n_nodes + 1
    small = tr.coarser(n_nodes)
    if small >= family.node_bounds[0] and tr.coarser_tail(nodes) <= tr.COARSEN * family.decay_tol:
        return small
    return n_nodes


class Resolution(ev.BranchEvent):
    """The point's node count no longer fits its circle (wanted_nodes): the engine's run ends there;
    follow_tori solves it again at the count it wants, or ends the branch (torus_breakdown) when
    that count exceeds max_nodes."""
    label, code, locates, end = "TB", "torus_breakdown", False, TORUS_BREAKDOWN

    def detect(self, problem, a, b):
        return wanted_nodes(problem, b) != problem.nodes(b.X).shape[0]

    def end_detail(self, problem, point, a, b):
        n_nodes = problem.nodes(b.X).shape[0]
        return (f"Fourier decay failed at {problem.where(b)}: tail {b.tail:.2g} > "
                f"{acceptable_tail(problem, n_nodes):g} with {n_nodes} nodes (at most {problem.node_bounds[1]})")


class StabilityChange(ev.BranchEvent):
    """The largest normal Lyapunov exponent changes sign (a fold of tori or a loss of normal
    hyperbolicity). The sign is read even where a point is undecided (its exponent within its
    error of 0): next to a fold both points around the crossing are (filipkovsky2016_torus_fold
    over 380-420 Hz: -0.71 and +0.31 1/s), and a rule on decided statuses alone missed it; a point
    without exponents (NaN) never flags. A flag to the engine, located afterwards (locate_flags)."""
    label, code, locates, end = ev.EVENT_LABELS[ev.TORUS_STABILITY], ev.TORUS_STABILITY, False, None

    def detect(self, problem, a, b):
        ea, eb = a.stability.exponents[0], b.stability.exponents[0]
        return bool(np.isfinite(ea) and np.isfinite(eb) and (ea < 0) != (eb < 0))

    def place(self, problem, a, b, settings, counter):
        """(point, correctors spent, Location): the zero of the largest exponent by Brent on the
        arclength, to the arclength ds_e = spread / |slope| over which the exponent's own error
        (Stability.spread, the larger of the two ends') hides its sign (slope: the exponent's
        secant over the step). Where 2 ds_e reaches the step (small steps near a fold), Brent has
        nothing to refine: the secant's zero, corrected once, to that same 2 ds_e, which then
        exceeds the step (an honest error bar rather than no value: the flag was raised)."""
        sigma_b = float(a.tangent @ (b.X - a.X))
        ea, eb = a.stability.exponents[0], b.stability.exponents[0]
        spread = max(a.stability.spread, b.stability.spread)
        ds_e = spread * abs(sigma_b / (eb - ea))
        if 2.0 * ds_e >= abs(sigma_b):
            return _located(problem, a, b, _secant_zero(problem, a, sigma_b * ea / (ea - eb), settings, counter),
                            2.0 * ds_e, settings)
        found = engine.locate_zero(problem, a, b, lambda sol: _as_point(problem, sol, a, settings, counter)
                                   .stability.exponents[0], replace(settings, locate_xtol=max(ds_e, settings.locate_xtol)),
                                   counter)
        return _located(problem, a, b, found, 2.0 * ds_e, settings)  # the estimate's zero within ds_e, Brent's too


class Fold(ev.BranchEvent):
    """A fold of tori: the tangent's parameter component d mu / ds changes sign (the branch turns
    back in lambda). A flag to the engine, located afterwards (locate_flags) at the zero of d mu /
    ds by Brent on the arclength to the engine's locate_xtol: lambda is stationary there, so its
    error is the corrector's (corrector_error), not the arclength's."""
    label, code, locates, end = ev.EVENT_LABELS[ev.TORUS_FOLD], ev.TORUS_FOLD, False, None

    def detect(self, problem, a, b):
        return a.tangent[-1] * b.tangent[-1] < 0

    def place(self, problem, a, b, settings, counter):
        """(point, correctors spent, Location)."""
        found = engine.locate_zero(problem, a, b, lambda sol: _as_point(problem, sol, a, settings, counter).tangent[-1],
                                   settings, counter)
        return _located(problem, a, b, found, settings.locate_xtol, settings)


class Location(NamedTuple):
    """Where a flag was located (locate_flags): lam_error the located lambda's error estimate
    (physical units; NaN where not located), bracket the lambdas of the step's two points, reason
    why it was not located ("" where it was)."""
    lam_error: float
    bracket: tuple
    reason: str


class LocatedFlag(NamedTuple):
    """A TS or TF flag after location: what a Found's event is then (its code and label, and
    where it was located)."""
    code: int
    label: str
    location: Location


def _as_point(problem, solution, a, settings, counter):
    """A corrector's solution made a point (its tangent and stability; a Point, e.g. a step's end,
    as it is); ValueError where it has no tangent (engine.locate_zero then gives up)."""
    if isinstance(solution, Point):
        return solution
    point = problem.point(solution, a, settings, counter)
    if point is None:
        raise ValueError("no tangent at a corrector's solution")
    return point


def _secant_zero(problem, a, sigma, settings, counter):
    """(the point corrected at arclength sigma from a, 1 corrector spent), or None where it fails
    (engine.locate_zero's answer, for one corrector)."""
    sol, failure = engine.on_arclength(problem, a, sigma, settings, counter)
    point = None if failure is not None else problem.point(sol, a, settings, counter)
    return None if point is None else (point, 1)


def _located(problem, a, b, found, ds, settings):
    """(point, correctors spent, Location) of engine.locate_zero's answer `found`, the located
    point's arclength known to ds: its lambda to |d lambda / ds| ds plus the curvature's term
    (the tangent's parameter component's change over the step times ds^2 / 2), plus the
    corrector's own error (corrector_error)."""
    bracket = (a.lam, b.lam)
    if found is None:
        return None, 0, Location(np.nan, bracket, "the branch could not be followed between the points, or Brent "
                                                  "did not converge")
    point, spent = found
    sigma_b = float(a.tangent @ (b.X - a.X))
    bend = abs((b.tangent[-1] - a.tangent[-1]) / sigma_b)
    err = problem.scale * (abs(point.tangent[-1]) * ds + 0.5 * bend * ds ** 2)
    return point, spent, Location(err + corrector_error(problem, point, settings), bracket, "")


def corrector_error(problem, point, settings):
    """The lambda error of a point solved to the corrector's tolerance: its residual, at most tol
    max(1, max |U|), times the norm of the inverse bordered Jacobian [dR/dU dR/dmu; t] (the
    distance from the exact branch point on its hyperplane), in lambda's units (inf where the
    point's shots or the Jacobian fail)."""
    _, jac, _, ok, _ = problem.residual(point.X, True)
    col, _ = problem.dr_dmu(point.X, settings.fd_step)
    if not ok or col is None:
        return np.inf
    smallest = np.linalg.svd(_bordered(jac, col, point.tangent), compute_uv=False)[-1]
    bound = settings.tol * max(1.0, np.abs(point.X[:-1]).max()) / smallest if smallest > 0 else np.inf
    return float(problem.scale * bound)


def locate_flags(problem, run, settings, counter):
    """The run with its TS and TF flags located: each such Found gets the located point (None where
    not located), the correctors spent and a LocatedFlag as its event (module docstring). The
    flags are located after the run, not by the engine, so that one not located keeps its row
    (the engine drops a located event it cannot locate)."""
    def placed(f):
        if not isinstance(f.event, (StabilityChange, Fold)):
            return f
        a = run.points[f.index]
        b = run.points[f.index + 1] if f.index + 1 < len(run.points) else run.points[0]  # a closed loop's last step
        point, spent, where = f.event.place(problem, a, b, settings, counter)
        return f._replace(event=LocatedFlag(f.event.code, f.event.label, where), point=point, evaluations=spent)
    return run._replace(found=[placed(f) for f in run.found])


class Locked(ev.Level):
    """Where the rotation is 2 pi p / q (a locked ratio of the two forcings): the torus solved
    exactly there. Its circle is then made of q-periodic points (P_theta^q(u(theta)) = u(theta +
    2 pi p) = u(theta)), each the periodic orbit of the forcing with that phase."""
    code = ev.LOCKED

    def __init__(self, level, p, q):
        super().__init__(level)
        self.p, self.q = p, q
        self.label = f"{ev.EVENT_LABELS[ev.LOCKED]} {p}/{q}"


def locked_ratios(family, lam_range, max_q):
    """The Locked events within lam_range: each ratio p / q (q <= max_q, lowest terms) that the
    rotation rho(lambda) / 2 pi takes there, at the lambda where it does (Brent on rho, which is
    monotone in lambda when lambda is either forcing frequency)."""
    lo, hi = sorted(lam_range)
    r_lo, r_hi = sorted(family.rotation(v) / (2.0 * np.pi) for v in (lo, hi))
    out = []
    for q in range(1, max_q + 1):
        for p in range(int(np.ceil(r_lo * q)), int(np.floor(r_hi * q)) + 1):
            if np.gcd(p, q) == 1 and p > 0:
                target = 2.0 * np.pi * p / q
                lam = brent_root(lambda v: family.rotation(v) - target, lo, hi, xtol=1e-13 * max(abs(lo), abs(hi)))
                out.append(Locked(lam, p, q))
    return sorted(out, key=lambda e: e.level)


def solve_at_lambda(family, X, seed, settings, counter):
    """The point at X's lambda from unknowns X (Newton at fixed lambda, START_NEWTON steps), its
    tangent oriented like seed.tangent: a Point or None."""
    c = np.zeros(X.size)
    c[-1] = 1.0
    sol, failure = family.correct(X, c, X[-1], seed, replace(settings, max_newton=START_NEWTON), counter)
    return None if failure is not None else family.point(sol, seed, settings, counter)


def start(family, lam0, guess, direction=1, settings=engine.Settings(), counter=None):
    """The first point at lambda = lam0 from node values `guess` (N x n, e.g. torus.solve_torus's),
    tangent towards increasing lambda for direction = +1. A Point or None."""
    X = family.unknowns(guess, lam0)
    e_mu = np.zeros(X.size)
    e_mu[-1] = direction
    return solve_at_lambda(family, X, engine.Seed(e_mu), settings, counter or engine.Counter())


def resampled(family, vector, n_nodes):
    """Unknowns (or a tangent) with the circle re-interpolated at n_nodes nodes (weighted anew)."""
    return np.append(tr.resample(family.nodes(vector), n_nodes).ravel() * family.weight(n_nodes), vector[-1])


def resolved(family, point, n_nodes, settings, counter):
    """The point solved again with n_nodes nodes at its lambda, from its circle and tangent
    re-interpolated there: a Point, or None where Newton fails or the tail still exceeds the
    acceptable one."""
    t = resampled(family, point.tangent, n_nodes)
    new = solve_at_lambda(family, resampled(family, point.X, n_nodes), engine.Seed(t / np.linalg.norm(t)),
                          settings, counter)
    return new if new is not None and new.tail <= acceptable_tail(family, n_nodes) else None


def refined(family, point, settings, counter):
    """(the point at the node count it wants, grown until its tail is within the decay tolerance,
    or None where that takes more than max_nodes nodes or a re-solve fails; that count)."""
    n_nodes = wanted_nodes(family, point)
    while n_nodes <= family.node_bounds[1]:
        new = resolved(family, point, n_nodes, settings, counter)
        if new is not None or n_nodes < family.nodes(point.X).shape[0]:
            return new, n_nodes
        n_nodes = 2 * n_nodes + 1
    return None, n_nodes


def follow_tori(family, first, lam_range, settings=engine.Settings(), counter=None, max_q=0):
    """engine.follow from `first` within lam_range with the torus events (Resolution, StabilityChange,
    Fold, and Locked at each ratio p / q with q <= max_q), the node count adapted between the
    engine's runs within family.node_bounds (module docstring): a Run whose points may differ in N.
    (A closed loop is recognized only within one run: its first point is that run's.)"""
    counter = counter or engine.Counter()
    events = (Resolution(), StabilityChange(), Fold(), *locked_ratios(family, lam_range, max_q))
    family = family._replace(min_nodes=family.node_bounds[0], max_nodes=family.node_bounds[1])
    points, found, ds = [], [], settings.ds
    while True:
        family = family._replace(n_nodes=family.nodes(first.X).shape[0])
        if len(points) >= settings.max_steps:
            return engine.Run(points + [first], found, engine.STEP_BUDGET, f"{settings.max_steps} steps")
        budget = replace(settings, ds=ds, max_steps=settings.max_steps - len(points))
        run = locate_flags(family, engine.follow(family, first, [tuple(lam_range)], budget, events, counter),
                           settings, counter)
        found += [f._replace(index=f.index + len(points)) for f in run.found if not isinstance(f.event, Resolution)]
        if run.end != TORUS_BREAKDOWN:
            last = run.points[-1]
            if last.tail > acceptable_tail(family, family.n_nodes):   # an edge point (solved after the last step)
                last = refined(family, last, settings, counter)[0] or last
            detail = run.detail.replace(f"{budget.max_steps} steps", f"{settings.max_steps} steps", 1)
            return engine.Run(points + run.points[:-1] + [last], found, run.end, detail)
        b = run.points[-1]
        new, n_nodes = refined(family, b, settings, counter)
        if new is None and n_nodes > family.nodes(b.X).shape[0]:
            return engine.Run(points + run.points, found, run.end, run.detail)
        if new is None:     # a coarser count missed the tolerance: keep this one from here on
            family = family._replace(min_nodes=family.nodes(b.X).shape[0])
            new = b
        points += run.points[:-1]
        ds = _next_step(family, run.points, new, settings)
        first = new


def _next_step(family, points, new, settings):
    """The step to go on with from `new` (a point re-solved at another count): the last chord's
    length measured at the new count."""
    if len(points) < 2:
        return settings.ds
    n_nodes = family.nodes(new.X).shape[0]
    chord = resampled(family, points[-1].X, n_nodes) - resampled(family, points[-2].X, n_nodes)
    return float(np.clip(np.linalg.norm(chord), settings.ds_min, settings.ds_max))

"""Pseudo-arclength continuation of invariant tori under two-frequency forcing (a problem class of
`engine.follow`) along one parameter lambda, e.g. the second forcing's frequency omega.

Unknowns X = (U, mu): the torus's node values U (N x n, rotorsweep.kernels.torus, N fixed along the
branch) and mu = lambda / scale. Equations: the collocation residual R(U, lambda) = 0 (the
rotation rho(lambda) and the kernel vector p(lambda) both follow lambda) and one scalar condition
c . X = target. Bordered Newton with dR/dU from the nodes' monodromies and the shift operator,
dR/dmu by a central difference of two plain collocation residuals (as arclength.Family's
dphi/dmu: it enters only the Newton matrix and the tangent, never the residual).

The imposed forcing phase is the torus coordinate, so a rational ratio omega / Omega = p / q is
no special point: there the circle is the union of the q-periodic orbits' stroboscopic points
over the forcing phases, and the branch passes through it. A branch ends with
`torus_breakdown` where the circle's Fourier tail exceeds the decay tolerance at the branch's N
(it is losing smoothness: N no longer resolves it), flags a change of normal stability
(`TS`: the largest normal Lyapunov exponent changes sign) and a fold of tori (`TF`: the branch
turns back in lambda), and solves the torus exactly where the rotation is 2 pi p / q with small q
(`Locked`: there the circle consists of q-periodic points, which the caller links to the
periodic-orbit solver's orbits).
"""
from dataclasses import replace
from typing import Callable, NamedTuple

import numpy as np

from rotorsweep.kernels import torus as tr
from rotorsweep.kernels.continuation import engine, events as ev
from rotorsweep.kernels.continuation.engine import INTEGRATION_FAILED, NEWTON_FAILED, START_NEWTON, TORUS_BREAKDOWN
from rotorsweep.kernels.roots import brent_root


class Solution(NamedTuple):
    X: np.ndarray
    jacobian: np.ndarray    # dR/dU at X
    monodromies: np.ndarray
    iterations: int
    residual: float


class Point(NamedTuple):
    X: np.ndarray           # (U.ravel(), mu)
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
    n_nodes: int
    scale: float = 1.0
    period: float = 1.0
    decay_tol: float = 1e-8

    @property
    def parameters(self):
        return (("lambda", -1, self.scale),)

    def lam(self, X):
        return float(X[-1] * self.scale)

    def nodes(self, X):
        return X[:-1].reshape(self.n_nodes, self.kernel.n_state)

    def torus(self, point):
        """The point's circle as a `torus.Torus` (its error estimate not computed: nan)."""
        lam = self.lam(point.X)
        return tr.Torus(self.nodes(point.X), float(self.rotation(lam)), self.period, tr.CONVERGED,
                        point.iterations, point.residual, point.tail, np.nan, point.monodromies, 0)

    def residual(self, X, variational):
        lam = self.lam(X)
        return tr.collocation(self.kernel, self.nodes(X), self.params(lam), self.phase_index,
                              self.rotation(lam), self.period, self.opts, variational)

    def dr_dmu(self, X, fd_step):
        """Central difference of R in mu: (column or None, n_rhs)."""
        step = fd_step * max(1.0, abs(X[-1]))
        cols, n_rhs = [], 0
        for sign in (1.0, -1.0):
            Y = X.copy()
            Y[-1] += sign * step
            r, _, _, ok, nr = self.residual(Y, False)
            n_rhs += nr
            if not ok:
                return None, n_rhs
            cols.append(r.ravel())
        return (cols[0] - cols[1]) / (2.0 * step), n_rhs

    def correct(self, X0, c, target, at, settings, counter):
        """Newton on [R(U, lambda) = 0, c . X = target]: (Solution, None) or (None, failure)."""
        X = X0.copy()
        for it in range(settings.max_newton + 1):
            r, jac, monos, ok, n_rhs = self.residual(X, True)
            counter.n += n_rhs
            if not ok:
                return None, INTEGRATION_FAILED
            res = np.abs(r).max() / max(1.0, np.abs(X[:-1]).max())
            if res <= settings.tol:
                return Solution(X, jac, monos, it, res), None
            if it == settings.max_newton:
                break
            col, n_rhs = self.dr_dmu(X, settings.fd_step)
            counter.n += n_rhs
            if col is None:
                return None, INTEGRATION_FAILED
            try:
                X = X + np.linalg.solve(_bordered(jac, col, c), np.append(-r.ravel(), target - c @ X))
            except np.linalg.LinAlgError:
                break
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
        return Point(sol.X, lam, t, sol.iterations, sol.residual, tr.fourier_tail(nodes),
                     tr.stability(circle), sol.monodromies)

    def where(self, point):
        return f"lambda = {point.lam!r}"

    def solves_edge(self, k, edge):
        return True


def polish(family, point, tol, max_iter=3):
    """The point with its circle refined by Newton at its fixed lambda until max |R| <= tol max(1,
    max |U|) (at most max_iter steps; the point as it was where a step fails). The corrector stops
    at the continuation's tolerance, relative to the largest node value, so its absolute residual
    varies from point to point by orders of magnitude (quadratic convergence lands anywhere below
    it), and the circle's distance from the invariant one is that residual times ||dR/dU^-1||."""
    X = point.X.copy()
    for _ in range(max_iter):
        r, jac, _, ok, _ = family.residual(X, True)
        if not ok or np.abs(r).max() <= tol * max(1.0, np.abs(X[:-1]).max()):
            break
        try:
            X[:-1] += np.linalg.solve(jac, -r.ravel())
        except np.linalg.LinAlgError:
            break
    return point._replace(X=X, tail=tr.fourier_tail(family.nodes(X)))


def _bordered(jac, col, c):
    m = col.size
    A = np.empty((m + 1, m + 1))
    A[:m, :m] = jac
    A[:m, m] = col
    A[m] = c
    return A


class Breakdown(ev.BranchEvent):
    """The circle's Fourier tail exceeds the family's decay tolerance: the branch ends there."""
    label, code, locates, end = "TB", "torus_breakdown", False, TORUS_BREAKDOWN

    def detect(self, problem, a, b):
        return b.tail > problem.decay_tol

    def end_detail(self, problem, point, a, b):
        return (f"Fourier decay failed at {problem.where(b)}: tail {b.tail:.2g} > {problem.decay_tol:g} "
                f"with {problem.n_nodes} nodes")


class StabilityChange(ev.BranchEvent):
    """The largest normal Lyapunov exponent changes sign (a fold of tori or a loss of normal
    hyperbolicity); a flag between two points. The sign is read even where a point is undecided
    (its exponent within its error of 0): next to a fold both points around the crossing are
    (filipkovsky2016_torus_fold over 380-420 Hz: -0.71 and +0.31 1/s), and a rule on decided
    statuses alone missed it; a point without exponents (NaN) never flags."""
    label, code, locates, end = ev.EVENT_LABELS[ev.TORUS_STABILITY], ev.TORUS_STABILITY, False, None

    def detect(self, problem, a, b):
        ea, eb = a.stability.exponents[0], b.stability.exponents[0]
        return bool(np.isfinite(ea) and np.isfinite(eb) and (ea < 0) != (eb < 0))


class Fold(ev.BranchEvent):
    """A fold of tori: the tangent's parameter component changes sign (the branch turns back in
    lambda); a flag between two points."""
    label, code, locates, end = ev.EVENT_LABELS[ev.TORUS_FOLD], ev.TORUS_FOLD, False, None

    def detect(self, problem, a, b):
        return a.tangent[-1] * b.tangent[-1] < 0


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


def start(family, lam0, guess, direction=1, settings=engine.Settings(), counter=None):
    """The first point at lambda = lam0 from node values `guess` (N x n, e.g. torus.solve_torus's),
    tangent towards increasing lambda for direction = +1. A Point or None."""
    counter = counter or engine.Counter()
    X = np.append(np.asarray(guess, float).ravel(), lam0 / family.scale)
    c = np.zeros(X.size)
    c[-1] = 1.0
    seed = engine.Seed(direction * c)
    sol, failure = family.correct(X, c, X[-1], seed, replace(settings, max_newton=START_NEWTON), counter)
    return None if failure is not None else family.point(sol, seed, settings, counter)


def follow_tori(family, first, lam_range, settings=engine.Settings(), counter=None, max_q=0):
    """engine.follow from `first` within lam_range with the torus events (Breakdown, StabilityChange,
    Fold, and Locked at each ratio p / q with q <= max_q): a Run."""
    events = (Breakdown(), StabilityChange(), Fold(), *locked_ratios(family, lam_range, max_q))
    return engine.follow(family, first, [tuple(lam_range)], settings, events, counter)

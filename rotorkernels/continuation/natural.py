"""Natural continuation: periodic orbits of forced-orbit problems (rotorsweep.kernels.orbits) along a
chain of parameter points, each started from its neighbours.

Each point starts Newton from the best guess available, in this order: the secant predictor
through the two previous converged orbits (the scaled state makes neighbouring orbits close),
the previous orbit itself, a transient settled from that guess, and last a cold start (a
transient from near static equilibrium); Newton from a transient or a cold start, far from the
orbit, is staged (its early iterations at a looser tolerance, shooting.shoot_staged). The first
start that converges wins; failure of all is recorded as data. Everything depends only on the
chain, never on how chains are scheduled.
"""
from collections import namedtuple

import numpy as np

from rotorsweep.kernels import floquet, shooting
from rotorsweep.kernels.orbits import ForcedOrbitProblem

PointSolution = namedtuple(
    "PointSolution",
    "status reason iterations residual multipliers max_abs stable bifurcation state samples n_rhs",
)


# Newton from a neighbour's orbit converges in a few iterations or not at all: give such starts
# this many iterations before falling back, so a wandering Newton costs little.
QUICK_ITERATIONS = 6
# Further cold starts, one forcing period apart, when Newton fails from the settled transient.
COLD_RETRIES = 4
# Slow passage: just past a fold the trajectories linger near the vanished orbit for many periods
# (31.2 Hz / 15.2 um in Bai 2006, Fig. 13: Newton fails after 30 periods, converges after 100), so
# the cold transient goes on, SLOW_PASSAGE_CHUNKS more transients at most, until the
# stroboscopic map has settled (|P(u) - u| <= SETTLED_RTOL max(1, |u|)); then Newton starts there.
SLOW_PASSAGE_CHUNKS = 10
SETTLED_RTOL = 1e-4


def _guesses(problem, history, transient_periods, cold_guess):
    """Yield (guess, n_rhs spent making it, quick) from cheapest to most robust."""
    if len(history) >= 2:
        yield 2.0 * history[-1] - history[-2], 0, True
    if history:
        yield history[-1], 0, True
        z, ok, n_rhs = problem.settle(history[-1], transient_periods)
        if ok:
            yield z, n_rhs, False
    cold = cold_guess(problem.p)
    z, ok, n_rhs = problem.settle(cold, transient_periods)
    yield (z if ok else cold), n_rhs, False
    # On a chaotic attractor Newton's basin around the unstable orbit is small: some transient
    # states lie in it and others do not, so try the next few states one period apart.
    for _ in range(COLD_RETRIES if ok else 0):
        z, ok, n_rhs = problem.settle(z, 1)
        if not ok:
            return
        yield z, n_rhs, False
    if ok:
        yield from _slow_passage(problem, z, transient_periods)


def _slow_passage(problem, z, transient_periods):
    """Yield the state once the stroboscopic map has settled (at most SLOW_PASSAGE_CHUNKS
    transients further on); nothing when it does not settle (chaos, a torus) or diverges."""
    spent = 0
    for _ in range(SLOW_PASSAGE_CHUNKS):
        z, ok, n_rhs = problem.settle(z, transient_periods)
        after, ok_map, n_map = problem.settle(z, 1)
        spent += n_rhs + n_map
        if not (ok and ok_map):
            return
        if np.abs(after - z).max() <= SETTLED_RTOL * max(1.0, np.abs(z).max()):
            yield after, spent, False
            return
        z = after


def solve_orbit(model, p, opts, history=(), *, cold_guess, periods=1, tol=1e-9, max_iter=30,
                transient_periods=30, n_samples=32):
    """Periodic orbit, multipliers and orbit samples at one parameter point.

    history: converged states of the previous points of the chain (most recent last);
    n_samples: orbit samples per forcing period (0: none, samples None -- a sweep takes its
    orbit means and extrema in one pass, rotorsweep.kernels.extrema.orbit_extent)."""
    problem = ForcedOrbitProblem(model, p, opts, periods)
    n_rhs = 0
    best = None
    for guess, cost, quick in _guesses(problem, list(history), transient_periods, cold_guess):
        n_rhs += cost
        out = problem.shoot(guess, tol, min(max_iter, QUICK_ITERATIONS) if quick else max_iter, far=not quick)
        n_rhs += out[6]
        if best is None or out[2] == shooting.CONVERGED:
            best = out
        if out[2] == shooting.CONVERGED:
            break
    state, mono, status, reason, iters, res, _ = best
    if status != shooting.CONVERGED:
        # no orbit: every multiplier component NaN (not NaN + 0j)
        no_multipliers = np.full(model.n_state, np.nan * (1 + 1j))
        return PointSolution(status, reason, iters, res, no_multipliers, np.nan, False, floquet.NONE,
                             state, None, n_rhs)
    lams = floquet.multipliers(mono)
    max_abs, stable, bif = floquet.classify(lams)
    samples = problem.samples(state, n_samples) if n_samples else None
    return PointSolution(status, reason, iters, res, lams, max_abs, stable, bif, state, samples, n_rhs)


def natural(model, params, opts, **kw):
    """Natural continuation: solve_orbit at each parameter vector of `params` in order, each
    started from the previous converged orbits (a failure restarts the history). A generator,
    so a caller can time or stop each point."""
    history = []
    for p in params:
        sol = solve_orbit(model, p, opts, history[-2:], **kw)
        if sol.status == shooting.CONVERGED:
            history.append(sol.state)
        else:
            history.clear()
        yield sol

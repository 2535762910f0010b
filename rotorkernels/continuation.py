"""Periodic orbits along a chain of parameter points (natural continuation in shaft speed).

Each point starts Newton from the best guess available, in this order: the secant predictor
through the two previous converged orbits (the scaled state makes neighbouring orbits close),
the previous orbit itself, a transient settled from that guess, and last a cold start (a
transient from near static equilibrium). The first start that converges wins; failure of all is
recorded as data. Everything depends only on the chain, never on how chains are scheduled.
"""
from collections import namedtuple

import numpy as np

from rotorkernels import floquet, shooting

PointSolution = namedtuple(
    "PointSolution",
    "status reason iterations residual multipliers max_abs stable bifurcation state samples n_rhs",
)


def _shoot(model, guess, p, opts, periods, tol, max_iter):
    return shooting.shoot(model.kernel, guess, p, float(periods), opts, tol, max_iter)


def _settle(model, u0, p, opts, n_periods):
    z, status, n_rhs = shooting.settle(model.kernel, u0, p, float(n_periods), opts)
    return z, status == 0, n_rhs


# Newton from a neighbour's orbit converges in a few iterations or not at all: give such starts
# this many iterations before falling back, so a wandering Newton costs little.
QUICK_ITERATIONS = 6
# Further cold starts, one forcing period apart, when Newton fails from the settled transient.
COLD_RETRIES = 4


def _guesses(model, p, opts, history, transient_periods, cold_guess):
    """Yield (guess, n_rhs spent making it, quick) from cheapest to most robust."""
    if len(history) >= 2:
        yield 2.0 * history[-1] - history[-2], 0, True
    if history:
        yield history[-1], 0, True
        z, ok, n_rhs = _settle(model, history[-1], p, opts, transient_periods)
        if ok:
            yield z, n_rhs, False
    z, ok, n_rhs = _settle(model, cold_guess(p), p, opts, transient_periods)
    yield (z if ok else cold_guess(p)), n_rhs, False
    # On a chaotic attractor Newton's basin around the unstable orbit is small: some transient
    # states lie in it and others do not, so try the next few states one period apart.
    for _ in range(COLD_RETRIES if ok else 0):
        z, ok, n_rhs = _settle(model, z, p, opts, 1)
        if not ok:
            return
        yield z, n_rhs, False


def solve_orbit(model, p, opts, history=(), *, cold_guess, periods=1, tol=1e-9, max_iter=30,
                transient_periods=30, n_samples=32):
    """Periodic orbit, multipliers and orbit samples at one parameter point.

    history: converged states of the previous points of the chain (most recent last)."""
    n_rhs = 0
    best = None
    for guess, cost, quick in _guesses(model, p, opts, list(history), transient_periods, cold_guess):
        n_rhs += cost
        out = _shoot(model, guess, p, opts, periods, tol, min(max_iter, QUICK_ITERATIONS) if quick else max_iter)
        n_rhs += out[6]
        if best is None or out[2] == shooting.CONVERGED:
            best = out
        if out[2] == shooting.CONVERGED:
            break
    state, mono, status, reason, iters, res, _ = best
    if status != shooting.CONVERGED:
        nan = np.full(model.n_state, np.nan)
        return PointSolution(status, reason, iters, res, nan + 0j, np.nan, False, floquet.NONE,
                             state, None, n_rhs)
    lams = floquet.multipliers(mono)
    max_abs, stable, bif = floquet.classify(lams)
    samples = shooting.sample_orbit(model.kernel, state, p, float(periods), n_samples * periods, opts)
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

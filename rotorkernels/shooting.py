"""Periodic orbits by shooting: Newton on r(s) = u(k T; s) - s with the monodromy from the
variational equations, a backtracking line search, and explicit statuses.

Codes match rotorsweep.pipeline.schema: ORBIT_STATUS (converged, not_converged, diverged) and ORBIT_REASON.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from rotorsweep.kernels import integrators as ig

CONVERGED, NOT_CONVERGED, DIVERGED = 0, 1, 2
(R_OK, R_MAX_ITER, R_LINE_SEARCH, R_NAN, R_AMPLITUDE, R_STEP_UNDERFLOW, R_SINGULAR) = range(7)
R_UNKNOWN_MODEL = 9     # rotorsweep.pipeline.schema.ORBIT_REASON: 7, 8 are set by the pipeline

Orbit = namedtuple("Orbit", "state monodromy status reason iterations residual n_rhs")

_MAX_HALVINGS = 8


@njit(cache=True, nogil=True)
def _failure(flow_status):
    """(status, reason) for an integration that did not reach the end of the period."""
    if flow_status == ig.STATUS_NAN:
        return DIVERGED, R_NAN
    if flow_status == ig.STATUS_AMPLITUDE:
        return DIVERGED, R_AMPLITUDE
    if flow_status == ig.STATUS_UNKNOWN_MODEL:
        return NOT_CONVERGED, R_UNKNOWN_MODEL
    return NOT_CONVERGED, R_STEP_UNDERFLOW


# Element loops below rather than array expressions (z[:n] - s, np.max(np.abs(r)), s + lam * step):
# the same arithmetic, without compiling Numba's broadcasting and reduction kernels for a
# first point (about 1 s).
@njit(cache=True, nogil=True, inline="always")
def _residual_norm(r, s):
    """Infinity norm of the residual relative to the orbit's size (scaled units, floor 1)."""
    r_max = 0.0
    s_max = 1.0
    for i in range(r.size):
        a, b = abs(r[i]), abs(s[i])
        if a != a or b != b:        # NaN, as np.max would give
            return np.nan
        r_max = max(r_max, a)
        s_max = max(s_max, b)
    return r_max / s_max


@njit(cache=True, nogil=True)
def _return_map(kernel, s, p, periods, opts, h):
    """(u(k T; s) - s, monodromy, flow status, n_rhs, h_next)."""
    n = kernel.n_state
    z0 = ig.initial_state(s, n, True)
    z, status, n_rhs, h = ig.flow(kernel, 0.0, periods, z0, p, True, opts, h)
    r = np.empty(n)
    mono = np.empty((n, n))
    for i in range(n):
        r[i] = z[i] - s[i]
        for j in range(n):
            mono[i, j] = z[n + i * n + j]
    return r, mono, status, n_rhs, h


@njit(cache=True, nogil=True)
def _newton_step(mono, r):
    """(x, ok): x solves (M - I) x = -r by Gaussian elimination with partial pivoting (LAPACK's
    gesv algorithm; written out because numba's np.linalg.solve compiles its error formatting,
    about 3 s of a first point); ok is False for a singular or non-finite matrix, where gesv
    fails."""
    n = r.size
    a = np.empty((n, n))
    x = np.empty(n)
    for i in range(n):
        x[i] = -r[i]
        for j in range(n):
            a[i, j] = mono[i, j] - (1.0 if i == j else 0.0)
            if not np.isfinite(a[i, j]):
                return x, False
    for k in range(n):
        piv = k
        for i in range(k + 1, n):
            if abs(a[i, k]) > abs(a[piv, k]):
                piv = i
        if a[piv, k] == 0.0:
            return x, False
        if piv != k:
            for j in range(n):
                a[k, j], a[piv, j] = a[piv, j], a[k, j]
            x[k], x[piv] = x[piv], x[k]
        for i in range(k + 1, n):
            f = a[i, k] / a[k, k]
            for j in range(k + 1, n):
                a[i, j] -= f * a[k, j]
            x[i] -= f * x[k]
    for i in range(n - 1, -1, -1):
        acc = x[i]
        for j in range(i + 1, n):
            acc -= a[i, j] * x[j]
        x[i] = acc / a[i, i]
    return x, True


# Staged (inexact) Newton for a start far from the orbit (a transient, a cold or perturbed state):
# while the residual is far above the integration error, a Newton step needs the return map only
# to a fraction of that residual, so those iterations integrate at the looser EARLY_RTOL (a
# third of the cost at rtol 1e-10). A trial point is integrated at the configured tolerance once
# the current residual is below EARLY_SWITCH (its Newton step lands near EARLY_SWITCH^2, at the
# early map's own error), and convergence is judged only on the configured map: the converged
# state, its residual and its monodromy are those of plain Newton on that map.
EARLY_RTOL = 1e-6
EARLY_SWITCH = 3e-3
# An early residual below this many EARLY_RTOL is the early map's error, not a distance to the
# orbit (the start was close after all): the configured map takes over at that point.
_EARLY_NOISE = 10.0


def early_settings(opts):
    """The early iterations' integrator settings for `shoot_staged` (rk4: the same settings)."""
    return ig.loosened(opts, EARLY_RTOL)


def shoot(kernel, guess, p, periods, opts, tol, max_iter):
    """Newton shooting for an orbit of period `periods` (scaled time) from `guess`.

    Returns (state, monodromy, status, reason, iterations, residual, n_rhs). The monodromy is
    evaluated at the returned state. Plain Newton is `shoot_staged` with the configured settings
    throughout, called from Python: a jitted wrapper was a second compilation (~1 s) of it."""
    return shoot_staged(kernel, guess, p, periods, opts, opts, tol, max_iter)


@njit(cache=True, nogil=True)
def shoot_staged(kernel, guess, p, periods, opts, early_opts, tol, max_iter):
    """`shoot` whose early iterations, while the residual is above EARLY_SWITCH, integrate with
    `early_opts` (`early_settings(opts)`; early_opts = opts is plain Newton). Any trouble on the
    early map (a failed integration, a singular matrix, a failed line search, the iteration
    limit, a residual at its error level) hands the current state to the configured map, so
    every status and reason comes from the configured map, as in plain Newton."""
    early = early_opts[ig.S_RTOL] > opts[ig.S_RTOL]
    staged = early
    noise = _EARLY_NOISE * early_opts[ig.S_RTOL]
    s = guess.copy()
    r, mono, fstat, n_rhs, h = _return_map(kernel, s, p, periods, early_opts if early else opts, 0.0)
    demote = fstat != ig.STATUS_OK
    res = _residual_norm(r, s) if not demote else np.inf
    it = 0
    while True:
        if early and (demote or res <= noise):
            early, demote = False, False
            r, mono, fstat, nr, h = _return_map(kernel, s, p, periods, opts, 0.0)
            n_rhs += nr
            res = _residual_norm(r, s) if fstat == ig.STATUS_OK else np.inf
        if fstat != ig.STATUS_OK:
            status, reason = _failure(fstat)
            return s, mono, status, reason, it, res, n_rhs
        if not early and res <= tol:
            return s, mono, CONVERGED, R_OK, it, res, n_rhs
        if it == max_iter:
            if early:
                demote = True
                continue
            return s, mono, NOT_CONVERGED, R_MAX_ITER, max_iter, res, n_rhs
        step, ok = _newton_step(mono, r)
        if not ok:
            if early:
                demote = True
                continue
            return s, mono, NOT_CONVERGED, R_SINGULAR, it, res, n_rhs
        it += 1
        trial_early = early and res > EARLY_SWITCH
        # the step size carried from the last map, except into a staged run's configured maps: all
        # of them start from the integrator's own first step, so their step sequences match and
        # the configured map stays smooth between iterates (its last two iterates decide)
        h0 = h if trial_early or not staged else 0.0
        lam = 1.0
        accepted = False
        last_fail = ig.STATUS_OK
        for _ in range(_MAX_HALVINGS):
            trial = np.empty(s.size)
            for i in range(s.size):
                trial[i] = s[i] + lam * step[i]
            r_t, mono_t, fstat_t, nr, h_t = _return_map(kernel, trial, p, periods,
                                                        early_opts if trial_early else opts, h0)
            n_rhs += nr
            if fstat_t == ig.STATUS_OK:
                res_t = _residual_norm(r_t, trial)
                if res_t < (1.0 - 1e-4 * lam) * res or res_t <= tol:
                    s, r, mono, res, h, early = trial, r_t, mono_t, res_t, h_t, trial_early
                    accepted = True
                    break
            else:
                last_fail = fstat_t
            lam *= 0.5
        if accepted:
            continue
        if early:
            demote = True
            continue
        if last_fail != ig.STATUS_OK:
            status, reason = _failure(last_fail)
            return s, mono, status, reason, it, res, n_rhs
        return s, mono, NOT_CONVERGED, R_LINE_SEARCH, it, res, n_rhs


def settle(kernel, u0, p, periods, opts):
    """Integrate a transient of `periods` forcing periods from u0: (state, flow status, n_rhs).
    A Python function: `flow` is compiled for Python callers anyway, and a jitted wrapper was
    one more compilation of the integrator (~0.6 s of a first sweep)."""
    z, status, n_rhs, _ = ig.flow(kernel, 0.0, float(periods), u0, p, False, opts, 0.0)
    return z, status, n_rhs


@njit(cache=True, nogil=True)
def sample_orbit(kernel, u0, p, periods, n_samples, opts):
    """States at n_samples equally spaced times over [0, periods) starting from u0."""
    out = np.empty((n_samples, kernel.n_state))
    z = u0.copy()
    h = 0.0
    dt = periods / n_samples
    n = kernel.n_state
    for i in range(n_samples):
        # element loops, not out[i] = z and out[i + 1:] = nan: the slice assignments' shape
        # checks compile Numba's error formatting (~2 s of a first point)
        for j in range(n):
            out[i, j] = z[j]
        z, status, _, h = ig.flow(kernel, i * dt, (i + 1) * dt, z, p, False, opts, h)
        if status != ig.STATUS_OK:
            for k in range(i + 1, n_samples):
                for j in range(n):
                    out[k, j] = np.nan
            break
    return out


def periodic_orbit(model, guess, p, opts, periods=1, tol=1e-9, max_iter=30, staged=True):
    """Python-facing wrapper of `shoot_staged` for a `models.ModelSpec` (`staged`: the start is
    far from the orbit, see EARLY_RTOL; False: plain Newton, `shoot`)."""
    early = early_settings(opts) if staged else opts
    res = shoot_staged(model.kernel, np.asarray(guess, float), p, float(periods), opts, early, tol, max_iter)
    return Orbit(*res)

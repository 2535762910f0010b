"""Exact extrema of linear observables along an orbit, located on the integrator's steps.

An observable o = w . u[:m] (w: one row of `weights`, in the units the caller wants) has the
time derivative g = w . (du/dt)[:m]: for velocity-form models whose observables read positions
only this is w . (velocity part of u), with no right-hand side evaluated; otherwise one
right-hand side per step end. The orbit is integrated step by step (each segment is the step
the integrator proposes, so it is one accepted step of the same method and tolerance); o is
recorded at every step end and, where g changes sign within a step, at the zero of g, refined by
the Illinois variant of regula falsi on a re-integration from the step's start (one step of the
same method, shorter than an accepted one, so as accurate). The zero is located to XTOL of the
step; an error d in its time moves o by o'' d^2 / 2 only, so the extrema are exact to the
integrator's tolerance. Poincare samples and orbit samples are not this module's business.
"""
import numpy as np
from numba import njit

from rotorkernels import integrators as ig

XTOL = 1e-10                # zero of g: bracket width relative to the step
MAX_REFINE = 60             # Illinois iterations per bracket (superlinear: ~6-10 suffice)


@njit(cache=True, nogil=True, inline="always")
def _values(weights, z, out):
    for k in range(weights.shape[0]):
        acc = 0.0
        for i in range(weights.shape[1]):
            acc += weights[k, i] * z[i]
        out[k] = acc


@njit(cache=True, nogil=True, inline="always")
def _rates(kernel, t, z, p, weights, f, jbuf, out):
    """g_k = w_k . (du/dt)[:m] at (t, z): the velocity part of z in velocity form (observables of
    positions), else the right-hand side's."""
    m = weights.shape[1]
    if kernel.velocity_form and m <= kernel.n_position:
        for k in range(weights.shape[0]):
            acc = 0.0
            for i in range(m):
                acc += weights[k, i] * z[kernel.n_position + i]
            out[k] = acc
    else:
        ig.derivative(kernel, t, z, p, False, f, jbuf)
        _values(weights, f, out)


@njit(cache=True, nogil=True)
def _refine(kernel, t, span, z, p, weights, k, ga, gb, opts, f, jbuf, rates, values):
    """o_k at the zero of g_k within the step [t, t + span] from state z (g_k(t) = ga and
    g_k(t + span) = gb of opposite signs), by Illinois on a re-integration from t; NaN when the
    re-integration fails."""
    a, b, fa, fb = 0.0, span, ga, gb
    best = np.nan
    for _ in range(MAX_REFINE):
        c = (a * fb - b * fa) / (fb - fa)
        zc, status, _, _ = ig.flow(kernel, t, t + c, z, p, False, opts, c)
        if status != ig.STATUS_OK:
            return np.nan
        _rates(kernel, t + c, zc, p, weights, f, jbuf, rates)
        _values(weights, zc, values)
        best = values[k]
        fc = rates[k]
        if fc == 0.0:
            break
        if (fc < 0.0) == (fb < 0.0):
            fa *= 0.5          # Illinois: the retained end's value halved, so it moves too
        else:
            a, fa = b, fb
        b, fb = c, fc
        if abs(b - a) <= XTOL * span:
            break
    return best


@njit(cache=True, nogil=True)
def orbit_extrema(kernel, u0, p, span, weights, opts):
    """(highest, lowest, status) of each observable o_k = weights[k] . u[:m] over the orbit from
    u0 on [0, span] (scaled time); status an integrators.STATUS_* code (not OK: NaN values)."""
    n, n_obs = kernel.n_state, weights.shape[0]
    hi, lo = np.empty(n_obs), np.empty(n_obs)
    ga, gb, values, rates = np.empty(n_obs), np.empty(n_obs), np.empty(n_obs), np.empty(n_obs)
    f, jbuf = np.empty(n), np.empty((n, n))
    z = u0.copy()
    _values(weights, z, values)
    for k in range(n_obs):
        hi[k] = values[k]
        lo[k] = values[k]
    _rates(kernel, 0.0, z, p, weights, f, jbuf, ga)
    t, h = 0.0, 0.01 * span
    status = ig.STATUS_STEP_UNDERFLOW       # unless the end is reached within max_steps
    for _ in range(int(opts[ig.S_MAX_STEPS])):
        if t >= span:
            return hi, lo, ig.STATUS_OK
        t1 = min(t + h, span)
        zb, status, _, h_next = ig.flow(kernel, t, t1, z, p, False, opts, h)
        if status != ig.STATUS_OK:
            break
        _rates(kernel, t1, zb, p, weights, f, jbuf, gb)
        _values(weights, zb, values)
        for k in range(n_obs):
            hi[k] = max(hi[k], values[k])
            lo[k] = min(lo[k], values[k])
        for k in range(n_obs):
            if (ga[k] < 0.0) != (gb[k] < 0.0) and ga[k] != 0.0 and gb[k] != 0.0:
                v = _refine(kernel, t, t1 - t, z, p, weights, k, ga[k], gb[k], opts, f, jbuf, rates, values)
                if not np.isfinite(v):
                    status = ig.STATUS_NAN
                    break
                hi[k] = max(hi[k], v)
                lo[k] = min(lo[k], v)
        if status != ig.STATUS_OK:
            break
        for k in range(n_obs):
            ga[k] = gb[k]
        z, t, h = zb, t1, h_next
    hi[:] = np.nan
    lo[:] = np.nan
    return hi, lo, status


def observable_weights(model, period):
    """The observables' weights on the scaled state, so that weights @ u[:m] is in SI (m: the
    components the observables read; period: the forcing period [s], for velocity components)."""
    w = np.array([o.weights for o in model.observables], float).reshape(len(model.observables), -1)
    scale = model.to_physical(np.ones(model.n_state), period)[:w.shape[1]]
    return np.ascontiguousarray(w * scale)


def extremes(model, state, p, span, opts, period):
    """(highest, lowest) of each observable over the orbit through `state` lasting `span` (scaled
    time: forcing periods), SI; NaN where the orbit could not be integrated."""
    hi, lo, _ = orbit_extrema(model.kernel, np.asarray(state, float), p, float(span),
                              observable_weights(model, period), opts)
    return hi, lo


def amplitudes(model, state, p, span, opts, period):
    """(max |o|, half peak-to-peak of o) for each observable o over the orbit, SI."""
    hi, lo = extremes(model, state, p, span, opts, period)
    return np.maximum(hi, -lo), 0.5 * (hi - lo)

"""Exact extrema of linear observables along an orbit, located on the integrator's steps.

An observable o = w . u[:m] (w: one row of `weights`, in the units the caller wants) has the
time derivative g = w . (du/dt)[:m]: for velocity-form models whose observables read positions
only this is w . (velocity part of u), with no right-hand side evaluated; otherwise one
right-hand side per step end. The orbit is integrated step by step (each segment is the step
the integrator proposes, so it is one accepted step of the same method and tolerance); o is
recorded at every step end; where g changes sign within a step, the cubic Hermite interpolant
of (o, g) at the step's ends estimates the extremum, and those estimates that can be the highest
or lowest value (CANDIDATE_MARGIN) are refined: the zero of g on a re-integration from the step's
start (one step of the same method, shorter than an accepted one, so as accurate), by Newton with
g' = w . (the acceleration part of du/dt) in velocity form, else by regula falsi. The zero is
located to XTOL of the step; an error d in its time moves o by o'' d^2 / 2 only, so the extrema
are exact to the integrator's tolerance. The same pass integrates each observable over the
accepted steps for its mean over the orbit (a two-point Hermite rule on the step ends' values and
derivatives, `_quadrature`), so a sweep point takes no orbit samples. Poincare samples and
orbit samples are not this module's business.
"""
import numpy as np
from numba import njit

from rotorsweep.kernels import integrators as ig

XTOL = 1e-9                 # zero of g: relative to the step (o's error o'' (XTOL h)^2 / 2 ~ 1e-20 o)
MAX_REFINE = 60             # iterations per bracket (Newton: 2-4, Illinois: ~6-10)


@njit(cache=True, nogil=True, inline="always")
def _values(weights, z, out):
    for k in range(weights.shape[0]):
        acc = 0.0
        for i in range(weights.shape[1]):
            acc += weights[k, i] * z[i]
        out[k] = acc


@njit(cache=True, nogil=True, inline="always")
def _accelerated(kernel, weights):
    """The observables read positions of a velocity-form model: g = w . (velocity part of u) and
    g' = w . (acceleration part of du/dt)."""
    return kernel.velocity_form and weights.shape[1] <= kernel.n_position


@njit(cache=True, nogil=True, inline="always")
def _rates(kernel, t, z, p, weights, f, jbuf, out, slopes, with_slopes):
    """g_k = w_k . (du/dt)[:m] at (t, z) into `out`; where `_accelerated`, g_k from the state and,
    if with_slopes, g_k' into `slopes` (one right-hand side), else g_k from the right-hand side."""
    m = weights.shape[1]
    accelerated = _accelerated(kernel, weights)
    if with_slopes or not accelerated:
        ig.derivative(kernel, t, z, p, False, f, jbuf)
    if accelerated:
        for k in range(weights.shape[0]):
            acc = 0.0
            slope = 0.0
            for i in range(m):
                acc += weights[k, i] * z[kernel.n_position + i]
                if with_slopes:
                    slope += weights[k, i] * f[kernel.n_position + i]
            out[k] = acc
            slopes[k] = slope
    else:
        _values(weights, f, out)


@njit(cache=True, nogil=True)
def _refine(kernel, t, span, c, z, p, weights, k, ga, gb, opts):
    """o_k at the zero of g_k within the step [t, t + span] from state z (g_k(t) = ga and
    g_k(t + span) = gb of opposite signs), from the estimate t + c, on a re-integration from t:
    Newton on g_k with g_k' where `_accelerated` (a step leaving the bracket replaced by regula
    falsi), else the Illinois variant of regula falsi; NaN when the re-integration fails. Returns
    (value, its time from t, right-hand sides evaluated)."""
    newton = _accelerated(kernel, weights)
    n, n_obs = kernel.n_state, weights.shape[0]
    f, jbuf, rates, slopes, values = np.empty(n), np.empty((n, n)), np.empty(n_obs), np.empty(n_obs), np.empty(n_obs)
    a, b, fa, fb = 0.0, span, ga, gb
    best, at = np.nan, c
    n_rhs = 0
    for _ in range(MAX_REFINE):
        zc, status, spent, _ = ig.flow(kernel, t, t + c, z, p, False, opts, c)
        n_rhs += spent + 1          # the rates below: one right-hand side
        if status != ig.STATUS_OK:
            return np.nan, c, n_rhs
        _rates(kernel, t + c, zc, p, weights, f, jbuf, rates, slopes, newton)
        _values(weights, zc, values)
        best, at = values[k], c
        fc = rates[k]
        if fc == 0.0:
            break
        if newton:
            if (fc < 0.0) == (fa < 0.0):
                a, fa = c, fc
            else:
                b, fb = c, fc
            step = -fc / slopes[k] if slopes[k] != 0.0 else np.inf
            # |step| <= XTOL span: c is the zero to within it, o_k(c) exact to o'' step^2 / 2
            if abs(step) <= XTOL * span:
                break
            c = c + step if a < c + step < b else (a * fb - b * fa) / (fb - fa)
            continue
        if (fc < 0.0) == (fb < 0.0):
            fa *= 0.5          # Illinois: the retained end's value halved, so it moves too
        else:
            a, fa = b, fb
        b, fb = c, fc
        if abs(b - a) <= XTOL * span:
            break
        c = (a * fb - b * fa) / (fb - fa)
    return best, at, n_rhs


@njit(cache=True, nogil=True)
def _hermite(oa, ob, ga, gb, h):
    """(time, value) of the extremum within a step of the cubic Hermite interpolant of o (values
    oa, ob and rates ga, gb of opposite signs at its ends): g is then the quadratic
    ga + alpha s + beta s^2 with g(h) = gb and integral ob - oa, whose one zero in (0, h) is
    bisected. Its error, O(h^4 o^(4)), is what CANDIDATE_MARGIN covers."""
    beta = 3.0 * (h * (ga + gb) - 2.0 * (ob - oa)) / h ** 3
    alpha = (gb - ga - beta * h * h) / h
    a, b = 0.0, h
    for _ in range(60):
        s = 0.5 * (a + b)
        if ((ga + alpha * s + beta * s * s) < 0.0) == (ga < 0.0):
            a = s
        else:
            b = s
    s = 0.5 * (a + b)
    return s, oa + ga * s + alpha * s * s / 2.0 + beta * s ** 3 / 3.0


# A local extremum is refined only when its Hermite estimate lies within this fraction of the
# observable's range of the estimated global one (the estimates' error is ~(h omega)^4 / 384 of
# the range, below 1e-5 for steps up to a tenth of a period): ripples far below are skipped.
CANDIDATE_MARGIN = 1e-3
CANDIDATES = 256            # brackets held for refinement after the integration (more: refined at once)


@njit(cache=True, nogil=True, inline="always")
def _quadrature(oa, ob, ga, gb, sa, sb, h, quintic, integral, error):
    """Add the integral of each o over a step of length h to `integral` and its error estimate to
    `error`, from the values (oa, ob), rates (ga, gb) and, if quintic, second derivatives (sa, sb)
    at its ends. Two-point Hermite rules: cubic h (oa + ob) / 2 + h^2 (ga - gb) / 12, error
    h^5 o''''/720; quintic h (oa + ob) / 2 + h^2 (ga - gb) / 10 + h^3 (sa + sb) / 120, error
    h^7 o^(6) / 100800. The error estimate is the difference to the rule one order lower (cubic
    vs quintic, trapezoid vs cubic): the lower rule's error, a bound on the rule used where the
    step resolves o (a step across a contact's onset, where o'''' is unbounded, is as short as
    the integrator's error control makes it)."""
    for k in range(oa.size):
        trapezoid = 0.5 * h * (oa[k] + ob[k])
        cubic = trapezoid + h * h * (ga[k] - gb[k]) / 12.0
        if quintic:
            value = trapezoid + h * h * (ga[k] - gb[k]) / 10.0 + h ** 3 * (sa[k] + sb[k]) / 120.0
            error[k] += abs(value - cubic)
        else:
            value = cubic
            error[k] += abs(cubic - trapezoid)
        integral[k] += value


@njit(cache=True, nogil=True)
def orbit_extent(kernel, u0, p, span, weights, opts, mean):
    """(highest, lowest, mean, mean_error, status, n_rhs) of each observable o_k = weights[k] . u[:m]
    over the orbit from u0 on [0, span] (scaled time), in one integration; status an
    integrators.STATUS_* code (not OK: NaN values), n_rhs the right-hand sides evaluated.
    The step ends give o, the brackets of a sign change of g their Hermite estimates; the
    brackets whose estimate can be the highest or lowest are refined afterwards. The mean is the
    integral of o by the quintic Hermite rule on the accepted steps where `_accelerated` and
    `mean` is set (g' from one right-hand side per step end: the cost of a mean that is wanted),
    else the cubic one (`_quadrature`); mean_error its estimate."""
    hi, lo, avg, error, _, _, _, status, n_rhs = _extent(kernel, u0, p, p, span, weights, opts, mean)
    return hi, lo, avg, error, status, n_rhs


@njit(cache=True, nogil=True)
def orbit_extent_slope(kernel, u0, v0, tangent, span, weights, opts):
    """(highest, lowest, d_highest, d_lowest, v_end, status, n_rhs): `orbit_extent`'s extremes, their
    derivatives along a direction (v0 of the state, the parameter change of `tangent`, an
    integrators.TangentParams whose p is the orbit's) and the flow's derivative v_end along it at
    span. The direction is integrated with the orbit (the integrator's tangent-linear mode), on
    the orbit's own steps: v is the exact derivative of the discrete orbit, no step-size noise.
    At an extremum o's time derivative vanishes, so the extremum's derivative is w . v at its
    refined time, whose own change does not enter (envelope theorem). Its error: the method's
    truncation error's derivative (~rtol relative) and the parameter term's central difference
    (TangentParams, ~1e-10). Kinks of the extremes (two local maxima of o exchange which is the
    highest) are where d jumps."""
    z0 = np.empty(2 * u0.size)
    for i in range(u0.size):    # element loops: no slice assignment's shape check
        z0[i], z0[u0.size + i] = u0[i], v0[i]
    hi, lo, _, _, d_hi, d_lo, v_end, status, n_rhs = _extent(kernel, z0, tangent.p, tangent, span, weights, opts,
                                                             False)
    return hi, lo, d_hi, d_lo, v_end, status, n_rhs


@njit(cache=True, nogil=True)
def _extent(kernel, z0, p, q, span, weights, opts, mean):
    """orbit_extent's pass from z0 = u0 (q = p), and orbit_extent_slope's from z0 = [u0, v0] (q
    the TangentParams): (highest, lowest, mean, mean_error, d_highest, d_lowest, v_end, status,
    n_rhs)."""
    n, n_obs = kernel.n_state, weights.shape[0]
    tangent = z0.size > n
    hi, lo, ga, gb, oa, ob = (np.empty(n_obs), np.empty(n_obs), np.empty(n_obs), np.empty(n_obs),
                              np.empty(n_obs), np.empty(n_obs))
    sa, sb, f, jbuf = np.zeros(n_obs), np.zeros(n_obs), np.empty(n), np.empty((n, n))
    integral, error, d_hi, d_lo, dv = np.zeros(n_obs), np.zeros(n_obs), np.zeros(n_obs), np.zeros(n_obs), np.zeros(n_obs)
    quintic = mean and _accelerated(kernel, weights)
    rhs_per_end = 1 if quintic or not _accelerated(kernel, weights) else 0     # `_rates`
    est_hi, est_lo = np.empty(n_obs), np.empty(n_obs)     # hi and lo with the brackets' estimates
    held = np.empty((CANDIDATES, 7))        # t, h, s, estimate, k, ga, gb of a bracket
    held_z = np.empty((CANDIDATES, z0.size))   # its starting states
    count = 0
    z = z0.copy()
    _values(weights, z, oa)
    _directional(weights, z, n, tangent, dv)
    for k in range(n_obs):
        hi[k] = lo[k] = est_hi[k] = est_lo[k] = oa[k]
        d_hi[k] = d_lo[k] = dv[k]
    _rates(kernel, 0.0, z, p, weights, f, jbuf, ga, sa, quintic)
    t, h, n_rhs = 0.0, 0.01 * span, rhs_per_end
    status = ig.STATUS_STEP_UNDERFLOW       # unless the end is reached within max_steps
    for _ in range(int(opts[ig.S_MAX_STEPS])):
        if t >= span:
            status = ig.STATUS_OK
            break
        t1 = min(t + h, span)
        zb, status, spent, h_next = ig.flow(kernel, t, t1, z, q, tangent, opts, h)
        n_rhs += spent + rhs_per_end
        if status != ig.STATUS_OK:
            break
        _directional(weights, zb, n, tangent, dv)
        _rates(kernel, t1, zb, p, weights, f, jbuf, gb, sb, quintic)
        _values(weights, zb, ob)
        _quadrature(oa, ob, ga, gb, sa, sb, t1 - t, quintic, integral, error)
        for k in range(n_obs):
            if ob[k] > hi[k]:
                hi[k], d_hi[k] = ob[k], dv[k]
            if ob[k] < lo[k]:
                lo[k], d_lo[k] = ob[k], dv[k]
            est_hi[k] = max(est_hi[k], ob[k])
            est_lo[k] = min(est_lo[k], ob[k])
            if (ga[k] < 0.0) != (gb[k] < 0.0) and ga[k] != 0.0 and gb[k] != 0.0:
                s, est = _hermite(oa[k], ob[k], ga[k], gb[k], t1 - t)
                if count == CANDIDATES:     # no room: refined at once
                    status, spent = _settle(kernel, p, q, weights, opts, k, t, t1 - t, s, ga[k], gb[k], z,
                                            (hi, lo, d_hi, d_lo))
                    n_rhs += spent
                else:
                    _hold(held, held_z, count, (t, t1 - t, s, est, float(k), ga[k], gb[k]), z)
                    count += 1
                est_hi[k] = max(est_hi[k], est)
                est_lo[k] = min(est_lo[k], est)
        if status != ig.STATUS_OK:
            break
        for k in range(n_obs):
            ga[k], oa[k], sa[k] = gb[k], ob[k], sb[k]
        z, t, h = zb, t1, h_next
    if status == ig.STATUS_OK and t < span:
        status = ig.STATUS_STEP_UNDERFLOW       # max_steps spent before the end
    if status == ig.STATUS_OK:
        status, spent = _refine_held(kernel, p, q, weights, opts, (hi, lo, d_hi, d_lo), est_hi, est_lo, held[:count],
                                     held_z)
        n_rhs += spent
    if status != ig.STATUS_OK:
        for a in (hi, lo, integral, error, d_hi, d_lo):
            a[:] = np.nan
    return hi, lo, integral / span, error / span, d_hi, d_lo, z[n:], status, n_rhs


def orbit_extrema(kernel, u0, p, span, weights, opts):
    """(highest, lowest, status) of each observable (`orbit_extent`)."""
    hi, lo, _, _, status, _ = orbit_extent(kernel, u0, p, span, weights, opts, False)
    return hi, lo, status


@njit(cache=True, nogil=True, inline="always")
def _directional(weights, z, n, tangent, out):
    """out = w . v for each observable where `tangent` (z = [u, v], v from index n), else 0."""
    for k in range(weights.shape[0]):
        acc = 0.0
        if tangent:
            for i in range(weights.shape[1]):
                acc += weights[k, i] * z[n + i]
        out[k] = acc


@njit(cache=True, nogil=True, inline="always")
def _hold(held, held_z, i, row, z):
    """Row i of the held brackets (element loops: no slice assignment's shape check)."""
    for j in range(7):
        held[i, j] = row[j]
    for j in range(z.size):
        held_z[i, j] = z[j]


@njit(cache=True, nogil=True)
def _settle(kernel, p, q, weights, opts, k, t, h, s, ga, gb, z, extremes):
    """Refine the bracket of o_k's extremum in the step [t, t + h] from z (estimate t + s); where
    it beats hi[k] (a maximum: g from + to -) or lo[k] (extremes = (hi, lo, d_hi, d_lo)), set it
    and, in the tangent-linear mode (z = [u, v], q its TangentParams), its derivative from the
    direction carried to its time (one step, the refinement's last): (status, n_rhs)."""
    hi, lo, d_hi, d_lo = extremes
    n = kernel.n_state
    v, c, n_rhs = _refine(kernel, t, h, s, z[:n], p, weights, k, ga, gb, opts)
    if not np.isfinite(v):
        return ig.STATUS_NAN, n_rhs
    maximum = ga > 0.0
    if (v > hi[k]) if maximum else (v < lo[k]):
        d = 0.0
        if z.size > n:
            zc, status, spent, _ = ig.flow(kernel, t, t + c, z, q, True, opts, c)
            n_rhs += spent
            if status != ig.STATUS_OK:
                return status, n_rhs
            dv = np.empty(weights.shape[0])
            _directional(weights, zc, n, True, dv)
            d = dv[k]
        if maximum:
            hi[k], d_hi[k] = v, d
        else:
            lo[k], d_lo[k] = v, d
    return ig.STATUS_OK, n_rhs


@njit(cache=True, nogil=True)
def _refine_held(kernel, p, q, weights, opts, extremes, est_hi, est_lo, held, held_z):
    """Refine the held brackets whose estimate is within CANDIDATE_MARGIN of the estimated
    highest (est_hi; a maximum: g from + to -) or lowest value (est_lo), updating extremes = (hi,
    lo, d_hi, d_lo) (`_settle`): (status, right-hand sides evaluated)."""
    n_rhs = 0
    for i in range(held.shape[0]):
        t, h, s, est, k, ga, gb = held[i, 0], held[i, 1], held[i, 2], held[i, 3], int(held[i, 4]), held[i, 5], held[i, 6]
        margin = CANDIDATE_MARGIN * (est_hi[k] - est_lo[k])
        maximum = ga > 0.0
        if (maximum and est < est_hi[k] - margin) or (not maximum and est > est_lo[k] + margin):
            continue
        status, spent = _settle(kernel, p, q, weights, opts, k, t, h, s, ga, gb, held_z[i], extremes)
        n_rhs += spent
        if status != ig.STATUS_OK:
            return status, n_rhs
    return ig.STATUS_OK, n_rhs


def observable_weights(model, period):
    """The observables' weights on the scaled state, so that weights @ u[:m] is in SI (m: the
    components the observables read; period: the forcing period [s], for velocity components)."""
    w = np.array([o.weights for o in model.observables], float).reshape(len(model.observables), -1)
    scale = model.to_physical(np.ones(model.n_state), period)[:w.shape[1]]
    return np.ascontiguousarray(w * scale)


def extent(model, state, p, span, opts, period):
    """(highest, lowest, mean, mean's error estimate, right-hand sides evaluated) of each
    observable over the orbit through `state` lasting `span` (scaled time: forcing periods), SI;
    NaN values where the orbit could not be integrated (`orbit_extent`)."""
    hi, lo, mean, error, _, n_rhs = orbit_extent(model.kernel, np.asarray(state, float), p, float(span),
                                                 observable_weights(model, period), opts, True)
    return hi, lo, mean, error, n_rhs


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


def tangent_params(params, lam, dlam, step):
    """integrators.TangentParams of a parameter change dlam at lam (params(lambda) -> p), its term
    a central difference of step `step` in lambda: truncation ~step^2, round-off ~1e-16 / step
    relative to f's change with lambda."""
    return ig.TangentParams(params(lam), params(lam + step), params(lam - step), dlam / (2.0 * step))


def parameter_pass(kernel, s, params, lam, step, span, weights, opts):
    """((highest, lowest, d_highest, d_lowest), d phi / d lambda, status, n_rhs): the orbit from s
    integrated with its derivative in the parameter on its own steps (orbit_extent_slope along
    dlambda = 1; `step`: the parameter term's), so a branch's tangent is as exact as its orbits
    (two independent adaptive integrations would leave rtol / step), and with it the extremes of
    the observables (the rows of weights) and their derivatives in lambda."""
    n = s.size
    hi, lo, d_hi, d_lo, v_end, status, n_rhs = orbit_extent_slope(
        kernel, np.ascontiguousarray(s, dtype=float), np.zeros(n), tangent_params(params, lam, 1.0, step), span,
        weights, opts)
    return (hi, lo, d_hi, d_lo), v_end.copy(), status, n_rhs


def amplitudes_and_slope(kernel, X, tangent, p, span, weights, row, opts, along):
    """(amplitudes, slope, n_rhs) at a branch point X = (s, mu) (p its kernel vector) with unit
    tangent: amplitudes = [max |o|, half peak-to-peak of o] per observable (the rows of weights),
    slope the derivative of row's half peak-to-peak along the tangent. `along`: the extremes at X
    and their derivatives in X's last coordinate (parameter_pass's, scaled); this pass adds their
    derivatives along the tangent's state part (orbit_extent_slope without a parameter term: one
    right-hand side per stage instead of three). An extremum's derivative is linear in the
    direction, and both passes take the orbit's own steps and extrema (their error control reads
    the orbit only), so the sum is the derivative along the whole tangent, to round-off. NaN where
    the orbit cannot be integrated."""
    s = np.ascontiguousarray(X[:-1], dtype=float)
    _, _, d_hi, d_lo, _, _, n_rhs = orbit_extent_slope(kernel, s, np.ascontiguousarray(tangent[:-1], dtype=float),
                                                       ig.TangentParams(p, p, p, 0.0), span, weights, opts)
    hi, lo, d_hi_mu, d_lo_mu = along
    slope = 0.5 * ((d_hi[row] + tangent[-1] * d_hi_mu[row]) - (d_lo[row] + tangent[-1] * d_lo_mu[row]))
    return np.array([np.maximum(hi, -lo), 0.5 * (hi - lo)]), float(slope), n_rhs

"""Lyapunov exponents (`lyapunov_spectrum`): the state and an orthonormal tangent frame Q (n x n)
are integrated together with the variational equations; every `renorm_periods` forcing periods
the evolved frame is re-orthonormalized, Phi = Q R (numpy QR, signs fixed so that diag R > 0),
and log R_ii of each interval is added to running (prefix) sums. Three phases:

1. state transient (`n_transient` periods, no variational equations): reach the attractor;
2. frame alignment (`align_periods`): QR steps whose logs are discarded, so that Q converges to
   the Gram-Schmidt (Lyapunov) vectors and the start-up offset -- which decays only like 1/t in
   a running mean -- does not bias the result. On a stable periodic orbit whose leading
   multipliers are real and distinct, every later period's R_ii is then exactly |lambda_i|;
3. measurement: intervals until `max_periods`, or until the largest exponent's standard error
   is below rtol_stop |lle| + atol_stop (checked from `min_periods` on), or -- weighted runs
   with converged_stop -- until the weighted average has converged to 0 (CONVERGED_FRACTION).

Estimate: the exponents are averages of the interval logs per unit tau -- by default a weighted
Birkhoff average (see WEIGHT_STDERR_FACTOR), or the plain running-sum mean (weighted=False). A
complex pair of multipliers (the rule on these lightly damped rotors: with isotropic damping a
stable orbit's four multipliers often share one modulus) has no invariant line, so log R_11
oscillates with the pair's rotation; the plain mean then converges like 1/t, the weighted one
much faster (60 Hz, 3.8 um, 1000 periods: 3e-4 -> 2e-6 relative). The sum of the exponents is
the divergence of the flow, exactly (Liouville): -2 D T / M per unit tau for jeffcott_clearance.

Uncertainty: the measured intervals are cut into `n_blocks` equal contiguous blocks, and
stderr = std(block means) / sqrt(n_blocks - 1) (std with ddof 0), times the weighting factor
when weighted. It measures the statistical error of a chaotic run; on a periodic orbit or a
torus it bounds the oscillation, which the weighted average removes far better than that.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from rotorsweep.kernels import integrators as ig

Lyapunov = namedtuple("Lyapunov", "exponents stderr lle lle_stderr periods_used status")

# Weighted Birkhoff average (Das & Yorke 2017): the exponents are averages of log R_ii over the
# intervals; weighting interval k of N by w(s) = exp(-1 / (s (1 - s))), s = (k + 1/2) / N, makes
# the average of a quasi-periodic sequence -- log R_ii on a stable orbit with complex
# multipliers, on a linear system with complex eigenvalues, on a torus -- converge faster than
# any power of N instead of like 1/N, and discounts the start (residual transient) and the end.
# For a chaotic (mixing) sequence it is as unbiased as the plain mean, with a standard error
# larger by sqrt(N sum w^2) / sum w -> WEIGHT_STDERR_FACTOR.
MIN_WEIGHTED = 16
WEIGHT_STDERR_FACTOR = 1.4009072495406112

# Converged stop, for a zero exponent (a torus, where the block standard error falls only like
# 1/N and kept these runs going to the period cap): the interval logs on a torus are a
# quasi-periodic sequence, whose weighted averages over the first N/2, 3N/4 and N intervals
# converge together much faster (Fig. 13's tori: within 1e-4 per period after 300-450 periods,
# 1e-6 after 600-1000; the block error is ~3e-3 then). The run stops once those three averages
# and the last of them are all within atol_stop of 0, and their spread is below
# CONVERGED_FRACTION x the block standard error (for a mixing sequence the three averages
# differ by the order of that error). A chaotic attractor (exponent > 2e-3 per period, see
# diagnosis.LLE_FLOOR) or a contracting one (a slowly settling orbit) is not near 0 and runs as
# before; the reported standard error stays the block estimate. The end state (the next speed's
# start) is then on the torus as the capped run's is, at another phase along it -- what the
# attractor benchmark's noise floor (a run one period longer) varies too. Checked every
# CONVERGED_EVERY intervals (three weighted sums cost ~1/3 of an interval's integration).
CONVERGED_FRACTION = 0.1
CONVERGED_EVERY = 8


@njit(cache=True, nogil=True)
def _block_stderr(csum, n_done, n_blocks, dt):
    """Standard error of the plain mean of each exponent from n_blocks equal contiguous blocks
    of the n_done intervals: std(block means) / sqrt(n_blocks - 1). csum[k] = sum of the logs of
    the first k intervals, shape (N + 1, n)."""
    n = csum.shape[1]
    stderr = np.full(n, np.inf)
    b = n_done // n_blocks
    if n_blocks < 2 or b < 1:
        return stderr
    means = np.empty((n_blocks, n))
    for j in range(n_blocks):
        means[j] = (csum[(j + 1) * b] - csum[j * b]) / (b * dt)
    for i in range(n):
        mu = 0.0
        for j in range(n_blocks):
            mu += means[j, i]
        mu /= n_blocks
        var = 0.0
        for j in range(n_blocks):
            var += (means[j, i] - mu) ** 2
        stderr[i] = np.sqrt(var / n_blocks) / np.sqrt(n_blocks - 1.0)
    return stderr


@njit(cache=True, nogil=True)
def _weighted_sums(csum, m, n):
    """(sum of w_k log R_ii over the first m intervals for the first n exponents, sum of w_k):
    the weighted Birkhoff average's numerator and denominator (see WEIGHT_STDERR_FACTOR)."""
    acc = np.zeros(n)
    wsum = 0.0
    for k in range(m):
        s = (k + 0.5) / m
        w = np.exp(-1.0 / (s * (1.0 - s)))
        wsum += w
        for i in range(n):
            acc[i] += w * (csum[k + 1, i] - csum[k, i])
    return acc, wsum


@njit(cache=True, nogil=True)
def _weighted_first(csum, m):
    """Weighted Birkhoff average of the first exponent's logs over the first m intervals (per
    interval, not per unit tau)."""
    acc, wsum = _weighted_sums(csum, m, 1)
    return acc[0] / wsum


@njit(cache=True, nogil=True)
def _weighted_spread(csum, n_done):
    """Spread (max - min) of the first exponent's weighted averages over the first n_done / 2,
    3 n_done / 4 and n_done intervals, and the last of them (per interval)."""
    a = _weighted_first(csum, n_done // 2)
    b = _weighted_first(csum, (3 * n_done) // 4)
    c = _weighted_first(csum, n_done)
    return max(a, b, c) - min(a, b, c), c


@njit(cache=True, nogil=True)
def _converged(csum, n_done, se, renorm, atol_stop):
    """The converged-stop test (CONVERGED_FRACTION); se: the block standard error of the
    weighted estimate, per unit tau."""
    spread, lle = _weighted_spread(csum, n_done)
    spread /= renorm
    return abs(lle / renorm) + spread <= atol_stop and spread <= CONVERGED_FRACTION * se


@njit(cache=True, nogil=True)
def _estimate(csum, n_done, n_blocks, dt, weighted):
    """(exponents, stderr) per unit time from the first n_done intervals."""
    stderr = _block_stderr(csum, n_done, n_blocks, dt)
    if not weighted or n_done < MIN_WEIGHTED:
        return csum[n_done] / (n_done * dt), stderr
    acc, wsum = _weighted_sums(csum, n_done, csum.shape[1])
    return acc / (wsum * dt), stderr * WEIGHT_STDERR_FACTOR


@njit(cache=True, nogil=True)
def _benettin(kernel, u0, p, opts, n_transient, align_intervals, renorm,
              max_intervals, min_intervals, n_blocks, rtol_stop, atol_stop, weighted, start=0.0,
              clock=0.0, converged_stop=False):
    """Benettin/QR kernel. Returns (exponents per unit tau, stderr, intervals measured, status,
    end state, end time); the end state is taken at the next whole period. start: the time of
    u0; clock as in _poincare (1: time runs on through the transient). converged_stop (weighted
    runs only): also stop once the weighted average has converged (CONVERGED_FRACTION)."""
    n = kernel.n_state
    nan = np.full(n, np.nan)
    u = u0.copy()
    h = 0.0
    for k in range(n_transient):
        t = start + k * clock
        u, status, _, h = ig.flow(kernel, t, t + 1.0, u, p, False, opts, h)
        if status != ig.STATUS_OK:
            return nan, nan.copy(), 0, status, u, start + float(k + 1)
    t0 = start + float(n_transient)
    z = ig.initial_state(u, n, True)
    csum = np.zeros((max_intervals + 1, n))
    n_done = 0
    hv = 0.0
    t = t0
    factor = WEIGHT_STDERR_FACTOR if weighted else 1.0
    for k in range(align_intervals + max_intervals):
        t1 = t0 + (k + 1) * renorm
        z, status, _, hv = ig.flow(kernel, t, t1, z, p, True, opts, hv)
        t = t1
        if status != ig.STATUS_OK:
            return nan, nan.copy(), n_done, status, z[:n].copy(), t
        phi = z[n:].copy().reshape((n, n))
        q, r = np.linalg.qr(phi)
        for i in range(n):
            d = r[i, i]
            sign = 1.0 if d >= 0.0 else -1.0
            for j in range(n):
                z[n + j * n + i] = sign * q[j, i]
            if k >= align_intervals:
                csum[n_done + 1, i] = csum[n_done, i] + np.log(max(abs(d), 1e-300))
        if k < align_intervals:
            continue
        n_done += 1
        if n_done >= min_intervals and n_done < max_intervals:
            se = _block_stderr(csum, n_done, n_blocks, renorm)[0] * factor
            if se <= rtol_stop * abs(csum[n_done, 0] / (n_done * renorm)) + atol_stop:
                break
            if (converged_stop and weighted and n_done % CONVERGED_EVERY == 0
                    and _converged(csum, n_done, se, renorm, atol_stop)):
                break
    expo, stderr = _estimate(csum, n_done, n_blocks, renorm, weighted)
    # finish on a whole period so the end state can start a neighbour's run at tau = 0
    u = z[:n].copy()
    t_end = np.ceil(t - 1e-9)
    if t_end > t:
        u, status, _, _ = ig.flow(kernel, t, t_end, u, p, False, opts, 0.0)
        if status != ig.STATUS_OK:
            return nan, nan.copy(), n_done, status, u, t_end
    return expo, stderr, n_done, ig.STATUS_OK, u, max(t, t_end)


def entry_points(kernel, opts):
    """(jitted function, example arguments) with the types `run_benettin` calls it with (warm-up)."""
    return [(_benettin, (kernel, np.zeros(kernel.n_state), np.zeros(1), opts, 0, 0, 1.0, 1, 2, 2, 1e-3, 1e-4, True,
                         0.0, 0.0, False))]


def run_problems(renorm_periods, n_blocks, max_periods):
    """Messages for run lengths a Lyapunov run cannot work with."""
    out = []
    if not renorm_periods > 0:
        out.append(f"renorm_periods must be > 0, got {renorm_periods!r}")
    if n_blocks < 2:
        out.append(f"n_blocks must be >= 2, got {n_blocks!r}")
    if not max_periods >= renorm_periods:
        out.append(f"max_periods must be >= renorm_periods, got {max_periods!r}")
    return out


def run_benettin(model, u0, p, opts, n_transient, renorm_periods, max_periods, n_blocks, rtol_stop,
                 min_periods=None, atol_stop=1e-4, align_periods=20.0, weighted=True, start=0.0,
                 clock=0.0, converged_stop=False):
    """`lyapunov_spectrum`'s run from u0 at time `start` (clock as in `poincare`), also returning
    its end state at a whole period and that time: (exponents per unit tau, stderr, intervals
    measured, status, end state, end time). Run lengths that cannot work raise ValueError."""
    problems = run_problems(renorm_periods, n_blocks, max_periods)
    if problems:
        raise ValueError("; ".join(problems))
    renorm = float(renorm_periods)
    max_intervals = max(1, int(round(max_periods / renorm)))
    if min_periods is None:
        min_periods = min(max_periods, 100.0)
    min_intervals = max(n_blocks, int(round(min_periods / renorm)))
    align_intervals = max(0, int(round(align_periods / renorm)))
    return _benettin(model.kernel, np.asarray(u0, float), p, opts, int(n_transient), align_intervals, renorm, max_intervals, min_intervals,
                     int(n_blocks), float(rtol_stop), float(atol_stop), bool(weighted), float(start),
                     float(clock), bool(converged_stop))


def lyapunov_spectrum(model, u0, p, opts, n_transient=200, renorm_periods=1.0, max_periods=2000,
                      n_blocks=10, rtol_stop=0.02, *, min_periods=None, atol_stop=1e-4,
                      align_periods=20.0, weighted=True, converged_stop=False):
    """Full Lyapunov spectrum from u0 at tau = 0: Benettin with QR every renorm_periods forcing
    periods (may be fractional, e.g. 0.5), after n_transient periods (state only) and
    align_periods (frame alignment, logs discarded).

    Returns (exponents per unit tau, largest first (n_state,), stderr (n_state,), periods_used,
    status). periods_used counts the measured periods. The run stops after max_periods, or
    earlier -- not before min_periods (default min(max_periods, 100)) -- once
    stderr[0] <= rtol_stop * |lle| + atol_stop. weighted: weighted Birkhoff average of the
    interval logs (default) or the plain running-sum mean; stderr is the block estimate of the
    plain mean, times WEIGHT_STDERR_FACTOR when weighted. converged_stop (weighted only): also
    stop once the weighted average has converged to 0 within atol_stop (a torus:
    CONVERGED_FRACTION; stderr stays the block estimate). A failed integration returns NaN
    exponents and its STATUS_* code. Divide by T for 1/s (`lyapunov_si`)."""
    expo, stderr, n_done, status, _, _ = run_benettin(
        model, u0, p, opts, n_transient, renorm_periods, max_periods, n_blocks, rtol_stop,
        min_periods, atol_stop, align_periods, weighted, converged_stop=converged_stop)
    return expo, stderr, n_done * float(renorm_periods), int(status)


def largest_lyapunov(model, u0, p, opts, n_transient=200, renorm_periods=1.0, max_periods=2000,
                     n_blocks=10, rtol_stop=0.02, **kw):
    """(lle, stderr, periods_used, status) per unit tau: the first component of the same run as
    `lyapunov_spectrum` (the full QR costs little more than one vector for these small systems,
    and keeps the sum rule available as a check)."""
    expo, stderr, used, status = lyapunov_spectrum(model, u0, p, opts, n_transient, renorm_periods,
                                                   max_periods, n_blocks, rtol_stop, **kw)
    return float(expo[0]), float(stderr[0]), used, status


def lyapunov_si(model, u0, p, period, opts, **kw):
    """`lyapunov_spectrum` in SI: a Lyapunov tuple with exponents and stderr in 1/s (the per-tau
    values / T, T = forcing period in s), the largest one separately, periods_used, status."""
    expo, stderr, used, status = lyapunov_spectrum(model, u0, p, opts, **kw)
    expo = np.asarray(expo) / period
    stderr = np.asarray(stderr) / period
    return Lyapunov(expo, stderr, float(expo[0]), float(stderr[0]), used, status)


def derived_lle(max_abs_multiplier, period_T):
    """ln(max |lambda|) / T: the largest exponent of a stable periodic orbit from its Floquet
    multipliers (the shortcut when the transient settles onto the period-1 orbit). Units of 1/T."""
    return float(np.log(max_abs_multiplier) / period_T)

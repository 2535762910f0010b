"""Attractor diagnostics from a long run after a transient: stroboscopic Poincare samples,
period-k detection, Lyapunov exponents (Benettin with QR), power spectrum, classification.

Everything works in the models' scaled time tau = t / T (the forcing period is 1), so the
kernels return exponents *per unit tau* (per forcing period); `lyapunov_si` divides by T to give
1/s. Pure numerics: arrays in, arrays out, failures as status codes (the integrators' STATUS_*).

Lyapunov exponents (`lyapunov_spectrum`): the state and an orthonormal tangent frame Q (n x n)
are integrated together with the variational equations; every `renorm_periods` forcing periods
the evolved frame is re-orthonormalized, Phi = Q R (numpy QR, signs fixed so that diag R > 0),
and log R_ii of each interval is added to running (prefix) sums. Three phases:

1. state transient (`n_transient` periods, no variational equations): reach the attractor;
2. frame alignment (`align_periods`): QR steps whose logs are discarded, so that Q converges to
   the Gram-Schmidt (Lyapunov) vectors and the start-up offset -- which decays only like 1/t in
   a running mean -- does not bias the result. On a stable periodic orbit whose leading
   multipliers are real and distinct, every later period's R_ii is then exactly |lambda_i|;
3. measurement: intervals until `max_periods`, or until the largest exponent's standard error
   is below rtol_stop |lle| + atol_stop (checked from `min_periods` on).

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

from rotorkernels import floquet, integrators as ig, shooting

ATTRACTOR = ("not_computed", "periodic", "quasi_periodic", "chaotic", "diverged")
NOT_COMPUTED, PERIODIC, QUASI_PERIODIC, CHAOTIC, DIVERGED = range(5)

# classify(): an exponent counts as positive (chaos) when lle > SIGMAS * stderr + LLE_FLOOR and
# as negative (a stable orbit) when lle < -(SIGMAS * stderr + LLE_FLOOR); in between it is zero
# within its uncertainty. LLE_FLOOR is per forcing period (per unit tau): a growth by
# exp(0.002) per period cannot be told from zero in the runs used here (a few hundred to a few
# thousand periods), and it keeps a slowly settling orbit or a torus from reading as chaos.
SIGMAS = 3.0
LLE_FLOOR = 2e-3

# detect_period(): a sample repeats when it is within rel_tol * scale of the one k periods
# later, scale = max(spread of the tail samples, PERIOD_FLOOR * their magnitude, tiny): the
# magnitude floor keeps a settled period-1 orbit (spread ~ 0) from needing exact equality.
PERIOD_FLOOR = 1.0

Lyapunov = namedtuple("Lyapunov", "exponents stderr lle lle_stderr periods_used status")
# exponents, lle, lle_stderr in 1/s; multipliers: of the period-k orbit when the attractor is
# periodic and its orbit was refined by shooting on k T (else NaN); derived: the exponents come
# from those multipliers, not from a Lyapunov run.
Attractor = namedtuple("Attractor", "code period lle lle_stderr samples end_state status periods_used "
                                    "exponents multipliers derived")


# --- Poincare samples -----------------------------------------------------------------------

@njit(cache=True, nogil=True)
def _poincare(model, u0, p, n, n_position, opts, n_transient, n_samples):
    """Samples at tau = n_transient + i, i = 0 .. n_samples - 1, starting from u0 at tau = 0.

    Returns (samples, status, end state); rows after a failure stay NaN."""
    out = np.full((n_samples, n), np.nan)
    u = u0.copy()
    h = 0.0
    # Every period is integrated over tau in [0, 1] (the models are 1-periodic in tau) and the
    # sampled ones all start with the same trial step, so that no time offset or carried-over
    # step size makes one period's computation differ from the next. (The adaptive step
    # sequence still varies with the state across the contact kinks: settled samples jitter by
    # ~1e2-1e3 x rtol, see default_period_rtol.)
    for _ in range(n_transient):
        u, status, _, h = ig.flow(model, 0.0, 1.0, u, p, n, n_position, False, opts, h)
        if status != ig.STATUS_OK:
            return out, status, u
    h_fixed = h
    for i in range(n_samples):
        out[i] = u
        if i == n_samples - 1:
            break
        u, status, _, _ = ig.flow(model, 0.0, 1.0, u, p, n, n_position, False, opts, h_fixed)
        if status != ig.STATUS_OK:
            return out, status, u
    return out, ig.STATUS_OK, u


def poincare(model, u0, p, opts, n_transient, n_samples):
    """Stroboscopic samples (n_samples, n_state), once per forcing period (tau integer) after a
    transient of n_transient periods from u0 at tau = 0, and the integrator status. A run that
    fails (STATUS_NAN, STATUS_AMPLITUDE, STATUS_STEP_UNDERFLOW) returns the samples taken so far
    with the rest NaN. The last row is the end state (the start of a neighbour's run)."""
    samples, status, _ = _poincare(model.id, np.asarray(u0, float), p, model.n_state,
                                   model.n_position, opts, int(n_transient), int(n_samples))
    return samples, int(status)


# --- period detection -----------------------------------------------------------------------

@njit(cache=True, nogil=True)
def _detect_period(samples, max_period, rel_tol, floor):
    n, d = samples.shape
    tail = samples[n // 2:] if n - n // 2 >= 2 else samples
    m = tail.shape[0]
    spread = 0.0
    magnitude = 0.0
    for j in range(d):
        lo = np.inf
        hi = -np.inf
        for i in range(m):
            v = tail[i, j]
            if not np.isfinite(v):
                return 0
            lo = min(lo, v)
            hi = max(hi, v)
            magnitude = max(magnitude, abs(v))
        spread = max(spread, hi - lo)
    tol = rel_tol * max(spread, floor * magnitude, 1e-300)
    for k in range(1, min(max_period, m // 2) + 1):
        ok = True
        for i in range(m - k):
            for j in range(d):
                if abs(tail[i + k, j] - tail[i, j]) > tol:
                    ok = False
                    break
            if not ok:
                break
        if ok:
            return k
    return 0


def default_period_rtol(opts):
    """Tolerance for detect_period on samples computed with integrator settings `opts`: the
    stroboscopic samples of a settled orbit jitter by about 1e2-1e3 x rtol of the adaptive
    integrator relative to their spread (the step sequence changes from period to period across
    the contact kinks), with rare excursions ten times larger, so max(1e-6, 1e5 x rtol); fixed-
    step RK4 computes the same map every period, 1e-6."""
    if opts[ig.S_METHOD] == ig.METHOD_RK4:
        return 1e-6
    return max(1e-6, 1e5 * float(opts[ig.S_RTOL]))


def detect_period(samples, max_period=32, rel_tol=1e-6, floor=PERIOD_FLOOR):
    """Smallest k <= max_period with samples[i + k] == samples[i] (within tolerance) for every i
    of the tail (the second half of the samples), or 0 when there is none.

    Tolerance: rel_tol * max(spread, floor * magnitude), spread = largest peak-to-peak range of a
    component over the tail, magnitude = largest |component|. k is also limited to half the tail
    (a period must be seen at least twice), so 128 samples resolve periods up to 32. Any NaN -> 0.
    """
    s = np.asarray(samples, float)
    if s.ndim == 1:
        s = s[:, None]
    return int(_detect_period(np.ascontiguousarray(s), int(max_period), float(rel_tol), float(floor)))


# --- Lyapunov exponents ---------------------------------------------------------------------

# Weighted Birkhoff average (Das & Yorke 2017): the exponents are averages of log R_ii over the
# intervals; weighting interval k of N by w(s) = exp(-1 / (s (1 - s))), s = (k + 1/2) / N, makes
# the average of a quasi-periodic sequence -- log R_ii on a stable orbit with complex
# multipliers, on a linear system with complex eigenvalues, on a torus -- converge faster than
# any power of N instead of like 1/N, and discounts the start (residual transient) and the end.
# For a chaotic (mixing) sequence it is as unbiased as the plain mean, with a standard error
# larger by sqrt(N sum w^2) / sum w -> WEIGHT_STDERR_FACTOR.
MIN_WEIGHTED = 16
WEIGHT_STDERR_FACTOR = 1.4009072495406112


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
def _estimate(csum, n_done, n_blocks, dt, weighted):
    """(exponents, stderr) per unit time from the first n_done intervals."""
    stderr = _block_stderr(csum, n_done, n_blocks, dt)
    if not weighted or n_done < MIN_WEIGHTED:
        return csum[n_done] / (n_done * dt), stderr
    n = csum.shape[1]
    acc = np.zeros(n)
    wsum = 0.0
    for k in range(n_done):
        s = (k + 0.5) / n_done
        w = np.exp(-1.0 / (s * (1.0 - s)))
        wsum += w
        for i in range(n):
            acc[i] += w * (csum[k + 1, i] - csum[k, i])
    return acc / (wsum * dt), stderr * WEIGHT_STDERR_FACTOR


@njit(cache=True, nogil=True)
def _benettin(model, u0, p, n, n_position, opts, n_transient, align_intervals, renorm,
              max_intervals, min_intervals, n_blocks, rtol_stop, atol_stop, weighted):
    """Benettin/QR kernel. Returns (exponents per unit tau, stderr, intervals measured, status,
    end state, end time); the end state is taken at the next whole period."""
    nan = np.full(n, np.nan)
    u = u0.copy()
    h = 0.0
    for k in range(n_transient):
        u, status, _, h = ig.flow(model, 0.0, 1.0, u, p, n, n_position, False, opts, h)
        if status != ig.STATUS_OK:
            return nan, nan.copy(), 0, status, u, float(k + 1)
    t0 = float(n_transient)
    z = ig.initial_state(u, n, True)
    csum = np.zeros((max_intervals + 1, n))
    n_done = 0
    hv = 0.0
    t = t0
    factor = WEIGHT_STDERR_FACTOR if weighted else 1.0
    for k in range(align_intervals + max_intervals):
        t1 = t0 + (k + 1) * renorm
        z, status, _, hv = ig.flow(model, t, t1, z, p, n, n_position, True, opts, hv)
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
    expo, stderr = _estimate(csum, n_done, n_blocks, renorm, weighted)
    # finish on a whole period so the end state can start a neighbour's run at tau = 0
    u = z[:n].copy()
    t_end = np.ceil(t - 1e-9)
    if t_end > t:
        u, status, _, _ = ig.flow(model, t, t_end, u, p, n, n_position, False, opts, 0.0)
        if status != ig.STATUS_OK:
            return nan, nan.copy(), n_done, status, u, t_end
    return expo, stderr, n_done, ig.STATUS_OK, u, max(t, t_end)


def _run_benettin(model, u0, p, opts, n_transient, renorm_periods, max_periods, n_blocks, rtol_stop,
                  min_periods=None, atol_stop=1e-4, align_periods=20.0, weighted=True):
    renorm = float(renorm_periods)
    if not renorm > 0:
        raise ValueError(f"renorm_periods must be > 0, got {renorm_periods!r}")
    if n_blocks < 2:
        raise ValueError(f"n_blocks must be >= 2, got {n_blocks!r}")
    if not max_periods >= renorm:
        raise ValueError(f"max_periods must be >= renorm_periods, got {max_periods!r}")
    max_intervals = max(1, int(round(max_periods / renorm)))
    if min_periods is None:
        min_periods = min(max_periods, 100.0)
    min_intervals = max(n_blocks, int(round(min_periods / renorm)))
    align_intervals = max(0, int(round(align_periods / renorm)))
    return _benettin(model.id, np.asarray(u0, float), p, model.n_state, model.n_position,
                     opts, int(n_transient), align_intervals, renorm, max_intervals, min_intervals,
                     int(n_blocks), float(rtol_stop), float(atol_stop), bool(weighted))


def lyapunov_spectrum(model, u0, p, opts, n_transient=200, renorm_periods=1.0, max_periods=2000,
                      n_blocks=10, rtol_stop=0.02, *, min_periods=None, atol_stop=1e-4,
                      align_periods=20.0, weighted=True):
    """Full Lyapunov spectrum from u0 at tau = 0: Benettin with QR every renorm_periods forcing
    periods (may be fractional, e.g. 0.5), after n_transient periods (state only) and
    align_periods (frame alignment, logs discarded).

    Returns (exponents per unit tau, largest first (n_state,), stderr (n_state,), periods_used,
    status). periods_used counts the measured periods. The run stops after max_periods, or
    earlier -- not before min_periods (default min(max_periods, 100)) -- once
    stderr[0] <= rtol_stop * |lle| + atol_stop. weighted: weighted Birkhoff average of the
    interval logs (default) or the plain running-sum mean; stderr is the block estimate of the
    plain mean, times WEIGHT_STDERR_FACTOR when weighted. A failed integration returns NaN
    exponents and its STATUS_* code. Divide by T for 1/s (`lyapunov_si`)."""
    expo, stderr, n_done, status, _, _ = _run_benettin(
        model, u0, p, opts, n_transient, renorm_periods, max_periods, n_blocks, rtol_stop,
        min_periods, atol_stop, align_periods, weighted)
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


# --- power spectrum -------------------------------------------------------------------------

def power_spectrum(signal, dt):
    """One-sided spectrum of a uniformly sampled signal: (frequencies [1/dt units, Hz for dt in
    s], power). The mean is removed and a Hann window applied; power = (2 |X_k| / sum(w))^2, so
    a sinusoid of amplitude A centred on a bin reads A^2."""
    x = np.asarray(signal, float)
    x = x - x.mean()
    w = np.hanning(x.size)
    spec = np.fft.rfft(w * x)
    power = (2.0 * np.abs(spec) / w.sum()) ** 2
    return np.fft.rfftfreq(x.size, dt), power


# --- classification -------------------------------------------------------------------------

def closed_curve(samples, max_gap=np.pi / 3, max_jump=0.25, min_aspect=0.02):
    """Whether the tail of the Poincare samples (second half) lies on one closed curve around
    its centroid, as the section of a 2-torus does (heuristic, documented thresholds).

    The tail is projected on its two principal axes; in polar coordinates about the centroid,
    sorted by angle, the points must (1) surround the centroid, no angular gap over `max_gap`
    (a circle map with irrational rotation fills its curve; settling period-k points leave k
    clusters), (2) trace a continuous radius, no jump between angular neighbours over
    `max_jump` x the mean radius (a chaotic cloud jumps), (3) not be collinear, second principal
    extent >= `min_aspect` x the first (a slowly settling orbit near a period doubling
    alternates along a line). Needs at least 16 tail points."""
    s = np.asarray(samples, float)
    tail = s[len(s) // 2:]
    if len(tail) < 16 or not np.all(np.isfinite(tail)):
        return False
    x = tail - tail.mean(axis=0)
    _, sv, vt = np.linalg.svd(x, full_matrices=False)
    if sv[0] == 0.0 or len(sv) < 2 or sv[1] < min_aspect * sv[0]:
        return False
    xy = x @ vt[:2].T
    ang = np.arctan2(xy[:, 1], xy[:, 0])
    rad = np.hypot(xy[:, 0], xy[:, 1])
    order = np.argsort(ang)
    ang, rad = ang[order], rad[order]
    gaps = np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi]))
    if gaps.max() > max_gap:
        return False
    jumps = np.abs(np.diff(np.concatenate([rad, rad[:1]])))
    return bool(jumps.max() <= max_jump * rad.mean())


def classify(samples, lle, lle_stderr, period_k, status=ig.STATUS_OK, *, sigmas=SIGMAS,
             floor=LLE_FLOOR, check_curve=True):
    """(code into ATTRACTOR, k) from the Poincare samples, the largest exponent and its standard
    error, and the detected period.

    - diverged: a failed integration (status != STATUS_OK), NaN samples, or a NaN exponent;
    - periodic, k = period_k, when the samples repeat with period k > 0;
    - chaotic when lle > sigmas * lle_stderr + floor (positive beyond its uncertainty);
    - periodic with k = 0 (period not resolved: longer than max_period, or not settled to the
      detection tolerance, typically close to a bifurcation) when lle < -(sigmas * lle_stderr +
      floor);
    - zero within the uncertainty: quasi_periodic -- unless check_curve is set and the tail
      samples do not lie on a closed curve (`closed_curve`): then periodic, k = 0. This is what
      an orbit next to a bifurcation looks like (a multiplier near -1 or +1: the state settles
      onto, or drifts off, the orbit over thousands of periods, leaving clustered or collinear
      points and |lle| ~ 0), and what the sweeps find within ~0.1 Hz of a period doubling.
    lle, lle_stderr and floor share units: per forcing period (per unit tau) for the default
    floor. `samples` may be None when only the exponent is known (no curve check then)."""
    if status != ig.STATUS_OK or not np.isfinite(lle):
        return DIVERGED, 0
    if samples is not None and not np.all(np.isfinite(samples)):
        return DIVERGED, 0
    if period_k > 0:
        return PERIODIC, int(period_k)
    margin = sigmas * (lle_stderr if np.isfinite(lle_stderr) else np.inf) + floor
    if lle > margin:
        return CHAOTIC, 0
    if lle < -margin:
        return PERIODIC, 0
    if check_curve and samples is not None and not closed_curve(samples):
        return PERIODIC, 0
    return QUASI_PERIODIC, 0


# --- one point ------------------------------------------------------------------------------

def _shoot_k(model, state, p, opts, k):
    """Newton on k forcing periods from a state already on (or next to) the orbit."""
    return shooting.shoot(model.id, state.copy(), p, model.n_state, model.n_position, float(k),
                          opts, max(1e-9, 10.0 * float(opts[ig.S_RTOL])), 10)


def _minimal_period(model, state, p, opts, k, rel_tol):
    """Smallest divisor d of k for which the converged period-k orbit through `state` returns
    after d periods (within rel_tol x max(1, max|state|)). Samples that settle slowly onto a
    period-d orbit whose multiplier is close to -1 alternate with a decay too slow for the
    detection tolerance and pass for period 2 d; the Newton-converged orbit does not."""
    scale = rel_tol * max(1.0, float(np.abs(state).max()))
    for d in range(1, k):
        if k % d:
            continue
        u, status, _, _ = ig.flow(model.id, 0.0, float(d), state.copy(), p, model.n_state,
                                  model.n_position, False, opts, 0.0)
        if status == ig.STATUS_OK and np.abs(u - state).max() <= scale:
            return d
    return k


def periodic_orbit_of(model, state, p, opts, k, rel_tol):
    """Refine a period-k attractor through `state` by shooting on k T: (k_min, orbit state,
    multipliers of the k_min-periodic orbit), or None when Newton does not converge. k is
    reduced to the orbit's minimal period (`_minimal_period`)."""
    orbit = _shoot_k(model, state, p, opts, k)
    if orbit[2] != shooting.CONVERGED:
        return None
    d = _minimal_period(model, orbit[0], p, opts, k, rel_tol)
    if d < k:
        again = _shoot_k(model, orbit[0], p, opts, d)
        if again[2] == shooting.CONVERGED:
            orbit, k = again, d
    return k, orbit[0], floquet.multipliers(orbit[1])


def exponents_of_orbit(multipliers, k, period):
    """The Lyapunov spectrum of a periodic orbit: ln|lambda_i| / (k T), largest first."""
    return np.sort(np.log(np.abs(np.asarray(multipliers))))[::-1] / (k * period)


def settle_on_orbit(model, u0, p, opts, orbit_state, max_periods, rel_tol):
    """Integrate from u0 one forcing period at a time until the state is within rel_tol x
    max(1, max|orbit_state|) of the periodic orbit's state. Returns (state, periods used,
    reached). A start in the orbit's basin converges like max|lambda|^n; one on another
    attractor does not, and its periods then count as that attractor's transient."""
    u = np.asarray(u0, float).copy()
    scale = rel_tol * max(1.0, float(np.abs(orbit_state).max()))
    h = 0.0
    for n in range(int(max_periods) + 1):
        if np.abs(u - orbit_state).max() <= scale:
            return u, n, True
        if n == max_periods:
            break
        u, status, _, h = ig.flow(model.id, 0.0, 1.0, u, p, model.n_state, model.n_position,
                                  False, opts, h)
        if status != ig.STATUS_OK:
            break
    return u, n, False


def _on_stable_orbit(model, orbit_state, multipliers, period, n_samples, end_state):
    lle_all = exponents_of_orbit(multipliers, 1, period)
    samples = np.tile(orbit_state, (n_samples, 1))
    return Attractor(PERIODIC, 1, float(lle_all[0]), 0.0, samples, end_state, ig.STATUS_OK, 0.0,
                     lle_all, np.asarray(multipliers, complex), True)


# diagnose(): periodic samples whose refined orbit has max|lambda| > 1 + UNSTABLE_MARGIN sit on an
# unstable orbit, not an attractor; up to ESCAPES new transients follow, each from the state
# kicked by ESCAPE_KICK x its size.
UNSTABLE_MARGIN = 1e-6
ESCAPES = 2
ESCAPE_KICK = 1e-3


def diagnose(model, u0, p, period, opts, *, n_transient=200, n_samples=128, max_period=32,
             period_rtol=None, orbit_lle=True, lyapunov_always=False, stable_orbit=None,
             renorm_periods=1.0, max_periods=2000, n_blocks=10, rtol_stop=0.02, min_periods=None,
             atol_stop=1e-4, align_periods=20.0, weighted=True):
    """One parameter point from u0 at tau = 0: Poincare samples after a transient, their period
    (tolerance `default_period_rtol(opts)` unless given), the largest exponent, and `classify`.

    A periodic attractor (period k found) is refined by shooting on k T from the last sample
    (already on the orbit: one or two iterations; `periodic_orbit_of`), and its multipliers are
    returned. When orbit_lle is set and the orbit is stable, the exponents follow from them,
    ln|lambda_i| / (k T), stderr 0 (derived=True) -- unless lyapunov_always.
    stable_orbit = (state, multipliers) of a stable period-1 orbit found by shooting: the
    transient stops as soon as the state reaches it (`settle_on_orbit`), and the point is that
    orbit (samples = its state) with derived exponents -- the 'derive when stable' shortcut.
    Samples that repeat on an unstable orbit (a start on or next to it) are retaken after a kick
    off it (ESCAPES). Otherwise (no period, the shooting fails, or lyapunov_always) a Lyapunov
    run starts where the samples end (no second transient). Returns an Attractor: code, period k, lle and lle_stderr
    in 1/s (NaN when not computed), samples, end_state (the state at the last whole period
    reached: the start of the next speed in a continuation of the attractor), status,
    periods_used (measured Lyapunov periods; 0 when none ran), exponents [1/s], multipliers,
    derived."""
    if period_rtol is None:
        period_rtol = default_period_rtol(opts)
    u0 = np.asarray(u0, float)
    if stable_orbit is not None and not lyapunov_always:
        state, lams = stable_orbit
        u0, used, reached = settle_on_orbit(model, u0, p, opts, state, n_transient, period_rtol)
        if reached:
            return _on_stable_orbit(model, state, lams, period, int(n_samples), state.copy())
        n_transient -= used
    nan = np.full(model.n_state, np.nan)
    for attempt in range(1 + ESCAPES):
        samples, status, end = _poincare(model.id, u0, p, model.n_state, model.n_position, opts,
                                         int(n_transient), int(n_samples))
        if status != ig.STATUS_OK:
            return Attractor(DIVERGED, 0, np.nan, np.nan, samples, end, int(status), 0.0, nan,
                             nan + 0j, False)
        k = detect_period(samples, max_period, period_rtol)
        orbit = periodic_orbit_of(model, end, p, opts, k, period_rtol) if k > 0 and orbit_lle else None
        # Samples that repeat on an unstable orbit only show a start too close to it (a weakly
        # unstable orbit is left slowly): kick the state off it and take a new transient.
        if orbit is None or np.abs(orbit[2]).max() <= 1.0 + UNSTABLE_MARGIN or attempt == ESCAPES:
            break
        u0 = end + ESCAPE_KICK * max(1.0, float(np.abs(end).max()))
        n_transient = max(int(n_transient), 1)
    lams = nan + 0j
    if orbit is not None:
        k, _, lams = orbit
        if np.abs(lams).max() < 1.0 and not lyapunov_always:
            expo = exponents_of_orbit(lams, k, period)
            return Attractor(PERIODIC, k, float(expo[0]), 0.0, samples, end, int(status), 0.0,
                             expo, lams, True)
    if k > 0 and not orbit_lle and not lyapunov_always:
        return Attractor(PERIODIC, k, np.nan, np.nan, samples, end, int(status), 0.0, nan, lams, False)
    expo, stderr, n_done, lstatus, end2, _ = _run_benettin(
        model, end, p, opts, 0, renorm_periods, max_periods, n_blocks, rtol_stop, min_periods,
        atol_stop, align_periods, weighted)
    code, k = classify(samples, expo[0], stderr[0], k, lstatus)
    if code == PERIODIC and k == 0 and lstatus == ig.STATUS_OK:
        # a contracting attractor whose samples had not settled: by the end of the Lyapunov run
        # they have, so sample again there
        again, status2, end3 = _poincare(model.id, end2, p, model.n_state, model.n_position, opts,
                                         0, int(n_samples))
        k2 = detect_period(again, max_period, period_rtol) if status2 == ig.STATUS_OK else 0
        orbit = periodic_orbit_of(model, end3, p, opts, k2, period_rtol) if k2 > 0 else None
        if orbit is not None and np.abs(orbit[2]).max() < 1.0:
            k, _, lams = orbit
            samples, end2 = again, end3
    if code != PERIODIC or k == 0:
        lams = nan + 0j
    return Attractor(code, k, float(expo[0]) / period, float(stderr[0]) / period, samples, end2,
                     int(lstatus), n_done * float(renorm_periods), np.asarray(expo) / period, lams,
                     False)

"""Period-k detection in stroboscopic samples."""
import numpy as np
from numba import njit

from rotorsweep.kernels import integrators as ig

# detect_period(): a sample repeats when it is within rel_tol * scale of the one k periods
# later, scale = max(spread of the tail samples, PERIOD_FLOOR * their magnitude, tiny): the
# magnitude floor keeps a settled period-1 orbit (spread ~ 0) from needing exact equality.
PERIOD_FLOOR = 1.0


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


def entry_points(n_state):
    """(jitted function, example arguments) with the types `detect_period` calls it with (warm-up)."""
    return [(_detect_period, (np.zeros((2, n_state)), 1, 1e-6, 1e-3))]


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

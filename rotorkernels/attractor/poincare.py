"""Stroboscopic (Poincare) samples once per forcing period, and the power spectrum of a signal."""
import numpy as np
from numba import njit

from rotorsweep.kernels import integrators as ig


@njit(cache=True, nogil=True)
def _poincare(kernel, u0, p, opts, n_transient, n_samples, t0=0.0, clock=0.0):
    """Samples at tau = n_transient + i, i = 0 .. n_samples - 1, starting from u0 at tau = 0.

    clock: 0 for a model 1-periodic in tau; 1 for a quasi-periodically forced one, whose time
    runs on from t0 (the time of u0). Returns (samples, status, end state); rows after a failure
    stay NaN."""
    out = np.full((n_samples, kernel.n_state), np.nan)
    u = u0.copy()
    h = 0.0
    # Every period is integrated over tau in [0, 1] (the models are 1-periodic in tau) and the
    # sampled ones all start with the same trial step, so that no time offset or carried-over
    # step size makes one period's computation differ from the next. (The adaptive step
    # sequence still varies with the state across the contact kinks: settled samples jitter by
    # ~1e2-1e3 x rtol, see default_period_rtol.)
    t = t0
    for _ in range(n_transient):
        u, status, _, h = ig.flow(kernel, t, t + 1.0, u, p, False, opts, h)
        if status != ig.STATUS_OK:
            return out, status, u
        t += clock
    h_fixed = h
    for i in range(n_samples):
        out[i] = u
        if i == n_samples - 1:
            break
        u, status, _, _ = ig.flow(kernel, t, t + 1.0, u, p, False, opts, h_fixed)
        if status != ig.STATUS_OK:
            return out, status, u
        t += clock
    return out, ig.STATUS_OK, u


def entry_points(kernel, opts):
    """(jitted function, example arguments) with the types `diagnosis` calls it with (warm-up)."""
    return [(_poincare, (kernel, np.zeros(kernel.n_state), np.zeros(1), opts, 0, 1, 0.0, 0.0))]


def poincare(model, u0, p, opts, n_transient, n_samples):
    """Stroboscopic samples (n_samples, n_state), once per forcing period (tau integer) after a
    transient of n_transient periods from u0 at tau = 0, and the integrator status. A run that
    fails (STATUS_NAN, STATUS_AMPLITUDE, STATUS_STEP_UNDERFLOW) returns the samples taken so far
    with the rest NaN. The last row is the end state (the start of a neighbour's run)."""
    samples, status, _ = _poincare(model.kernel, np.asarray(u0, float), p, opts, int(n_transient),
                                   int(n_samples))
    return samples, int(status)



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

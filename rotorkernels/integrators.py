"""Numba integrators for any model (by id, see models.rhs/jac), optionally carrying the
variational equations.

The integrated vector is z = [u (n), Phi (n x n, row-major)] when `variational` is set, with
Phi' = J(t, u) Phi; otherwise z = u. Both integrators return (z_end, status, n_rhs, h_next):
`status` is one of the STATUS_* codes (failure is data, never an exception), `n_rhs` counts
right-hand-side evaluations (for benchmarks) and `h_next` is the step size to reuse on the next
call over a similar interval.

- dop853: Dormand-Prince 8(5,3) with the step-size control of Hairer/scipy (error measured on
  every component of z, so the monodromy is as accurate as the orbit).
- rk4: classical fixed-step Runge-Kutta, n_steps over the interval.
"""
import numpy as np
from numba import njit
from scipy.integrate._ivp import dop853_coefficients as _dop

from rotorkernels import models

STATUS_OK, STATUS_NAN, STATUS_AMPLITUDE, STATUS_STEP_UNDERFLOW = range(4)

_N_STAGES = _dop.N_STAGES
_A = np.ascontiguousarray(_dop.A[:_N_STAGES, :_N_STAGES])
_B = np.ascontiguousarray(_dop.B)
_C = np.ascontiguousarray(_dop.C[:_N_STAGES])
_E3 = np.ascontiguousarray(_dop.E3)
_E5 = np.ascontiguousarray(_dop.E5)
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_ERR_EXPONENT = -1.0 / 8.0


@njit(cache=True, nogil=True)
def derivative(model, t, z, p, n, variational, dz, jbuf):
    """dz/dt of the (possibly augmented) system."""
    models.rhs(model, t, z[:n], p, dz[:n])
    if variational:
        models.jac(model, t, z[:n], p, jbuf)
        for i in range(n):
            for j in range(n):
                acc = 0.0
                for k in range(n):
                    acc += jbuf[i, k] * z[n + k * n + j]
                dz[n + i * n + j] = acc


@njit(cache=True, nogil=True)
def state_status(z, n, n_position, amplitude_limit):
    """NaN/inf anywhere in the state, or a displacement beyond the physical limit."""
    for i in range(n):
        if not np.isfinite(z[i]):
            return STATUS_NAN
    for i in range(n_position):
        if abs(z[i]) > amplitude_limit:
            return STATUS_AMPLITUDE
    return STATUS_OK


@njit(cache=True, nogil=True)
def initial_state(u0, n, variational):
    """z0 = u0, or [u0, I] with the variational equations."""
    m = n + n * n if variational else n
    z = np.zeros(m)
    z[:n] = u0
    if variational:
        for i in range(n):
            z[n + i * n + i] = 1.0
    return z


@njit(cache=True, nogil=True)
def _error_norm(K, h, z, znew, rtol, atol):
    m = z.size
    e5 = 0.0
    e3 = 0.0
    for i in range(m):
        scale = atol + rtol * max(abs(z[i]), abs(znew[i]))
        s5 = 0.0
        s3 = 0.0
        for j in range(_N_STAGES + 1):
            s5 += K[j, i] * _E5[j]
            s3 += K[j, i] * _E3[j]
        e5 += (s5 / scale) ** 2
        e3 += (s3 / scale) ** 2
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    return abs(h) * e5 / np.sqrt((e5 + 0.01 * e3) * m)


@njit(cache=True, nogil=True)
def dop853(model, t0, t1, z0, p, n, n_position, variational, rtol, atol, h0, max_steps,
           amplitude_limit):
    """Integrate z from t0 to t1 > t0 with adaptive Dormand-Prince 8(5,3)."""
    m = z0.size
    z = z0.copy()
    status = state_status(z, n, n_position, amplitude_limit)
    if status != STATUS_OK:
        return z, status, 0, h0
    znew = np.empty(m)
    stage = np.empty(m)
    K = np.empty((_N_STAGES + 1, m))
    jbuf = np.empty((n, n))
    derivative(model, t0, z, p, n, variational, K[0], jbuf)
    n_rhs = 1
    t = t0
    h = h0 if h0 > 0.0 else 0.01 * (t1 - t0)
    for _ in range(max_steps):
        if t >= t1:
            return z, STATUS_OK, n_rhs, h
        last = t + h >= t1
        step = t1 - t if last else h
        rejected = False
        while True:
            if step < 10.0 * np.spacing(max(abs(t), 1.0)):
                return z, STATUS_STEP_UNDERFLOW, n_rhs, h
            for s in range(1, _N_STAGES):
                for i in range(m):
                    acc = 0.0
                    for j in range(s):
                        acc += _A[s, j] * K[j, i]
                    stage[i] = z[i] + step * acc
                derivative(model, t + _C[s] * step, stage, p, n, variational, K[s], jbuf)
            for i in range(m):
                acc = 0.0
                for j in range(_N_STAGES):
                    acc += _B[j] * K[j, i]
                znew[i] = z[i] + step * acc
            derivative(model, t + step, znew, p, n, variational, K[_N_STAGES], jbuf)
            n_rhs += _N_STAGES
            err = _error_norm(K, step, z, znew, rtol, atol)
            if err < 1.0:
                break
            # a NaN error (overflow inside a too-large step) shrinks the step like a huge error
            step *= max(_MIN_FACTOR, _SAFETY * err ** _ERR_EXPONENT) if np.isfinite(err) else _MIN_FACTOR
            last = False
            rejected = True
        t = t1 if last else t + step
        z[:] = znew
        K[0, :] = K[_N_STAGES, :]
        status = state_status(z, n, n_position, amplitude_limit)
        if status != STATUS_OK:
            return z, status, n_rhs, h
        factor = _MAX_FACTOR if err == 0.0 else min(_MAX_FACTOR, _SAFETY * err ** _ERR_EXPONENT)
        if rejected:
            factor = min(1.0, factor)
        h = step * factor
    return z, STATUS_STEP_UNDERFLOW, n_rhs, h


@njit(cache=True, nogil=True)
def rk4(model, t0, t1, z0, p, n, n_position, variational, n_steps, amplitude_limit):
    """Integrate z from t0 to t1 with n_steps classical RK4 steps."""
    m = z0.size
    z = z0.copy()
    k1 = np.empty(m)
    k2 = np.empty(m)
    k3 = np.empty(m)
    k4 = np.empty(m)
    stage = np.empty(m)
    jbuf = np.empty((n, n))
    h = (t1 - t0) / n_steps
    status = state_status(z, n, n_position, amplitude_limit)
    if status != STATUS_OK:
        return z, status, 0, h
    for step in range(n_steps):
        t = t0 + step * h
        derivative(model, t, z, p, n, variational, k1, jbuf)
        for i in range(m):
            stage[i] = z[i] + 0.5 * h * k1[i]
        derivative(model, t + 0.5 * h, stage, p, n, variational, k2, jbuf)
        for i in range(m):
            stage[i] = z[i] + 0.5 * h * k2[i]
        derivative(model, t + 0.5 * h, stage, p, n, variational, k3, jbuf)
        for i in range(m):
            stage[i] = z[i] + h * k3[i]
        derivative(model, t + h, stage, p, n, variational, k4, jbuf)
        for i in range(m):
            z[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        status = state_status(z, n, n_position, amplitude_limit)
        if status != STATUS_OK:
            return z, status, 4 * (step + 1), h
    return z, STATUS_OK, 4 * n_steps, h


# Integrator settings travel as one float vector so that every caller passes the same thing.
METHOD_DOP853, METHOD_RK4 = 0, 1
S_METHOD, S_RTOL, S_ATOL, S_STEPS_PER_UNIT, S_MAX_STEPS, S_AMPLITUDE = range(6)


def settings(method="dop853", rtol=1e-10, atol=1e-12, steps_per_unit=512, max_steps=200_000,
             amplitude_limit=1e3):
    """Integrator settings vector. steps_per_unit: RK4 steps per unit of (scaled) time, i.e. per
    forcing period; amplitude_limit: largest displacement (scaled) before a state counts as
    diverged."""
    codes = {"dop853": METHOD_DOP853, "rk4": METHOD_RK4}
    if method not in codes:
        raise ValueError(f"integrator must be one of {sorted(codes)}, got {method!r}")
    return np.array([codes[method], rtol, atol, steps_per_unit, max_steps, amplitude_limit], float)


@njit(cache=True, nogil=True)
def flow(model, t0, t1, z0, p, n, n_position, variational, opts, h0):
    """Integrate with the method and tolerances in `opts` (see `settings`)."""
    if opts[S_METHOD] == METHOD_RK4:
        n_steps = max(1, int(round(opts[S_STEPS_PER_UNIT] * (t1 - t0))))
        return rk4(model, t0, t1, z0, p, n, n_position, variational, n_steps, opts[S_AMPLITUDE])
    return dop853(model, t0, t1, z0, p, n, n_position, variational, opts[S_RTOL], opts[S_ATOL],
                  h0, int(opts[S_MAX_STEPS]), opts[S_AMPLITUDE])

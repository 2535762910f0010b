"""Numba integrators for any registered model (by its kernel identity, through the generated
`models.dispatch`: each function is compiled once per kernel group, the tag's type), optionally
carrying the variational equations.

The integrated vector is z = [u (n), Phi (n x n, row-major)] when `variational` is set, with
Phi' = J(t, u) Phi; otherwise z = u. With parameters `TangentParams` instead of the kernel vector
p (the tangent-linear mode), z = [u, v] with v' = J(t, u) v + df/dlambda dlambda, one direction
of the variational equations and a parameter change; its error control reads u only, so u takes
exactly the steps it takes alone, and v is the derivative of that discrete solution. Both
integrators return (z_end, status, n_rhs, h_next): `status` is one of the STATUS_* codes (failure
is data, never an exception), `n_rhs` counts right-hand-side evaluations (for benchmarks) and
`h_next` is the step size to reuse on the next call over a similar interval.

- dop853: Dormand-Prince 8(5,3) with the step-size control of Hairer/scipy (error measured on
  every component of z, so the monodromy is as accurate as the orbit).
- rk4: classical fixed-step Runge-Kutta, n_steps over the interval.

Cost (docs/benchmarks): the step loops (`_dop853_steps`, `_rk4_steps`) contain the model
inlined once (`_derivative`), take only arrays allocated by their caller and are compiled without
Numba's reference counting, so a stage costs the model's arithmetic plus the vectorised stage
sums; with the variational equations the model's right-hand side and Jacobian come from one
contact sum (`rhs_jac`) and J Phi uses the block form [[0, I], [A, B]] of the models. The
results are those of the straightforward formulation, operation by operation.
"""
from collections import namedtuple

import numpy as np
from numba import njit
from numba.core.errors import TypingError
from numba.extending import overload

from rotorsweep.kernels import PICKED_BODY, dop853_tableau as _dop
from rotorsweep.kernels.models import dispatch

STATUS_OK, STATUS_NAN, STATUS_AMPLITUDE, STATUS_STEP_UNDERFLOW, STATUS_UNKNOWN_MODEL = range(5)

_N_STAGES = _dop.N_STAGES
# Stage s = 1..11 of a step evaluates at t + C[s] h, z + h sum_j A[s, j] K[j]; the solution
# z + h sum_j B[j] K[j] is evaluated as stage 12 (row 12 of _A is B, _C[12] = 1) and the very
# first K[0] = f(t0, z0) as stage 0 (C[0] = 0): the stage loop is one loop with one (inlined)
# evaluation of the model, which keeps compilation time down.
_A = np.zeros((_N_STAGES + 1, _N_STAGES))
_A[:_N_STAGES] = _dop.A[:_N_STAGES, :_N_STAGES]
_A[_N_STAGES] = _dop.B
_C = np.ones(_N_STAGES + 1)
_C[:_N_STAGES] = _dop.C[:_N_STAGES]
_E3 = np.ascontiguousarray(_dop.E3)
_E5 = np.ascontiguousarray(_dop.E5)
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_ERR_EXPONENT = -1.0 / 8.0


# The tangent-linear mode's parameters (`_derivative`): the kernel vector p of the orbit, p at
# lambda + e and lambda - e, and scale = dlambda / (2 e), so that the direction's parameter term
# df/dlambda dlambda is the central difference (f(u, plus) - f(u, minus)) scale (f is smooth in
# the parameters at fixed u; scale 0: no parameter change, no extra evaluation).
TangentParams = namedtuple("TangentParams", ("p", "plus", "minus", "scale"))


def _is_tangent(p):
    return getattr(p, "instance_class", None) is TangentParams


def _controlled(z, n, p):
    raise TypeError("jitted code only: the overload below picks the body")


@overload(_controlled, jit_options=PICKED_BODY)
def _controlled_of(z, n, p):
    """The components of z the error control reads: all (the monodromy as accurate as the orbit),
    or u alone in the tangent-linear mode (u's steps those of the orbit alone)."""
    return (lambda z, n, p: n) if _is_tangent(p) else (lambda z, n, p: z.size)


def _evaluations(p):
    raise TypeError("jitted code only: the overload below picks the body")


@overload(_evaluations, jit_options=PICKED_BODY)
def _evaluations_of(p):
    """Right-hand sides per stage, as n_rhs counts them: one (with the Jacobian: one ball sum),
    and in the tangent-linear mode two more for a parameter change's term."""
    if _is_tangent(p):
        return lambda p: 3 if p.scale != 0.0 else 1
    return lambda p: 1


@njit(cache=True, nogil=True, inline="always")
def _orbit_derivative(kernel, t, z, p, variational, dz, jbuf):
    """`_derivative` with the kernel vector p. With the variational equations the model's
    right-hand side and Jacobian come from one evaluation (`rhs_jac`, one ball sum)."""
    if variational:
        dispatch.rhs_jac(kernel.tag, t, z, p, dz, jbuf)
        dispatch.tangent(kernel.tag, kernel.velocity_form, z, kernel.n_state, jbuf, dz)
    else:
        dispatch.rhs(kernel.tag, t, z, p, dz)


@njit(cache=True, nogil=True, inline="always")
def _tangent_linear_derivative(kernel, t, z, q, variational, dz, jbuf):
    """`_derivative` in the tangent-linear mode (q: TangentParams): with `variational`, dz[n:] =
    J v + the parameter term, f at q.plus and q.minus in jbuf's first two rows once J v is done."""
    if not variational:
        dispatch.rhs(kernel.tag, t, z, q.p, dz)
        return
    dispatch.rhs_jac(kernel.tag, t, z, q.p, dz, jbuf)
    n = kernel.n_state
    half = n // 2 if kernel.velocity_form else 0    # J = [[0, I], [A, B]]: the upper half of J v is v's lower half
    for i in range(half):
        dz[n + i] = z[n + half + i]
    for i in range(half, n):
        acc = 0.0
        for k in range(n):
            acc += jbuf[i, k] * z[n + k]
        dz[n + i] = acc
    if q.scale != 0.0:
        dispatch.rhs(kernel.tag, t, z, q.plus, jbuf[0])
        dispatch.rhs(kernel.tag, t, z, q.minus, jbuf[1])
        for i in range(n):
            dz[n + i] += (jbuf[0, i] - jbuf[1, i]) * q.scale


def _derivative(kernel, t, z, p, variational, dz, jbuf):
    raise TypeError("jitted code only: the overload below picks the body")


@overload(_derivative, jit_options=PICKED_BODY)
def _derivative_of(kernel, t, z, p, variational, dz, jbuf):
    """dz/dt of the (possibly augmented) system, inlined into the step loops: no call and no
    array views of z and dz (the models read and write the first n entries); the body by p's
    type (a TangentParams: the tangent-linear mode)."""
    body = _tangent_linear_derivative if _is_tangent(p) else _orbit_derivative

    def picked(kernel, t, z, p, variational, dz, jbuf):
        body(kernel, t, z, p, variational, dz, jbuf)
    return picked


@njit(cache=True, nogil=True)
def derivative(kernel, t, z, p, variational, dz, jbuf):
    """dz/dt of the (possibly augmented) system (jbuf: n x n scratch for the Jacobian)."""
    _derivative(kernel, t, z, p, variational, dz, jbuf)


@njit(cache=True, nogil=True, inline="always")
def state_status(z, n, n_position, amplitude_limit):
    """NaN/inf anywhere in the state, or a displacement beyond the physical limit."""
    for i in range(n):
        if not np.isfinite(z[i]):
            return STATUS_NAN
    for i in range(n_position):
        if abs(z[i]) > amplitude_limit:
            return STATUS_AMPLITUDE
    return STATUS_OK


@njit(cache=True, nogil=True, inline="always")
def start_status(kernel, z, amplitude_limit):
    """An id that is no model of the tag's group is an error status (the dispatch would give
    NaN), else state_status."""
    if not dispatch.known(kernel.tag):
        return STATUS_UNKNOWN_MODEL
    return state_status(z, kernel.n_state, kernel.n_position, amplitude_limit)


@njit(cache=True, nogil=True)
def initial_state(u0, n, variational):
    """z0 = u0, or [u0, I] with the variational equations."""
    m = n + n * n if variational else n
    z = np.zeros(m)
    for i in range(n):      # not z[:n] = u0: the slice assignment's shape check compiles Numba's error formatting (~2 s)
        z[i] = u0[i]
    if variational:
        for i in range(n):
            z[n + i * n + i] = 1.0
    return z


@njit(cache=True, nogil=True, inline="always")
def _error_norm(K, h, z, znew, rtol, atol, w5, w3, m):
    """Hairer's DOP853 error norm of the step on z's first m components (w5, w3: work arrays of
    size z.size)."""
    for i in range(m):
        w5[i] = 0.0
        w3[i] = 0.0
    for j in range(_N_STAGES + 1):
        c5 = _E5[j]
        c3 = _E3[j]
        for i in range(m):
            w5[i] += K[j, i] * c5
            w3[i] += K[j, i] * c3
    e5 = 0.0
    e3 = 0.0
    for i in range(m):
        scale = atol + rtol * max(abs(z[i]), abs(znew[i]))
        e5 += (w5[i] / scale) ** 2
        e3 += (w3[i] / scale) ** 2
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    return abs(h) * e5 / np.sqrt((e5 + 0.01 * e3) * m)


# `dop853` and `rk4` are inlined into their one caller, the body `flow` picks (`_flow_dop853`,
# `_flow_rk4`): a function of their own was one more compilation of the step loop beneath it
# (each jitted function re-optimizes and emits the code it calls: ~0.9 s of a first point).
@njit(cache=True, nogil=True, inline="always")
def dop853(kernel, t0, t1, z0, p, variational, rtol, atol, h0, max_steps, amplitude_limit):
    """Integrate z from t0 to t1 > t0 with adaptive Dormand-Prince 8(5,3)."""
    m = z0.size
    n = kernel.n_state
    z = z0.copy()
    status = start_status(kernel, z, amplitude_limit)
    if status != STATUS_OK:
        return z, status, 0, h0
    K = np.empty((_N_STAGES + 1, m))
    work = np.empty((4, m))
    jbuf = np.empty((n, n))
    status, n_rhs, h = _dop853_steps(kernel, t0, t1, z, p, variational, rtol, atol, h0, max_steps,
                                     amplitude_limit, K, work, jbuf)
    return z, status, n_rhs, h


@njit(cache=True, nogil=True, _nrt=False)
def _dop853_steps(kernel, t0, t1, z, p, variational, rtol, atol, h0, max_steps, amplitude_limit,
                  K, work, jbuf):
    """The step loop of `dop853`, advancing z in place: (status, n_rhs, h_next).

    It only reads and writes the caller's arrays (K: stage derivatives, work: 4 rows of scratch,
    jbuf: the Jacobian), so it is compiled without Numba's reference counting (`_nrt=False`):
    with the model inlined, the reference counts of the arrays and views passed around in every
    stage would otherwise cost atomic updates that take longer than the stage's arithmetic."""
    znew = work[0]
    stage = work[1]
    w5 = work[2]
    w3 = work[3]
    n_rhs = 0
    first_stage = 0     # K[0] = f(t0, z) is evaluated as stage 0 of the first step
    t = t0
    h = h0 if h0 > 0.0 else 0.01 * (t1 - t0)
    m = z.size
    controlled = _controlled(z, kernel.n_state, p)
    per_stage = _evaluations(p)
    for _ in range(max_steps):
        if t >= t1:
            return STATUS_OK, n_rhs, h
        last = t + h >= t1
        step = t1 - t if last else h
        rejected = False
        while True:
            if step < 10.0 * np.spacing(max(abs(t), 1.0)):
                return STATUS_STEP_UNDERFLOW, n_rhs, h
            for s in range(first_stage, _N_STAGES + 1):
                if s == 0:
                    target = z
                else:
                    target = znew if s == _N_STAGES else stage
                    dispatch.combine(kernel.tag, K, _A[s], s, z, step, target)
                _derivative(kernel, t + _C[s] * step, target, p, variational, K[s], jbuf)
            n_rhs += (_N_STAGES + 1 - first_stage) * per_stage
            first_stage = 1
            err = _error_norm(K, step, z, znew, rtol, atol, w5, w3, controlled)
            if err < 1.0:
                break
            # a NaN error (overflow inside a too-large step) shrinks the step like a huge error
            step *= max(_MIN_FACTOR, _SAFETY * err ** _ERR_EXPONENT) if np.isfinite(err) else _MIN_FACTOR
            last = False
            rejected = True
        t = t1 if last else t + step
        for i in range(m):
            z[i] = znew[i]
            K[0, i] = K[_N_STAGES, i]
        status = state_status(z, kernel.n_state, kernel.n_position, amplitude_limit)
        if status != STATUS_OK:
            return status, n_rhs, h
        factor = _MAX_FACTOR if err == 0.0 else min(_MAX_FACTOR, _SAFETY * err ** _ERR_EXPONENT)
        if rejected:
            factor = min(1.0, factor)
        h = step * factor
    return STATUS_STEP_UNDERFLOW, n_rhs, h


@njit(cache=True, nogil=True, inline="always")
def rk4(kernel, t0, t1, z0, p, variational, n_steps, amplitude_limit):
    """Integrate z from t0 to t1 with n_steps classical RK4 steps."""
    m = z0.size
    n = kernel.n_state
    z = z0.copy()
    h = (t1 - t0) / n_steps
    status = start_status(kernel, z, amplitude_limit)
    if status != STATUS_OK:
        return z, status, 0, h
    work = np.empty((5, m))
    jbuf = np.empty((n, n))
    status, n_rhs = _rk4_steps(kernel, t0, z, p, variational, n_steps, h, amplitude_limit, work, jbuf)
    return z, status, n_rhs, h


@njit(cache=True, nogil=True, _nrt=False)
def _rk4_steps(kernel, t0, z, p, variational, n_steps, h, amplitude_limit, work, jbuf):
    """The step loop of `rk4`, advancing z in place: (status, n_rhs). Like `_dop853_steps`, it
    touches only the caller's arrays and is compiled without reference counting."""
    m = z.size
    stage = work[4]
    for step in range(n_steps):
        t = t0 + step * h
        for q in range(4):
            # stage q at t + c_q h, z + a_q h k_{q-1}, with (c, a) = (0, -), (1/2, 1/2), (1/2, 1/2), (1, 1)
            if q == 0:
                for i in range(m):
                    stage[i] = z[i]
                tq = t
            elif q < 3:
                for i in range(m):
                    stage[i] = z[i] + 0.5 * h * work[q - 1, i]
                tq = t + 0.5 * h
            else:
                for i in range(m):
                    stage[i] = z[i] + h * work[2, i]
                tq = t + h
            _derivative(kernel, tq, stage, p, variational, work[q], jbuf)
        for i in range(m):
            z[i] += h / 6.0 * (work[0, i] + 2.0 * work[1, i] + 2.0 * work[2, i] + work[3, i])
        status = state_status(z, kernel.n_state, kernel.n_position, amplitude_limit)
        if status != STATUS_OK:
            return status, 4 * (step + 1) * _evaluations(p)
    return STATUS_OK, 4 * n_steps * _evaluations(p)


# Integrator settings travel as one named tuple of floats so that every caller passes the same
# thing; its class is the method, so each compiled caller holds only the integrator its scene
# uses (as a kernel tag picks the model): a dop853 scene never compiles rk4, and the other way round.
METHOD_DOP853, METHOD_RK4 = 0, 1
S_METHOD, S_RTOL, S_ATOL, S_STEPS_PER_UNIT, S_MAX_STEPS, S_AMPLITUDE = range(6)


_FIELDS = ("method", "rtol", "atol", "steps_per_unit", "max_steps", "amplitude_limit")
Dop853Settings = namedtuple("Dop853Settings", _FIELDS)    # adaptive Dormand-Prince 8(5,3)
RK4Settings = namedtuple("RK4Settings", _FIELDS)          # classical RK4, fixed steps


_SETTINGS = {"dop853": (METHOD_DOP853, Dop853Settings), "rk4": (METHOD_RK4, RK4Settings)}
METHODS = tuple(_SETTINGS)


def settings(method="dop853", rtol=1e-10, atol=1e-12, steps_per_unit=512, max_steps=200_000,
             amplitude_limit=1e3):
    """Integrator settings (indexed by the S_* constants). steps_per_unit: RK4 steps per unit of
    (scaled) time, i.e. per forcing period; amplitude_limit: largest displacement (scaled) before
    a state counts as diverged."""
    if method not in _SETTINGS:
        raise ValueError(f"integrator must be one of {sorted(_SETTINGS)}, got {method!r}")
    code, cls = _SETTINGS[method]
    return cls(*(float(v) for v in (code, rtol, atol, steps_per_unit, max_steps, amplitude_limit)))


def loosened(opts, rtol):
    """`opts` with its rtol raised to at least `rtol` and atol in the same proportion (the
    rtol / atol ratio kept); RK4 settings unchanged (fixed steps, no tolerance to loosen)."""
    if type(opts) is not Dop853Settings or opts.rtol >= rtol:
        return opts
    return opts._replace(rtol=float(rtol), atol=opts.atol * (rtol / opts.rtol))


def _flow_dop853(kernel, t0, t1, z0, p, variational, opts, h0):
    return dop853(kernel, t0, t1, z0, p, variational, opts[S_RTOL], opts[S_ATOL], h0,
                  int(opts[S_MAX_STEPS]), opts[S_AMPLITUDE])


def _flow_rk4(kernel, t0, t1, z0, p, variational, opts, h0):
    n_steps = max(1, int(round(opts[S_STEPS_PER_UNIT] * (t1 - t0))))
    return rk4(kernel, t0, t1, z0, p, variational, n_steps, opts[S_AMPLITUDE])


def _integrate(kernel, t0, t1, z0, p, variational, opts, h0):
    raise TypeError("jitted code only: the overload below picks the method")


@overload(_integrate, jit_options=PICKED_BODY)
def _integrate_by_method(kernel, t0, t1, z0, p, variational, opts, h0):
    method = getattr(opts, "instance_class", None)
    if method is RK4Settings:
        return _flow_rk4
    if method is Dop853Settings:
        return _flow_dop853
    raise TypingError(f"integrator settings must come from integrators.settings(), got {opts}")


@njit(cache=True, nogil=True, inline="always")
def flow(kernel, t0, t1, z0, p, variational, opts, h0):
    """Integrate with the method and tolerances in `opts` (see `settings`).

    kernel: the model's identity, a `KernelId` (`ModelSpec.kernel`).
    Inlined into its jitted callers, so that a literal True or False there becomes a plain bool
    before it reaches the integrator: one compilation of the integrator serves every caller."""
    return _integrate(kernel, t0, t1, z0, p, bool(variational), opts, h0)

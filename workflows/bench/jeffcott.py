"""The kernels as the benchmarks call them, on the Bai 2006 rotor (`jeffcott_clearance`).

Every `rotorsweep.kernels` name the kernel benchmarks use is imported here and nowhere else in
workflows/bench, so that a rename in the kernels is one edit. Scaled units: tau = t / T,
lengths in um, so the basic orbit has period 1."""
import numpy as np
from numba import njit

from rotorsweep.kernels import continuation, floquet, integrators as ig, models, shooting
from rotorsweep.kernels.continuation import events as boundary
from rotorsweep.kernels.contact import ring_load
from rotorsweep.kernels.models import jeffcott_clearance as jc

from workflows.bench.scene import ATOL_OVER_RTOL, BAI, BOUNDARY, contact_angle, newton_tol, setting_label

JEFF = models.get("jeffcott_clearance")
LINEAR = models.get("linear_oscillator")
N, NPOS = JEFF.n_state, JEFF.n_position
CONVERGED = shooting.CONVERGED
EARLY_RTOL, EARLY_SWITCH = shooting.EARLY_RTOL, shooting.EARLY_SWITCH    # the staged Newton's early stage
BoundaryError = boundary.BoundaryError
multipliers = floquet.multipliers
static_guess = jc.static_guess
to_physical = jc.to_physical
# indices of the parameter vector read by the Numba force loop below
P_DAMP, P_GAIN, P_OFFSET, P_LOAD = jc.P_DAMP, jc.P_GAIN, jc.P_OFFSET, jc.P_LOAD
P_COS_A, P_SIN_A, P_NBALLS, P_PHI0 = jc.P_COS_A, jc.P_SIN_A, jc.P_NBALLS, jc.P_PHI0
P_CAGE, P_COS_D, P_SIN_D = jc.P_CAGE, jc.P_COS_D, jc.P_SIN_D


def bai_params(speed, clearance):
    """(p, T) of the Bai 2006 rotor at shaft speed [Hz] and radial clearance [m]."""
    return jc.jeffcott_params(
        speed=speed, stiffness=BAI["stiffness"], clearance=clearance,
        contact_angle=contact_angle(clearance), axial_approach=0.0, mass=BAI["mass"],
        damping=BAI["damping"], radial_load=BAI["radial_load"], n_balls=BAI["n_balls"],
        ball_diameter=BAI["ball_diameter"], pitch_diameter=BAI["pitch_diameter"])


def named_params(p):
    """The parameter vector by name, for the scipy peer (which must not share our kernels)."""
    return dict(damp=p[P_DAMP], gain=p[P_GAIN], offset=p[P_OFFSET], load=p[P_LOAD], cos_a=p[P_COS_A],
                n_balls=int(p[P_NBALLS]), phi0=p[P_PHI0], cage=p[P_CAGE])


def dop853(rtol, atol):
    return ig.settings("dop853", rtol=rtol, atol=atol)


def rk4(steps):
    return ig.settings("rk4", steps_per_unit=steps)


def make_setting(method, value):
    """One benchmarked integrator setting (DOP853 at rtol `value` or RK4 at `value` steps)."""
    opts = dop853(value, value * ATOL_OVER_RTOL) if method == "dop853" else rk4(value)
    return dict(method=method, value=value, label=setting_label(method, value), opts=opts,
                tol=newton_tol(method, value))


def orbit(p, guess, opts, tol, max_iter=30, staged=True):
    """Newton shooting from a start off the orbit: staged, as the pipeline solves a transient or
    cold start (shooting.shoot_staged); staged=False: plain Newton, the scipy peer's algorithm."""
    return shooting.periodic_orbit(JEFF, guess, p, opts, tol=tol, max_iter=max_iter, staged=staged)


def point(p, guess, opts, tol, staged=True):
    """One point the way the pipeline computes it: shooting, then the Floquet multipliers."""
    sol = orbit(p, guess, opts, tol, staged=staged)
    return sol, floquet.multipliers(sol.monodromy)


def classify(lam):
    """(max |lambda|, stable, crossing type of the leading multiplier as words)."""
    max_abs, stable, _ = floquet.classify(lam)
    kind = ["fold (+1)", "period doubling (-1)", "Neimark-Sacker (complex pair)"][
        floquet.crossing_type(lam[0]) - 1]
    return max_abs, stable, kind


def approach(point_spec, opts, tol):
    """State of the orbit at the point, by natural continuation in speed along
    point_spec['approach'] (continuation.natural, as a sweep does), stopping at a failed speed."""
    params = [bai_params(speed, point_spec["clearance"])[0] for speed in point_spec["approach"]]
    chain = continuation.natural(JEFF, params, opts, cold_guess=jc.static_guess, tol=tol,
                                 transient_periods=100)
    for speed, sol in zip(point_spec["approach"], chain):
        if sol.status != CONVERGED:
            raise RuntimeError(f"no orbit at {speed} Hz on the approach to {point_spec['name']}")
    return sol.state


def flow(p, z0, opts, variational, t1=1.0, h0=0.0, model=JEFF):
    """(z, status ok, n_rhs) of one integration over [0, t1] (scaled time)."""
    z, status, n_rhs, _ = ig.flow(model.kernel, 0.0, float(t1), z0, p, variational, opts, float(h0))
    return z, status == ig.STATUS_OK, n_rhs


def initial_state(u0, variational, n=N):
    return ig.initial_state(np.asarray(u0, float), n, variational)


def monodromies(p, state, opts, placements):
    """Monodromy (flattened) of one variational period from `state`, once per initial step h0."""
    z0 = initial_state(state, True)
    out = []
    for h0 in placements:
        z, ok, _ = flow(p, z0, opts, True, h0=h0)
        out.append(z[N:].copy() if ok else np.full(N * N, np.nan))
    return np.array(out)


def fixed_point_residual(p, state, opts):
    """Relative return-map residual of `state` over one period (inf if the integration fails)."""
    z, ok, _ = flow(p, np.array(state, float), opts, False)
    return float(np.max(np.abs(z - state)) / max(1.0, np.max(np.abs(state)))) if ok else np.inf


def largest_lyapunov(p, u0, opts, n_transient=300, n_periods=2000, n_blocks=10):
    """Largest Lyapunov exponent per forcing period (Benettin, one tangent vector renormalised
    every period) with the standard error of its block means."""
    z, _, _ = flow(p, np.array(u0, float), opts, False, t1=n_transient)
    v = np.array([1.0, 0.3, -0.2, 0.1])
    v /= np.linalg.norm(v)
    logs = np.empty(n_periods)
    for k in range(n_periods):
        zz, ok, _ = flow(p, initial_state(z, True), opts, True)
        if not ok:
            return np.nan, np.nan
        z = zz[:N].copy()
        v = zz[N:].reshape(N, N) @ v
        norm = np.linalg.norm(v)
        logs[k] = np.log(norm)
        v /= norm
    blocks = logs.reshape(n_blocks, -1).mean(axis=1)
    return float(logs.mean()), float(blocks.std() / np.sqrt(n_blocks - 1))


def sample_orbit(p, state, n_states, opts):
    """n_states states along one period of the orbit through `state`."""
    return shooting.sample_orbit(JEFF.kernel, state, p, 1.0, n_states, opts)


# --- stability boundary -------------------------------------------------------------------------

def boundary_solver(opts, tol):
    clearance = BOUNDARY["clearance"]

    def solve(speed, guess):
        p, _ = bai_params(speed, clearance)
        return continuation.solve_orbit(JEFF, p, opts, [guess], cold_guess=jc.static_guess,
                                        tol=tol, n_samples=1)
    return solve


def locate(opts, tol, states, xtol_rel, bracket=None):
    """The period-doubling boundary (`boundary.locate_boundary`) in the bracket [Hz], from the
    orbit states at its ends."""
    a, b = bracket or BOUNDARY["bracket"]
    return boundary.locate_boundary(boundary_solver(opts, tol), a, b, states[0], states[1],
                                    xtol_rel=xtol_rel)


# --- per-evaluation loops for the C floor comparison --------------------------------------------

@njit(cache=True)
def _rhs_loop(tag, taus, states, p):
    """The model dispatch's rhs over many states, the way an integrator calls it (array arguments);
    the checksum adds the first and last acceleration (du[n / 2] and du[n - 1])."""
    n = states.shape[1]
    du = np.empty(n)
    acc = 0.0
    for i in range(taus.size):
        models.dispatch.rhs(tag, taus[i], states[i], p, du)
        acc += du[n // 2] + du[n - 1]
    return acc


@njit(cache=True)
def _force_loop(taus, states, p):
    """The same right-hand side from contact.ring_load with scalar arguments only."""
    acc = 0.0
    n_balls = int(p[P_NBALLS])
    for i in range(taus.size):
        theta = p[P_PHI0] + p[P_CAGE] * 2.0 * np.pi * taus[i] / p[P_NBALLS]
        fx, fy, _, _, _, _, _, _, _ = ring_load(
            states[i, 0], states[i, 1], 0.0, p[P_OFFSET], p[P_COS_A], p[P_SIN_A],
            n_balls, np.cos(theta), np.sin(theta), p[P_COS_D], p[P_SIN_D])
        du2 = -p[P_DAMP] * states[i, 2] - p[P_GAIN] * fx
        du3 = -p[P_DAMP] * states[i, 3] - p[P_GAIN] * fy - p[P_LOAD]
        acc += du2 + du3
    return acc


@njit(cache=True, nogil=True, _nrt=False)
def _variational_steps(kernel, taus, states, p, z, dz, jbuf):
    n = states.shape[1]
    acc = 0.0
    for i in range(taus.size):
        for k in range(n):
            z[k] = states[i, k]
        ig._derivative(kernel, taus[i], z, p, True, dz, jbuf)
        for k in range(2, n + n * n):
            acc += dz[k]
    return acc


@njit(cache=True)
def _variational_loop(kernel, taus, states, p):
    """integrators._derivative with the variational equations (20 components) over many states,
    in a loop compiled like the integrators' step loops (inlined, no reference counting), so that
    it is the derivative's share of an evaluation inside `flow`."""
    n = states.shape[1]
    z = np.zeros(n + n * n)
    for k in range(n):
        z[n + k * n + k] = 1.0
    return _variational_steps(kernel, taus, states, p, z, np.empty(n + n * n), np.empty((n, n)))


def rhs_loop(taus, states, p, model=JEFF):
    return _rhs_loop(model.kernel.tag, taus, states, p)


def force_loop(taus, states, p):
    return _force_loop(taus, states, p)


def variational_loop(taus, states, p, model=JEFF):
    return _variational_loop(model.kernel, taus, states, p)

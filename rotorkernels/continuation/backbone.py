"""Backbone curves: periodic orbits of an unforced, undamped model (its right-hand side must not
depend on tau) continued in amplitude from a linear mode by pseudo-arclength, shooting with the
monodromy (`orbits.AutonomousOrbitProblem.residual`).

Unknowns Y = (c / S, T, A / S): the orbit's initial state s = B c in an invariant subspace with
orthonormal basis B (the whole state space by default), its period T (scaled time) and amplitude A,
S the largest amplitude (so that all parts are O(1) in the arclength). Equations:

    B^T (phi(T; s) - s) = 0            (k rows, one redundant: energy is conserved)
    s_j - A = 0, s_{n_pos + j} = 0     (amplitude and phase: q_j starts at a turning point)
    t . (Y - Y_k) = ds                 (arclength)

The redundancy is handled as `orbits.AutonomousOrbitProblem` does, by Gauss-Newton (least-squares
steps on the consistent overdetermined system, quadratic convergence), not by an unfolding
parameter (Munoz-Almaraz et al. 2003): that would need a dissipation term grad(H) in every
model's kernel, while least squares needs nothing of the model. The tangent is the null vector of
the Jacobian of the first three blocks (by SVD).

j, the reference coordinate, is the position with the largest component of the linear mode; the
backbone's amplitude is q_j at its turning point t = 0 [m] (SI: A times the model's length scale).

Start: the linear mode (eigenvector of the linearized first-order system at rest, in the subspace)
scaled to q_j = amplitude_start, period 2 pi / omega. A repeated linear frequency makes Newton
ill-posed (a whole plane of linear modes): it is refused unless an invariant subspace in which
the frequency is simple is given (e.g. symmetric4's planar cylindrical modes, its spec's
`invariant_subspaces`).

The family is a problem of the continuation engine (`Shooting`): `engine.follow` owns the steps
(engine.Settings: ds, ds_min, ds_max, max_steps, max_angle, max_newton, fast_newton, grow, tol)
and the END_REASONS vocabulary; the amplitude is bounded by (0, amplitude_max], the upper edge
solved exactly. A backbone that stops early is data (status + detail), never an exception.
"""
from dataclasses import replace
from typing import NamedTuple

import numpy as np

from rotorsweep.kernels import floquet, shooting
from rotorsweep.kernels.continuation import engine
from rotorsweep.kernels.continuation.engine import Settings  # noqa: F401 (the settings this module takes)
from rotorsweep.kernels.modal import eigenpairs
from rotorsweep.kernels.orbits import AutonomousOrbitProblem

# Relative gap below which two linear frequencies count as one repeated frequency.
REPEATED_RTOL = 1e-6
# A second singular value below this (relative) makes the null space two-dimensional (a
# rotationally symmetric model's circular whirl): the tangent is then the previous one projected.
NULL_RTOL = 1e-8
# Samples per orbit for its energy drift and harmonic amplitude (the DFT's first harmonic is exact
# for harmonics below half of it: the orbits' spectra fall far below rounding by then).
ORBIT_SAMPLES = 64


class BackbonePoint(NamedTuple):
    Y: np.ndarray
    state: np.ndarray       # scaled initial state
    period: float           # scaled
    monodromy: np.ndarray
    multipliers: np.ndarray
    tangent: np.ndarray
    iterations: int
    residual: float

    @property
    def X(self):
        """The unknowns (the engine's name for Y)."""
        return self.Y


class Backbone(NamedTuple):
    amplitude: np.ndarray       # q_j at its turning point [m]
    harmonic_amplitude: np.ndarray  # amplitude of q_j's first harmonic [m] (the manifold's amplitude)
    frequency: np.ndarray       # [Hz]
    period: np.ndarray          # [s]
    states: np.ndarray          # initial states, SI (model.to_physical)
    multipliers: np.ndarray     # (points, n_state) complex
    energy_drift: np.ndarray    # (max - min) / mean of T + V along each orbit; NaN without polynomial form
    coordinate: int             # j (position index)
    linear_frequency: float     # [Hz]
    status: str                 # END_REASONS entry
    detail: str
    n_rhs: int


class Shooting(NamedTuple):
    """The autonomous orbit family along its amplitude, an engine problem (engine's contract):
    unknowns Y = (c / S, T, A / S), Gauss-Newton corrector, SVD tangent."""
    orbit: AutonomousOrbitProblem
    basis: np.ndarray       # n x k, orthonormal columns
    j: int
    scale: float            # S (scaled units)

    # the continued parameter: the amplitude in units of S, bounded by (0, 1)
    parameters = (("amplitude / amplitude_max", -1, 1.0),)

    def state(self, Y):
        return self.basis @ (self.scale * Y[:-2])

    def equations(self, Y, counter):
        """(F, Jacobian, monodromy, ok, residual): F = the first three blocks of equations."""
        model, k = self.orbit.model, self.basis.shape[1]
        s, period = self.state(Y), Y[-2]
        r, mono, f_end, ok, n_rhs = self.orbit.residual(s, period)
        counter.n += n_rhs
        npos = model.n_position
        F = np.concatenate([self.basis.T @ r / self.scale,
                            [s[self.j] / self.scale - Y[-1], s[npos + self.j] / self.scale]])
        jac = np.zeros((k + 2, k + 2))
        jac[:k, :k] = self.basis.T @ (mono - np.eye(mono.shape[0])) @ self.basis
        jac[:k, k] = self.basis.T @ f_end / self.scale
        jac[k, :k], jac[k, k + 1] = self.basis[self.j], -1.0
        jac[k + 1, :k] = self.basis[npos + self.j]
        residual = np.abs(r).max() / max(np.abs(s).max(), np.finfo(float).tiny)
        return F, jac, mono, ok, residual

    def correct(self, Y0, c, target, at, settings, counter):
        """Gauss-Newton on [F(Y) = 0, c . Y = target]: (BackbonePoint, None) or (None, failure);
        the tangent (free with the Jacobian at hand) is oriented like at.tangent."""
        Y = Y0.copy()
        for it in range(settings.max_newton + 1):
            F, jac, mono, ok, res = self.equations(Y, counter)
            if not ok:
                return None, engine.INTEGRATION_FAILED
            if res <= settings.tol and np.abs(F[-2:]).max() <= settings.tol:
                t = _null_tangent(jac, at.tangent)
                return BackbonePoint(Y, self.state(Y), Y[-2], mono, floquet.multipliers(mono), t, it, res), None
            if it == settings.max_newton:
                break
            A = np.vstack([jac, c])
            Y = Y + np.linalg.lstsq(A, -np.append(F, c @ Y - target), rcond=None)[0]
        return None, engine.NEWTON_FAILED

    def point(self, solution, at, settings, counter):
        return solution

    def where(self, point):
        return f"amplitude {point.Y[-1]!r} S"

    def solves_edge(self, k, edge):
        """Amplitude zero is the trivial orbit: the branch just ends there."""
        return edge > 0


def _null_tangent(jac, t_prev):
    """Unit null vector of the Jacobian oriented like t_prev. By SVD, not engine.tangent: the
    Jacobian is square with one redundant row (energy is conserved)."""
    _, sigma, vt = np.linalg.svd(jac)
    if sigma.size > 1 and sigma[-2] <= NULL_RTOL * sigma[0]:
        t = vt[-2:].T @ (vt[-2:] @ t_prev)
    else:
        t = vt[-1]
    t = t / np.linalg.norm(t)
    return t if t @ t_prev >= 0 else -t


def linear_modes(model, p, basis):
    """(omega [rad per unit tau], complex state vectors) of the linearization at rest restricted
    to the subspace, ascending in omega, each pair once."""
    from rotorsweep.kernels.models import dispatch

    n = model.n_state
    jac = np.empty((n, n))
    dispatch.jac(model.kernel.tag, 0.0, np.zeros(n), p, jac)
    lam, vec = eigenpairs(basis.T @ jac @ basis)
    return lam.imag, basis @ vec


def _problems(model, built, mode, omegas, amplitude_max, amplitude_start):
    out = []
    if not 0 <= mode < len(omegas):
        out.append(f"mode = {mode}: must be in [0, {len(omegas) - 1}] ({len(omegas)} linear modes)")
    elif (np.abs(np.delete(omegas, mode) / omegas[mode] - 1) < REPEATED_RTOL).any():
        out.append(f"mode = {mode}: its linear frequency is repeated; give an invariant subspace in which "
                   f"it is simple (the model's: {', '.join(model.invariant_subspaces) or 'none'})")
    bound = model.amplitude_bound
    hi = built.derived[bound] if bound else np.inf
    if not 0 < amplitude_max < hi:
        out.append(f"amplitude_max = {amplitude_max!r} m: must be in (0, {hi!r}) m"
                   + (f" (the model's amplitude bound: {model.derived[bound][1]})" if bound else ""))
    elif not 0 < amplitude_start < amplitude_max:
        out.append(f"amplitude_start = {amplitude_start!r} m: must be in (0, amplitude_max = {amplitude_max!r}) m")
    return out


def follow_backbone(model, values, opts, mode, amplitude_max, settings=Settings(), subspace=None,
                    amplitude_start=None):
    """The backbone of linear mode `mode` (0: the lowest frequency in the subspace) of the model
    at `values`, from amplitude_start (default amplitude_max / 1000) to amplitude_max [m].
    Invalid input raises ValueError before any integration."""
    built = model.build(values)
    n = model.n_state
    basis = np.eye(n) if subspace is None else np.linalg.qr(np.asarray(subspace, float))[0]
    omegas, vectors = linear_modes(model, built.p, basis)
    amplitude_start = amplitude_max / 1000 if amplitude_start is None else amplitude_start
    problems = settings.problems() + _problems(model, built, mode, omegas, amplitude_max, amplitude_start)
    if problems:
        raise ValueError(f"backbone of {model.name}: " + "; ".join(problems))
    v = vectors[:, mode]
    j = int(np.argmax(np.abs(v[:model.n_position])))
    v = (v / v[j]).real
    el = model.length_scale
    sh = Shooting(AutonomousOrbitProblem(model, built.p, opts, j), basis, j, amplitude_max / el)
    a0 = amplitude_start / amplitude_max
    Y0 = np.concatenate([basis.T @ v * a0, [2 * np.pi / omegas[mode], a0]])
    e_a = np.zeros(Y0.size)
    e_a[-1] = 1.0
    counter = engine.Counter()
    patient = replace(settings, max_newton=max(settings.max_newton, engine.START_NEWTON))
    first, failure = sh.correct(Y0, e_a, a0, engine.Seed(e_a), patient, counter)
    if first is None:
        points, end = [], engine.START_FAILED
        detail = f"no orbit at amplitude {amplitude_start!r} m ({engine.END_REASONS[failure]})"
    else:
        points, _, end, detail = engine.follow(sh, first, [(0.0, 1.0)], settings, counter=counter)
    return _result(model, values, built, sh, points, end, detail, omegas[mode], counter.n)


def energy(system, q, v):
    """T + V of a PolynomialSystem at positions q and velocities v (SI, last axis): the gyroscopic
    forces do no work; V = q K q / 2 + Q2 qqq / 3 + Q3 qqqq / 4 (Q2, Q3 fully symmetric)."""
    return (0.5 * np.einsum("...i,ij,...j", v, system.M, v) + 0.5 * np.einsum("...i,ij,...j", q, system.K, q)
            + np.einsum("ijk,...i,...j,...k", system.Q2, q, q, q) / 3
            + np.einsum("ijkl,...i,...j,...k,...l", system.Q3, q, q, q, q) / 4)


def _orbit_measures(model, system, built, point, opts, j):
    """(energy drift (max - min) / mean of T + V along the orbit, NaN without polynomial form;
    first-harmonic amplitude of q_j [m]) from ORBIT_SAMPLES states over one period."""
    u = shooting.sample_orbit(model.kernel, point.state, built.p, point.period, ORBIT_SAMPLES, opts)
    phys = model.to_physical(u, built.period)
    harmonic = 2.0 * np.abs(np.fft.rfft(phys[:, j])[1]) / ORBIT_SAMPLES
    if system is None:
        return np.nan, harmonic
    e = energy(system, phys[:, :model.n_position], phys[:, model.n_position:])
    return float((e.max() - e.min()) / e.mean()), harmonic


def _result(model, values, built, sh, points, end, detail, omega, n_rhs):
    system = model.polynomial(values) if model.polynomial is not None else None
    periods = np.array([pt.period for pt in points]) * built.period
    measures = np.array([_orbit_measures(model, system, built, pt, sh.orbit.opts, sh.j) for pt in points]).reshape(-1, 2)
    return Backbone(
        amplitude=np.array([pt.Y[-1] for pt in points]) * sh.scale * model.length_scale,
        harmonic_amplitude=measures[:, 1],
        frequency=1.0 / periods if points else np.zeros(0),
        period=periods,
        states=model.to_physical(np.array([pt.state for pt in points]).reshape(-1, model.n_state), built.period),
        multipliers=np.array([pt.multipliers for pt in points]).reshape(-1, model.n_state),
        energy_drift=measures[:, 0],
        coordinate=sh.j, linear_frequency=omega / (2 * np.pi * built.period),
        status=engine.END_REASONS[end], detail=detail, n_rhs=n_rhs)

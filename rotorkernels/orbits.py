"""Periodic-orbit problems, apart from the strategies that follow them along a parameter
(rotorsweep.kernels.continuation), as BifurcationKit separates a ShootingProblem from `continuation`.

- ForcedOrbitProblem: a forced model at one parameter point; the period is fixed by the forcing
  (k forcing periods, scaled time), the unknown is the state s, the residual phi(k; s) - s, its
  Jacobian M - I from the variational flow (shooting.shoot does the Newton iteration).
- AutonomousOrbitProblem: an unforced (e.g. conservative) model; the period T is unknown too.
  The family of orbits of a conservative system is fixed by two extra conditions: a phase
  condition (the velocity of coordinate j is zero at t = 0: the orbit starts at a turning point)
  and an amplitude condition (q_j(0) = A), imposed exactly by leaving those two components out
  of the unknowns. The remaining system phi(T; s) - s = 0 has one equation more than unknowns
  (energy conservation makes one row redundant), so it is solved by Gauss-Newton with a
  least-squares step, which converges quadratically on a consistent system.
"""
from typing import NamedTuple

import numpy as np

from rotorsweep.kernels import extrema, floquet, integrators as ig, shooting
from rotorsweep.kernels.models import dispatch


class ForcedOrbitProblem(NamedTuple):
    model: object           # ModelSpec
    p: np.ndarray
    opts: np.ndarray        # integrator settings
    periods: float = 1.0    # forcing periods in one orbit

    def shoot(self, guess, tol, max_iter, far=False):
        """Newton shooting from `guess`: (state, monodromy, status, reason, iterations, residual, n_rhs).
        far: the guess is no neighbour's orbit (a transient, a cold start): staged Newton, whose
        early iterations integrate at a looser tolerance (shooting.shoot_staged)."""
        return shooting.periodic_orbit(self.model, guess, self.p, self.opts, self.periods, tol, max_iter,
                                       staged=far)

    def settle(self, u0, n_periods):
        """(state after n_periods forcing periods from u0, integration ok, n_rhs)."""
        z, status, n_rhs = shooting.settle(self.model.kernel, u0, self.p, float(n_periods), self.opts)
        return z, status == ig.STATUS_OK, n_rhs

    def samples(self, state, n_per_period):
        """States along the orbit through `state`, n_per_period per forcing period."""
        n = int(n_per_period * self.periods)
        return shooting.sample_orbit(self.model.kernel, state, self.p, float(self.periods), n, self.opts)


class AutonomousOrbit(NamedTuple):
    state: np.ndarray
    period: float           # in the model's scaled time
    multipliers: np.ndarray
    converged: bool
    iterations: int
    residual: float


class AutonomousOrbitProblem(NamedTuple):
    model: object           # ModelSpec of a model whose right-hand side does not depend on tau
    p: np.ndarray
    opts: np.ndarray
    coordinate: int = 0     # j of the phase and amplitude conditions

    def residual(self, s, period):
        """(phi(T; s) - s, monodromy M, f(phi(T; s)), integration ok, right-hand sides evaluated)."""
        kernel = self.model.kernel
        n = kernel.n_state
        z, status, n_rhs, _ = ig.flow(kernel, 0.0, period, ig.initial_state(s, n, True), self.p, True, self.opts, 0.0)
        end = z[:n]
        mono = z[n:].reshape((n, n))
        f_end = np.empty(n)
        ig.derivative(kernel, period, end.copy(), self.p, False, f_end, np.empty((n, n)))
        return end - s, mono, f_end, status == ig.STATUS_OK, n_rhs

    def solve(self, amplitude, guess, period_guess, tol=1e-10, max_iter=30):
        """The orbit with q_j(0) = amplitude and dq_j/dtau(0) = 0 from a guess of state and period
        (Newton's basin: a neighbour's orbit on a branch, or a harmonic-balance estimate).

        Convergence: the residual max|phi(T; s) - s| relative to max|s| below tol (relative to
        the orbit's own size: a backbone starts at vanishing amplitude)."""
        n, j = self.model.n_state, self.coordinate
        s = np.asarray(guess, float).copy()
        s[j], s[self.model.n_position + j] = amplitude, 0.0
        period = float(period_guess)
        res = np.inf
        for it in range(max_iter + 1):
            r, mono, f_end, ok, _ = self.residual(s, period)
            if not ok:
                break
            res = np.abs(r).max() / np.abs(s).max()
            if res <= tol:
                return AutonomousOrbit(s, period, floquet.multipliers(mono), True, it, res)
            if it == max_iter:
                break
            step = self._gauss_newton_step(r, mono, f_end, n, j)
            s += step[:n]
            period += step[n]
        return AutonomousOrbit(s, period, np.full(n, np.nan + 0j), False, it, res)

    def _gauss_newton_step(self, r, mono, f_end, n, j):
        """Least-squares Newton step in the free unknowns: every state component except q_j and
        dq_j/dtau (held at the amplitude and phase conditions, so they hold exactly) and the
        period; columns of [M - I, f] for them, n equations, one of them redundant."""
        free = [i for i in range(n) if i not in (j, self.model.n_position + j)]
        jac = np.column_stack([(mono - np.eye(n))[:, free], f_end])
        delta = np.linalg.lstsq(jac, -r, rcond=None)[0]
        step = np.zeros(n + 1)
        step[free] = delta[:-1]
        step[n] = delta[-1]
        return step


def entry_points(spec, opts):
    """(jitted function, example arguments) of each kernel that the orbit problems and their
    continuation call from Python for model `spec` with integrator settings `opts`, with the types
    of those calls, so that a warm-up compiles exactly those (`rotorsweep.pipeline.warmup`): a forced model's
    shooting and its orbits' exact extrema; a conservative one's backbones neither shoot at a fixed period nor settle a
    transient, but take the vector field at the period's end and the linear modes at rest."""
    kernel, n = spec.kernel, spec.n_state
    u, p = np.zeros(n), np.zeros(1)
    calls = [
        (shooting.sample_orbit, (kernel, u, p, 1.0, 1, opts)),
        (ig.flow, (kernel, 0.0, 1.0, u, p, False, opts, 0.0)),     # Python's bool, either value
        (ig.initial_state, (u, n, False)),       # continuation (the boundaries' refinement)
    ]
    if spec.forced:     # shoot_staged is also `shoot` (plain Newton: an attractor's orbit refined)
        return calls + [(shooting.shoot_staged, (kernel, u, p, 1.0, opts, opts, 1e-9, 1)),
                        (extrema.orbit_extent, (kernel, u, p, 1.0, np.zeros((1, n)), opts, True)),   # amplitudes (, means)
                        (extrema.orbit_extent_slope,   # a peak's slope and a locked tangent (continuation)
                         (kernel, u, u, ig.TangentParams(p, p, p, 0.0), 1.0, np.zeros((1, n)), opts))]
    return calls + [
        (ig.derivative, (kernel, 0.0, u, p, False, u, np.zeros((n, n)))),
        (dispatch.jac, (kernel.tag, 0.0, u, p, np.zeros((n, n)))),
    ]

"""The forced Duffing oscillator x'' + 2 zeta x' + x + gamma x^3 = F cos(omega t) the way a scipy
user writes it: the peer of our continuation (`ScipyContinuation`) and a tight fold reference
(`fold_reference`). Numpy right-hand sides and `solve_ivp`; no code shared with rotorsweep.kernels."""
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve


class Duffing(NamedTuple):
    zeta: float
    gamma: float
    force: float

    def scaled(self, tau, z, omega):
        """[u, Phi] in scaled time tau = omega t / 2 pi (one forcing period = 1), u = (x, dx/dtau):
        the model's equations as its docstring states them, with the variational equations."""
        period = 2 * np.pi / omega
        x, y = z[0], z[1]
        phi = z[2:].reshape(2, 2)
        jac = np.array([[0.0, 1.0], [-period ** 2 * (1 + 3 * self.gamma * x * x), -2 * self.zeta * period]])
        du = [y, period ** 2 * (self.force * np.cos(2 * np.pi * tau) - x - self.gamma * x ** 3)
              - 2 * self.zeta * period * y]
        return np.concatenate([du, (jac @ phi).ravel()])

    def physical(self, t, z, omega):
        """[u, Phi] in physical time, u = (x, dx/dt) (the reference: another formulation)."""
        x, v = z[0], z[1]
        phi = z[2:].reshape(2, 2)
        jac = np.array([[0.0, 1.0], [-(1 + 3 * self.gamma * x * x), -2 * self.zeta]])
        du = [v, self.force * np.cos(omega * t) - x - self.gamma * x ** 3 - 2 * self.zeta * v]
        return np.concatenate([du, (jac @ phi).ravel()])


def period_map(rhs, u, omega, end, rtol, atol, variational=True):
    """(phi(u) - u, monodromy or None, RHS calls) over [0, end] with solve_ivp DOP853."""
    z0 = np.concatenate([u, np.eye(2).ravel()]) if variational else np.asarray(u, float)
    f = rhs if variational else (lambda t, z, w: rhs(t, np.concatenate([z, np.eye(2).ravel()]), w)[:2])
    sol = solve_ivp(f, (0.0, end), z0, method="DOP853", rtol=rtol, atol=atol, args=(omega,))
    mono = sol.y[2:, -1].reshape(2, 2) if variational else None
    return sol.y[:2, -1] - u, mono, sol.nfev


def fold_reference(duffing, omega, state, rtol=1e-13, atol=1e-15):
    """A fold of the resonance curve at the duffing's force: fsolve on [phi(u) - u, det(M - I)] in
    the unknowns (x, dx/dt, omega), physical time, from a nearby (omega, scaled state) guess.
    Returns (omega, scaled state (x, dx/dtau), max residual)."""
    def equations(z):
        r, mono, _ = period_map(duffing.physical, z[:2], z[2], 2 * np.pi / z[2], rtol, atol)
        return np.append(r, np.linalg.det(mono - np.eye(2)))

    guess = [state[0], state[1] * omega / (2 * np.pi), omega]
    z = fsolve(equations, guess, xtol=1e-12)   # relative step; the last Newton step gains more
    return z[2], np.array([z[0], z[1] * 2 * np.pi / z[2]]), float(np.abs(equations(z)).max())


class ScipyContinuation:
    """Shooting pseudo-arclength continuation in omega as a user writes it with scipy: unknowns
    X = (x, dx/dtau, omega / scale), bordered Newton with M from the variational equations and
    dphi/domega by a central difference of two plain integrations, tangent predictor, the step
    grows by `grow` after <= fast_newton iterations and halves after a failed or slow corrector
    or a tangent turn above max_angle; folds where det(M - I) changes sign, located by Brent on
    the arclength. The same algorithm and settings as rotorsweep.kernels.continuation.arclength."""

    def __init__(self, duffing, scale, rtol, atol, settings):
        self.duffing, self.scale, self.rtol, self.atol, self.s = duffing, scale, rtol, atol, settings
        self.n_rhs = 0

    def _map(self, X, variational=True):
        r, mono, nfev = period_map(self.duffing.scaled, X[:2], X[2] * self.scale, 1.0, self.rtol, self.atol,
                                   variational)
        self.n_rhs += nfev
        return r, mono

    def _dphi(self, X):
        h = self.s.fd_step * max(1.0, abs(X[2]))
        plus, _ = self._map(X + [0, 0, h], False)
        minus, _ = self._map(X - [0, 0, h], False)
        return (plus - minus) / (2 * h)

    def _bordered(self, mono, dphi, c):
        return np.vstack([np.column_stack([mono - np.eye(2), dphi]), c])

    def correct(self, X, c, target):
        """(X, monodromy, iterations) or None."""
        for it in range(self.s.max_newton + 1):
            r, mono = self._map(X)
            if np.abs(r).max() / max(1.0, np.abs(X[:2]).max()) <= self.s.tol:
                return X, mono, it
            if it == self.s.max_newton:
                return None
            X = X + np.linalg.solve(self._bordered(mono, self._dphi(X), c), np.append(-r, target - c @ X))

    def tangent(self, X, mono, t_prev):
        t = np.linalg.solve(self._bordered(mono, self._dphi(X), t_prev), [0.0, 0.0, 1.0])
        return t / np.linalg.norm(t)

    def run(self, omega0, guess, omega_range):
        """Follow the branch from omega0 up to the range's end: (points [(X, monodromy)], folds [X])."""
        e = np.array([0.0, 0.0, 1.0])
        X, mono, _ = self.correct(np.append(guess, omega0 / self.scale), e, omega0 / self.scale)
        t = self.tangent(X, mono, e)
        points, folds, ds = [(X, mono)], [], self.s.ds
        while len(points) <= self.s.max_steps and X[2] * self.scale < omega_range[1]:
            step = self.correct(X + ds * t, t, t @ X + ds)
            if step is not None:
                t_new = self.tangent(step[0], step[1], t)
                if step[2] > self.s.max_newton - 2 or np.arccos(np.clip(t @ t_new, -1, 1)) > self.s.max_angle:
                    step = None
            if step is None:
                if ds <= self.s.ds_min:
                    break
                ds = max(self.s.ds_min, ds / 2)
                continue
            if np.sign(np.linalg.det(mono - np.eye(2))) != np.sign(np.linalg.det(step[1] - np.eye(2))):
                folds.append(self.locate(X, t, t @ (step[0] - X)))
            X, mono, t = step[0], step[1], t_new
            points.append((X, mono))
            if step[2] <= self.s.fast_newton:
                ds = min(self.s.ds_max, ds * self.s.grow)
        return points, folds

    def locate(self, X, t, sigma_end):
        """The point between X and X + sigma_end t where det(M - I) = 0 (Brent on sigma)."""
        found = {}

        def det(sigma):
            found[sigma] = self.correct(X + sigma * t, t, t @ X + sigma)
            return np.linalg.det(found[sigma][1] - np.eye(2))
        root = brentq(det, 0.0, sigma_end, xtol=self.s.locate_xtol)
        return found[root][0] if root in found else self.correct(X + root * t, t, t @ X + root)[0]

"""The rotor models the way a scipy user writes them: the peers of our per-point solves.

- `RigidPreloadedPeer`: rigid_preloaded's scaled equations in numpy from its parameter vector
  (by name), the ball sums as matrix products over the balls (P = W^T [delta]_+^{3/2} with W the
  balls' contact directions in q-space, the stiffness W^T diag(1.5 [delta]_+^{1/2}) W), the
  augmented 110-dim system [u, Phi] integrated by `solve_ivp`, plain Newton on the return map.
- `SeriesRotorPeer`: symmetric4 / asymmetric5 from their polynomial form (`PolynomialSystem`:
  M, G, K, Q2, Q3 in SI, contracted with einsum), the autonomous orbit at a given amplitude by
  the same Gauss-Newton as `rotorsweep.kernels.orbits.AutonomousOrbitProblem`, with `solve_ivp`.

Neither shares code with the kernels (the ball sum in contact.py, the series in cubic_law.py);
tests/test_bench_smoke.py checks that they compute the kernels' equations. Why these equations are
written again: a peer is the user's own numpy code, so it must not call the kernels. The tests'
other numpy writings serve other checks and stay where they are: tests/test_rigid_preloaded.py's
ball sum is the paper's eq. 1 in SI with loops (it checks the kernel's scaling and M^-1), and the
series rotors' polynomial form used here is itself tested against the kernel in
tests/test_nnm_models.py."""
import numpy as np
from scipy.integrate import solve_ivp

from workflows.bench.peers.jeffcott_scipy import newton


def _augmented_end(rhs_aug, s, period, method, rtol, atol):
    """(end state, monodromy, nfev) of [u, Phi] over [0, period] from [s, I]."""
    n = s.size
    sol = solve_ivp(rhs_aug, (0.0, period), np.concatenate([s, np.eye(n).ravel()]), method=method,
                    rtol=rtol, atol=atol)
    end = sol.y[:n, -1]
    return end, sol.y[n:, -1].reshape(n, n), sol.nfev


class RigidPreloadedPeer:
    """params: gain, damp (5x5), const, ucos, usin, sup (5), wu, ws, offset, cos_a, sin_a, n_balls
    (the kernel's scaled parameters, `rigid_preloaded` docstring)."""

    def __init__(self, params):
        self.__dict__.update(params)
        b = 2 * np.pi * np.arange(int(self.n_balls)) / self.n_balls
        ca, sa = self.cos_a, self.sin_a
        self.w = np.zeros((2 * b.size, 5))          # rows: contact directions of A's, then B's balls
        self.w[:b.size, 0], self.w[:b.size, 1], self.w[:b.size, 4] = ca * np.cos(b), ca * np.sin(b), sa
        self.w[b.size:, 2], self.w[b.size:, 3], self.w[b.size:, 4] = ca * np.cos(b), ca * np.sin(b), -sa

    def _forcing(self, t, v):
        return (-self.damp @ v + self.const + self.ucos * np.cos(self.wu * t) + self.usin * np.sin(self.wu * t)
                + self.sup * np.sin(self.ws * t))

    def rhs(self, t, u):
        delta = np.maximum(self.w @ u[:5] + self.offset, 0.0)
        force = self.w.T @ (delta * np.sqrt(delta))
        return np.concatenate([u[5:], self._forcing(t, u[5:]) - self.gain @ force])

    def augmented(self, t, z):
        u = z[:10]
        delta = np.maximum(self.w @ u[:5] + self.offset, 0.0)
        root = np.sqrt(delta)
        force = self.w.T @ (delta * root)
        stiffness = self.w.T @ ((1.5 * root)[:, None] * self.w)
        jac = np.block([[np.zeros((5, 5)), np.eye(5)], [-self.gain @ stiffness, -self.damp]])
        return np.concatenate([u[5:], self._forcing(t, u[5:]) - self.gain @ force,
                               (jac @ z[10:].reshape(10, 10)).ravel()])

    def shoot(self, guess, method, rtol, atol, tol, max_iter=30):
        """(state, monodromy, iterations, nfev, converged) over one forcing period (tau = 1)."""
        return newton(lambda s: _augmented_end(self.augmented, s, 1.0, method, rtol, atol), guess, tol, max_iter)


class SeriesRotorPeer:
    """The series rotor's polynomial form in the kernel's scaled units (tau = t / period, lengths
    in `length`): dy/dtau = -(Gs y + Ks x + Q2s x x + Q3s x x x) with Gs = T M^-1 G,
    Ks = T^2 M^-1 K, Q2s = T^2 L M^-1 Q2, Q3s = T^2 L^2 M^-1 Q3; Q2 and Q3 are fully symmetric,
    so the stiffness is Ks + 2 Q2s x + 3 Q3s x x."""

    def __init__(self, system, period, length):
        m_inv = np.linalg.inv(system.M)
        t2 = period * period
        self.n = system.M.shape[0]
        self.gs = period * m_inv @ system.G
        self.ks = t2 * m_inv @ system.K
        self.q2 = t2 * length * np.einsum("ia,ajk->ijk", m_inv, system.Q2)
        self.q3 = t2 * length ** 2 * np.einsum("ia,ajkl->ijkl", m_inv, system.Q3)

    def _force(self, x):
        return self.ks @ x + np.einsum("ijk,j,k", self.q2, x, x) + np.einsum("ijkl,j,k,l", self.q3, x, x, x)

    def rhs(self, t, u):
        x, y = u[:self.n], u[self.n:]
        return np.concatenate([y, -self.gs @ y - self._force(x)])

    def augmented(self, t, z):
        n = self.n
        x, y = z[:n], z[n:2 * n]
        stiffness = self.ks + 2 * np.einsum("ijk,k", self.q2, x) + 3 * np.einsum("ijkl,k,l", self.q3, x, x)
        jac = np.block([[np.zeros((n, n)), np.eye(n)], [-stiffness, -self.gs]])
        return np.concatenate([y, -self.gs @ y - self._force(x), (jac @ z[2 * n:].reshape(2 * n, 2 * n)).ravel()])

    def solve(self, amplitude, j, guess, period_guess, method, rtol, atol, tol, max_iter=30):
        """The orbit with q_j(0) = amplitude, dq_j/dtau(0) = 0 and unknown period, by Gauss-Newton
        (least-squares steps on [M - I, f(end)] in the free unknowns, one equation redundant by
        energy conservation), converged when max|r| / max|s| <= tol.
        Returns (state, period, monodromy, iterations, nfev, converged)."""
        n2 = 2 * self.n
        free = [i for i in range(n2) if i not in (j, self.n + j)]
        s = np.array(guess, float)
        s[j], s[self.n + j] = amplitude, 0.0
        period, nfev = float(period_guess), 0
        for it in range(max_iter + 1):
            end, mono, k = _augmented_end(self.augmented, s, period, method, rtol, atol)
            nfev += k + 1
            r = end - s
            if np.abs(r).max() / np.abs(s).max() <= tol:
                return s, period, mono, it, nfev, True
            if it == max_iter:
                break
            jac = np.column_stack([(mono - np.eye(n2))[:, free], self.rhs(period, end)])
            step = np.linalg.lstsq(jac, -r, rcond=None)[0]
            s[free] += step[:-1]
            period += step[-1]
        return s, period, mono, max_iter, nfev, False

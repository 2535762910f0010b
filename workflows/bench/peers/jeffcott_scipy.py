"""The Jeffcott/Bai rotor the way a scipy user writes it: the peer of our orbit solve."""
import numpy as np
from scipy.integrate import solve_ivp


def newton(period_map, guess, tol, max_iter):
    """(state, monodromy, iterations, nfev, converged) of plain Newton s <- s - (M - I)^-1 r on
    the return map (period_map(s) -> (end state, monodromy, nfev)), converged when
    max|r| / max(1, max|s|) <= tol (the kernels' test)."""
    s = np.array(guess, float)
    nfev = 0
    for it in range(max_iter + 1):
        end, mono, n = period_map(s)
        nfev += n
        r = end - s
        if np.max(np.abs(r)) / max(1.0, np.max(np.abs(s))) <= tol:
            return s, mono, it, nfev, True
        if it < max_iter:
            s = s + np.linalg.solve(mono - np.eye(s.size), -r)
    return s, mono, max_iter, nfev, False


class ScipyPeer:
    """Periodic orbit + monodromy the way a scipy user writes it: the same scaled equations in
    numpy (vectorised over the balls), the analytic 4x4 Jacobian, the augmented 20-dim system
    [u, Phi] integrated by `solve_ivp`, and plain Newton s <- s - (M - I)^-1 r (no line search).
    `shoot_fd` is the other natural choice (monodromy by forward finite differences, 5
    integrations of the 4-dim system per iteration).

    params: the scaled parameters by name (damp, gain, offset, load, cos_a, n_balls, phi0, cage)."""

    def __init__(self, params):
        self.damp, self.gain = params["damp"], params["gain"]
        self.offset, self.load, self.cos_a = params["offset"], params["load"], params["cos_a"]
        self.n_balls = int(params["n_balls"])
        self.phi0, self.cage = params["phi0"], params["cage"]
        self.spacing = 2 * np.pi * np.arange(self.n_balls) / self.n_balls

    def _contact(self, t, x, y):
        phi = self.phi0 + self.cage * 2 * np.pi * t / self.n_balls + self.spacing
        ux, uy = np.cos(phi) * self.cos_a, np.sin(phi) * self.cos_a
        delta = x * ux + y * uy + self.offset
        loaded = delta > 0
        return delta[loaded], ux[loaded], uy[loaded]

    def rhs(self, t, u):
        x, y, vx, vy = u
        delta, ux, uy = self._contact(t, x, y)
        q = delta * np.sqrt(delta)
        return np.array([vx, vy, -self.damp * vx - self.gain * (q @ ux),
                         -self.damp * vy - self.gain * (q @ uy) - self.load])

    def augmented(self, t, z):
        x, y, vx, vy = z[:4]
        delta, ux, uy = self._contact(t, x, y)
        root = np.sqrt(delta)
        q, dq = delta * root, 1.5 * root
        kxx, kxy, kyy = dq @ (ux * ux), dq @ (ux * uy), dq @ (uy * uy)
        g, a = self.gain, self.damp
        jac = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0],
                        [-g * kxx, -g * kxy, -a, 0.0], [-g * kxy, -g * kyy, 0.0, -a]])
        out = np.empty(20)
        out[:4] = (vx, vy, -a * vx - g * (q @ ux), -a * vy - g * (q @ uy) - self.load)
        out[4:] = (jac @ z[4:].reshape(4, 4)).ravel()
        return out

    def _monodromy_aug(self, s, method, rtol, atol):
        sol = solve_ivp(self.augmented, (0.0, 1.0), np.concatenate([s, np.eye(4).ravel()]),
                        method=method, rtol=rtol, atol=atol)
        return sol.y[:4, -1], sol.y[4:, -1].reshape(4, 4), sol.nfev

    def _monodromy_fd(self, s, method, rtol, atol, rel_step=1e-6):
        base = solve_ivp(self.rhs, (0.0, 1.0), s, method=method, rtol=rtol, atol=atol)
        nfev = base.nfev
        mono = np.empty((4, 4))
        for j in range(4):
            h = rel_step * max(1.0, abs(s[j]))
            sp = s.copy()
            sp[j] += h
            sol = solve_ivp(self.rhs, (0.0, 1.0), sp, method=method, rtol=rtol, atol=atol)
            nfev += sol.nfev
            mono[:, j] = (sol.y[:, -1] - base.y[:, -1]) / h
        return base.y[:, -1], mono, nfev

    def shoot(self, guess, method, rtol, atol, tol, max_iter=30):
        """(state, monodromy, iterations, nfev, converged), monodromy from the augmented system."""
        return newton(lambda s: self._monodromy_aug(s, method, rtol, atol), guess, tol, max_iter)

    def shoot_fd(self, guess, method, rtol, atol, tol, max_iter=30):
        """As shoot, monodromy by forward finite differences."""
        return newton(lambda s: self._monodromy_fd(s, method, rtol, atol), guess, tol, max_iter)

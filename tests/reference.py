"""An independent reference for the Bai 2006 model: the equations written again in SI units with
numpy, integrated by scipy's solve_ivp, the periodic orbit found by Newton with a finite-
difference Jacobian and the monodromy by central finite differences. It shares no code with
rotorkernels (no scaling, no analytic Jacobian, no Numba), so agreement tests the kernels."""
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

BAI = dict(mass=2.0, damping=300.0, load=2.0 * 9.8, K=2.883e9, n_balls=9, Db=12.7e-3, Dm=65e-3,
           groove_sum=2 * 6.6e-3 - 12.7e-3)


@dataclass
class BaiPoint:
    speed: float
    clearance: float
    mass: float = BAI["mass"]
    damping: float = BAI["damping"]
    load: float = BAI["load"]
    K: float = BAI["K"]
    n_balls: int = BAI["n_balls"]

    @property
    def alpha(self):
        return np.arccos(1.0 - self.clearance / BAI["groove_sum"])  # Bai 2006 eq. 6

    @property
    def omega_cage(self):
        return 2 * np.pi * self.speed * (1 - BAI["Db"] / BAI["Dm"] * np.cos(self.alpha)) / 2

    @property
    def period(self):
        return 2 * np.pi / (self.n_balls * self.omega_cage)

    def rhs(self, t, u):
        x, y, vx, vy = u
        phi = 2 * np.pi * np.arange(self.n_balls) / self.n_balls + self.omega_cage * t
        ca = np.cos(self.alpha)
        delta = (x * np.cos(phi) + y * np.sin(phi)) * ca - self.clearance
        q = self.K * np.clip(delta, 0.0, None) ** 1.5
        fx = np.sum(q * np.cos(phi)) * ca
        fy = np.sum(q * np.sin(phi)) * ca
        return [vx, vy, (-self.damping * vx - fx) / self.mass, (-self.damping * vy - fy - self.load) / self.mass]

    def period_map(self, u0, rtol=1e-13):
        sol = solve_ivp(self.rhs, (0.0, self.period), u0, method="DOP853", rtol=rtol,
                        atol=1e-15 * np.abs(np.asarray(u0)).max())
        return sol.y[:, -1]

    def fd_monodromy(self, u0, scale, rel_step=1e-4):
        cols = []
        for i in range(4):
            du = np.zeros(4)
            du[i] = rel_step * scale[i]
            cols.append((self.period_map(u0 + du) - self.period_map(u0 - du)) / (2 * du[i]))
        return np.array(cols).T

    def periodic_orbit(self, u0, iterations=3):
        """Newton with the finite-difference monodromy, from u0 (physical units)."""
        u = np.asarray(u0, float)
        scale = np.array([1e-6, 1e-6, 1e-6 / self.period, 1e-6 / self.period])
        for _ in range(iterations):
            mono = self.fd_monodromy(u, scale)
            r = self.period_map(u) - u
            u = u - np.linalg.solve(mono - np.eye(4), r)
        mono = self.fd_monodromy(u, scale)
        residual = np.max(np.abs((self.period_map(u) - u) / scale))
        return u, mono, residual

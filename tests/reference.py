"""An independent reference for the Bai 2006 model: the equations written again in SI units with
numpy, integrated by scipy's solve_ivp, the periodic orbit found by Newton with a finite-
difference Jacobian and the monodromy by central finite differences. It shares no code with
rotorsweep.kernels (no scaling, no analytic Jacobian, no Numba), so agreement tests the kernels.
The tori are checked likewise against scipy DOP853 runs (torus_half_swing, duffing2_strobe)."""
from dataclasses import dataclass

import numpy as np
from scipy.integrate import ode, solve_ivp

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

    def fd_monodromy_median(self, u0, scale, rel_steps=(5e-5, 1e-4, 2e-4)):
        """Element-wise median of fd_monodromy over three step sizes. Where balls leave and regain
        contact, one of a column's two integrations can take a step across a contact instant that
        passes the error test with a larger error (the heavy tail in docs/benchmarks): measured,
        one step size off by 1.4e-5 in the multipliers while the other two agree to 1e-7. The
        median drops such an outlier; the O(h^2) truncation error stays below 1e-7."""
        return np.median([self.fd_monodromy(u0, scale, rel_step=h) for h in rel_steps], axis=0)

    def periodic_orbit(self, u0, iterations=3):
        """Newton with the finite-difference monodromy, from u0 (physical units); the monodromy
        returned is fd_monodromy_median's (one step size's can be an outlier)."""
        u = np.asarray(u0, float)
        scale = np.array([1e-6, 1e-6, 1e-6 / self.period, 1e-6 / self.period])
        for _ in range(iterations):
            mono = self.fd_monodromy(u, scale)
            r = self.period_map(u) - u
            u = u - np.linalg.solve(mono - np.eye(4), r)
        mono = self.fd_monodromy_median(u, scale)
        residual = np.max(np.abs((self.period_map(u) - u) / scale))
        return u, mono, residual


# --- the same rotor on an axially preloaded bearing ---------------------------------------------
#
# Written from the geometry, not from rotorsweep.kernels.bearing: the rings of a bearing with free
# contact angle a0 shift axially under the preload P0; the radial distance between the inner and
# outer groove centres stays A cos(a0) (A = r_i + r_o - D_b), so their distance grows to
# A cos(a0) / cos(a) and each ball is squeezed by delta_n = A (cos(a0) / cos(a) - 1) along the
# loaded contact line at angle a. Axial equilibrium: N K delta_n^{3/2} sin(a) = P0. At a journal
# displacement (x, y) (angle frozen at a) ball j is squeezed by
#     delta_j = (x cos phi_j + y sin phi_j) cos(a) + delta_n,
# and carries K [delta_j]_+^{3/2} along the contact line.

from functools import cached_property  # noqa: E402

from scipy.optimize import brentq  # noqa: E402


@dataclass
class PreloadedPoint(BaiPoint):
    """BaiPoint on a preloaded bearing of any geometry (SI). free_angle [rad]: the unloaded
    contact angle (None: Bai eq. 6 from the clearance with groove_sum = r_i + r_o - D_b)."""
    preload: float = 0.0
    free_angle: float = None
    groove_sum: float = BAI["groove_sum"]
    ball_diameter: float = BAI["Db"]
    pitch_diameter: float = BAI["Dm"]

    @cached_property
    def _loaded(self):
        a0 = self.free_angle
        if a0 is None:
            a0 = np.arccos(1.0 - self.clearance / self.groove_sum)
        if self.preload == 0.0:
            return a0, 0.0

        def approach(a):
            return self.groove_sum * (np.cos(a0) / np.cos(a) - 1.0)

        def axial_force(a):
            return self.n_balls * self.K * approach(a) ** 1.5 * np.sin(a) - self.preload

        a = brentq(axial_force, a0, np.pi / 2 - 1e-9, xtol=1e-15, rtol=1e-15, maxiter=500)
        return a, approach(a)

    @property
    def alpha(self):
        """Loaded contact angle [rad]."""
        return self._loaded[0]

    @property
    def normal_approach(self):
        """delta_n [m]: squeeze of every ball at x = y = 0 (0 without preload)."""
        return self._loaded[1]

    @property
    def omega_cage(self):
        return 2 * np.pi * self.speed * (1 - self.ball_diameter / self.pitch_diameter * np.cos(self.alpha)) / 2

    def ball_deflections(self, t, x, y):
        """delta_j [m] of every ball (columns) at times t for journal positions x, y (arrays)."""
        t, x, y = (np.asarray(v, float)[..., None] for v in (t, x, y))
        phi = 2 * np.pi * np.arange(self.n_balls) / self.n_balls + self.omega_cage * t
        offset = self.normal_approach if self.preload > 0 else -self.clearance
        return (x * np.cos(phi) + y * np.sin(phi)) * np.cos(self.alpha) + offset

    def rhs(self, t, u):
        x, y, vx, vy = u
        phi = 2 * np.pi * np.arange(self.n_balls) / self.n_balls + self.omega_cage * t
        ca = np.cos(self.alpha)
        offset = self.normal_approach if self.preload > 0 else -self.clearance
        delta = (x * np.cos(phi) + y * np.sin(phi)) * ca + offset
        q = self.K * np.clip(delta, 0.0, None) ** 1.5
        fx = np.sum(q * np.cos(phi)) * ca
        fy = np.sum(q * np.sin(phi)) * ca
        return [vx, vy, (-self.damping * vx - fx) / self.mass, (-self.damping * vy - fy - self.load) / self.mass]

    def trajectory(self, u0, n_times=400, rtol=1e-12):
        """(t, states (n_times, 4)) over one forcing period from u0, equally spaced in time."""
        t = np.linspace(0.0, self.period, n_times, endpoint=False)
        sol = solve_ivp(self.rhs, (0.0, self.period), u0, method="DOP853", t_eval=t, rtol=rtol,
                        atol=1e-15 * np.abs(np.asarray(u0)).max())
        return t, sol.y.T


def torus_half_swing(scene, ds, k, observable="y_B", turns=150):
    """Half peak-to-peak of `observable` over `turns` shaft turns of a scipy DOP853 run (rtol
    1e-10, 256 samples per turn) of the rigid_preloaded rotor from point k of a continuation
    result's first (torus) branch, at that point's parameter: the torus's half-swing measured
    without the torus solver (the run covers the torus densely at an irrational rotation; it
    samples the sup from below)."""
    from rotorsweep.kernels.models import rigid_preloaded_kernels as rp
    from rotorsweep.pipeline import continuation, torus_branches

    pl = continuation.plan(scene)
    _, built = torus_branches.torus_family(scene, pl, pl.lines[0], 1)
    b = built(float(ds["parameter"].values[0, k]))
    p = b.p.copy()

    def f(tau, u):
        du = np.empty_like(u)
        rp.rhs(tau, u, p, du)
        return du
    sol = solve_ivp(f, (0.0, turns), ds["orbit_state"].values[0, k], method="DOP853", rtol=1e-10, atol=1e-12,
                    t_eval=np.linspace(0.0, turns, 256 * turns + 1))
    assert sol.success
    y = scene.model.observe(sol.y.T, b.period)[:, list(ds["observable"].values).index(observable)]
    return 0.5 * (y.max() - y.min())


def duffing2_strobe(p, u0, n_periods):
    """The stroboscopic iterates u_n, n = 1..n_periods, of scipy's DOP853 (Hairer's code,
    `scipy.integrate.ode`, rtol 1e-12) from u0 at phase p[theta]: the run is continued period by
    period, each period from tau = 0 with the second forcing's phase theta + n w2 reduced mod
    2 pi, the phase the circle is read at. One run in absolute time carries the rounding of
    w2 t at t ~ 10^4 (eps w2 t ~ 1e-11 rad, growing with t) into the forcing, above the 1e-12
    level tested here; solve_ivp's Python step loop took a minute for 10^4 periods."""
    k, c, gamma, f1, f2, w2, theta = p
    tw = 2.0 * np.pi
    phase = [0.0]

    def f(t, u):
        x, v = u
        return [v, f1 * np.cos(tw * t) + f2 * np.cos(w2 * t + phase[0]) - k * x - gamma * x ** 3 - c * v]
    run = ode(f).set_integrator("dop853", rtol=1e-12, atol=1e-13, nsteps=10 ** 6)
    out = np.empty((n_periods, 2))
    u = np.array(u0, float)
    for i in range(n_periods):
        phase[0] = np.fmod(theta + i * w2, 2.0 * np.pi)
        run.set_initial_value(u, 0.0)
        u = out[i] = run.integrate(1.0)
        assert run.successful()
    return out

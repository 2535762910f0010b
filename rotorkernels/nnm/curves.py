r"""Backbone (skeleton) curve of a mode from its reduced oscillator, and the checks and figure data
of the manifold (the papers' Figs. 3-4).

Amplitude: A is the amplitude of the first harmonic of the master displacement p [m] (equal to
half its peak-to-peak excursion up to O(A^3)).

Backbone: the papers apply harmonic balance with one harmonic to the reduced oscillator; with
quadratic terms that misses their contribution, which enters at the same order (A^2) as the cubic
terms through the mean and the second harmonic. We use the second-order Lindstedt-Poincare result
(equivalently harmonic balance with harmonics 0, 1, 2), written for the general reduced oscillator

    p'' + w^2 p + a1 p^2 + a2 p r + a3 r^2 + b1 p^3 + b2 p^2 r + b3 p r^2 + b4 r^3 = 0,  r = p',

through the cubic Poincare normal-form coefficient c1 (Kuznetsov, Elements of Applied Bifurcation
Theory, sec. 3.5), the same algebra for a one-DOF oscillator:

    omega(A) = w + kappa A^2 + O(A^4),
    kappa = (3 b1 + w^2 b3) / (8 w)
          - [(a1 - w^2 a3)(a1 + w^2 a3) + 2 (a1 + w^2 a3)^2 + ((a1 - w^2 a3)^2 + w^2 a2^2) / 3] / (8 w^3).

(Duffing: kappa = 3 b1 / (8 w); u'' + w^2 u + a u^2: kappa = -5 a^2 / (12 w^3), Nayfeh.) The
neglected term is O(A^4): omega is even in A (the normal form has only odd powers of |z| and A
equals 2|z| up to O(|z|^3)). The real part of c1 gives the amplitude's growth rate
(1/A) dA/dt = sigma A^2, sigma = [a2 (a1 + w^2 a3) / (2 w^2) - (b2 + 3 w^2 b4) / 2] / 4; it vanishes
on the manifold of a conservative system (the reduced flow is a centre), which is a check.

The second-order orbit p(theta) = A cos(theta) + A^2 [-(a1 + w^2 a3) / (2 w^2)
+ (a1 - w^2 a3) / (6 w^2) cos(2 theta) - a2 / (6 w) sin(2 theta)], r = omega dp/dtheta, mapped
through the manifold, gives each coordinate's amplitude and the start of the invariance check.
"""
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp

from rotorsweep.kernels.nnm import system as ps

# Integration tolerances of the full system in the invariance check (relative; the absolute one
# is this times the amplitude, times omega for velocities).
RTOL = 1e-12


def _reduced(manifold):
    b = manifold.reduced
    return (b["p^2"], b["p r"], b["r^2"], b["p^3"], b["p^2 r"], b["p r^2"], b["r^3"])


def frequency_coefficient(manifold):
    """kappa [rad/s/m^2] of omega(A) = omega_0 + kappa A^2 (module docstring)."""
    w = manifold.omega
    a1, a2, a3, b1, _, b3, _ = _reduced(manifold)
    s, d = a1 + w ** 2 * a3, a1 - w ** 2 * a3
    return (3 * b1 + w ** 2 * b3) / (8 * w) - (d * s + 2 * s ** 2 + (d ** 2 + w ** 2 * a2 ** 2) / 3) / (8 * w ** 3)


def growth_coefficient(manifold):
    """sigma [1/s/m^2] of (1/A) dA/dt = sigma A^2: zero for a conservative system (a check)."""
    w = manifold.omega
    a1, a2, a3, _, b2, _, b4 = _reduced(manifold)
    return (a2 * (a1 + w ** 2 * a3) / (2 * w ** 2) - (b2 + 3 * w ** 2 * b4) / 2) / 4


def angular_frequency(manifold, amplitudes):
    """omega(A) [rad/s] at master amplitudes A [m]."""
    return manifold.omega + frequency_coefficient(manifold) * np.asarray(amplitudes, float) ** 2


def backbone(manifold, amplitudes):
    """Backbone frequencies [Hz] at master amplitudes A [m] (first harmonic of p)."""
    return angular_frequency(manifold, amplitudes) / (2 * np.pi)


def orbit(manifold, amplitude, n=64):
    """(p, r) at n phases theta = 2 pi k / n of the second-order periodic orbit (module docstring)."""
    w = manifold.omega
    a1, a2, a3 = _reduced(manifold)[:3]
    theta = 2 * np.pi * np.arange(n) / n
    mean, cos2, sin2 = -(a1 + w ** 2 * a3) / (2 * w ** 2), (a1 - w ** 2 * a3) / (6 * w ** 2), -a2 / (6 * w)
    a = float(amplitude)
    p = a * np.cos(theta) + a ** 2 * (mean + cos2 * np.cos(2 * theta) + sin2 * np.sin(2 * theta))
    dp = -a * np.sin(theta) + a ** 2 * (-2 * cos2 * np.sin(2 * theta) + 2 * sin2 * np.cos(2 * theta))
    return p, angular_frequency(manifold, a) * dp


def coordinate_amplitudes(manifold, amplitudes, n=64):
    """Half peak-to-peak of every state component (manifold.names; SI) on the second-order orbit,
    shape (len(amplitudes), 2 x coordinates)."""
    out = []
    for a in np.atleast_1d(amplitudes):
        states = manifold.slaves(*orbit(manifold, a, n))
        out.append((states.max(axis=0) - states.min(axis=0)) / 2)
    return np.array(out)


class OrbitOnManifold(NamedTuple):
    t: np.ndarray            # [s]
    state: np.ndarray        # full system's state (q, q') at t, shape (len(t), 2n)
    manifold_state: np.ndarray  # the manifold's state at the same master (p, r)


def orbit_on_manifold(system, manifold, amplitude, periods=10, samples_per_period=64):
    """The full system integrated (solve_ivp DOP853, rtol RTOL) from the manifold point at phase 0
    of the amplitude-A orbit, with the manifold's state at each sample's master (p, r): the orbit
    lies on the surface (the papers' Fig. 3)."""
    ps.validate(system)
    n = len(system.coordinates)
    p, r = orbit(manifold, amplitude, 1)
    x0 = manifold.slaves(p[0], r[0])
    period = 2 * np.pi / angular_frequency(manifold, amplitude)
    t = np.linspace(0.0, periods * period, int(periods * samples_per_period) + 1)
    scale = np.concatenate([np.full(n, amplitude), np.full(n, amplitude * manifold.omega)])
    sol = solve_ivp(ps.rhs(system), (0.0, t[-1]), x0, method="DOP853", t_eval=t, rtol=RTOL,
                    atol=RTOL * scale)
    if not sol.success:
        raise RuntimeError(f"integration from the manifold failed: {sol.message}")
    state = sol.y.T
    j = manifold.master
    return OrbitOnManifold(sol.t, state, manifold.slaves(state[:, j], state[:, n + j]))


def invariance_error(system, manifold, amplitude, periods=10):
    """Largest distance [m] from the manifold over `periods` periods of the full-system orbit
    started on it: |q - X_q(p, r)|^2 + |q' - X_q'(p, r)|^2 / omega^2, square-rooted (velocities
    over omega to be lengths). O(A^4) for a manifold exact to cubic order."""
    o = orbit_on_manifold(system, manifold, amplitude, periods)
    n = len(system.coordinates)
    diff = o.state - o.manifold_state
    diff[:, n:] /= manifold.omega
    return float(np.sqrt((diff ** 2).sum(axis=1)).max())


def surface(manifold, coordinate, p_range, r_range, n=41):
    """(p, r, value) grids (n x n) of one state component (a name of manifold.names, velocities
    named "x1'", or an index) over master displacement p_range and velocity r_range (pairs)."""
    index = manifold.names.index(coordinate) if isinstance(coordinate, str) else int(coordinate)
    p, r = np.meshgrid(np.linspace(*p_range, n), np.linspace(*r_range, n), indexing="ij")
    return p, r, manifold.slaves(p, r)[..., index]

"""Periodic-orbit problems (rotorsweep.kernels.orbits) against closed forms, on the Duffing validation
model: forced orbits of the linear oscillator, free (conservative) orbits with unknown period."""
import numpy as np
import pytest
from scipy.integrate import quad

from rotorsweep.kernels import integrators as ig, models, shooting
from rotorsweep.kernels.orbits import AutonomousOrbitProblem, ForcedOrbitProblem

DUFFING = models.get("duffing")
TIGHT = ig.settings("dop853", rtol=1e-12, atol=1e-14, amplitude_limit=1e3)


def duffing(omega, zeta=0.0, gamma=0.0, force=0.0):
    return DUFFING.build({"omega": omega, "zeta": zeta, "gamma": gamma, "force": force})


@pytest.mark.parametrize("omega", [0.5, 0.97, 1.6])
def test_forced_linear_orbit_is_the_steady_state(omega):
    """gamma = 0: x(t) = Re(X e^(i omega t)), X = F / (1 - omega^2 + 2 i zeta omega); the scaled
    state is (Re X, T Re(i omega X)) = (Re X, -2 pi Im X). Newton to 1e-12 on DOP853 at rtol
    1e-12: the state is exact to ~1e-11 relative to max(1, |s|); 1e-9 leaves room."""
    zeta, force = 0.05, 0.3
    built = duffing(omega, zeta, 0.0, force)
    X = force / (1 - omega ** 2 + 2j * zeta * omega)
    out = ForcedOrbitProblem(DUFFING, built.p, TIGHT).shoot(np.zeros(2), 1e-12, 20)
    assert out[2] == shooting.CONVERGED
    np.testing.assert_allclose(out[0], [X.real, -2 * np.pi * X.imag], atol=1e-9 * max(1, abs(X)))


def free_period(amplitude, gamma):
    """Period of x'' + x + gamma x^3 = 0 through x = A, x' = 0: with x = A sin(theta),
    T = 4 int_0^(pi/2) dtheta / sqrt(1 + gamma A^2 (1 + sin^2 theta) / 2) (quadrature to 1e-13)."""
    g = lambda th: 1.0 / np.sqrt(1.0 + gamma * amplitude ** 2 * (1.0 + np.sin(th) ** 2) / 2.0)
    return 4.0 * quad(g, 0.0, np.pi / 2, epsabs=0.0, epsrel=1e-13)[0]


@pytest.mark.parametrize("gamma, amplitude", [(0.1, 1e-3), (0.1, 1.0), (0.1, 3.0), (-0.1, 1.5)])
def test_autonomous_orbit_period_is_the_exact_free_period(gamma, amplitude):
    """Conservative Duffing (hardening and softening): the period found with phase and amplitude
    conditions equals the quadrature. Scaled time with omega = 1 is t / 2 pi. The period error
    is the integration error over one period (DOP853, rtol 1e-12: ~1e-11) plus Newton's residual
    (1e-11) over |f|: 1e-9 relative bounds both. Both multipliers are 1 (a Jordan block: round-off
    of size eps splits them by ~sqrt(eps) = 1e-6)."""
    built = duffing(1.0, gamma=gamma)
    problem = AutonomousOrbitProblem(DUFFING, built.p, TIGHT)
    # the one-harmonic balance period 1 / sqrt(1 + 3 gamma A^2 / 4) as the guess (a continuation
    # supplies its neighbour's period instead)
    orbit = problem.solve(amplitude, np.zeros(2), 1 / np.sqrt(1 + 0.75 * gamma * amplitude ** 2), tol=1e-11)
    assert orbit.converged
    assert orbit.period * 2 * np.pi == pytest.approx(free_period(amplitude, gamma), rel=1e-9)
    assert orbit.state[0] == amplitude and orbit.state[1] == 0.0
    np.testing.assert_allclose(orbit.multipliers, [1.0, 1.0], atol=1e-5)


def test_autonomous_orbit_reports_failure_instead_of_raising():
    """A softening spring past its turning amplitude (1 + gamma A^2 < 0 at A = 4, gamma = -0.1)
    has no periodic orbit: the solve ends with converged False."""
    built = duffing(1.0, gamma=-0.1)
    orbit = AutonomousOrbitProblem(DUFFING, built.p, TIGHT).solve(4.0, np.zeros(2), 1.0, max_iter=8)
    assert not orbit.converged and np.isnan(orbit.multipliers).all()


def test_a_point_without_orbit_has_every_multiplier_component_nan():
    """Failure is data, uniformly: no orbit means NaN real and imaginary parts (not NaN + 0j)."""
    from rotorsweep.pipeline import compute
    from rotorsweep.kernels import continuation

    jeff = models.get("jeffcott_clearance")
    built = jeff.build({"speed": 60.0, "clearance": 3.8e-6, "preset": "209", "free_angle": "geometry",
                        "stiffness": "bai2006", "preload_constant": "consistent", "cage_rotation": True, "mass": 2.0,
                        "damping": 300.0, "radial_load": "gravity", "gravity": 9.8})
    sol = continuation.solve_orbit(jeff, built.p, TIGHT, cold_guess=jeff.cold_guess, max_iter=1,
                                   tol=1e-300, transient_periods=0)
    assert sol.status != shooting.CONVERGED
    row = compute.point_variables(jeff, sol, built, 0.0)
    assert np.isnan(row["multiplier_real"]).all() and np.isnan(row["multiplier_imag"]).all()


def test_follow_returns_a_branch_with_a_status_per_step():
    """Natural continuation of the forced linear oscillator over omega: every step converges to
    the closed-form steady state; an unknown strategy is refused by name."""
    from rotorsweep.kernels import continuation

    omegas = [0.6, 0.7, 0.8]
    params = [duffing(w, 0.05, 0.0, 0.3).p for w in omegas]
    branch = continuation.follow(DUFFING, params, TIGHT, cold_guess=DUFFING.cold_guess, tol=1e-12)
    assert branch.complete and branch.failed == []
    for w, sol in zip(omegas, branch.solutions):
        X = 0.3 / (1 - w ** 2 + 0.1j * w)
        np.testing.assert_allclose(sol.state, [X.real, -2 * np.pi * X.imag], atol=1e-9)
    with pytest.raises(ValueError, match="unknown continuation strategy 'palc'; known: natural"):
        continuation.follow(DUFFING, params, TIGHT, strategy="palc", cold_guess=DUFFING.cold_guess)


def test_newton_step_is_lapacks_solve_and_flags_singular_matrices():
    """shooting._newton_step (pivoted elimination, written out to keep numba's np.linalg.solve out
    of a first point's compilation) against numpy's LAPACK gesv: two backward-stable solvers agree
    to about n eps cond(M - I) relative to |x|; 10x that is the bound. A zero column, NaN or inf
    in M is refused (gesv's failure, R_SINGULAR in shoot)."""
    rng = np.random.default_rng(7)
    eps = np.finfo(float).eps
    for n in (2, 4, 10):
        mono = rng.normal(size=(n, n))
        r = rng.normal(size=n)
        a = mono - np.eye(n)
        x, ok = shooting._newton_step(mono, r)
        ref = np.linalg.solve(a, -r)
        assert ok
        assert np.abs(x - ref).max() <= 10 * n * eps * np.linalg.cond(a) * np.abs(ref).max()
    singular = 2.0 * np.eye(3)
    singular[:, 1] = [0.0, 1.0, 0.0]        # M - I has a zero column
    assert not shooting._newton_step(singular, np.ones(3))[1]
    for bad in (np.nan, np.inf):
        mono = np.eye(3) * 2.0
        mono[1, 2] = bad
        assert not shooting._newton_step(mono, np.ones(3))[1]


@pytest.mark.slow
def test_a_dop853_first_point_compiles_no_rk4_and_one_integrator(tmp_path):
    """The integrator is chosen by the settings' type at compile time: a cold dop853 point (fresh
    process, empty cache) compiles the DOP853 step loop once (literal True and False callers
    share its bool signature) and RK4's never (`dop853` and `rk4` are inlined into the body
    `flow` picks, so their step loops are what is compiled)."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    code = ("import rotorsweep.pipeline as pipeline\nfrom rotorsweep.kernels import integrators as ig\n"
            "pipeline.point(speed=100, clearance=7.6e-6)\n"
            "print(len(ig._dop853_steps.signatures), len(ig._rk4_steps.signatures))\n")
    root = Path(__file__).resolve().parents[1]
    env = {**os.environ, "ROTORSWEEP_CACHE": str(tmp_path), "PYTHONPATH": str(root)}
    for name in ("NUMBA_CACHE_DIR", "ROTORSWEEP_NUMBA_CACHE_DIR"):
        env.pop(name, None)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["1", "0"]

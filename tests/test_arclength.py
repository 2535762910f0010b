"""Pseudo-arclength continuation (rotorsweep.kernels.continuation.arclength) against independent values.

- Forced Duffing resonance curves, hardening and softening: both folds passed in one run; the
  fold frequency and the orbit there against a reference computed another way (scipy solve_ivp
  on the variational equations in physical time, fsolve on [phi(s) - s, det(M - I)]).
- Bai 2006 rotor at 7.6 um: the jump of the natural sweep near 40-42 Hz is a fold pair; inside
  the overlap two stable orbits coexist, each reached by a long transient from its own start.
- Bai 2006 rotor at 19 um: period doublings on the period-1 branch located where the grid
  sweep's boundary refinement puts them, and the period-2 and period-4 branches reached by
  branch switching.
- A branch that cannot go on ends with a status, and settings that cannot work are refused.
"""
import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

from rotorsweep.pipeline import compute, config
from rotorsweep.kernels import integrators as ig, models, shooting
from rotorsweep.kernels.continuation import arclength as al, engine, events, solve_orbit

DUFFING = models.get("duffing")
# Integrator tolerance of the continuation runs; the Newton tolerance (1e-10) sits above it.
OPTS = ig.settings("dop853", rtol=1e-12, atol=1e-14)
SETTINGS = al.Settings(ds=0.05, ds_max=0.3)


def duffing_family(gamma, zeta=0.05, force=0.1):
    def params(omega):
        return DUFFING.build({"omega": omega, "zeta": zeta, "gamma": gamma, "force": force}).p
    return al.Family(DUFFING, params, OPTS, scale=1.0)


def reference_fold(gamma, omega, x0, v0, zeta=0.05, force=0.1):
    """(omega, x0, dx/dt(0)) of the fold nearest the guess, in physical time: scipy's DOP853 at
    rtol 1e-13 on the state and its variational equations, fsolve on the shooting residual and
    det(M - I) (a fold of a forced orbit: one multiplier at +1)."""
    def flow(u):
        x0_, v0_, w = u
        def f(t, z):
            x, v = z[0], z[1]
            phi = z[2:].reshape(2, 2)
            jac = np.array([[0.0, 1.0], [-1.0 - 3.0 * gamma * x * x, -2.0 * zeta]])
            return np.concatenate(([v, force * np.cos(w * t) - 2.0 * zeta * v - x - gamma * x ** 3],
                                   (jac @ phi).ravel()))
        sol = solve_ivp(f, (0.0, 2.0 * np.pi / w), [x0_, v0_, 1.0, 0.0, 0.0, 1.0], method="DOP853",
                        rtol=1e-13, atol=1e-15)
        return sol.y[:, -1]

    def residual(u):
        z = flow(u)
        return [z[0] - u[0], z[1] - u[1], np.linalg.det(z[2:].reshape(2, 2) - np.eye(2))]
    x0, v0, omega = fsolve(residual, [x0, v0, omega], xtol=1e-12)
    return np.array([omega, x0, v0])


def physical(point):
    """(omega, x0, dx/dt(0)) of a Duffing branch point (scaled time tau = omega t / 2 pi)."""
    omega = point.lam
    return np.array([omega, point.state[0], point.state[1] * omega / (2.0 * np.pi)])


@pytest.mark.parametrize("gamma", [1.0, -0.2], ids=["hardening", "softening"])
def test_duffing_folds_against_independent_reference(gamma):
    family = duffing_family(gamma)
    branch = al.continue_orbit(family, 0.5, np.zeros(2), (0.5, 2.0), SETTINGS)
    assert branch.end == al.LEFT_RANGE, branch.detail
    folds = [e for e in branch.events if e.kind == al.FOLD]
    assert len(folds) == 2 and not [e for e in branch.events if e.kind != al.FOLD]
    for fold in folds:
        ours = physical(fold.point)
        # start the reference 1e-3 away from our answer: it converges on its own
        ref = reference_fold(gamma, *(ours * (1 + 1e-3)))
        # Both sides solve to ~1e-10 (Newton tolerance; located arclength 1e-11, and the
        # parameter is quadratic in the arclength at a fold), well inside 1e-6.
        np.testing.assert_allclose(ours, ref, rtol=1e-6, atol=1e-6 * np.abs(ref).max())
        # one multiplier at +1: the monodromy's error is the integrator's (1e-12)
        assert np.abs(fold.point.multipliers - 1.0).min() < 1e-6
    # stable - unstable - stable: the middle segment between the two folds is unstable
    i, j = sorted(e.index for e in folds)
    stable = np.array([np.abs(p.multipliers).max() < 1 for p in branch.points])
    assert stable[:i + 1].all() and stable[j + 1:].all()
    assert not stable[i + 1:j + 1].any()
    # hardening bends the resonance right of the linear one (omega = 1), softening left
    assert all((f.point.lam > 1) == (gamma > 0) for f in folds)


def test_duffing_amplitude_at_fold_against_reference():
    """The amplitude max|x| over the orbit at a fold: ours (our orbit samples) against the
    reference orbit (scipy dense output) at the same 400 phases."""
    family = duffing_family(1.0)
    branch = al.continue_orbit(family, 0.5, np.zeros(2), (0.5, 2.0), SETTINGS)
    fold = branch.events[0].point
    omega, x0, v0 = reference_fold(1.0, *physical(fold))
    ours = np.abs(al.orbit_samples(family, fold, 400)[:, 0]).max()

    def f(t, z):
        return [z[1], 0.1 * np.cos(omega * t) - 0.1 * z[1] - z[0] - z[0] ** 3]
    period = 2.0 * np.pi / omega
    ref = solve_ivp(f, (0.0, period), [x0, v0], method="DOP853", rtol=1e-13, atol=1e-15, dense_output=True)
    ref_amp = np.abs(ref.sol(np.arange(400) * period / 400)[0]).max()
    assert ours == pytest.approx(ref_amp, rel=1e-6)


@pytest.fixture(scope="module")
def bai():
    cfg = config.load_config("configs/bai2006_fig13.toml")
    build = compute.builder(cfg.scene)
    fixed = {k: v for k, v in cfg.scene.fixed.items() if v is not None}
    opts = cfg.scene.integrator

    def family(clearance, scale):
        return al.Family(cfg.model, lambda speed: build({**fixed, "speed": speed, "clearance": clearance}).p,
                         opts, scale=scale)

    def start(family, speed):
        return solve_orbit(cfg.model, family.params(speed), opts, cold_guess=cfg.model.cold_guess, tol=1e-10).state
    return cfg.model, opts, family, start


BAI_SETTINGS = al.Settings(ds=0.02, ds_max=0.5, max_steps=2000)


def bai_branch(bai, clearance, lo, hi):
    """(family, the period-1 branch from a cold start at lo over [lo, hi]), which reaches hi."""
    _, _, family_at, start = bai
    family = family_at(clearance, 20.0)
    branch = al.continue_orbit(family, lo, start(family, lo), (lo, hi), BAI_SETTINGS)
    assert branch.end == al.LEFT_RANGE, branch.detail
    return family, branch


def test_bai_7p6um_jump_is_a_fold_pair_with_two_stable_orbits(bai):
    model, opts, _, _ = bai
    family, branch = bai_branch(bai, 7.6e-6, 30.0, 50.0)
    folds = [e for e in branch.events if e.kind == al.FOLD]
    assert len(folds) == 2
    upper, lower = folds[0].point.lam, folds[1].point.lam
    assert 40 < lower < upper < 42       # the natural sweep's jump lies in 40-42 Hz
    # the speed inside the overlap, and the two stable orbits there (outer branches)
    speed = 0.5 * (lower + upper)
    on_branch = [p for p in branch.points if abs(p.lam - speed) < 0.5 * (upper - lower)]
    stable = [p for p in on_branch if np.abs(p.multipliers).max() < 1]
    assert len(stable) >= 2
    a = min(stable, key=lambda p: p.state[0])
    b = max(stable, key=lambda p: p.state[0])
    # the two stable orbits at the overlap speed itself (Newton from the branch neighbours)
    p = family.params(speed)
    orbits = [solve_orbit(model, p, opts, [o.state], cold_guess=model.cold_guess, tol=1e-10) for o in (a, b)]
    assert all(o.stable for o in orbits)
    # long time integration from two different starts, each 1 % of the orbit's size off one of
    # them: each transient ends on its own orbit. The slowest multiplier (~0.84 here) leaves
    # 1e-2 * 0.84^2000 of the start; what remains is the integrator's error of the long run
    # (rtol 1e-10 per period, through contact switching), far below 1e-5.
    for orbit in orbits:
        z, status, _ = shooting.settle(model.kernel, orbit.state * 1.01, p, 2000.0, opts)
        assert status == ig.STATUS_OK
        assert np.abs(z - orbit.state).max() < 1e-5 * np.abs(orbit.state).max()
    # two different orbits: far apart compared with that
    assert np.abs(orbits[0].state - orbits[1].state).max() > 0.1 * np.abs(orbits[0].state).max()


def test_bai_19um_period_doublings_and_branch_switching(bai):
    model, opts, _, _ = bai
    family, branch = bai_branch(bai, 19e-6, 20.0, 40.0)
    pds = [e for e in branch.events if e.kind == al.PERIOD_DOUBLING]
    assert len(pds) >= 1
    # the cascade's first doubling: the PD on the period-1 branch inside 27-28 Hz
    pd = next(e for e in pds if 27 < e.point.lam < 28)
    assert np.abs(pd.point.multipliers + 1.0).min() < 1e-6
    # a second method on the same crossing: the grid sweep's refinement (Brent on
    # max|mu| - 1 with natural continuation from the stable side), whose xtol is 1e-8 relative
    a_, b_ = pd.point.lam - 0.05, pd.point.lam + 0.05

    def solve(v, guess):
        return solve_orbit(model, family.params(v), opts, [guess], cold_guess=model.cold_guess, tol=1e-10)
    grid = events.locate_boundary(solve, a_, b_, solve(a_, pd.point.state).state, xtol_rel=1e-10)
    assert grid.value == pytest.approx(pd.point.lam, rel=1e-8)

    period2 = al.switch_period_doubling(family, pd, (20.0, 40.0), BAI_SETTINGS)
    assert period2.periods == 2 and len(period2.points) > 3, period2.detail
    first = period2.points[0]
    # the new branch starts at the doubling and is a genuine period-2 orbit
    assert abs(first.lam - pd.point.lam) < 0.05
    r1, _, _, _ = family.return_map(first.state, first.lam, False)
    assert np.abs(r1).max() > 1e3 * BAI_SETTINGS.tol
    pd2 = next(e for e in period2.events if e.kind == al.PERIOD_DOUBLING)
    assert pd2.point.lam > pd.point.lam
    period4 = al.switch_period_doubling(family.with_periods(2), pd2, (20.0, 40.0), BAI_SETTINGS)
    assert period4.periods == 4 and len(period4.points) > 3, period4.detail
    pd4 = next(e for e in period4.events if e.kind == al.PERIOD_DOUBLING)
    # the cascade accumulates: each doubling interval shorter than the one before
    assert pd4.point.lam - pd2.point.lam < pd2.point.lam - pd.point.lam


def test_ends_are_statuses_not_exceptions():
    # no orbit at the start: a start from NaN cannot converge
    family = duffing_family(1.0)
    branch = al.continue_orbit(family, 0.5, np.full(2, np.nan), (0.5, 2.0), SETTINGS)
    assert branch.end == al.START_FAILED and "0.5" in branch.detail
    # step budget
    branch = al.continue_orbit(family, 0.5, np.zeros(2), (0.5, 2.0), al.Settings(max_steps=3))
    assert branch.end == al.STEP_BUDGET and len(branch.points) == 4
    # a softening oscillator driven out of its potential well (barrier at |x| = 1 for
    # gamma = -1): the branch cannot go on
    escaping = duffing_family(-1.0, force=0.2)._replace(opts=ig.settings("dop853", 1e-10, 1e-12, amplitude_limit=10.0))
    branch = al.continue_orbit(escaping, 0.3, np.zeros(2), (0.3, 2.0), al.Settings(ds=0.05, ds_min=1e-3))
    assert branch.end in (al.NEWTON_FAILED, al.INTEGRATION_FAILED)
    assert "minimum step" in branch.detail


def test_settings_that_cannot_work_are_named():
    assert al.Settings().problems() == []
    problems = al.Settings(ds=0.0, max_steps=0, max_angle=2.0).problems()
    text = "\n".join(problems)
    assert "ds = 0.0" in text and "max_steps" in text and "max_angle" in text
    assert al.Settings(ds=-1.0).problems()


def test_sweep_boundary_table_locates_the_fold_on_the_branch(bai):
    """The grid sweep at 19 um brackets the loss of stability near 28.4 Hz between a stable orbit
    and an orbit of another branch (past the fold Newton lands there). Its boundary table puts
    the boundary at the fold of the stable branch, typed as a fold, to the table's 1e-8."""
    import xarray as xr

    from rotorsweep.pipeline import boundaries, schema

    cfg = config.load_config("configs/bai2006_fig13.toml")
    fixed = {k: v for k, v in cfg.scene.fixed.items() if v is not None}
    speeds = [26.0, 26.5, 27.0, 27.5, 28.0, 28.3, 28.5]   # natural continuation from 26 Hz
    rows = compute.solve_segment(cfg.scene, [{**fixed, "speed": s, "clearance": 19e-6} for s in speeds])
    variables = schema.variables_of(cfg.model)
    ds = xr.Dataset({name: (("clearance", "speed") + variables[name][0], values[None])
                     for name, values in rows.items() if name in variables},
                    coords={"speed": ("speed", speeds, {"units": "Hz", "long_name": "shaft speed"}),
                            "clearance": ("clearance", [19e-6], {"units": "m", "long_name": "radial clearance"})})
    assert ds["stable"].values[0, -2:].tolist() == [1, 0]
    ds.attrs["continued_axis"] = "speed"
    row = next(r for r in boundaries.boundary_rows(cfg.scene, ds) if r["boundary_grid_low"] == 28.3)
    _, branch = bai_branch(bai, 19e-6, 26.0, 29.0)
    fold = next(e for e in branch.events if e.kind == al.FOLD)
    assert row["boundary_type"] == schema.BIFURCATION.index("fold")
    assert row["boundary_speed"] == pytest.approx(fold.point.lam, rel=1e-8)


def test_an_event_brent_cannot_locate_is_left_out_and_the_branch_goes_on(monkeypatch):
    """The hardening Duffing branch with Brent made to give up on every event: the two folds are
    not listed (they have no located point), the branch's detail says where they were detected,
    and the branch still runs to the end of its range."""
    from rotorsweep.kernels.roots import NotConverged

    def not_converging(f, a, b, xtol):
        raise NotConverged("no convergence", (a, b))
    monkeypatch.setattr(al, "brent_root", not_converging)
    branch = al.continue_orbit(duffing_family(1.0), 0.5, np.zeros(2), (0.5, 2.0), SETTINGS)
    assert branch.end == al.LEFT_RANGE, branch.detail
    assert branch.events == [] and len(branch.points) > 10
    missed = re.findall(r"; LP not located between points (\d+) and (\d+) \(lambda = ", branch.detail)
    assert branch.detail.startswith("lambda left [0.5, 2.0]") and len(missed) == 2
    monkeypatch.undo()          # located, each fold lies after the point the detail names
    folds = al.continue_orbit(duffing_family(1.0), 0.5, np.zeros(2), (0.5, 2.0), SETTINGS).events
    assert [(str(f.index), str(f.index + 1)) for f in folds] == missed


def test_a_step_corrector_stops_where_its_step_would_be_refused(bai, monkeypatch):
    """A step's corrector stops after max_newton - 2 iterations (engine._step): a step that needs
    more is refused whether or not it converges (engine.rejected), so the branch is the one the
    full corrector gives, point for point, at less cost where correctors diverge (the 7.6 um
    period-1 branch over 20-50 Hz has some; over 38-44 Hz it has none and costs the same)."""
    _, capped = bai_branch(bai, 7.6e-6, 20.0, 50.0)

    def full_step(problem, a, ds, settings, counter):
        sol, failure = engine.on_arclength(problem, a, ds, settings, counter)
        if failure is not None:
            return None, failure
        b = problem.point(sol, a, settings, counter)
        return (b, None) if b is not None else (None, engine.INTEGRATION_FAILED)
    monkeypatch.setattr(engine, "_step", full_step)
    _, full = bai_branch(bai, 7.6e-6, 20.0, 50.0)
    assert [p.lam for p in capped.points] == [p.lam for p in full.points]
    assert [(e.kind, e.point.lam) for e in capped.events] == [(e.kind, e.point.lam) for e in full.events]
    assert capped.n_rhs < full.n_rhs

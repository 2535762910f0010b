"""Two-parameter continuation of bifurcation points (rotorsweep.kernels.continuation.twoparam): the
period-doubling, Neimark-Sacker and fold curves of the Bai 2006 model in (speed, clearance)
against the sweep's refined boundaries and one-parameter fold locations, the forced Duffing fold
curve in (omega, force) against a scipy reference, the codimension-2 flags and the statuses."""
import math

import numpy as np
import pytest

from rotorsweep.pipeline import boundaries, compute, config
from rotorsweep.kernels import integrators as ig, models
from rotorsweep.kernels.continuation import arclength as al, events, solve_orbit, twoparam as tp
from workflows.bench.peers import duffing_scipy

FIG13 = (3.8e-6, 7.6e-6, 11.4e-6, 15.2e-6, 19e-6)      # the Fig. 13 grid's clearances
GRID_START, GRID_STEP = 10.0, 0.1                       # ... and speeds [Hz]
BAI_BOX = ((10.0, 250.0), (3.0e-6, 20e-6))
DUFFING = models.get("duffing")
TIGHT = ig.settings("dop853", rtol=1e-12, atol=1e-14, amplitude_limit=1e3)


@pytest.fixture(scope="module")
def fig13():
    cfg = config.load_config("configs/bai2006_fig13.toml")
    build = compute.builder(cfg.scene)
    fixed = {k: v for k, v in cfg.scene.fixed.items() if v is not None}
    plane = tp.Plane(cfg.model, lambda speed, c: build({**fixed, "speed": speed, "clearance": c}).p,
                     cfg.scene.integrator, lam_scale=20.0, nu_scale=1e-5)
    return cfg.scene, plane


def branch_events(plane, nu, lo, hi):
    """The located events of the period-1 branch at nu over [lo, hi] (started cold at lo)."""
    family = plane.family(nu)
    sol = solve_orbit(plane.model, family.params(lo), plane.opts, cold_guess=plane.model.cold_guess, tol=1e-10)
    branch = al.continue_orbit(family, lo, sol.state, (lo, hi), al.Settings(ds=0.02, ds_max=0.5, max_steps=2000))
    assert branch.end == al.LEFT_RANGE
    return branch.events


def grid_boundary(scene, point):
    """The grid's refined boundary next to a curve point by Brent's method, the boundary table's
    fallback (rotorsweep.pipeline.boundaries; the table itself now refines on the branch by arclength, so
    this is a second, independent method): the bracketing grid speeds, their orbits by
    solve_orbit from a neighbour, Brent on max|multiplier| - 1 with natural continuation
    (events.locate_boundary)."""
    solve = boundaries.axis_solver(scene, {**scene.fixed, "clearance": point.nu}, "speed")[0]
    low = GRID_START + GRID_STEP * math.floor((point.lam - GRID_START) / GRID_STEP)
    a, b = solve(low, point.state), solve(low + GRID_STEP, point.state)
    assert a.status == b.status == 0 and a.stable != b.stable     # the grid sees this boundary
    return events.locate_boundary(solve, low, low + GRID_STEP, a.state, b.state, xtol_rel=boundaries.XTOL_REL).value


def test_period_doubling_curve_crosses_the_fig13_grid_at_the_sweeps_refined_boundaries(fig13):
    """Issue 12's acceptance case. The PD point at 3.8 um near 93 Hz (93.0651 Hz), continued in
    clearance: the curve turns at ~8.96 um and comes back to 3.8 um at ~113.09 Hz, so it crosses
    the grid's clearances 3.8 and 7.6 um twice each and never reaches 11.4 um. At each crossing
    the speed equals the sweep's refined boundary to 1e-6 relative (the issue's figure): that
    refinement (orbits to Newton tol 1e-9 at rtol 1e-10, Brent to 1e-8 relative) is the looser
    of the two; both solve |multiplier| = 1 on the same orbits, so they differ by the multiplier
    errors (<~1e-8 at rtol 1e-10, docs/benchmarks) over the slope d|mu|/d(speed) (~0.1 per Hz),
    ~1e-9 relative (measured: 2e-12 to 1.5e-9). Every curve point has a multiplier at -1 within
    1e-6: |g| <= 1e-9 puts it there to ~1e-9 plus the monodromy's error (measured: 2.3e-9)."""
    data, plane = fig13
    [pd] = [e for e in branch_events(plane, 3.8e-6, 85.0, 100.0) if e.kind == al.PERIOD_DOUBLING]
    assert pd.point.lam == pytest.approx(93.065, abs=1e-3)
    curve = tp.continue_bifurcation(plane, pd, 3.8e-6, BAI_BOX, tp.Settings(ds=0.02, ds_max=0.2), marks=FIG13)
    assert curve.end == tp.LEFT_RANGE and curve.points[-1].nu == pytest.approx(3.0e-6, rel=1e-12)
    assert max(abs(p.critical + 1.0) for p in curve.points) < 1e-6
    assert max(p.nu for p in curve.points) < 9e-6
    assert [round(p.nu * 1e7) for p in curve.marked] == [38, 76, 76, 38]
    for point in curve.marked:
        assert point.lam == pytest.approx(grid_boundary(data, point), rel=1e-6)


def test_fold_curve_is_a_closed_loop_through_the_one_parameter_folds(fig13):
    """The 7.6 um fold pair (40.83 / 40.74 Hz) continued in clearance: one closed curve with two
    cusps (~7.96 um, ~40 Hz and ~3.96 um, ~51.4 Hz) between which the hysteresis exists; at 5 and
    7 um it passes through both folds that one-parameter continuation in speed locates there. The
    grid's 3.8 um row lies below the lower cusp (no fold there). Both locate det(M - I) = 0 on the
    same branch; lambda is stationary at a fold, so a shift of the zero along the branch by the
    multiplier error (~1e-9) moves the speed only to second order: agreement to 1e-9 relative
    (measured: 3e-14 to 3.4e-12)."""
    _, plane = fig13
    fold = branch_events(plane, 7.6e-6, 30.0, 50.0)[0]
    curve = tp.continue_bifurcation(plane, fold, 7.6e-6, BAI_BOX, tp.Settings(ds=0.02, ds_max=0.2),
                                    marks=(5.0e-6, 7.0e-6, 7.6e-6))
    assert curve.end == tp.CLOSED
    assert [c.kind for c in curve.codim2] == [tp.CUSP, tp.CUSP]
    assert 3.9e-6 < min(p.nu for p in curve.points) and max(p.nu for p in curve.points) < 8e-6
    assert max(abs(p.critical - 1.0) for p in curve.points) < 1e-6
    for c in (5.0e-6, 7.0e-6, 7.6e-6):
        on_curve = sorted(p.lam for p in curve.marked if p.nu == pytest.approx(c, rel=1e-12))
        folds = sorted(e.point.lam for e in branch_events(plane, c, 35.0, 55.0) if e.kind == al.FOLD)
        assert len(on_curve) == len(folds) == 2
        np.testing.assert_allclose(on_curve, folds, rtol=1e-9)


def test_neimark_sacker_curve_crosses_the_fig13_grid_at_the_sweeps_refined_boundaries(fig13):
    """The NS point at 11.4 um, 129.95 Hz (pair near +-i), continued in clearance: a closed curve
    between ~5.58 and ~12.33 um that crosses 11.4 and 7.6 um twice each, where the speeds equal
    the sweep's refined boundaries (a complex pair crossing |mu| = 1 is a continuous crossing of
    max|mu| - 1, so the grid's Brent refinement is valid for NS): 1e-6 relative as for the PD
    curve (the grid's Brent tolerance 1e-8 relative dominates; measured 6e-12 to 1.4e-8). Every
    point has its pair on the unit circle within 1e-6 (|G| <= 1e-9; measured <= 1e-9)."""
    data, plane = fig13
    ns = next(e for e in branch_events(plane, 11.4e-6, 110.0, 140.0) if e.kind == al.NEIMARK_SACKER)
    assert ns.point.lam == pytest.approx(129.95, abs=0.01)
    curve = tp.continue_bifurcation(plane, ns, 11.4e-6, BAI_BOX, tp.Settings(ds=0.02, ds_max=0.2), direction=-1,
                                    marks=FIG13)
    assert curve.end == tp.CLOSED and curve.codim2 == []
    assert max(abs(abs(p.critical) - 1.0) for p in curve.points) < 1e-6
    assert 5.5e-6 < min(p.nu for p in curve.points) and max(p.nu for p in curve.points) < 12.4e-6
    assert [round(p.nu * 1e7) for p in curve.marked] == [114, 76, 76, 114]
    for point in curve.marked:
        assert point.lam == pytest.approx(grid_boundary(data, point), rel=1e-6)


def duffing_plane(gamma=1.0):
    params = lambda omega, force: DUFFING.build({"omega": omega, "zeta": 0.05, "gamma": gamma, "force": force}).p
    return tp.Plane(DUFFING, params, TIGHT, lam_scale=1.0, nu_scale=0.1)


def duffing_folds(plane, force=0.1):
    family = plane.family(force)
    sol = solve_orbit(DUFFING, family.params(0.5), TIGHT, cold_guess=DUFFING.cold_guess, tol=1e-12)
    return al.continue_orbit(family, 0.5, sol.state, (0.5, 2.0), al.Settings(ds=0.02, ds_max=0.1)).events


def test_duffing_fold_curve_against_a_scipy_reference():
    """Hardening Duffing (zeta 0.05, gamma 1): the upper fold at F = 0.1 continued to smaller F
    passes the cusp (F ~ 0.051) and comes back as the lower fold up to the box edge F = 0.25.
    Reference at F = 0.08 (both folds) and 0.2: scipy solve_ivp DOP853 at rtol 1e-13 in physical
    time, fsolve on [phi(u) - u, det(M - I)] (workflows.bench.peers.duffing_scipy). Both sides
    solve a regular system to their integrators' accuracy (rtol 1e-12 here), amplified by its
    condition, which grows towards the cusp: measured 1e-14 relative in omega and 1e-13 in the
    state at F = 0.08 (upper) and 0.2, 7e-12 and 1.6e-10 at the lower fold at F = 0.08 (nearer
    the cusp); 1e-9 in omega and 1e-8 in the state leave a factor >= 60 for other step placements."""
    plane = duffing_plane()
    upper = max(duffing_folds(plane), key=lambda e: e.point.lam)
    curve = tp.continue_bifurcation(plane, upper, 0.1, ((0.5, 3.0), (0.01, 0.25)), tp.Settings(ds=0.02, ds_max=0.2),
                                    direction=-1, marks=(0.08, 0.2))
    assert curve.end == tp.LEFT_RANGE and curve.points[-1].nu == pytest.approx(0.25, rel=1e-12)
    assert [c.kind for c in curve.codim2] == [tp.CUSP]
    assert [p.nu for p in curve.marked] == pytest.approx([0.08, 0.08, 0.2], rel=1e-12)
    for point in curve.marked:
        assert abs(point.critical - 1.0) < 1e-6
        omega, state, residual = duffing_scipy.fold_reference(duffing_scipy.Duffing(0.05, 1.0, point.nu),
                                                               point.lam, point.state)
        assert residual < 1e-11      # the reference converged: its equations hold to ~1e-13 at rtol 1e-13
        assert point.lam == pytest.approx(omega, rel=1e-9)
        np.testing.assert_allclose(point.state, state, atol=1e-8 * max(1.0, np.abs(state).max()))


def test_statuses_and_rejected_arguments():
    """Failures are statuses: no fold exists for the linear oscillator (gamma = 0), so a 'fold'
    event there cannot be corrected (start_failed); a step budget ends the curve
    (step_budget). Arguments that cannot work are refused before any integration."""
    plane = duffing_plane()
    upper = duffing_folds(plane)[0]
    short = tp.continue_bifurcation(plane, upper, 0.1, ((0.5, 3.0), (0.01, 0.25)), tp.Settings(max_steps=3))
    assert short.end == tp.STEP_BUDGET and len(short.points) == 4
    linear = tp.continue_bifurcation(duffing_plane(gamma=0.0), upper, 0.1, ((0.5, 3.0), (0.01, 0.25)))
    assert linear.end == tp.START_FAILED and linear.points == [] and "lambda = " in linear.detail
    with pytest.raises(ValueError, match="ds = 0"):
        tp.continue_bifurcation(plane, upper, 0.1, ((0.5, 3.0), (0.01, 0.25)), tp.Settings(ds=0.0, ds_min=0.0))
    with pytest.raises(ValueError, match="outside the box"):
        tp.continue_bifurcation(plane, upper, 0.3, ((0.5, 3.0), (0.01, 0.25)))
    with pytest.raises(ValueError, match="only fold, period_doubling and neimark_sacker"):
        tp.continue_bifurcation(plane, upper._replace(kind=al.BRANCH_POINT), 0.1, ((0.5, 3.0), (0.01, 0.25)))


def test_shipped_continuation_benchmark_is_its_json_rendered():
    """docs/benchmarks/continuation.md is what the template makes of the JSON beside it."""
    import json

    from workflows.bench import continuation
    from workflows.bench.common import DOCS

    result = json.loads((DOCS / "continuation.json").read_text())
    assert continuation.markdown(result) == (DOCS / "continuation.md").read_text()


def _fake_point(kind, multipliers, kappa=None, tangent=(0.0, 1.0)):
    """A CurvePoint with only what the codimension-2 flags read (2 x 2 monodromy)."""
    lams = np.asarray(multipliers, complex)
    Y = np.array([0.0, 0.0] + ([kappa] if kappa is not None else []) + [1.0, 1.0])
    return tp.CurvePoint(Y, 1.0, 1.0, np.eye(2), lams, tp._critical(kind, Y, lams), np.array([0.0, 0.0, *tangent]),
                         None, 0, 0.0, 0.0)


def test_codimension_two_flags():
    """The flags between two curve points, on made-up multipliers: fold-flip on a fold curve (the
    other multiplier through -1), fold-flip and 1:2 on a PD curve, a cusp (the parameter part of
    the tangent reverses), the 1:4 and 1:3 resonances on an NS curve (kappa through 0, -1/2)."""
    between = tp._codim2_between
    assert between(al.FOLD, _fake_point(al.FOLD, [1, -0.9]), _fake_point(al.FOLD, [1, -1.1])) == [tp.FOLD_FLIP]
    reversed_tangent = _fake_point(al.FOLD, [1, 0.5], tangent=(0, -1))
    assert between(al.FOLD, _fake_point(al.FOLD, [1, 0.5]), reversed_tangent) == [tp.CUSP]
    pd = al.PERIOD_DOUBLING
    assert between(pd, _fake_point(pd, [-1, 0.9]), _fake_point(pd, [-1, 1.1])) == [tp.FOLD_FLIP]
    assert between(pd, _fake_point(pd, [-1, -0.9]), _fake_point(pd, [-1, -1.1])) == [tp.RESONANCE_1_2]
    ns = al.NEIMARK_SACKER
    pair = lambda kappa: [complex(kappa, np.sqrt(1 - kappa ** 2)), complex(kappa, -np.sqrt(1 - kappa ** 2))]
    assert between(ns, _fake_point(ns, pair(0.1), 0.1), _fake_point(ns, pair(-0.1), -0.1)) == [tp.RESONANCE_1_4]
    assert between(ns, _fake_point(ns, pair(-0.4), -0.4), _fake_point(ns, pair(-0.6), -0.6)) == [tp.RESONANCE_1_3]

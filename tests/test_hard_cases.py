"""The hard cases of SPEC section 5: each asserts the right status and accuracy."""
import numpy as np
import pytest

from rotorsweep.kernels import attractor as at, continuation, floquet, integrators as ig, shooting
from rotorsweep.kernels.continuation import events as boundary
from rotorsweep.kernels.models import jeffcott_clearance as jc
from tests.reference import BaiPoint, PreloadedPoint
from tests.test_kernels import JEFF, bai_params, match

OPTS = ig.settings(rtol=1e-11, atol=1e-13)


def solve(point, opts=OPTS, history=(), **overrides):
    p, period = bai_params(point, **overrides)
    sol = continuation.solve_orbit(JEFF, p, opts, history, cold_guess=jc.static_guess, tol=1e-10,
                                   transient_periods=100)
    return sol, p, period


def liouville(point, period):
    return np.exp(-point.damping * period / point.mass) ** 2


def loaded_balls(state_samples, p):
    """Number of loaded balls at each orbit sample."""
    counts = []
    for k, (x, y) in enumerate(state_samples[:, :2]):
        theta = 2 * np.pi * (k / len(state_samples)) / p[jc.P_NBALLS]
        phi = theta + 2 * np.pi * np.arange(int(p[jc.P_NBALLS])) / p[jc.P_NBALLS]
        delta = (x * np.cos(phi) + y * np.sin(phi)) * p[jc.P_COS_A] + p[jc.P_OFFSET]
        counts.append(int((delta > 0).sum()))
    return np.array(counts)


def test_large_clearance_with_most_balls_unloaded():
    point = BaiPoint(30.0, 19.0e-6)
    sol, p, period = solve(point)
    assert sol.status == shooting.CONVERGED
    assert loaded_balls(sol.samples, p).max() <= 3          # 9 balls, at most 3 carry load
    assert abs(np.prod(sol.multipliers).real - liouville(point, period)) < 1e-9
    # the reference monodromy is the median over three finite-difference steps: with 6 of the 9
    # balls leaving contact, one step's integrations crossed a contact instant with a heavy-tail
    # error (5e-6 in the multipliers on an AMD EPYC; the median is 4.5e-8 off)
    _, ref_mono, _ = point.periodic_orbit(jc.to_physical(sol.state, period), iterations=1)
    assert match(sol.multipliers, np.linalg.eigvals(ref_mono)) < 1e-6


def test_grazing_contact_every_ball_passage():
    """A ball enters and leaves contact within every forcing period (the force is only C^1)."""
    point = BaiPoint(100.0, 7.6e-6)
    sol, p, _ = solve(point)
    counts = loaded_balls(sol.samples, p)
    assert sol.status == shooting.CONVERGED and counts.min() < counts.max()


@pytest.mark.parametrize("clearance", [5e-8, 1e-9])
def test_very_small_clearance_is_stiff_but_solved(clearance):
    point = BaiPoint(150.0, clearance)
    sol, _, period = solve(point)
    assert sol.status == shooting.CONVERGED
    assert abs(np.prod(sol.multipliers).real - liouville(point, period)) < 1e-9


def test_zero_damping_keeps_multipliers_on_the_unit_circle():
    point = BaiPoint(60.0, 7.6e-6)
    point.damping = 0.0
    sol, _, _ = solve(point, damping=0.0)
    assert sol.status == shooting.CONVERGED
    np.testing.assert_allclose(np.abs(sol.multipliers), 1.0, atol=1e-7)
    assert abs(np.prod(sol.multipliers).real - 1.0) < 1e-9


def test_multiplier_within_1e_3_of_minus_one_is_resolved():
    """Near period doubling Newton still converges (M - I stays regular at lambda = -1) and the
    multiplier is as accurate as anywhere else."""
    clearance = 7.6e-6

    def at(speed, guess):
        return continuation.solve_orbit(JEFF, bai_params(BaiPoint(speed, clearance))[0], OPTS, [guess],
                                        cold_guess=jc.static_guess, tol=1e-10)

    lo, _, _ = solve(BaiPoint(76.0, clearance))
    hi = at(84.0, lo.state)
    assert lo.max_abs < 1 < hi.max_abs
    crossing = boundary.locate_boundary(at, 76.0, 84.0, lo.state, hi.state, xtol_rel=1e-6)
    speed = crossing.value * (1 + 2e-5)
    sol = at(speed, crossing.solution.state)
    lead = sol.multipliers[0]
    assert sol.status == shooting.CONVERGED and abs(lead + 1) < 1e-3
    point = BaiPoint(speed, clearance)
    _, ref_mono, _ = point.periodic_orbit(jc.to_physical(sol.state, bai_params(point)[1]), iterations=1)
    assert match(sol.multipliers, np.linalg.eigvals(ref_mono)) < 1e-7


def test_nonconvergence_is_reported_as_data():
    point = BaiPoint(190.0, 19.0e-6)
    p, _ = bai_params(point)
    orbit = shooting.periodic_orbit(JEFF, jc.static_guess(p), p, OPTS, tol=1e-14, max_iter=1)
    assert orbit.status == shooting.NOT_CONVERGED
    assert orbit.reason in (shooting.R_MAX_ITER, shooting.R_LINE_SEARCH)
    tiny = ig.settings(rtol=1e-11, atol=1e-13, amplitude_limit=1e-3)   # 1 nm limit: 'diverged'
    orbit = shooting.periodic_orbit(JEFF, jc.static_guess(p), p, tiny)
    assert orbit.status == shooting.DIVERGED and orbit.reason == shooting.R_AMPLITUDE
    nan_guess = np.full(4, np.nan)
    orbit = shooting.periodic_orbit(JEFF, nan_guess, p, OPTS)
    assert orbit.status == shooting.DIVERGED and orbit.reason == shooting.R_NAN


# --- preloaded bearing driven hard enough that balls unload -------------------------------------

PRELOADED_SCENE = """
[scene]
name = "preloaded_hard"
model = "jeffcott_clearance"
[bearing]
preset = "angular_contact_medium"
nominal_angle = 26
free_angle = "nominal"
stiffness = 1.0e10
preload = 300.0
[rotor]
mass = 2.0
damping = 300.0
radial_load = {load}
[sweep]
speed = [350.0]
"""


def preloaded_reference(speed, load):
    """The Filipkovsky medium-series bearing (26 deg, R1 = 16.0, R2 = 27.5399, R_K = 5.930, ball
    11.510 mm, 7 balls; pitch diameter R1 + R2) under the 2010 papers' 300 N preload."""
    return PreloadedPoint(speed, 0.0, K=1.0e10, n_balls=7, load=load, preload=300.0,
                          free_angle=np.radians(26.0), groove_sum=2 * 5.930e-3 - 11.510e-3,
                          ball_diameter=11.510e-3, pitch_diameter=16.0e-3 + 27.5399e-3)


@pytest.mark.parametrize("load, unloads", [(300.0, False), (600.0, True)])
def test_preloaded_bearing_driven_until_balls_unload(load, unloads):
    """300 N preload squeezes all 7 balls at rest (delta_n = 4.4 um). At 350 Hz the ball-passage
    frequency (938 Hz) is near the linearized radial natural frequency (about 1050 Hz): under a
    300 N radial load the preload still holds every ball loaded over the whole orbit; under 600 N
    the orbit (about 3 um peak to peak) unloads up to 3 balls, which leave and regain contact every
    ball passage (the force is only C^1 there). Both orbits converge and match the independent
    scipy reference."""
    from rotorsweep.pipeline import compute, config

    cfg = config.parse_config(PRELOADED_SCENE.format(load=load))
    params = compute.point_params(cfg.scene, {"speed": 350.0, "clearance": 0.0, "contact_angle": None,
                                             "preload": 300.0})
    point = preloaded_reference(350.0, load)
    p, period = params.p, params.period
    # the preloaded static state, solved independently from the geometry
    assert params.derived["contact_angle_used"] == pytest.approx(np.degrees(point.alpha), rel=1e-12)
    assert p[jc.P_OFFSET] * jc.LENGTH_SCALE == pytest.approx(point.normal_approach, rel=1e-10)
    assert period == pytest.approx(point.period, rel=1e-12)
    at_rest = point.ball_deflections(0.0, 0.0, 0.0)
    assert np.all(at_rest > 4e-6)                                   # every ball loaded at rest

    sol = continuation.solve_orbit(JEFF, p, OPTS, cold_guess=jc.static_guess, tol=1e-10,
                                   transient_periods=100)
    assert sol.status == shooting.CONVERGED and sol.stable
    assert abs(np.prod(sol.multipliers).real - liouville(point, period)) < 1e-9
    state = jc.to_physical(sol.state, period)
    ref_state, ref_mono, residual = point.periodic_orbit(state, iterations=1)
    scale = np.array([1e-6, 1e-6, 1e-6 / period, 1e-6 / period])
    assert residual < 1e-9
    assert np.abs((ref_state - state) / scale).max() < 1e-8
    assert match(sol.multipliers, np.linalg.eigvals(ref_mono)) < 1e-6

    # ball deflections along the reference orbit (10 points per kernel sample)
    t, traj = point.trajectory(ref_state, n_times=10 * len(sol.samples))
    np.testing.assert_allclose(jc.to_physical(sol.samples, period)[:, :2], traj[::10, :2],
                               rtol=0, atol=1e-8 * 1e-6)
    delta = point.ball_deflections(t, traj[:, 0], traj[:, 1])
    loaded = (delta > 0).sum(axis=1)
    if unloads:
        assert delta.min() < -1e-6                                  # clearly out of contact
        assert loaded.min() <= 4 and loaded.max() < 7                # never all 7 loaded
        assert loaded.min() < loaded.max()                          # contacts open and close
    else:
        assert delta.min() > 1e-6 and loaded.min() == 7


# --- chaotic and boundary-crisis regimes (19 um) ------------------------------------------------
#
# At 19 um the period-1 orbit loses stability by period doubling at 28.40 Hz and regains it at
# 64.9 Hz; a chaotic attractor lives at 27.6-29.5 Hz and 39.0-39.7 Hz (among others). Below
# 28.40 Hz the stable period-1 orbit coexists with the chaotic attractor down to 27.6 Hz (the
# chaotic attractor's basin boundary collides with the orbit's at the crisis).

ATT_OPTS = ig.settings(rtol=1e-10, atol=1e-12)
CHAOS_CLEARANCE = 19.0e-6


def divergence_si(point):
    """Sum of the Lyapunov exponents [1/s] (Liouville): -2 D / M for jeffcott_clearance."""
    return -2.0 * point.damping / point.mass


@pytest.mark.parametrize("speed", [29.0, pytest.param(39.3, marks=pytest.mark.slow)])
def test_chaotic_regime_shooting_fails_gracefully(speed):
    """On a chaotic attractor Newton started from attractor states either converges to the (only)
    period-1 orbit -- unstable, period doubled, multipliers as the independent reference's -- or
    returns not_converged with its reason and residual; it never raises. The attractor itself
    is classified chaotic, its largest exponent positive beyond 3 standard errors and the
    spectrum summing to the divergence."""
    point = BaiPoint(speed, CHAOS_CLEARANCE)
    p, period = bai_params(point)
    att = at.diagnose(JEFF, jc.static_guess(p), p, period, ATT_OPTS, at.Settings(transient_periods=300,
                      lyapunov_max_periods=400))
    assert att.code == at.CHAOTIC and att.status == ig.STATUS_OK
    assert att.lle > 3 * att.lle_stderr > 0
    assert abs(att.exponents.sum() - divergence_si(point)) < 1e-6 * abs(divergence_si(point))

    outcomes = []
    for start in att.samples[::8]:                          # 16 states on the attractor
        orbit = shooting.periodic_orbit(JEFF, start, p, OPTS, tol=1e-10, max_iter=30)
        outcomes.append(orbit)
        if orbit.status == shooting.CONVERGED:
            assert orbit.residual <= 1e-10
        else:
            assert orbit.status == shooting.NOT_CONVERGED
            assert orbit.reason in (shooting.R_MAX_ITER, shooting.R_LINE_SEARCH, shooting.R_SINGULAR)
            assert orbit.residual > 1e-10
    # the pipeline's per-point solve (cold start: a transient that lands on the attractor)
    cold = continuation.solve_orbit(JEFF, p, OPTS, cold_guess=jc.static_guess, tol=1e-10,
                                    transient_periods=100)
    assert cold.status in (shooting.CONVERGED, shooting.NOT_CONVERGED)
    if cold.status != shooting.CONVERGED:
        assert np.isnan(cold.max_abs) and np.all(np.isnan(cold.multipliers)) and cold.samples is None
    if speed == 29.0:   # the first transient state misses Newton's basin; a retry one period on hits it
        assert cold.status == shooting.CONVERGED
    converged = [o for o in outcomes if o.status == shooting.CONVERGED]
    if speed == 29.0:                       # Newton's basin is small here: some starts fail
        assert len(converged) < len(outcomes)
    assert converged
    states = np.array([o.state for o in converged])
    np.testing.assert_allclose(states, np.broadcast_to(states[0], states.shape), rtol=0,
                               atol=1e-8 * np.abs(states[0]).max())
    if cold.status == shooting.CONVERGED:
        np.testing.assert_allclose(cold.state, states[0], rtol=0, atol=1e-8 * np.abs(states[0]).max())
    lams = floquet.multipliers(converged[0].monodromy)
    max_abs, stable, bif = floquet.classify(lams)
    assert not stable and max_abs > 2 and bif == floquet.PERIOD_DOUBLING and lams[0].real < -2
    _, ref_mono, residual = point.periodic_orbit(jc.to_physical(states[0], period), iterations=1)
    assert residual < 1e-9
    assert match(lams, np.linalg.eigvals(ref_mono)) < 1e-6


def attractor_carried_from(speed_from, speed_to, step=0.2, periods=100):
    """A state on the chaotic attractor at speed_to, continued down from speed_from in steps."""
    u = None
    for speed in np.arange(speed_from, speed_to - 0.5 * step, -step):
        p, _ = bai_params(BaiPoint(speed, CHAOS_CLEARANCE))
        first = u is None
        u = at.poincare(JEFF, jc.static_guess(p) if first else u, p, ATT_OPTS,
                        3 * periods if first else periods, 1)[0][-1]
    return u


@pytest.mark.parametrize("speed", [28.0, 28.2])
def test_stable_orbit_coexists_with_a_chaotic_attractor(speed):
    """Boundary crisis: two attractors at one parameter. From the stable period-1 orbit the run
    stays on it (period 1, Lyapunov exponent from a Benettin run = ln max|lambda| / T); from the
    chaotic attractor carried down from 29 Hz it stays chaotic, never approaching the orbit."""
    point = BaiPoint(speed, CHAOS_CLEARANCE)
    p, period = bai_params(point)
    sol = continuation.solve_orbit(JEFF, p, OPTS, cold_guess=jc.static_guess, tol=1e-11,
                                   transient_periods=100)
    assert sol.status == shooting.CONVERGED and sol.stable
    _, ref_mono, _ = point.periodic_orbit(jc.to_physical(sol.state, period), iterations=1)
    assert match(sol.multipliers, np.linalg.eigvals(ref_mono)) < 1e-6
    expected = at.derived_lle(sol.max_abs, period)

    on_orbit = at.diagnose(JEFF, sol.state, p, period, ATT_OPTS, at.Settings(transient_periods=0,
                           derive_when_stable=False, lyapunov_max_periods=1000, lyapunov_rtol=0.0,
                           lyapunov_atol=0.0))
    assert (on_orbit.code, on_orbit.period) == (at.PERIODIC, 1)
    assert abs(on_orbit.lle - expected) < 1e-3 * abs(expected), (on_orbit.lle, expected)

    u_chaos = attractor_carried_from(29.0, speed)
    samples, status = at.poincare(JEFF, u_chaos, p, ATT_OPTS, 0, 1000)
    assert status == ig.STATUS_OK
    distance = np.abs(samples - sol.state).max(axis=1)
    assert distance.min() > 0.1 * np.abs(sol.state).max()          # never near the stable orbit
    chaos = at.diagnose(JEFF, samples[-1], p, period, ATT_OPTS, at.Settings(transient_periods=0,
                        lyapunov_max_periods=400), stable_orbit=(sol.state, sol.multipliers))
    assert chaos.code == at.CHAOTIC and chaos.lle > 3 * chaos.lle_stderr > 0
    assert abs(chaos.exponents.sum() - divergence_si(point)) < 1e-6 * abs(divergence_si(point))
    # the same call from the orbit's basin reports the orbit (the derive-when-stable shortcut)
    settled = at.diagnose(JEFF, jc.static_guess(p), p, period, ATT_OPTS, at.Settings(transient_periods=300),
                          stable_orbit=(sol.state, sol.multipliers))
    assert (settled.code, settled.period, settled.derived) == (at.PERIODIC, 1, True)
    assert settled.lle == pytest.approx(expected, rel=1e-12)

"""Attractor diagnostics: Poincare samples, period detection, Lyapunov exponents, classification.

Independent values: Floquet multipliers from shooting (a different integration, with Newton),
eigenvalues of a constant matrix, Liouville's formula for the divergence, synthetic sequences.
"""
import numpy as np
import pytest

from rotorsweep.kernels import attractor as at, continuation, floquet, integrators as ig, models, shooting
from rotorsweep.kernels.attractor import lyapunov
from rotorsweep.kernels.models import jeffcott_clearance as jc
from tests.reference import BaiPoint
from tests.test_kernels import JEFF, bai_params

OPTS = ig.settings(rtol=1e-10, atol=1e-12)
TIGHT = ig.settings(rtol=1e-12, atol=1e-14)
LINEAR = models.get("linear_oscillator")
CHAOTIC_POINT = BaiPoint(36.5, 19.0e-6)      # chaotic attractor, reached from the static guess


def stable_orbit(point, opts=OPTS):
    p, period = bai_params(point)
    sol = continuation.solve_orbit(JEFF, p, opts, cold_guess=jc.static_guess, tol=1e-11,
                                   transient_periods=100)
    assert sol.status == shooting.CONVERGED and sol.stable, sol
    return sol, p, period


# --- Lyapunov exponents ---------------------------------------------------------------------

@pytest.mark.parametrize("point, weighted, align, rtol", [
    # the brief's point: the four multipliers share one modulus (two complex pairs), so the
    # individual Benettin exponents oscillate; the weighted average settles them
    (BaiPoint(60.0, 3.8e-6), True, 20.0, 1e-3),
    # a real leading multiplier (-0.88, just above the period doubling): once the frame is
    # aligned (gap 0.19 per period: 100 periods), every period's R_11 is |lambda_1| exactly,
    # so even the plain running mean matches to integration accuracy
    (BaiPoint(66.0, 19.0e-6), False, 100.0, 1e-6),
], ids=["60Hz-3.8um", "66Hz-19um"])
def test_lle_of_stable_orbit_matches_floquet_multipliers(point, weighted, align, rtol):
    sol, p, period = stable_orbit(point)
    expected = at.derived_lle(sol.max_abs, period)                     # 1/s
    res = at.lyapunov_si(JEFF, jc.static_guess(p), p, period, OPTS, n_transient=200,
                         max_periods=1000, rtol_stop=0.0, min_periods=1000, weighted=weighted,
                         align_periods=align)
    assert res.status == ig.STATUS_OK and res.periods_used == 1000
    assert abs(res.lle - expected) < rtol * abs(expected), (res.lle, expected)


def linear_system(p):
    a = np.zeros((4, 4))
    models.dispatch.jac(LINEAR.kernel.tag, 0.0, np.zeros(4), p, a)
    return a


def test_linear_oscillator_spectrum_is_real_parts_of_eigenvalues():
    """Real eigenvalues (overdamped): once the frame is aligned on the invariant flag (gap 0.15
    per period: 200 periods), each interval's R_ii is exp(lambda_i) exactly."""
    p = np.array([2.0, 0.5, 3.0, 6.0, 9.0])
    expected = np.sort(np.linalg.eigvals(linear_system(p)).real)[::-1]
    assert np.all(np.diff(expected) < -0.1)                       # distinct, real
    for weighted in (True, False):
        expo, stderr, used, status = at.lyapunov_spectrum(
            LINEAR, np.array([1.0, -2.0, 0.5, 0.3]), p, TIGHT, n_transient=0, max_periods=200,
            rtol_stop=0.0, min_periods=200, weighted=weighted, align_periods=200.0)
        assert status == ig.STATUS_OK and used == 200
        np.testing.assert_allclose(expo, expected, rtol=1e-6)


def test_linear_oscillator_with_complex_pairs():
    """A complex pair has no invariant line: each of its two Benettin exponents carries a
    bounded oscillating error (slowly averaged out, slower still when the rotation per period is
    close to a rational: here 6.282 rad, almost 2 pi), while the pair's sum -- the growth of the
    invariant plane -- is exact."""
    p = np.array([40.0, 5.0, 90.0, 0.4, 0.9])
    expected = np.sort(np.linalg.eigvals(linear_system(p)).real)[::-1]   # two equal pairs
    expo, _, _, status = at.lyapunov_spectrum(LINEAR, np.ones(4), p, TIGHT, n_transient=0,
                                              max_periods=400, rtol_stop=0.0, min_periods=400)
    assert status == ig.STATUS_OK
    np.testing.assert_allclose([expo[0] + expo[1], expo[2] + expo[3]],
                               [expected[0] + expected[1], expected[2] + expected[3]], rtol=1e-8)
    np.testing.assert_allclose(expo, expected, rtol=3e-2)
    assert expo.sum() == pytest.approx(np.trace(linear_system(p)), rel=1e-10)


@pytest.mark.parametrize("point", [BaiPoint(60.0, 3.8e-6), CHAOTIC_POINT], ids=["stable", "chaotic"])
def test_sum_of_spectrum_is_the_divergence(point):
    p, period = bai_params(point)
    expo, _, _, status = at.lyapunov_spectrum(JEFF, jc.static_guess(p), p, OPTS, n_transient=100,
                                              max_periods=300, rtol_stop=0.0)
    assert status == ig.STATUS_OK
    divergence = -2.0 * point.damping * period / point.mass               # per unit tau
    assert abs(expo.sum() - divergence) < 1e-6 * abs(divergence)
    si = at.lyapunov_si(JEFF, jc.static_guess(p), p, period, OPTS, n_transient=100, max_periods=300,
                        rtol_stop=0.0)
    divergence_si = -2.0 * point.damping / point.mass                        # 1/s
    assert abs(si.exponents.sum() - divergence_si) < 1e-6 * abs(divergence_si)


def test_chaotic_exponents_do_not_depend_on_the_renormalization_interval():
    p, period = bai_params(CHAOTIC_POINT)
    u0 = at.poincare(JEFF, jc.static_guess(p), p, OPTS, 200, 1)[0][-1]
    runs = {}
    for renorm in (0.5, 1.0, 2.0):
        expo, stderr, used, status = at.lyapunov_spectrum(JEFF, u0, p, OPTS, 0, renorm, 1000,
                                                          rtol_stop=0.0)
        assert status == ig.STATUS_OK and used == 1000
        runs[renorm] = expo, stderr
    assert runs[1.0][0][0] > 0.1                                          # clearly chaotic
    for a, b in [(0.5, 1.0), (1.0, 2.0), (0.5, 2.0)]:
        (ea, sa), (eb, sb) = runs[a], runs[b]
        assert np.all(np.abs(ea - eb) <= 4.0 * np.hypot(sa, sb)), (a, b, ea, eb, sa, sb)


def test_early_stop_and_largest_lyapunov_is_the_first_component():
    p, period = bai_params(CHAOTIC_POINT)
    u0 = at.poincare(JEFF, jc.static_guess(p), p, OPTS, 200, 1)[0][-1]
    kw = dict(n_transient=0, renorm_periods=1.0, max_periods=3000, n_blocks=10, rtol_stop=0.1,
              min_periods=200)
    expo, stderr, used, status = at.lyapunov_spectrum(JEFF, u0, p, OPTS, **kw)
    lle, lle_err, used2, status2 = at.largest_lyapunov(JEFF, u0, p, OPTS, **kw)
    assert (lle, lle_err, used2, status2) == (expo[0], stderr[0], used, status)
    assert 200 <= used < 3000                                  # stopped on its uncertainty
    assert stderr[0] <= 0.1 * abs(expo[0]) + 1e-4


def test_converged_stop_on_an_undamped_oscillator_gives_zero_exponents():
    """An undamped linear oscillator (rotations of 5.48 and 8.37 rad per period, generic): every
    exponent is 0 exactly, and log R_11 is a quasi-periodic sequence, so the weighted average
    converges faster than any power of N while the block standard error falls only like 1/N.
    The converged stop ends the run long before the standard-error rule does (608 against 1910
    periods, where its blocks happen to cancel), at 0 to within its tolerance atol_stop; the
    spectrum's sum is the trace, 0."""
    p = np.array([30.0, 0.0, 70.0, 0.0, 0.0])
    lam = np.linalg.eigvals(linear_system(p))
    assert np.all(lam.real == 0.0) and np.all(np.abs(lam.imag) > 5.0)
    # rtol_stop ~0: the standard-error rule compares with rtol x the plain mean, whose O(1/N)
    # oscillation would stand in for the exponent here
    kw = dict(n_transient=0, max_periods=3000, rtol_stop=1e-12, min_periods=100, atol_stop=1e-7)
    expo, stderr, used, status = at.lyapunov_spectrum(LINEAR, np.ones(4), p, TIGHT, converged_stop=True, **kw)
    assert status == ig.STATUS_OK and used < 1500, used
    assert stderr[0] > 1e-7                                             # not the standard-error rule
    assert abs(expo[0]) <= 1e-7 and abs(expo.sum()) < 1e-10
    _, _, used_plain, _ = at.lyapunov_spectrum(LINEAR, np.ones(4), p, TIGHT, **kw)
    assert used_plain > 3 * used, used_plain   # its blocks happen to cancel at 1910
    # a damped one (exponents -0.25 and -0.5, not 0) is not stopped by it
    damped = np.array([30.0, 1.0, 70.0, 1.0, 0.5])
    _, _, used_damped, _ = at.lyapunov_spectrum(LINEAR, np.ones(4), damped, TIGHT, converged_stop=True, **kw)
    assert used_damped == 3000


def test_converged_test_rejects_a_random_sequence_and_accepts_a_quasi_periodic_one():
    """`_converged` alone, with a tolerance that any average passes (atol 1): on i.i.d. interval
    logs of mean 0 (a mixing sequence, the hardest case: its exponent is within any atol of 0)
    the three weighted averages differ by the order of the statistical error, so their spread is
    below 10 % of the block standard error in about 0.3 % of the runs (measured on 2000 runs at
    304 and 600 intervals); on g(k alpha), alpha irrational, the test passes at 400 intervals."""
    def converged(logs):
        csum = np.concatenate([np.zeros(1), np.cumsum(logs)])[:, None]
        se = lyapunov._block_stderr(csum, len(logs), 10, 1.0)[0] * lyapunov.WEIGHT_STDERR_FACTOR
        return lyapunov._converged(csum, len(logs), se, 1.0, 1.0)

    rng = np.random.default_rng(5)
    passed = sum(converged(rng.standard_normal(400)) for _ in range(500))
    assert passed <= 7, passed                                          # ~1.5 expected
    k = np.arange(400)
    assert converged(0.05 * np.cos(2 * np.pi * k * (np.sqrt(5) - 1) / 2) + 0.1 * np.sin(k * np.sqrt(2)))


def test_converged_stop_on_the_torus_gives_a_zero_exponent():
    """Past the Neimark-Sacker bifurcation (148 Hz, 7.6 um) the attractor is a torus, whose
    largest exponent is 0 exactly. With the converged stop the Lyapunov run ends well before the
    cap with |lle| per period within the stop's tolerance (atol 1e-4, rtol |lle| negligible)."""
    p, period = bai_params(BaiPoint(148.0, 7.6e-6))
    p1 = continuation.solve_orbit(JEFF, p, OPTS, cold_guess=jc.static_guess, tol=1e-10)
    res = at.diagnose(JEFF, p1.state, p, period, OPTS, at.Settings(lyapunov_max_periods=1000,
                      lyapunov_min_periods=300, lyapunov_rtol=0.1, lyapunov_converged_stop=True))
    assert (res.code, res.period) == (at.QUASI_PERIODIC, 0)
    assert 300 <= res.periods_used < 1000
    assert abs(res.lle * period) <= 1e-4 * (1 + 0.1), res.lle * period


def test_diverging_run_reports_its_status():
    p = np.array([-40.0, 0.0, -40.0, 0.0, 0.0])                 # x'' = 40 x: unstable
    opts = ig.settings(amplitude_limit=1e3)
    expo, _, _, status = at.lyapunov_spectrum(LINEAR, np.ones(4), p, opts, n_transient=10)
    assert status == ig.STATUS_AMPLITUDE and np.all(np.isnan(expo))
    samples, status = at.poincare(LINEAR, np.ones(4), p, opts, 0, 8)
    assert status == ig.STATUS_AMPLITUDE
    assert np.all(np.isfinite(samples[0])) and np.all(np.isnan(samples[-1]))
    assert at.classify(samples, np.nan, np.nan, 0, status) == (at.DIVERGED, 0)


def test_derived_lle():
    assert at.derived_lle(np.exp(-0.5), 0.01) == pytest.approx(-50.0)


# --- Poincare samples and period detection --------------------------------------------------

def test_poincare_samples_of_a_stable_orbit_are_the_shooting_state():
    sol, p, _ = stable_orbit(BaiPoint(60.0, 3.8e-6), TIGHT)
    samples, status = at.poincare(JEFF, jc.static_guess(p), p, TIGHT, 200, 32)
    assert status == ig.STATUS_OK and samples.shape == (32, 4)
    scale = np.abs(sol.state).max()
    np.testing.assert_allclose(samples, np.broadcast_to(sol.state, samples.shape), rtol=0,
                               atol=1e-9 * scale)
    assert at.detect_period(samples) == 1


def test_poincare_samples_of_a_period_two_orbit_alternate_between_its_points():
    p, _ = bai_params(BaiPoint(55.0, 19.0e-6))
    samples, status = at.poincare(JEFF, jc.static_guess(p), p, TIGHT, 300, 16)
    assert status == ig.STATUS_OK and at.detect_period(samples) == 2
    orbit = shooting.periodic_orbit(JEFF, samples[-1], p, TIGHT, periods=2, tol=1e-11)
    assert orbit.status == shooting.CONVERGED
    assert floquet.multipliers(orbit.monodromy)[0].real != 0       # a genuine period-2 solve
    scale = np.abs(orbit.state).max()
    np.testing.assert_allclose(samples[-1::-2], np.broadcast_to(orbit.state, samples[-1::-2].shape),
                               rtol=0, atol=1e-8 * scale)
    assert np.abs(samples[-1] - samples[-2]).max() > 1.0          # the two points are distinct


def periodic_sequence(k, n=128, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    base = rng.normal(scale=5.0, size=(k, 4)) + 20.0
    seq = base[np.arange(n) % k]
    return seq + noise * rng.normal(size=seq.shape)


@pytest.mark.parametrize("k", [1, 2, 3, 4, 8, 32])
def test_detect_period_of_synthetic_sequences(k):
    assert at.detect_period(periodic_sequence(k)) == k
    spread = 10.0 if k > 1 else 20.0
    assert at.detect_period(periodic_sequence(k, noise=1e-9 * spread)) == k      # below tolerance
    if k > 1:
        assert at.detect_period(periodic_sequence(k, noise=1e-3 * spread)) == 0  # above it


def test_detect_period_rejects_an_irrational_rotation_and_nan():
    n = np.arange(128)
    golden = (np.sqrt(5.0) - 1.0) / 2.0
    circle = np.column_stack([np.cos(2 * np.pi * golden * n), np.sin(2 * np.pi * golden * n)])
    assert at.detect_period(circle) == 0
    assert at.detect_period(circle, max_period=64) == 0
    rational = np.column_stack([np.cos(2 * np.pi * 3 * n / 7), np.sin(2 * np.pi * 3 * n / 7)])
    assert at.detect_period(rational) == 7
    seq = periodic_sequence(2)
    seq[-1, 0] = np.nan
    assert at.detect_period(seq) == 0
    assert at.detect_period(periodic_sequence(32, n=64)) == 0      # not seen twice in the tail


# --- classification and spectrum ------------------------------------------------------------

def test_classify():
    rng = np.random.default_rng(2)
    n = np.arange(128)
    golden = (np.sqrt(5.0) - 1.0) / 2.0
    torus = np.column_stack([np.cos(2 * np.pi * golden * n), 0.6 * np.sin(2 * np.pi * golden * n),
                             np.zeros(128), np.zeros(128)]) + 5.0
    cloud = rng.normal(size=(128, 4))
    assert at.classify(periodic_sequence(4), np.nan, np.nan, 4) == (at.DIVERGED, 0)
    assert at.classify(periodic_sequence(4), -0.3, 0.01, 4) == (at.PERIODIC, 4)
    assert at.classify(cloud, 0.3, 0.01, 0) == (at.CHAOTIC, 0)
    assert at.classify(cloud, 0.02, 0.01, 0) == (at.NOT_SETTLED, 0)         # within 3 sigma
    assert at.classify(cloud, 0.033, 0.01, 0)[0] == at.CHAOTIC              # 3 sigma + floor
    assert at.classify(torus, 1e-4, 2e-4, 0) == (at.QUASI_PERIODIC, 0)
    assert at.classify(torus, -0.2, 1e-3, 0) == (at.NOT_SETTLED, 0)         # unresolved period
    # zero exponent but no closed curve: a slowly settling orbit (two clusters), not a torus
    settling = periodic_sequence(2) + 1e-3 * rng.normal(size=(128, 4))
    assert at.classify(settling, -1e-3, 1e-4, 0) == (at.NOT_SETTLED, 0)
    assert at.classify(settling, -1e-3, 1e-4, 0, check_curve=False) == (at.QUASI_PERIODIC, 0)
    assert at.classify(torus, 0.0, 0.0, 0, ig.STATUS_NAN) == (at.DIVERGED, 0)
    # a step-size underflow is the integrator's failure, not the rotor's divergence
    assert at.classify(torus, 0.0, 0.0, 0, ig.STATUS_STEP_UNDERFLOW) == (at.INTEGRATION_FAILED, 0)
    assert at.ATTRACTOR[at.QUASI_PERIODIC] == "quasi_periodic"


def test_closed_curve():
    n = np.arange(200)
    golden = (np.sqrt(5.0) - 1.0) / 2.0
    theta = 2 * np.pi * golden * n
    r = 1.0 + 0.3 * np.cos(3 * theta)
    curve = np.column_stack([r * np.cos(theta), r * np.sin(theta), 0.1 * np.sin(theta), np.ones(200)])
    assert at.closed_curve(curve)
    assert not at.closed_curve(np.random.default_rng(1).normal(size=(200, 4)))
    assert not at.closed_curve(periodic_sequence(5, n=200))
    assert not at.closed_curve(curve[:20])


def test_power_spectrum_peak():
    dt = 1e-3
    t = np.arange(4096) * dt
    x = 0.7 * np.sin(2 * np.pi * 125.0 * t) + 0.1 * np.sin(2 * np.pi * 40.0 * t) + 3.0
    freqs, power = at.power_spectrum(x, dt)
    assert freqs[np.argmax(power)] == pytest.approx(125.0, abs=1.0 / (4096 * dt))
    assert power.max() == pytest.approx(0.7 ** 2, rel=0.2)
    assert freqs[-1] == pytest.approx(0.5 / dt)


# --- one point ------------------------------------------------------------------------------

def test_diagnose_periodic_and_chaotic_points():
    p, period = bai_params(BaiPoint(55.0, 19.0e-6))                     # period 2
    res = at.diagnose(JEFF, jc.static_guess(p), p, period, OPTS, at.Settings(transient_periods=300))
    assert (res.code, res.period, res.periods_used) == (at.PERIODIC, 2, 0.0)
    bench = at.diagnose(JEFF, jc.static_guess(p), p, period, OPTS, at.Settings(transient_periods=300,
                        derive_when_stable=False, lyapunov_max_periods=1000, lyapunov_rtol=0.0))
    assert (bench.code, bench.period, bench.periods_used) == (at.PERIODIC, 2, 1000.0)
    assert res.lle < 0 and abs(res.lle - bench.lle) < 1e-3 * abs(res.lle), (res.lle, bench.lle)
    np.testing.assert_allclose(res.end_state, res.samples[-1])
    p, period = bai_params(CHAOTIC_POINT)
    res = at.diagnose(JEFF, jc.static_guess(p), p, period, OPTS, at.Settings(lyapunov_max_periods=400))
    assert res.code == at.CHAOTIC and res.period == 0 and res.lle > 3 * res.lle_stderr > 0
    assert 100 <= res.periods_used <= 400 and res.status == ig.STATUS_OK
    # the end state is on the attractor at a whole period: restarting there stays chaotic
    again = at.diagnose(JEFF, res.end_state, p, period, OPTS, at.Settings(transient_periods=0,
                        lyapunov_max_periods=400))
    assert again.code == at.CHAOTIC


def test_derive_when_stable_shortcut_matches_the_integrated_exponents():
    """The shortcut (transient stops on the shooting orbit, exponents ln|lambda_i| / T) against
    a full Benettin run of the whole spectrum from the same start: 1e-3 relative."""
    sol, p, period = stable_orbit(BaiPoint(66.0, 19.0e-6))
    start = sol.state + 0.05 * np.abs(sol.state).max()                 # off the orbit, in its basin
    fast = at.diagnose(JEFF, start, p, period, OPTS, stable_orbit=(sol.state, sol.multipliers))
    assert fast.derived and (fast.code, fast.period, fast.periods_used) == (at.PERIODIC, 1, 0.0)
    np.testing.assert_array_equal(fast.samples, np.tile(sol.state, (128, 1)))
    full = at.diagnose(JEFF, start, p, period, OPTS, at.Settings(derive_when_stable=False,
                       lyapunov_max_periods=1000, lyapunov_rtol=0.0, lyapunov_min_periods=1000,
                       lyapunov_weighted=False, lyapunov_align_periods=100.0))
    assert not full.derived and full.periods_used == 1000 and full.code == at.PERIODIC
    np.testing.assert_allclose(fast.exponents, full.exponents, rtol=1e-3)
    assert fast.exponents.sum() == pytest.approx(-2 * 300.0 / 2.0, rel=1e-9)   # -2 D / M


def test_settle_on_orbit_stops_only_on_the_orbit():
    sol, p, _ = stable_orbit(BaiPoint(66.0, 19.0e-6))
    start = sol.state + 0.05 * np.abs(sol.state).max()
    u, used, reached = at.settle_on_orbit(JEFF, start, p, OPTS, sol.state, 400, 1e-6)
    assert reached and 0 < used < 400
    assert np.abs(u - sol.state).max() <= 1e-6 * np.abs(sol.state).max()
    # too few periods to converge: not reached (the state then continues as a plain transient)
    _, _, reached = at.settle_on_orbit(JEFF, start, p, OPTS, sol.state, 3, 1e-6)
    assert not reached
    # the near stop (multipliers given, max |lambda| = 0.88 <= SETTLE_CONTRACTION): within
    # SETTLE_NEAR and contracting, in fewer periods; from there the state does reach the orbit
    assert np.abs(sol.multipliers).max() <= at.diagnosis.SETTLE_CONTRACTION
    near, used_near, reached = at.settle_on_orbit(JEFF, start, p, OPTS, sol.state, 400, 1e-6,
                                                  multipliers=sol.multipliers)
    assert reached and 0 < used_near < used
    assert np.abs(near - sol.state).max() <= at.diagnosis.SETTLE_NEAR * np.abs(sol.state).max()
    _, _, reached = at.settle_on_orbit(JEFF, near, p, OPTS, sol.state, 400, 1e-6)
    assert reached
    # an orbit closer to a bifurcation (max |lambda| > SETTLE_CONTRACTION) gets no near stop
    slow = sol.multipliers / np.abs(sol.multipliers).max() * 0.95
    _, used_slow, _ = at.settle_on_orbit(JEFF, start, p, OPTS, sol.state, 400, 1e-6, multipliers=slow)
    assert used_slow == used


def test_period_two_attractor_is_refined_and_stable_although_period_one_is_not():
    """After the period doubling, the period-1 orbit is unstable while the attractor is a stable
    period-2 orbit. Its multipliers (shooting on 2 T) are checked against a separate Newton solve
    at tighter tolerance."""
    point = BaiPoint(55.0, 19.0e-6)
    p, period = bai_params(point)
    p1 = continuation.solve_orbit(JEFF, p, OPTS, cold_guess=jc.static_guess, tol=1e-10)
    assert p1.status == shooting.CONVERGED and not p1.stable and p1.bifurcation == floquet.PERIOD_DOUBLING
    res = at.diagnose(JEFF, p1.state, p, period, OPTS, at.Settings(transient_periods=300))
    assert (res.code, res.period) == (at.PERIODIC, 2) and res.derived
    assert np.abs(res.multipliers).max() < 1.0
    ref = shooting.periodic_orbit(JEFF, res.end_state, p, TIGHT, periods=2, tol=1e-12)
    ref_lams = floquet.multipliers(ref.monodromy)
    np.testing.assert_allclose(np.sort_complex(res.multipliers), np.sort_complex(ref_lams), atol=1e-7)
    assert res.lle == pytest.approx(np.log(np.abs(ref_lams).max()) / (2 * period), rel=1e-6)


def test_transient_stopped_when_settled_finds_the_long_transients_period_two_attractor():
    """The settled stop (`settle_periodic`: blocks of 8 periods, period test, stable refined
    orbit) against the full transient of 300 periods plus 128 samples from the same start (the
    static guess, 55 Hz, 19 um: period 2): same k, the same two points on the section (within the
    detection tolerance, 1e5 x rtol relative: the samples' jitter), the same multipliers (both
    refined by Newton to 1e-9), and it stops well before the 300 periods."""
    p, period = bai_params(BaiPoint(55.0, 19.0e-6))
    start = jc.static_guess(p)
    tol = at.default_period_rtol(OPTS)
    orbit, _, used, status = at.settle_periodic(JEFF, start, p, OPTS, 300, 32, tol)
    assert status == ig.STATUS_OK and orbit is not None and orbit[0] == 2 and used < 300
    fast = at.diagnose(JEFF, start, p, period, OPTS, at.Settings(transient_periods=300, stop_when_settled=True))
    long = at.diagnose(JEFF, start, p, period, OPTS, at.Settings(transient_periods=300))
    assert (fast.code, fast.period, fast.derived) == (long.code, long.period, long.derived) == (at.PERIODIC, 2, True)
    scale = tol * np.abs(long.samples).max()
    gaps = np.abs(fast.samples[:, None, :] - long.samples[None, :, :]).max(axis=2).min(axis=1)
    assert gaps.max() <= scale, (gaps.max(), scale)
    assert np.abs(fast.samples[-1] - fast.end_state).max() <= scale         # the state reached, next to the orbit
    np.testing.assert_allclose(fast.samples[::2], np.tile(fast.samples[-2], (64, 1)))   # period 2, exact
    np.testing.assert_allclose(np.sort_complex(fast.multipliers), np.sort_complex(long.multipliers), atol=1e-7)
    assert fast.lle == pytest.approx(long.lle, rel=1e-6)


def test_settled_stop_does_not_stop_on_an_unstable_orbit():
    """Started on the unstable period-1 orbit (55 Hz, 19 um), the samples first repeat with
    period 1; the refined orbit is unstable, so the transient goes on, kicked off it, and stops
    on the stable period-2 attractor -- the one the full transient finds from there (checked
    against a separate Newton solve at tighter tolerance in the test above it). Without kicks
    (ESCAPES = 0) the testing ends at the unstable orbit and the transient runs its length."""
    p, period = bai_params(BaiPoint(55.0, 19.0e-6))
    p1 = continuation.solve_orbit(JEFF, p, OPTS, cold_guess=jc.static_guess, tol=1e-10)
    assert p1.status == shooting.CONVERGED and not p1.stable
    tol = at.default_period_rtol(OPTS)
    orbit, _, used, _ = at.settle_periodic(JEFF, p1.state, p, OPTS, 300, 32, tol)
    assert orbit is not None and orbit[0] == 2 and np.abs(orbit[2]).max() < 1.0 and used < 300
    long = at.diagnose(JEFF, p1.state, p, period, OPTS, at.Settings(transient_periods=300))
    np.testing.assert_allclose(np.sort_complex(orbit[2]), np.sort_complex(long.multipliers), atol=1e-7)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(at.diagnosis, "ESCAPES", 0)
        orbit, _, used, _ = at.settle_periodic(JEFF, p1.state, p, OPTS, 300, 32, tol)
    assert orbit is None and used == 300


def test_continued_period_two_orbit_is_the_full_transients_attractor():
    """The neighbour's period-2 attractor continued (`settle_on_continued_orbit`: shooting on 2 T
    from its end state, then the transient 2 periods at a time until it reaches the orbit)
    against the full transient of 300 periods from the same start, 55.0 Hz from 55.1 Hz's
    attractor: same k, multipliers (both refined by Newton to 1e-9), points on the section
    (detection tolerance); far fewer periods. From the unstable period-1 orbit it declines
    (None, no periods used) and the transient goes on as without it."""
    tol = at.default_period_rtol(OPTS)
    p_next, period_next = bai_params(BaiPoint(55.1, 19.0e-6))
    neighbour = at.diagnose(JEFF, jc.static_guess(p_next), p_next, period_next, OPTS,
                            at.Settings(transient_periods=300))
    assert (neighbour.code, neighbour.period) == (at.PERIODIC, 2)
    p, period = bai_params(BaiPoint(55.0, 19.0e-6))
    orbit, reached, used = at.settle_on_continued_orbit(JEFF, neighbour.end_state, p, OPTS, 2, 300, tol)
    assert orbit is not None and orbit[0] == 2 and used < 100
    fast = at.diagnose(JEFF, neighbour.end_state, p, period, OPTS, at.Settings(transient_periods=300,
                       stop_when_settled=True), continued_period=2)
    long = at.diagnose(JEFF, neighbour.end_state, p, period, OPTS, at.Settings(transient_periods=300))
    assert (fast.code, fast.period, fast.derived) == (long.code, long.period, long.derived) == (at.PERIODIC, 2, True)
    np.testing.assert_allclose(np.sort_complex(fast.multipliers), np.sort_complex(long.multipliers), atol=1e-7)
    scale = tol * np.abs(long.samples).max()
    gaps = np.abs(fast.samples[:, None, :] - long.samples[None, :, :]).max(axis=2).min(axis=1)
    assert gaps.max() <= scale and np.abs(reached - fast.end_state).max() == 0.0
    p1 = continuation.solve_orbit(JEFF, p, OPTS, cold_guess=jc.static_guess, tol=1e-10)
    assert not p1.stable
    orbit, reached, used = at.settle_on_continued_orbit(JEFF, p1.state, p, OPTS, 1, 300, tol)
    assert orbit is None and used == 0 and reached is p1.state


def test_just_past_a_flip_the_transient_goes_on_from_the_period_two_orbit_born_there():
    """Fig. 13 at 93.1 Hz, 3.8 um: the period-1 orbit has flipped (multiplier -1.0018) and is
    left so slowly (x1.0018 a period) that a kicked 200-period transient still repeats on it:
    the diagnosis read period 1 with a positive exponent. `escape_from` starts the next transient
    on the stable period-2 orbit born at the flip (Newton on 2 T from the period-1 state offset
    along the flip's eigenvector). Independent value: a brute-force transient of 6000 periods
    from a 1e-3 offset along that eigenvector (about ln(30) / 0.0018 = 1900 periods to get away,
    then the period-2 orbit's multiplier 0.9927 every 2 periods: its distance to the orbit ends
    below 1e-6 of the state's size), whose last two samples are the orbit's two points."""
    p, period = bai_params(BaiPoint(93.1, 3.8e-6))
    p1 = continuation.solve_orbit(JEFF, p, OPTS, cold_guess=jc.static_guess, tol=1e-10)
    lams, vecs = np.linalg.eig(shooting.periodic_orbit(JEFF, p1.state, p, OPTS, tol=1e-10).monodromy)
    flip = int(np.argmax(np.abs(lams)))
    assert p1.bifurcation == floquet.PERIOD_DOUBLING and -1.01 < lams[flip].real < -1.0
    size = np.abs(p1.state).max()
    v = vecs[:, flip].real / np.abs(vecs[:, flip].real).max()
    brute, status = at.poincare(JEFF, p1.state + 1e-3 * size * v, p, OPTS, 6000, 2)
    assert status == ig.STATUS_OK
    assert np.abs(brute[1] - brute[0]).max() > 1e-2 * size          # period 2, not 1
    res = at.diagnose(JEFF, p1.state, p, period, OPTS, at.Settings(transient_periods=200))
    assert (res.code, res.period, res.derived) == (at.PERIODIC, 2, True) and res.lle < 0
    gaps = np.abs(res.samples[-2:, None, :] - brute[None, :, :]).max(axis=2).min(axis=1)
    assert gaps.max() <= 1e-6 * size, gaps
    with pytest.MonkeyPatch.context() as mp:       # the plain kick: still on the period-1 orbit
        mp.setattr(at.diagnosis, "FLIP_OFFSETS", ())
        kicked = at.diagnose(JEFF, p1.state, p, period, OPTS, at.Settings(transient_periods=200))
    assert (kicked.code, kicked.period) == (at.PERIODIC, 1)


@pytest.mark.parametrize("point, expected", [
    (BaiPoint(148.0, 7.6e-6), (at.QUASI_PERIODIC, 0)),   # past the Neimark-Sacker: a torus
    (BaiPoint(84.0, 7.6e-6), (at.PERIODIC, 2)),          # past the period doubling
], ids=["torus-148Hz", "period2-84Hz"])
def test_a_start_on_the_unstable_orbit_still_finds_the_attractor(point, expected):
    """A segment's first speed starts on its periodic orbit even when that is unstable; a weakly
    unstable orbit is left so slowly that the samples first repeat on it (kicked off, retaken),
    or have not settled on the attractor yet (sampled again after the Lyapunov run)."""
    p, period = bai_params(point)
    p1 = continuation.solve_orbit(JEFF, p, OPTS, cold_guess=jc.static_guess, tol=1e-10)
    assert p1.status == shooting.CONVERGED and not p1.stable
    res = at.diagnose(JEFF, p1.state, p, period, OPTS)
    assert (res.code, res.period) == expected
    if res.code == at.PERIODIC:
        assert np.abs(res.multipliers).max() < 1.0


# --- the period-doubling route to chaos of Bai 2006 (19 um) --------------------------------

CASCADE_SPEEDS = np.concatenate([np.arange(70.0, 43.0, -2.0), np.arange(43.0, 38.95, -0.1),
                                 np.arange(38.5, 30.9, -0.5)])


@pytest.mark.slow
def test_period_doubling_cascade_to_chaos_at_19um():
    """Attractor continuation downwards in speed (each speed starts from the previous end state):
    period 1 -> 2 -> 4 -> 8 in order, then chaos (positive exponent) with periodic windows."""
    u = None
    found = []
    for speed in CASCADE_SPEEDS:
        p, period = bai_params(BaiPoint(speed, 19.0e-6))
        u = jc.static_guess(p) if u is None else u
        res = at.diagnose(JEFF, u, p, period, OPTS, at.Settings(transient_periods=400, poincare_samples=128,
                          lyapunov_max_periods=1000, lyapunov_min_periods=200))
        assert res.status == ig.STATUS_OK
        u = res.end_state
        found.append((speed, res.code, res.period, res.lle))
    codes = [(c, k) for _, c, k, _ in found]
    first = {k: next(i for i, ck in enumerate(codes) if ck == (at.PERIODIC, k)) for k in (1, 2, 4, 8)}
    first_chaos = next(i for i, (c, _) in enumerate(codes) if c == at.CHAOTIC)
    assert first[1] < first[2] < first[4] < first[8] < first_chaos, found
    assert all(lle > 0 for _, c, _, lle in found if c == at.CHAOTIC)
    windows = [k for c, k in codes[first_chaos:] if c == at.PERIODIC and k > 0]
    assert windows and sum(c == at.CHAOTIC for c, _ in codes[first_chaos:]) >= 10, found


def test_settings_report_every_problem_and_diagnose_refuses_them():
    """Settings that cannot work are named (with the caller's prefix) before any work starts."""
    bad = at.Settings(poincare_samples=64, max_period=32, lyapunov_rtol=-1.0, lyapunov_blocks=1)
    problems = bad.problems("analysis.")
    assert any(p.startswith("analysis.poincare_samples: must be >= 4 x analysis.max_period") for p in problems)
    assert any(p.startswith("analysis.lyapunov_rtol") for p in problems)
    assert any("n_blocks" in p for p in problems) and len(problems) == 3
    assert at.Settings().problems() == []
    with pytest.raises(ValueError, match="poincare_samples"):
        p, period = bai_params(BaiPoint(40.0, 7.6e-6))
        at.diagnose(JEFF, jc.static_guess(p), p, period, OPTS, bad)

"""Exact extrema (rotorsweep.kernels.extrema) and the amplitudes built on them, each against an
independent value: a closed form, or scipy's DOP853 at rtol 1e-13 with a bounded scalar search
on its dense solution (scipy_extremes)."""
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.optimize import minimize_scalar

from rotorsweep.pipeline import compute, config, continuation, continuation_result, scene
from rotorsweep.kernels import extrema, integrators as ig, models
from rotorsweep.kernels.continuation import arclength as al, solve_orbit

DUFFING = models.get("duffing")
TIGHT = ig.settings(rtol=1e-12, atol=1e-14)


def scipy_extremes(fun, u0, span, weights, grid=4001):
    """(highest, lowest) of o = weights @ u[:m] along scipy's DOP853 solution from u0 over
    [0, span]: the extremes of a fine grid refined by a bounded search (xatol 1e-14 of the span:
    the value's error o'' d^2 / 2 is far below the integration's 1e-13) on the dense output."""
    sol = solve_ivp(fun, (0.0, span), np.asarray(u0, float), method="DOP853", rtol=1e-13, atol=1e-16,
                    dense_output=True)
    m = weights.shape[1]
    t = np.linspace(0.0, span, grid)
    out = []
    for w in weights:
        o = w @ sol.sol(t)[:m]
        found = []
        for sign in (1.0, -1.0):
            i = int(np.argmax(sign * o))
            lo, hi = t[max(i - 1, 0)], t[min(i + 1, grid - 1)]
            r = minimize_scalar(lambda s: -sign * (w @ sol.sol(s)[:m]), bounds=(lo, hi), method="bounded",
                                options={"xatol": 1e-14 * span})
            found.append(sign * max(-r.fun, sign * o[i]))
        out.append(found)
    out = np.array(out)
    return out[:, 0], out[:, 1]


def duffing_rhs(w, zeta, gamma, force):
    """The Duffing equation x'' + 2 zeta x' + x + gamma x^3 = F cos(w t) in the model's scaled time
    tau = w t / 2 pi, written out here (not the model's kernel)."""
    T = 2 * np.pi / w

    def fun(tau, u):
        x, v = u
        return [v, T * T * (force * np.cos(2 * np.pi * tau) - x - gamma * x ** 3) - 2 * zeta * T * v]
    return fun


def duffing(w, zeta, gamma, force):
    return DUFFING.build({"omega": w, "zeta": zeta, "gamma": gamma, "force": force})


@pytest.mark.parametrize("w", [0.5, 0.99, 1.4])
def test_linear_oscillator_amplitude_is_the_closed_form(w):
    """gamma = 0: x = Re(X e^{i w t}), |X| = F / |1 - w^2 + 2 i zeta w|; max |x| and the half
    peak-to-peak are |X|. Orbit to Newton tol 1e-12 and integration at rtol 1e-12: 1e-9 holds
    with three orders to spare."""
    built = duffing(w, 0.05, 0.0, 0.3)
    sol = solve_orbit(DUFFING, built.p, TIGHT, cold_guess=DUFFING.cold_guess, tol=1e-12)
    amp_max, half = extrema.amplitudes(DUFFING, sol.state, built.p, 1.0, TIGHT, built.period)
    exact = 0.3 / abs(1 - w * w + 0.1j * w)
    np.testing.assert_allclose([amp_max[0], half[0]], [exact, exact], rtol=1e-9)


def test_extrema_match_scipy_on_a_non_periodic_stretch():
    """From a state off the orbit (a transient: several extrema of unequal size) over 3.3
    periods, highest and lowest x against scipy. Both integrate at rtol <= 1e-12 from one state
    over a few periods: 1e-9 relative to the range."""
    built = duffing(1.3, 0.05, 1.0, 0.3)
    u0 = np.array([0.7, -2.0])
    hi, lo = extrema.extremes(DUFFING, u0, built.p, 3.3, TIGHT, built.period)
    ref_hi, ref_lo = scipy_extremes(duffing_rhs(1.3, 0.05, 1.0, 0.3), u0, 3.3, np.array([[1.0]]))
    np.testing.assert_allclose([hi[0], lo[0]], [ref_hi[0], ref_lo[0]], rtol=1e-9 * 2)


def test_failed_integration_is_nan():
    built = duffing(1.0, 0.05, 1.0, 0.3)
    hi, lo, status = extrema.orbit_extrema(DUFFING.kernel, np.array([1e3, 0.0]), built.p, 1.0,
                                           np.array([[1.0]]), ig.settings(amplitude_limit=10.0))
    assert status == ig.STATUS_AMPLITUDE and np.isnan(hi).all() and np.isnan(lo).all()


DUFFING_SCENE = """
[scene]
name = "duffing_extrema"
model = "duffing"

[duffing]
zeta = 0.05
gamma = {gamma}
force = {force}

[sweep]
omega = [{lo}, {hi}]

[numerics]
rtol = 1e-12
atol = 1e-14
newton_tol = 1e-10
amplitude_limit = 100.0

[continuation]
ds = 0.02
max_steps = 2000
"""


# Softening at F = 0.1 has no fold (its peak, |x| ~ F / 2 zeta = 1, shifts the frequency by
# 3/8 |gamma| = 0.019, below the damping's half-width 0.05; checked by the peak test): F = 0.2 folds.
@pytest.mark.parametrize("gamma, force, lo, hi", [(1.0, 0.3, 0.5, 5.0), (-0.05, 0.2, 0.5, 2.0)])
def test_duffing_fold_amplitudes_match_scipy(gamma, force, lo, hi):
    """max |x| and the half peak-to-peak at both folds of the hardening and softening resonance
    curves (the continuation result's event amplitudes) against scipy from the fold's orbit
    state. Both integrate at rtol <= 1e-12 over one period: 1e-7 is met with room (the sampled
    amplitudes were low by 5e-4 and 1e-3 here)."""
    cfg = config.parse_config(DUFFING_SCENE.format(gamma=gamma, force=force, lo=lo, hi=hi))
    (where,) = continuation.plan(cfg.scene).lines
    first = continuation.continue_line(cfg.scene, where)[0]
    folds = np.flatnonzero(first["event_type"] == al.FOLD)
    assert folds.size == 2
    for k in folds:
        w = first["event_parameter"][k]
        ref_hi, ref_lo = scipy_extremes(duffing_rhs(w, 0.05, gamma, force), first["event_state"][k], 1.0,
                                        np.array([[1.0]]))
        np.testing.assert_allclose(first["event_amplitude_max"][k], max(ref_hi[0], -ref_lo[0]), rtol=1e-7)
        np.testing.assert_allclose(first["event_amplitude_half_pp"][k], 0.5 * (ref_hi[0] - ref_lo[0]), rtol=1e-7)


@pytest.fixture(scope="module")
def bai_segment():
    """The Bai rotor at 15.2 um: `point` at 31.2 Hz (one point, as point_detail solves it) and a
    sweep segment 31.0-31.2 Hz (solve_segment, as a sweep task)."""
    text = Path("configs/bai2006_fig13.toml").read_text()
    text = text.replace("speed = {start = 10.0, stop = 250.0, step = 0.1}", "speed = [31.0, 31.1, 31.2]")
    text = text.replace("clearance = [3.8e-6, 7.6e-6, 11.4e-6, 15.2e-6, 19.0e-6]", "clearance = [15.2e-6]")
    data = config.parse_config(text).data
    data = scene.from_data({**data, "analysis": {**data["analysis"], "attractor": False}})
    points = [{**data.fixed, "clearance": 15.2e-6, "speed": s} for s in (31.0, 31.1, 31.2)]
    return data, points, compute.solve_segment(data, points[-1:]), compute.solve_segment(data, points)


def test_bai_half_peak_to_peak_from_point_and_sweep_match_scipy(bai_segment):
    """Half peak-to-peak x and y at 15.2 um, 31.2 Hz against scipy DOP853 from the orbit's state
    (the model's right-hand side, our integrator and extremum search replaced). The orbit
    integrates at rtol 1e-10 over one period: ~1e-9 relative; 1e-7 (the sampled y was low by 2e-3)."""
    data, points, point_row, sweep_rows = bai_segment
    model = data.model
    built = compute.builder(data)(points[-1])
    n = model.n_state
    jbuf, du = np.empty((n, n)), np.empty(n)

    def fun(t, u):
        ig.derivative(model.kernel, t, np.array(u), built.p, False, du, jbuf)
        return du.copy()
    for row in (point_row, {k: v[-1:] for k, v in sweep_rows.items()}):
        state = row["orbit_state"][0]
        weights = extrema.observable_weights(model, built.period)
        hi, lo = scipy_extremes(fun, state, 1.0, weights)
        np.testing.assert_allclose([row["amplitude_x"][0], row["amplitude_y"][0]], 0.5 * (hi - lo), rtol=1e-7)


def duffing_first_branch(gamma, force, hi):
    cfg = config.parse_config(DUFFING_SCENE.format(gamma=gamma, force=force, lo=0.5, hi=hi))
    (where,) = continuation.plan(cfg.scene).lines
    return continuation.continue_line(cfg.scene, where)[0]


def test_linear_oscillator_peak_is_the_closed_form():
    """gamma = 0: the resonance peak of |X| = F / |1 - w^2 + 2 i zeta w| is at w = sqrt(1 - 2 zeta^2)
    with |X| = F / (2 zeta sqrt(1 - zeta^2)), one `peak` event, stable. The peak's slope is a
    central difference (noise rtol / fd_step = 1e-7 of the slope, truncation fd_step^2 = 1e-10)
    whose zero Brent locates to 1e-11 in arclength: the frequency to ~1e-10, the amplitude
    (quadratic in the frequency's error) to the integration's 1e-12; 1e-9 holds."""
    zeta, force = 0.05, 0.3
    first = duffing_first_branch(0.0, force, 2.0)
    (k,) = np.flatnonzero(first["event_type"] == al.PEAK)
    assert first["event_type"].tolist() == [al.PEAK]
    np.testing.assert_allclose(first["event_parameter"][k], np.sqrt(1 - 2 * zeta ** 2), rtol=1e-9)
    exact = force / (2 * zeta * np.sqrt(1 - zeta ** 2))
    np.testing.assert_allclose(first["event_amplitude_max"][k, 0], exact, rtol=1e-9)
    assert np.abs(first["event_multipliers"][k]).max() < 1.0


def scipy_duffing_peak(gamma, force, guess_state, w0, width=1e-3):
    """(w, max |x|) of the resonance peak near w0 by scipy alone: the orbit at each w by Newton
    shooting (scipy's fsolve on DOP853 at rtol 1e-13, started from guess_state), its max |x| by
    scipy_extremes, the zero of d max|x| / dw (central difference, step 1e-5: truncation 1e-10,
    noise 1e-13 / 1e-5 = 1e-8 of the slope) by brentq within w0 +- width."""
    from scipy.optimize import brentq, fsolve

    def orbit(w):
        fun = duffing_rhs(w, 0.05, gamma, force)

        def residual(s):
            return solve_ivp(fun, (0.0, 1.0), s, method="DOP853", rtol=1e-13, atol=1e-16).y[:, -1] - s
        return fun, fsolve(residual, guess_state, xtol=1e-13)

    def amplitude(w):
        fun, s = orbit(w)
        hi, lo = scipy_extremes(fun, s, 1.0, np.array([[1.0]]))
        return max(hi[0], -lo[0])

    h = 1e-5
    w = brentq(lambda w: amplitude(w + h) - amplitude(w - h), w0 - width, w0 + width, xtol=1e-13)
    return w, amplitude(w)


@pytest.mark.parametrize("gamma, force, hi", [(1.0, 0.3, 5.0), (-0.05, 0.1, 2.0)])
def test_duffing_peak_matches_scipy(gamma, force, hi):
    """The hardening and softening resonance peaks (one `peak` event each): frequency and max |x|
    against scipy_duffing_peak. Its frequency is good to ~1e-10 (it meets the linear closed form
    to 5e-11); ours carries the slope's difference noise, rtol / fd_step = 1e-7 of the slope,
    divided by the amplitude's curvature along the branch: measured 8e-9 (hardening, next to the
    fold) and 7e-10 (softening). The amplitude, quadratic in that error, agrees to 2e-13. 1e-7."""
    first = duffing_first_branch(gamma, force, hi)
    (k,) = np.flatnonzero(first["event_type"] == al.PEAK)
    w, amp = scipy_duffing_peak(gamma, force, first["event_state"][k], first["event_parameter"][k])
    np.testing.assert_allclose(first["event_parameter"][k], w, rtol=1e-7)
    np.testing.assert_allclose(first["event_amplitude_max"][k, 0], amp, rtol=1e-7)


def test_peak_in_info_events_table_and_csv():
    """The linear oscillator's peak in `info`, the events table (the report's and the CSV's):
    parameter, amplitudes (as the event recorded them), stability."""
    from rotorsweep.pipeline import query

    cfg = config.parse_config(DUFFING_SCENE.format(gamma=0.0, force=0.3, lo=0.5, hi=2.0))
    pl = continuation.plan(cfg.scene)
    lines = [(where, continuation.continue_line(cfg.scene, where)) for where in pl.lines]
    ds = continuation.to_dataset(cfg.scene, pl, lines, {})
    info = continuation_result.describe(ds)
    w = float(ds["event_parameter"].values[0])
    assert f"peak on branch 0: omega {w:.10g}" in info and "half peak-to-peak x 3.00375" in info and "stable" in info
    cols = continuation_result.events_table(ds)
    assert cols["type"] == ["PK"] and cols["stable"] == [1] and cols["omega"] == [w]
    assert cols["amplitude_max_x"] == ds["event_amplitude_max"].values[:, 0].tolist()
    assert cols["amplitude_half_pp_x"] == ds["event_amplitude_half_pp"].values[:, 0].tolist()
    # a symmetric orbit's: equal to the orbit's own error, the Newton tolerance (1e-10 of the state)
    np.testing.assert_allclose(cols["amplitude_half_pp_x"], cols["amplitude_max_x"], rtol=1e-10)
    assert "PK" in query.render(cols, "csv")


def scipy_mean(fun, u0, span, weights):
    """Mean of o = weights @ u[:m] over [0, span] by scipy's quad (epsrel 1e-13) on scipy's DOP853
    solution at rtol 1e-13 (its dense output: 7th order, far below the means' errors here)."""
    sol = solve_ivp(fun, (0.0, span), np.asarray(u0, float), method="DOP853", rtol=1e-13, atol=1e-16,
                    dense_output=True)
    m = weights.shape[1]
    return np.array([quad(lambda t: w @ sol.sol(t)[:m], 0.0, span, limit=500, epsabs=0.0, epsrel=1e-13)[0]
                     for w in weights]) / span


@pytest.mark.parametrize("weights", [np.array([[1.0]]), np.array([[1.0, 0.3]])])
def test_duffing_mean_matches_scipy_quad(weights):
    """The mean of x (position: the quintic Hermite rule) and of x + 0.3 x' (the cubic rule, g
    from the right-hand side) over 0.37 of a hardening Duffing orbit (over a whole period its
    odd symmetry makes the mean zero) against scipy quad on a rtol 1e-13 solution: within the
    stated error estimate (the rule one order lower's difference, summed over the steps) plus
    the integration's ~10 rtol |x|."""
    built = duffing(1.3, 0.05, 1.0, 0.3)
    sol = solve_orbit(DUFFING, built.p, TIGHT, cold_guess=DUFFING.cold_guess, tol=1e-12)
    hi, lo, mean, error, status, n_rhs = extrema.orbit_extent(DUFFING.kernel, sol.state, built.p, 0.37, weights, TIGHT, True)
    ref = scipy_mean(duffing_rhs(1.3, 0.05, 1.0, 0.3), sol.state, 0.37, weights)
    assert status == ig.STATUS_OK and n_rhs > 0
    assert abs(mean[0] - ref[0]) <= error[0] + 10 * 1e-12 * max(hi[0], -lo[0])
    assert abs(ref[0]) > 1e3 * abs(mean[0] - ref[0])       # a nonzero mean, resolved


def test_bai_orbit_means_from_the_sweep_match_scipy_quad(bai_segment):
    """x and y means of the sweep's orbit at 15.2 um, 31.2 Hz (one pass with the extrema, no orbit
    samples) against scipy quad on scipy's DOP853 solution from the orbit's state: within the
    stated error estimate plus the integration's ~10 rtol (1e-10) of the range."""
    data, points, _, sweep_rows = bai_segment
    model = data.model
    built = compute.builder(data)(points[-1])
    state = sweep_rows["orbit_state"][-1]
    opts = data.integrator
    hi, lo, mean, error, _ = extrema.extent(model, state, built.p, 1.0, opts, built.period)
    n = model.n_state
    jbuf, du = np.empty((n, n)), np.empty(n)

    def fun(t, u):
        ig.derivative(model.kernel, t, np.array(u), built.p, False, du, jbuf)
        return du.copy()
    ref = scipy_mean(fun, state, 1.0, extrema.observable_weights(model, built.period))
    got = np.array([sweep_rows["x_mean"][-1], sweep_rows["y_mean"][-1]])
    np.testing.assert_array_equal(got, mean)
    assert np.all(np.abs(got - ref) <= error + 10 * 1e-10 * (hi - lo))


def test_branch_n_rhs_counts_every_integration(monkeypatch):
    """A branch's n_rhs is the right-hand sides of all its integrations (issue 32 gap b): the
    Newton maps and their differences (Family.return_map), the tangents' parameter passes
    (Family.parameter_pass), the extrema passes of weighted points (Family.extremes) and the peak
    slopes' state passes (extrema.amplitudes_and_slope), each recounted here as it is made, on a
    plain, a weighted and a peaked Duffing branch (the peak's location and error estimate make
    more of them). The weighted branch takes the plain one's steps: it costs exactly its extrema
    passes more."""
    spent = {}

    def recount(owner, name, index):
        made = getattr(owner, name)

        def counted(*args, **kw):
            out = made(*args, **kw)
            spent[name] = spent.get(name, 0) + out[index]
            return out
        monkeypatch.setattr(owner, name, counted)
    recount(al.Family, "return_map", 3)
    recount(al.Family, "parameter_pass", 3)
    recount(al.Family, "extremes", 2)
    recount(extrema, "amplitudes_and_slope", 2)

    def branch(**kw):
        spent.clear()
        family = al.Family(DUFFING, lambda w: duffing(w, 0.05, 1.0, 0.3).p, TIGHT, **kw)
        b = al.continue_orbit(family, 0.5, np.zeros(2), (0.5, 2.0), al.Settings(ds=0.05, ds_max=0.3))
        assert b.n_rhs == sum(spent.values())
        return b, dict(spent)
    plain, _ = branch()
    weighted, passes = branch(weights=np.array([[1.0]]))
    assert [p.lam for p in weighted.points] == [p.lam for p in plain.points]
    assert passes["extremes"] > 0 and weighted.n_rhs - plain.n_rhs == passes["extremes"]
    peaked, passes = branch(weights=np.array([[1.0]]), peak=0)
    assert [e.kind for e in peaked.events].count(al.PEAK) == 1
    assert passes["parameter_pass"] > 0 and passes["amplitudes_and_slope"] > 0


def test_extremes_change_and_parameter_derivative_match_scipy():
    """orbit_extent_slope's d_highest, d_lowest / (2 h) (the extremes' derivative along a state
    direction du and a frequency change, from two perturbed orbits on the orbit's own steps) and
    parameter_pass's d phi / d omega, on a hardening Duffing orbit, against scipy alone: the
    extremes (scipy_extremes) and the end states of DOP853 at rtol 1e-13 from u0 +- eps du at
    omega +- eps dw, central differences of step eps = 1e-4 (truncation eps^2 ~ 1e-8 relative,
    noise 1e-13 / eps = 1e-9). Ours: round-off 1e-16 / h = 1e-11 and the method's truncation
    error's change, ~1e-12; 1e-6."""
    w, dw, h, eps = 1.3, 0.7, 1e-5, 1e-4
    built = duffing(w, 0.05, 1.0, 0.3)
    sol = solve_orbit(DUFFING, built.p, TIGHT, cold_guess=DUFFING.cold_guess, tol=1e-12)
    du = np.array([0.3, -0.2])
    hi, lo, d_hi, d_lo, _, status, _ = extrema.orbit_extent_slope(
        DUFFING.kernel, sol.state, du, extrema.tangent_params(lambda v: duffing(v, 0.05, 1.0, 0.3).p, w, dw, h), 1.0,
        np.array([[1.0]]), TIGHT)
    assert status == ig.STATUS_OK
    ref = [scipy_extremes(duffing_rhs(w + sign * eps * dw, 0.05, 1.0, 0.3), sol.state + sign * eps * du, 1.0,
                          np.array([[1.0]])) for sign in (1.0, -1.0)]
    for ours, j in ((d_hi, 0), (d_lo, 1)):
        np.testing.assert_allclose(ours[0], (ref[0][j][0] - ref[1][j][0]) / (2 * eps), rtol=1e-6)
    _, dphi, status, _ = extrema.parameter_pass(DUFFING.kernel, sol.state, lambda v: duffing(v, 0.05, 1.0, 0.3).p,
                                                w, h, 1.0, np.array([[1.0]]), TIGHT)
    ends = [solve_ivp(duffing_rhs(w + sign * eps, 0.05, 1.0, 0.3), (0.0, 1.0), sol.state, method="DOP853",
                      rtol=1e-13, atol=1e-16).y[:, -1] for sign in (1.0, -1.0)]
    np.testing.assert_allclose(dphi, (ends[0] - ends[1]) / (2 * eps), rtol=1e-6, atol=1e-6 * np.abs(dphi).max())


def linear_orbit(w, zeta=0.05, force=0.3):
    """The linear oscillator's orbit x = Re(X e^{i w t}), X = F / (1 - w^2 + 2 i zeta w), in the
    model's scaled state [x, dx/dtau] (tau = w t / 2 pi, so dx/dtau = Re(2 pi i X e^{i w t})):
    (state at tau = 0, its derivative in w, |X|, d|X|/dw), in closed form."""
    d = 1 - w * w + 2j * zeta * w
    X, dX = force / d, force * (2 * w - 2j * zeta) / d ** 2
    state = np.array([X.real, (2j * np.pi * X).real])
    dstate = np.array([dX.real, (2j * np.pi * dX).real])
    return state, dstate, abs(X), (np.conj(X) * dX).real / abs(X)


@pytest.mark.parametrize("w", [0.5, 0.99, 1.4])
def test_slope_and_parameter_derivative_are_the_linear_closed_form(w):
    """gamma = 0, along the branch's tangent (ds/dw, 1) in closed form: the half peak-to-peak's
    slope is d|X|/dw, and the flow's parameter derivative is (I - M) ds/dw (differentiate
    phi(s(w), w) = s(w); M = expm of the scaled system matrix over one period). Ours carries the
    method's truncation error's derivative (~rtol = 1e-12 relative) and the parameter term's
    central difference (step 1e-5: truncation ~1e-10, measured 3e-11 on the Duffing); 1e-9. The
    slope from the parameter pass and the state direction's pass (amplitudes_and_slope)
    equals one pass along the whole tangent to round-off and the two parameter terms' truncation
    (~1e-10): 1e-9."""
    from scipy.linalg import expm
    state, dstate, amplitude, slope = linear_orbit(w)
    params = lambda v: duffing(v, 0.05, 0.0, 0.3).p     # noqa: E731
    weights = np.array([[1.0]])
    along, dphi, status, _ = extrema.parameter_pass(DUFFING.kernel, state, params, w, 1e-5, 1.0, weights, TIGHT)
    assert status == ig.STATUS_OK
    amplitudes, got, _ = extrema.amplitudes_and_slope(DUFFING.kernel, np.append(state, w), np.append(dstate, 1.0),
                                                      params(w), 1.0, weights, 0, TIGHT, along)
    np.testing.assert_allclose(amplitudes[:, 0], [amplitude, amplitude], rtol=1e-9)
    np.testing.assert_allclose(got, slope, rtol=1e-9, atol=1e-9 * amplitude)
    _, _, d_hi, d_lo, _, _, _ = extrema.orbit_extent_slope(DUFFING.kernel, state, dstate,
                                                           extrema.tangent_params(params, w, 1.0, 1e-5), 1.0, weights,
                                                           TIGHT)
    np.testing.assert_allclose(got, 0.5 * (d_hi[0] - d_lo[0]), rtol=1e-9)
    period = 2 * np.pi / w
    monodromy = expm(np.array([[0.0, 1.0], [-period ** 2, -0.1 * period]]))
    expected = (np.eye(2) - monodromy) @ dstate
    np.testing.assert_allclose(dphi, expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())


def test_extremes_derivative_matches_scipy_to_its_noise():
    """orbit_extent_slope on the hardening Duffing (the Duffing's cubic: no closed form) along a
    state direction and a frequency change, against scipy's extremes (scipy_extremes) from
    u0 +- eps du at w +- eps dw, Richardson-extrapolated central differences of steps 2 eps and
    eps = 1e-4 (truncation O(eps^4) ~ 1e-15; noise rtol / eps = 1e-9 relative). Ours: the
    method's ~1e-12 and the parameter term's ~1e-10 (step 1e-5); 5e-9."""
    w, dw, eps = 1.3, 0.7, 1e-4
    sol = solve_orbit(DUFFING, duffing(w, 0.05, 1.0, 0.3).p, TIGHT, cold_guess=DUFFING.cold_guess, tol=1e-12)
    du = np.array([0.3, -0.2])
    params = lambda v: duffing(v, 0.05, 1.0, 0.3).p     # noqa: E731
    _, _, d_hi, d_lo, _, status, _ = extrema.orbit_extent_slope(
        DUFFING.kernel, sol.state, du, extrema.tangent_params(params, w, dw, 1e-5), 1.0, np.array([[1.0]]), TIGHT)
    assert status == ig.STATUS_OK

    def difference(e):
        ref = [scipy_extremes(duffing_rhs(w + sign * e * dw, 0.05, 1.0, 0.3), sol.state + sign * e * du, 1.0,
                              np.array([[1.0]])) for sign in (1.0, -1.0)]
        return np.array([ref[0][j][0] - ref[1][j][0] for j in (0, 1)]) / (2 * e)
    near, far = difference(eps), difference(2 * eps)
    np.testing.assert_allclose([d_hi[0], d_lo[0]], near + (near - far) / 3, rtol=5e-9)

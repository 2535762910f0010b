"""The Filipkovsky 2016 scenes by continuation (Figs. 2a, 2b-4), the unstable-branch point
(Figs. 5-6), and the preloaded rotor driven hard enough that balls unload."""
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import compute, config, continuation
from rotorsweep.kernels import continuation as kc, integrators as ig, shooting
from rotorsweep.kernels.continuation import arclength as al
from rotorsweep.kernels.models import rigid_preloaded as rp

SPEC = rp.SPEC
FIG2A = Path("configs/filipkovsky2016_fig2a_continue.toml")
FIG2B = Path("configs/filipkovsky2016_fig2b_continue.toml")
FIG2A_PRINTED = Path("configs/filipkovsky2016_fig2a_printed.toml")


def _quick_fig2a():
    """Fig. 2a's scene narrowed to 15 deg and 560-720 Hz (both folds inside; ~15 s)."""
    text = FIG2A.read_text().replace("speed = {start = 300.0, stop = 800.0, step = 5.0}",
                                     "speed = {start = 560.0, stop = 720.0, step = 5.0}")
    return config.parse_config(text.replace("nominal_angle = [12, 15, 26, 36, 40]", "nominal_angle = [15]"))


def _half_pp_y_b(built, u0, periods, opts):
    """Half peak-to-peak of y_B [m] over the last of `periods` forcing periods from u0 (a
    transient: integration only, no shooting)."""
    traj = shooting.sample_orbit(SPEC.kernel, u0, built.p, float(periods), 64 * periods, opts)
    y = traj[-64:, 3] * rp.LENGTH_SCALE
    return 0.5 * (y.max() - y.min()), traj[-1]


def _without_peaks(rec):
    """The line record with its located points other than response peaks (peaks are events of
    their own, issue 32; these tests are about the folds)."""
    keep = np.asarray(rec["event_type"]) != al.PEAK
    return {k: (np.asarray(v)[keep] if k.startswith("event_") else v) for k, v in rec.items()}


@pytest.fixture(scope="module")
def fig2a_line():
    cfg = _quick_fig2a()
    (where,) = continuation.plan(cfg.scene).lines
    return cfg, where, _without_peaks(continuation.continue_line(cfg.scene, where)[0])


def test_fig2a_continuation_passes_the_fold_pair(fig2a_line):
    """Unbalance response at 15 deg through the resonance: the branch turns at two folds (LP,
    one multiplier +1), the middle part between them unstable through a real multiplier > 1
    (saddle: the paper's 'left branches' lose stability by a saddle-node), and the soft
    characteristic the paper describes: the upper fold lies below the lower one, both below
    the linear forward cylindrical frequency at 1x (Campbell crossing ~ 690 Hz)."""
    _, _, rec = fig2a_line
    assert al.EVENT_LABELS[rec["event_type"][0]] == "LP" and list(rec["event_type"]) == [al.FOLD, al.FOLD]
    lower, upper = rec["event_parameter"]
    assert 600.0 < upper < lower < 690.0
    # the folds' critical multiplier: +1 to the located point's accuracy (Brent on the
    # arclength to the Newton tolerance; test functions of the multipliers ~1e-6)
    for m in rec["event_multipliers"]:
        assert np.min(np.abs(m - 1.0)) < 1e-4
    mid = (rec["parameter"] > upper) & (rec["parameter"] < lower)
    idx = np.arange(len(rec["parameter"]))
    between = (idx > rec["event_index"][0]) & (idx <= rec["event_index"][1])
    lead = rec["multipliers"][between][np.arange(between.sum()), np.abs(rec["multipliers"][between]).argmax(axis=1)]
    assert mid[between].all() and (np.abs(lead) > 1).all() and np.allclose(lead.imag, 0) and (lead.real > 1).all()


def test_fig2a_bistability_between_the_folds_by_transients(fig2a_line):
    """Independent of the continuation's Newton: between the folds, a long transient from rest
    and one from the upper branch's nearest computed orbit (a few Hz away) settle on two
    different orbits whose y_B half
    peak-to-peak equal the branch's lower and upper stable amplitudes there. 400 periods:
    |multiplier| <= 0.969 on the stable parts, 0.969^400 ~ 3e-6 of the initial offset left,
    far below the 2 % tolerance (the branch amplitudes are linear interpolations between
    continuation points ~ 1 Hz apart)."""
    cfg, where, rec = fig2a_line
    lower, upper = rec["event_parameter"]
    f = 0.5 * (lower + upper)
    built = compute.builder(cfg.scene)({**cfg.scene.fixed, **where, "speed": f})
    opts = cfg.scene.integrator
    lam, amp = rec["parameter"], rec["amplitude_half_pp"][:, 3]
    stable = np.abs(rec["multipliers"]).max(axis=1) < 1
    first, last = rec["event_index"][0], rec["event_index"][1] + 1
    on_lower = np.interp(f, lam[:first + 1][stable[:first + 1]], amp[:first + 1][stable[:first + 1]])
    tail = slice(last, None)
    order = np.argsort(lam[tail])
    on_upper = np.interp(f, lam[tail][order], amp[tail][order])
    from_rest, _ = _half_pp_y_b(built, np.zeros(10), 400, opts)
    near_upper = last + np.argmin(np.abs(lam[tail] - f))
    from_far, _ = _half_pp_y_b(built, rec["state"][near_upper], 400, opts)
    assert from_rest == pytest.approx(on_lower, rel=0.02)
    assert from_far == pytest.approx(on_upper, rel=0.02)
    assert on_upper > 1.5 * on_lower


def test_fig2a_with_the_law_as_printed_turns_at_a_soft_fold_pair():
    """The scene with the papers' law as printed, narrowed to 15 deg and 370-430 Hz (~15 s): the
    forward cylindrical resonance is soft (folds below the linear 1x crossing, 422.5 Hz at 250 Hz
    and about 423 Hz at the crossing), the middle branch a saddle (multiplier > 1), the peak about
    half the balls' deformation at rest (z0 sin a = 24.2 um), and the line's derived values say
    the law as printed: static thrust 1.5 P0, z0 from eq. 7."""
    text = FIG2A_PRINTED.read_text().replace("speed = {start = 50.0, stop = 700.0, step = 5.0}",
                                             "speed = {start = 370.0, stop = 430.0, step = 5.0}")
    cfg = config.parse_config(text.replace("nominal_angle = [12, 15, 26, 36, 40]", "nominal_angle = [15]"))
    (where,) = continuation.plan(cfg.scene).lines
    rec = _without_peaks(continuation.continue_line(cfg.scene, where)[0])
    assert [al.EVENT_LABELS[e] for e in rec["event_type"]] == ["LP", "LP"]
    lower, upper = rec["event_parameter"]
    assert 385.0 < upper < lower < 422.5
    peak = rec["amplitude_half_pp"][:, 3].max()
    assert 0.3 < peak / 24.2e-6 < 0.7
    derived = compute.point_params(cfg.scene, {**cfg.scene.fixed, **where, "speed": 400.0}).derived
    assert derived["static_thrust"] == pytest.approx(450.0, rel=1e-12)
    assert derived["axial_approach"] == pytest.approx(92.69e-6, rel=1e-3)


def test_continuing_a_frequency_with_both_forcings_on_follows_tori():
    """Unbalance and support vibration together: the common period jumps with either frequency,
    so no periodic orbit can be continued; `rotorsweep continue` follows the invariant torus
    instead (issue 38; it refused such a scene before). Without the unbalance the line stays a
    periodic-orbit line."""
    from rotorsweep.pipeline import torus_branches

    text = FIG2B.read_text().replace("eccentricity = 0.0", "eccentricity = 0.2e-6")
    both = config.parse_config(text).scene
    pl = continuation.plan(both)
    assert pl.parameter == "support_frequency"
    assert torus_branches.is_torus_line(both, pl.parameter, pl.start, pl.lines[0])
    alone = config.parse_config(FIG2B.read_text()).scene
    pl = continuation.plan(alone)
    assert pl.parameter == "support_frequency"
    assert not torus_branches.is_torus_line(alone, pl.parameter, pl.start, pl.lines[0])


# --- balls unloading -------------------------------------------------------------------------

def _unloading_point():
    """Vertical support vibration of 150 m/s^2 at 400 Hz, 15 deg, 250 Hz shaft speed: the
    inertia force M A ~ 1800 N against a 300 N preload; the journals' excursion exceeds
    z0 sin(a) / cos(a) ~ 5 um. The bearing is explicit: the 15 deg row with its label as the free
    angle, which these tests' numbers were measured with (the model's default takes the free angle
    from the groove geometry)."""
    v = {p.name: (p.unset if p.axis else p.default) for p in SPEC.parameters}
    v.update(speed=250.0, eccentricity=0.0, support_acceleration=150.0, support_frequency=400.0,
             nominal_angle=15.0, free_angle="nominal")
    return v


def _min_delta(traj, p):
    """Smallest ball deformation [m] of both bearings along the samples (the kernel's delta_k
    written out, SPEC 2.2)."""
    b = 2 * np.pi * np.arange(int(p[rp.P_NBALLS])) / p[rp.P_NBALLS]
    ca, sa, off = p[rp.P_COS_A], p[rp.P_SIN_A], p[rp.P_OFFSET]
    da = (traj[:, [0]] * np.cos(b) + traj[:, [1]] * np.sin(b)) * ca + traj[:, [4]] * sa + off
    db = (traj[:, [2]] * np.cos(b) + traj[:, [3]] * np.sin(b)) * ca - traj[:, [4]] * sa + off
    return min(da.min(), db.min()) * rp.LENGTH_SCALE


def test_balls_unload_and_the_integration_error_follows_the_tolerance():
    """Along the converged orbit at the unloading point some balls lose contact (delta < 0,
    also seen through bearing_load: a ball-free direction carries no force). The force is only
    C^1 where a ball leaves contact, which the embedded error estimate sees as a larger local
    error and answers with smaller steps: the error over 5 periods against an rtol = 1e-13
    reference shrinks with the tolerance, by at least 100x from rtol 1e-8 to 1e-11 (1000x for
    a tolerance-proportional error; a factor 10 margin for DOP853's step-control constant across
    the kinks), and stays within 100 x rtol x the orbit's size at each tolerance. Measured: 4.0e-6
    at 1e-8, 1.2e-8 at 1e-11 (orbit size 141 um-units: 2.8 and 8.6 x rtol x size; slope ~0.85
    per decade of rtol from 1e-6 to 1e-12)."""
    v = _unloading_point()
    built = SPEC.build(v)
    opts = ig.settings(rtol=1e-11, atol=1e-13)
    sol = kc.solve_orbit(SPEC, built.p, opts, cold_guess=SPEC.cold_guess, tol=1e-9)
    assert sol.status == shooting.CONVERGED
    orbit = shooting.sample_orbit(SPEC.kernel, sol.state, built.p, 1.0, 256, opts)
    assert _min_delta(orbit, built.p) < -0.5e-6
    # bearing_load where a ball of bearing A (next to the disk) is most unloaded: unloaded balls
    # carry nothing (A's force equals the sum over its balls with delta > 0 only, written out)
    state = rp.bearing_state(v)
    b = 2 * np.pi * np.arange(int(built.p[rp.P_NBALLS])) / built.p[rp.P_NBALLS]
    a = state.contact_angle
    q = orbit[:, :5] * rp.LENGTH_SCALE
    deltas = ((q[:, [0]] * np.cos(b) + q[:, [1]] * np.sin(b)) * np.cos(a)
              + (state.axial_approach + q[:, [4]]) * np.sin(a))
    worst = np.argmin(deltas.min(axis=1))
    delta = deltas[worst]
    assert (delta < 0).any() and (delta > 0).any()
    force, _ = rp.bearing_load(q[worst], state, rp.geometry(15).n_balls)
    load = state.contact_constant * np.maximum(delta, 0.0) ** 1.5 * np.cos(a)
    np.testing.assert_allclose(force[0:2], [np.sum(load * np.cos(b)), np.sum(load * np.sin(b))], rtol=1e-12)

    def end_state(rtol):
        return shooting.sample_orbit(SPEC.kernel, sol.state, built.p, 5.0, 5,
                                     ig.settings(rtol=rtol, atol=rtol * 1e-2))[-1]
    ref = end_state(1e-13)
    size = np.abs(orbit).max()
    errors = {rtol: np.abs(end_state(rtol) - ref).max() for rtol in (1e-8, 1e-11)}
    assert errors[1e-8] <= 100 * 1e-8 * size and errors[1e-11] <= 100 * 1e-11 * size
    assert errors[1e-11] * 100 <= errors[1e-8]


def test_forcing_too_strong_for_newton_gives_a_status_not_an_exception():
    """At 10^4 m/s^2 (the parameter's upper bound) and 500 Hz the shooting's integrations run
    into the amplitude limit: a diverged status with its reason (amplitude_limit), no
    multipliers. (At 300 and 600 Hz the same forcing still converges: a failure is found, not
    assumed.)"""
    v = {**_unloading_point(), "support_acceleration": 1e4, "support_frequency": 500.0}
    built = SPEC.build(v)
    sol = kc.solve_orbit(SPEC, built.p, ig.settings(rtol=1e-9, atol=1e-11), cold_guess=SPEC.cold_guess,
                         tol=1e-9, max_iter=15)
    from rotorsweep.pipeline import schema
    assert (sol.status, schema.ORBIT_REASON[sol.reason]) == (shooting.DIVERGED, "amplitude_limit")
    assert np.isnan(sol.multipliers.real).all()


# --- the paper's frequency unit and the report ---------------------------------------------------

def test_omega_l_is_the_axial_mode_at_15_deg():
    """omega_l = the lowest natural frequency of `rotorsweep modes` with the 15 deg bearing;
    independently, the axial mode of the rigid rotor on two bearings of axial stiffness k_a
    (bearing.preload_state, closed form): sqrt(2 k_a / (m_B + m_0)) sqrt(1 - zeta^2) / 2 pi,
    zeta = C / (2 sqrt(2 k_a (m_B + m_0))); equal to 1e-9 (the linearization at the static
    state, q = 0, is exact)."""
    from rotorsweep.pipeline import modes
    data = config.parse_config(FIG2A.read_text().replace("nominal_angle = [12, 15, 26, 36, 40]",
                                                         "nominal_angle = [40]")).scene
    wl = modes.omega_l(data)
    at15 = modes.scene_values(data, {"speed": 300.0, "nominal_angle": 15.0})
    assert wl == modes.modes(rp.SPEC, at15)[0].frequency
    k = 2 * rp.bearing_state(at15).axial_stiffness
    m = at15["shaft_mass"] + at15["disk_mass"]
    zeta = at15["damping"] / (2 * np.sqrt(k * m))
    assert wl == pytest.approx(np.sqrt(k / m) * np.sqrt(1 - zeta ** 2) / (2 * np.pi), rel=1e-9)


def test_continuation_report_draws_the_response_in_omega_l_and_the_campbell_diagram(fig2a_line, tmp_path):
    """The result carries the continued speed over omega_l (the paper's axis), the report draws
    the half peak-to-peak of y_B (the [report] observable) against it, and the Campbell diagram
    (forward / backward whirl, the 1x line)."""
    from rotorsweep.pipeline.report import branch_result
    cfg, where, rec = fig2a_line
    pl = continuation.plan(cfg.scene)
    ds = continuation.to_dataset(cfg.scene, pl, [(where, [rec])],
                                 {"config_toml": cfg.source, "model": "rigid_preloaded", "scene": "fig2a_quick"})
    wl = ds["parameter_over_omega_l"].attrs["omega_l"]
    np.testing.assert_array_equal(ds["parameter_over_omega_l"].values, ds["parameter"].values / wl)
    np.testing.assert_array_equal(ds["event_parameter_over_omega_l"].values, ds["event_parameter"].values / wl)
    assert ds.attrs["report_observable"] == "y_B"
    j = list(ds["observable"].values).index("y_B")
    np.testing.assert_allclose(ds["event_amplitude_half_pp"].values[:, j],
                               rec["event_amplitude_half_pp"][:, j], rtol=0)
    out = branch_result.make_report(ds, tmp_path)
    names = {p.name for p in out["png"]}
    assert {"response_y_B.png", "mode_campbell.png", "branch_stability_map.png"} <= names
    page = out["html"].read_text()
    assert "Response: half peak-to-peak of y_B" in page
    assert "speed / \\\\u03c9_l (\\\\u03c9_l = 340 Hz)" in page       # bokeh's JSON escapes the omega
    assert "Campbell diagram" in page and "forward whirl" in page and "backward whirl" in page and "1x (shaft speed)" in page


SWEEP_GRID = """
[scene]
name = "angle_preload_map"
model = "rigid_preloaded"

[forcing]
eccentricity = 0.2e-6

[sweep]
speed = [640.0, 660.0, 680.0]
nominal_angle = [15, 26]
preload = [200.0, 300.0]
"""


@pytest.mark.slow    # 17-41 s: the default suite stays under 15 min on 2 cores (make test-slow)
def test_sweep_report_maps_stability_over_contact_angle_and_preload(tmp_path):
    """A rigid_preloaded sweep with the contact angle and the preload as the other axes: the
    stability map has one band per nominal angle (y) and one panel per preload (facet), the
    derived contact angle reads 'from the preload solve' (not the clearance model's text), and
    the report adds the Campbell diagram with the grid's speeds marked, and draws a --point of
    this model (no x, y observables)."""
    from rotorsweep.pipeline import cube, query, sweep
    from rotorsweep.pipeline.report import axes_plan, make_report, map_rectangles
    from rotorsweep.pipeline.report.plan import fmt
    cfg = config.parse_config(SWEEP_GRID)
    ds = cube.open_cube(sweep.run(cfg, tmp_path / "grid.nc", workers=1, progress=False))
    plan = axes_plan(ds)
    assert (plan["x"], plan["y"], plan["facets"]) == ("speed", "nominal_angle", ["preload"])
    rects, _ = map_rectangles(ds, plan, {"preload": 300.0}, query.bistable_intervals(ds))
    bands = sorted({round(r[1] + 0.45) for rows in rects.values() for r in rows})
    assert bands == [0, 1]
    assert fmt(ds, "contact_angle", float("nan")) == "from the preload solve"
    out = make_report(ds, tmp_path / "report", points=[{"speed": 660.0, "nominal_angle": 15.0, "preload": 300.0}])
    names = {p.name for p in out["png"]}
    assert {"stability_map.png", "mode_campbell.png", "branches.png"} <= names
    assert [p.name for p in out["points"]] == ["point_660Hz_15deg_300N.png"]     # drawn in (x_A, y_A)
    page = out["html"].read_text()
    assert "Campbell diagram" in page and "from clearance" not in page


# --- Figs. 5-6: the motion at a point of an unstable branch --------------------------------------

FIG5 = Path("configs/filipkovsky2016_fig5.toml")


@pytest.fixture(scope="module")
def ns_branch():
    """The 15 deg branch of Fig. 2b/3 (support vibration alone) from 590 to 700 Hz: two fold
    pairs and the Neimark-Sacker pair between them (~15 s)."""
    text = FIG2B.read_text().replace("support_frequency = {start = 300.0, stop = 800.0, step = 5.0}",
                                     "support_frequency = {start = 590.0, stop = 700.0, step = 5.0}")
    cfg = config.parse_config(text.replace("nominal_angle = [15, 26, 36]", "nominal_angle = [15]"))
    (where,) = continuation.plan(cfg.scene).lines
    return cfg, where, continuation.continue_line(cfg.scene, where)[0]


def test_transient_leaves_the_torus_unstable_orbit_beating_and_settles_on_the_stable_one(ns_branch):
    """At the branch point nearest 627.3 Hz (between the NS points: a complex pair |lambda| > 1)
    a transient started on the orbit (perturbed by 1e-4 of its size) leaves it as the
    multipliers say: the stroboscopic distance grows by |lambda| per period (fit over periods
    5-40, still linear: distance < 2 % of the orbit; 3 % for the other, decaying components in
    the fit) and y_B's deviation changes sign every pi / arg(lambda) periods (the beats of
    Figs. 5-6; +-30 %: a count of ~3 sign changes). After 400 periods it sits on a stable
    period-1 orbit of smaller amplitude (the lower branch's: Newton from there converges,
    stable): the unstable orbit's beating is a transient, not an attractor."""
    cfg, where, rec = ns_branch
    ns = rec["event_parameter"][rec["event_type"] == al.NEIMARK_SACKER]
    assert ns.size == 2
    i = int(np.argmin(np.abs(rec["parameter"] - 627.3)))
    assert ns.min() < rec["parameter"][i] < ns.max()
    mult = rec["multipliers"][i]
    lead = mult[np.argmax(np.abs(mult))]
    assert abs(lead) > 1.0 and abs(lead.imag) > 0.05
    built = compute.builder(cfg.scene)({**cfg.scene.fixed, **where,
                                       "support_frequency": rec["parameter"][i]})
    opts = cfg.scene.integrator
    u = rec["state"][i]
    start = u + 1e-4 * np.abs(u).max() * np.random.default_rng(0).standard_normal(u.size)
    strobe = shooting.sample_orbit(SPEC.kernel, start, built.p, 400.0, 400, opts)
    distance = np.abs(strobe - u).max(axis=1)
    assert distance[40] < 0.02 * np.abs(u).max()
    growth = np.exp(np.polyfit(np.arange(5, 41), np.log(distance[5:41]), 1)[0])
    assert growth == pytest.approx(abs(lead), rel=0.03)
    dev = strobe[5:90, 3] - u[3]
    spacing = np.diff(np.flatnonzero(np.diff(np.sign(dev)) != 0)).mean()
    assert spacing == pytest.approx(np.pi / abs(np.angle(lead)), rel=0.3)
    # period-1 by now: |multiplier| 0.966 on the stable orbit, ~200 periods since the landing
    assert np.abs(strobe[-1] - strobe[-2]).max() < 1e-3 * np.abs(strobe[-1]).max()
    sol = kc.solve_orbit(SPEC, built.p, opts, [strobe[-1]], cold_guess=SPEC.cold_guess, tol=1e-9)
    assert sol.status == shooting.CONVERGED and sol.stable
    assert np.abs(sol.state - u).max() > 0.1 * np.abs(u).max()
    assert _half_pp_y_b(built, sol.state, 1, opts)[0] < _half_pp_y_b(built, u, 1, opts)[0]


def test_fig5_point_with_the_unbalance_on_beats_on_a_forced_torus():
    """configs/filipkovsky2016_fig5.toml: 627.3 / 250 Hz is no ratio of small integers, so the
    forcing is quasi-periodic: no orbit, and the attractor (Poincare once per shaft revolution)
    is the forced torus, quasi_periodic, not period-1: its y_B samples spread over a band (beats)
    while its Lyapunov exponents are all negative (a forced torus contracts)."""
    from rotorsweep.pipeline import schema, scene
    cfg = config.load_config(FIG5)
    data = scene.from_data({**cfg.data, "analysis": {**cfg.data["analysis"], "transient_periods": 200,
                                                     "lyapunov_max_periods": 200}})
    out = compute.solve_segment(data, [{**data.fixed, "speed": 250.0, "support_frequency": 627.3,
                                        "nominal_angle": 15.0}])
    assert out["periodic_forcing"][0] == 0.0
    assert schema.ATTRACTOR[int(out["attractor"][0])] == "quasi_periodic"
    assert out["lle"][0] < 0
    y = out["poincare_y_B"][0]
    assert np.ptp(y) > 0.1 * np.abs(y).max()

"""One orbit, one record (issue 32 item 3): the Bai 2006 rotor's continuation at 15.2 and 19 um
lists each located orbit once, claims coexistence only between distinct orbits, and its band
map, `info` and coexistence table agree."""
import itertools
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rotorsweep.pipeline import coexistence, config, continuation, continuation_result
from tests.reference import BaiPoint


def bai_line(clearance):
    text = Path("configs/bai2006_fold.toml").read_text().replace(
        "clearance = [7.6e-6, 19.0e-6]", f"clearance = [{clearance!r}]")
    scene = config.parse_config(text).scene
    pl = continuation.plan(scene)
    records = continuation.continue_line(scene, pl.lines[0])
    return scene, continuation.to_dataset(scene, pl, [(pl.lines[0], records)], {})


@pytest.fixture(scope="module")
def bai15():
    return bai_line(15.2e-6)


@pytest.fixture(scope="module")
def bai19():
    return bai_line(19.0e-6)


# samples per forcing period of the reference curves: a point of a curve lies within one sample
# spacing of its samples, far below the distance between distinct orbits (O(1) scaled units)
SAMPLES = 600


def reference_curve(spec, ds, e, clearance):
    """The located orbit of event e integrated again with scipy (tests.reference: SI, no kernel
    code) over its k forcing periods: samples in the kernel's scaled units, and their spacing."""
    lam, k = float(ds["event_parameter"].values[e]), int(ds["branch_periods"].values[ds["event_branch"].values[e]])
    ref = BaiPoint(lam, clearance)
    scale = spec.to_physical(np.ones(spec.n_state), ref.period)
    t = np.linspace(0.0, k * ref.period, k * SAMPLES + 1)
    sol = solve_ivp(ref.rhs, (0.0, t[-1]), ds["event_state"].values[e] * scale, method="DOP853", rtol=1e-11,
                    atol=1e-14, t_eval=t)
    curve = sol.y.T / scale
    # closed: the orbit returns to its start after k periods (the located orbit is one)
    assert np.abs(curve[-1] - curve[0]).max() < 1e-5 * max(1.0, np.abs(curve).max())
    return k, curve, np.linalg.norm(np.diff(curve, axis=0), axis=1).max()


# Events of one kind and period closer than this in the parameter [Hz] are candidates for one
# orbit: far above the location tolerance of the bifurcation points (1e-9 Hz) and of the peaks
# (their copies agree to 2e-5 Hz on the flat period-4 peak, within their stated errors), far below
# the gaps between distinct events of one kind (> 0.05 Hz here); the curves decide.
WINDOW = {continuation.al.PEAK: 3e-3}


def independent_count(spec, ds, clearance):
    """Distinct located orbits: events of one kind and period at one parameter (within WINDOW,
    else 1e-6 Hz) whose curves coincide as closed curves (every sample of one within a sample
    spacing of the other's) are one."""
    kept = []
    for e in range(ds.sizes["event"]):
        kind, lam = int(ds["event_type"].values[e]), float(ds["event_parameter"].values[e])
        k, curve, spacing = reference_curve(spec, ds, e, clearance)
        same = [K for K in kept if K[0] == (kind, k) and abs(K[1] - lam) < WINDOW.get(kind, 1e-6) and
                np.linalg.norm(curve[:, None, :] - K[2][None, ::7, :], axis=2).min(axis=0).max() <= 2 * spacing]
        if not same:
            kept.append(((kind, k), lam, curve))
    return len(kept)


def test_bai_15um_lists_each_orbit_once_and_claims_no_coexistence_between_copies(bai15):
    scene, ds = bai15
    distinct = coexistence.distinct_events(ds)
    assert len(distinct) < ds.sizes["event"]         # the period-2 and -4 loops meet their points several times
    assert len(distinct) == independent_count(scene.model, ds, 15.2e-6)
    # one response peak per period: the period-1 curve's (between its folds), the period-2 and -4 loops'
    peaks = [e for e in distinct if ds["event_type"].values[e] == continuation.al.PEAK]
    assert sorted(ds["branch_periods"].values[ds["event_branch"].values[peaks]]) == [1, 2, 4]
    assert len(continuation_result.events_table(ds)["type"]) == len(distinct)
    # the only coexistence: the period-1 fold pair (31.05-31.15 Hz), both outer arms stable
    folds = sorted(ds["event_parameter"].values[ds["event_type"].values == continuation.al.FOLD])
    (iv,) = coexistence.bistable_intervals(ds)
    assert iv["branches"] == [0] and (iv["lo"], iv["hi"]) == pytest.approx(tuple(folds), rel=1e-12)


def test_bai_19um_band_map_info_and_table_agree(bai19):
    _, ds = bai19
    _, lines = coexistence.stability_classes(ds)
    (pieces,) = lines.values()
    rows = coexistence.bistable_intervals(ds)
    width = 30.0
    bands = [(lo, hi) for lo, hi, n in pieces if n >= 2 and hi - lo > 1e-9 * width]
    covered = lambda ivs, x: any(lo <= x <= hi for lo, hi in ivs)  # noqa: E731
    for x in np.linspace(20.0, 50.0, 3001):
        assert covered(bands, x) == covered([(r["lo"], r["hi"]) for r in rows], x)
    info = continuation_result.describe(ds)
    assert info.count("two stable orbits coexist") == len(rows)
    for r in rows:
        assert f"{r['lo']:.10g} to {r['hi']:.10g}" in info
    # the period-4 branch's copies (40.1-41.6 Hz) are one orbit: no band there
    assert not covered(bands, 41.0)


def test_bai_15um_lists_each_branch_once(bai15):
    """Whole branches that are one family of closed orbits (the period-2 loop reached from both
    its period doublings, a period-4 branch met from another phase) are marked (branch_copy_of)
    and listed once by info. Independently: branches of one period whose located bifurcation
    orbits coincide as closed curves (scipy, reference_curve) are one family; a branch without
    such an event is its own."""
    scene, ds = bai15
    spec = scene.model
    copy_of = coexistence.branch_copy_of(ds)
    family = list(range(ds.sizes["branch"]))

    def root(b):
        while family[b] != b:
            b = family[b]
        return b
    curves = [(int(ds["event_branch"].values[e]), e, *reference_curve(spec, ds, e, 15.2e-6))
              for e in range(ds.sizes["event"]) if ds["event_type"].values[e] != continuation.al.PEAK]
    for (b1, e1, k1, c1, sp1), (b2, e2, k2, c2, sp2) in itertools.combinations(curves, 2):
        same_kind = ds["event_type"].values[e1] == ds["event_type"].values[e2]
        same_period = ds["branch_periods"].values[b1] == ds["branch_periods"].values[b2]
        near = abs(ds["event_parameter"].values[e1] - ds["event_parameter"].values[e2]) < 1e-6
        if b1 != b2 and same_kind and same_period and near and \
                np.linalg.norm(c1[:, None, :] - c2[None, ::7, :], axis=2).min(axis=0).max() <= 2 * max(sp1, sp2):
            family[max(root(b1), root(b2))] = min(root(b1), root(b2))
    expected = [root(b) for b in range(ds.sizes["branch"])]
    assert copy_of.tolist() == expected
    assert len(coexistence.distinct_branches(ds)) < ds.sizes["branch"]     # the loop is met twice
    info = continuation_result.describe(ds)
    assert f"({len(coexistence.distinct_branches(ds))} distinct" in info
    assert sum(line.startswith("  branch ") for line in info.splitlines()) == len(coexistence.distinct_branches(ds))


def scipy_half_swing_slope(lam, guess, k, clearance, width=1e-4):
    """d(half peak-to-peak x)/d(speed) [m/Hz] of the period-k orbit at `lam` by scipy alone
    (tests.reference.BaiPoint: SI, no kernel code): the orbits at lam +- width by chord Newton on
    the k-period map (DOP853 at rtol 1e-13, the Jacobian by central differences once, at lam, from
    `guess` [SI]), half peak-to-peak x by test_extrema.scipy_extremes (a bounded search on the
    dense output), their central difference: noise ~1e-12 A / (2 width) = 5e-9 A per Hz, truncation
    width^2 A''' / 6 ~ 2e-9 A per Hz (A''' ~ A'' / 0.1 Hz), both far below the slope 1e-7 relative
    away from the peak, A'' 3.3e-6 Hz ~ 4e-7 A per Hz."""
    from tests.test_extrema import scipy_extremes

    def k_map(ref, u):
        return solve_ivp(ref.rhs, (0.0, k * ref.period), u, method="DOP853", rtol=1e-13,
                         atol=1e-16 * np.abs(u).max()).y[:, -1]
    ref0 = BaiPoint(lam, clearance)
    scale = np.array([1e-6, 1e-6, 1e-6 / ref0.period, 1e-6 / ref0.period])
    jac = np.array([(k_map(ref0, guess + d) - k_map(ref0, guess - d)) / (2 * d[i])
                    for i, d in enumerate(np.diag(1e-4 * scale))]).T - np.eye(4)
    swing = []
    for v in (lam - width, lam + width):
        ref, u = BaiPoint(v, clearance), np.array(guess, float)
        for _ in range(8):      # the chord's rate ~ |jac^-1 d jac| ~ 1e-3: 1e-13 in ~5 steps
            u = u - np.linalg.solve(jac, k_map(ref, u) - u)
        hi, lo = scipy_extremes(ref.rhs, u, k * ref.period, np.array([[1.0]]))
        swing.append(0.5 * (hi[0] - lo[0]))
    return (swing[1] - swing[0]) / (2 * width)


def test_bai_15um_peak_copies_agree_within_their_errors_and_distinct_peaks_do_not(bai15):
    """Each located peak's parameter error (event_parameter_error): every two copies of one orbit's
    peak (the period-2 loop's, the flat period-4 one's: 5.6e-7 relative apart) lie within the sum
    of their stated errors, so coexistence merges them; the three distinct peaks (periods 1, 2, 4)
    lie farther apart than their errors' sum (they are not merged; 0.06 Hz and more against
    errors below 1e-4 Hz). Measured against a run at rtol 1e-12, Newton 1e-11 (each default-run
    peak within its error of it: period 4 up to 1.25e-5 Hz off with 9.5e-5 stated)."""
    _, ds = bai15
    kinds, lams = ds["event_type"].values, ds["event_parameter"].values
    errors, periods = ds["event_parameter_error"].values, ds["branch_periods"].values[ds["event_branch"].values]
    peaks = np.flatnonzero(kinds == continuation.al.PEAK)
    assert np.all(np.isfinite(errors[peaks]) & (errors[peaks] > 0.0))
    assert np.isnan(errors[kinds != continuation.al.PEAK]).all()
    for i, j in itertools.combinations(peaks, 2):
        apart = abs(lams[i] - lams[j])
        assert (apart <= errors[i] + errors[j]) == (periods[i] == periods[j])
    distinct = coexistence.distinct_events(ds)
    assert sorted(periods[np.intersect1d(distinct, peaks)]) == [1, 2, 4]


def test_bai_15um_period_2_peak_brackets_the_scipy_slope_zero(bai15):
    """The period-2 loop's response peak (half peak-to-peak x, the plotted observable) lies
    within 1e-7 relative of the zero of its slope along the orbits by scipy alone: the scipy
    slope changes sign between the peak's speed - 1e-7 and + 1e-7 relative. Its copies (the loop
    met from both its period doublings, both halves) agree to 2e-7 relative (the amplitude's
    slope along the branch from the tangent-linear solution at the extremes' times; the contact
    force's C^1 leaves ~2e-8 of the flat peak's curvature, A'' ~ 0.13 A per Hz^2)."""
    scene, ds = bai15
    spec = scene.model
    def peaks_of(k):
        return [e for e in range(ds.sizes["event"]) if ds["event_type"].values[e] == continuation.al.PEAK and
                ds["branch_periods"].values[ds["event_branch"].values[e]] == k]
    peaks = peaks_of(2)
    lams = ds["event_parameter"].values[peaks]
    assert len(peaks) >= 2 and np.ptp(lams) <= 2e-7 * lams.mean()     # measured 2.3e-8
    e = coexistence.distinct_events(ds)[np.isin(coexistence.distinct_events(ds), peaks)][0]
    lam = float(ds["event_parameter"].values[e])
    guess = ds["event_state"].values[e] * spec.to_physical(np.ones(spec.n_state), BaiPoint(lam, 15.2e-6).period)
    below, above = (scipy_half_swing_slope(lam * (1 + sign * 1e-7), guess, 2, 15.2e-6) for sign in (-1.0, 1.0))
    assert below > 0.0 > above

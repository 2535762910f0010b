"""Events of a torus branch (rotorsweep.pipeline.torus_events): a locked ratio omega / Omega = 3/5 passed by
the branch of the preloaded rotor is recognized, solved there and linked to the periodic orbit of
5 shaft turns, which is checked against a torus solved independently at that ratio and against
the multipliers composed from one-turn flows along the circle; the ratio search and the fold flag
on their own; the report's torus in detail."""
from types import SimpleNamespace

import numpy as np
import pytest

from rotorsweep.pipeline import cli, config, continuation, continuation_result, torus_branches
from rotorsweep.kernels import integrators as ig, torus as tr
from rotorsweep.kernels.continuation import events as ev, tori

SCENE = "configs/filipkovsky2016_fig2b_tori.toml"
OMEGA = 250.0       # the scene's shaft speed [Hz]: 3/5 is at 150 Hz


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    d = tmp_path_factory.mktemp("locked")
    text = open(SCENE).read().replace("stop = 315.0", "stop = 150.3").replace("start = 305.0", "start = 149.8").replace(
        "support_frequency = [305.0]", "support_frequency = [145.0]")
    (d / "locked.toml").write_text(text)
    assert cli.main(["continue", str(d / "locked.toml"), "-o", str(d / "locked.nc"), "--workers", "0"]) in (0, None)
    return continuation_result.open_result(d / "locked.nc"), config.parse_config(text).scene


def test_the_branch_lists_the_locked_ratio_in_the_events_and_info(result, capsys, tmp_path):
    ds, _ = result
    k = np.flatnonzero(ds["event_type"].values == ev.LOCKED)
    assert len(k) == 1
    # solved exactly at 3/5 Omega (Brent on the rotation to 1e-13, then the torus solved there)
    assert ds["event_parameter"].values[k[0]] == pytest.approx(0.6 * OMEGA, rel=1e-12)
    note = str(ds["event_note"].values[k[0]])
    assert note.startswith("3/5: torus stable") and "5 shaft turns linked" in note
    table = continuation_result.events_table(ds)
    assert table["type"] == ["locked"] and table["note"] == [note] and table["stable"] == [1]
    assert table["periods"] == [5] and ds["branch_periods"].values.tolist() == [1]    # the linked orbit's q
    assert ds["event_amplitude_half_pp"].values[k[0]].max() > 0


def test_the_linked_orbit_lies_on_an_independently_solved_torus(result):
    """The event's orbit (shooting over 5 turns) against a torus solved by collocation at 150 Hz from
    a constant guess (tol 1e-12, nodes grown to a 1e-9 tail): both are solved far below 1e-8, so
    they agree to 1e-8 in the scaled state (um, um per turn). Its multipliers against the
    product of the five one-turn monodromies along the circle (theta_k = 3/5 * 2 pi k), each flown
    from the independent circle: the monodromy of the orbit composed, to the integration's 1e-10
    and the circles' distance times the flow's Lipschitz constant, hence 1e-7."""
    ds, data = result
    k = int(np.flatnonzero(ds["event_type"].values == ev.LOCKED)[0])
    state = ds["event_state"].values[k]
    pl = continuation.plan(data)
    family, _ = torus_branches.torus_family(data, pl, pl.lines[0], 15)
    spec = data.model
    lam = 0.6 * OMEGA
    p = np.array(family.params(lam), float)
    circle = tr.solve_torus(spec.kernel, tr.periodic_guess(state, 15), p, family.phase_index, family.rotation(lam),
                            family.opts, tol=1e-12, decay_tol=1e-9, max_nodes=63)
    assert circle.status == tr.CONVERGED
    assert np.abs(circle.at(0.0)[0] - state).max() < 1e-8
    n = spec.n_state
    product = np.eye(n)
    for j in range(5):
        theta = family.rotation(lam) * j
        p[family.phase_index] = theta
        z, status, _, _ = ig.flow(spec.kernel, 0.0, 1.0, ig.initial_state(circle.at(theta)[0], n, True), p, True,
                                  family.opts, 0.0)
        assert status == ig.STATUS_OK
        product = z[n:].reshape(n, n) @ product
    mult = ds["event_multiplier_real"].values[k] + 1j * ds["event_multiplier_imag"].values[k]
    composed = np.linalg.eigvals(product)
    assert np.sort(np.abs(mult)) == pytest.approx(np.sort(np.abs(composed)), abs=1e-7)


def test_locked_ratios_are_the_fractions_of_small_denominator_in_the_range():
    """rho(lambda) = 2 pi lambda / 10 over [5.5, 7.6]: ratios 0.55 .. 0.76; with q <= 5 the
    fractions 3/5, 2/3, 3/4 at lambda = 6, 20/3, 7.5 (closed form)."""
    family = SimpleNamespace(rotation=lambda v: 2.0 * np.pi * v / 10.0)
    found = tori.locked_ratios(family, (7.6, 5.5), 5)
    assert [(e.p, e.q) for e in found] == [(3, 5), (2, 3), (3, 4)]
    assert [e.level for e in found] == pytest.approx([6.0, 20.0 / 3.0, 7.5], rel=1e-13)
    assert all(e.code == ev.LOCKED and e.label == f"locked {e.p}/{e.q}" for e in found)


def test_a_fold_of_tori_is_flagged_where_the_tangent_turns_back_in_lambda():
    def at(dlam):
        return SimpleNamespace(tangent=np.array([0.3, dlam]))
    assert tori.Fold().detect(None, at(0.2), at(-0.1)) and not tori.Fold().detect(None, at(0.2), at(0.1))


def test_the_torus_in_detail_passes_its_once_per_turn_points_through_the_circle(result):
    """The report's torus in detail (rotorsweep.pipeline.report.figures.torus_detail): a trajectory from the
    circle at phase 0, integrated anew from the scene, visits the circle at phases k rho after k
    turns (the invariance the collocation solved, checked by the flow over 40 turns: the torus
    attracts, so the circle's error ~1e-8 and the integration's 1e-10 do not grow; 1e-6 in the
    scaled state). The point drawn: the largest half-swing, or the one nearest [report] torus_detail."""
    from rotorsweep.pipeline.report.figures import torus_detail as td

    ds, data = result
    d = td.torus_detail(ds, data)
    n = int(ds["branch_points"].values[0])
    j = list(ds["observable"].values).index("y_B")
    assert d.point == int(np.argmax(ds["amplitude_half_pp"].values[0, :n, j])) and d.names == ("z", "y_B")
    strobe = d.states[::td.SAMPLES_PER_TURN]
    expected = d.torus.at(d.torus.rho * np.arange(len(strobe)))
    assert np.abs(strobe - expected).max() < 1e-6
    assert d.spectrum[-1] < 1e-7 * d.spectrum[0]       # resolved: the branch's breakdown test passed
    assert td.chosen_point(ds, 150.0) == (0, int(np.argmin(np.abs(ds["parameter"].values[0, :n] - 150.0))))


def test_the_continuation_report_draws_the_torus_in_detail(result, tmp_path):
    ds, _ = result
    from rotorsweep.pipeline.report import branch_result

    branch_result.make_report(ds, tmp_path / "report")
    assert (tmp_path / "report" / "torus_detail.png").exists()
    text = (tmp_path / "report" / "report.html").read_text()
    assert "A torus in detail" in text and "locked" in text and "3/5: torus stable" in text


def test_each_stored_circle_lies_within_its_error_estimate_of_a_finer_torus(result):
    """The stored circles are polished to a residual of 1e-12 (relative) at their parameter
    (torus_branches.POLISH_TOL), so the estimate is at its floor at every point, not the corrector's
    1e-9 relative residual times ||dR/dU^-1|| (up to 1.6e-6 before, docs/guide/continue.md). Each
    against a finer torus solved anew at its parameter: 31 nodes, integration tolerances 100x
    tighter, Newton to 1e-13: the distance (discretization, integration and solve together) lies
    below the estimate."""
    ds, data = result
    pl = continuation.plan(data)
    family, _ = torus_branches.torus_family(data, pl, pl.lines[0], 15)
    spec = data.model
    fine = family.opts._replace(rtol=family.opts.rtol / 100, atol=family.opts.atol / 100)
    n = int(ds["branch_points"].values[0])
    err = ds["torus_error"].values[0, :n]
    # the floor of the estimate (the shots' integration error against the fine flow, 9e-9 to 1.1e-8
    # here) rather than the corrector's residual, which varied by orders of magnitude between points
    assert err.max() < 1e-7 and err.max() < 2.0 * err.min()
    for k in (0, n - 1):
        lam = float(ds["parameter"].values[0, k])
        nodes = ds["torus_nodes"].values[0, k]
        fresh = tr.solve_torus(spec.kernel, tr.resample(nodes, 31), family.params(lam), family.phase_index,
                               family.rotation(lam), fine, tol=1e-13, decay_tol=1.0)
        assert fresh.status == tr.CONVERGED
        assert np.abs(fresh.at(tr.node_phases(15)) - nodes).max() <= ds["torus_error"].values[0, k]


def test_the_locked_marker_sits_on_the_torus_curve_and_its_hover_reads_the_linked_orbit(result):
    """The response panel's locked 3/5 marker: its y is the torus curve's half-swing at the event
    parameter, here np.interp over the branch's points (monotone in the parameter on this short
    branch), the same piecewise-linear curve the panel draws, so they agree to rounding (1e-12
    relative). Linear interpolation's own error against the torus at 150 Hz is h^2/8 max|y''|, below
    the two neighbouring points' spread, so the marker lies between them. The linked orbit at theta = 0
    is one of the torus's locked orbits: its half-swing (the hover's) is at most the torus's (the
    maximum over all phases), to that spread plus the torus amplitude's phase-sampling shortfall
    (64 phases: ~1e-4 relative, rotorsweep.pipeline.torus_points; 2e-4 allowed, 7e-5 seen)."""
    from rotorsweep.pipeline.report import branch_result
    from tests.figure_checks import assert_legend_hover_and_width, plots_of

    ds, _ = result
    k = int(np.flatnonzero(ds["event_type"].values == ev.LOCKED)[0])
    n = int(np.isfinite(ds["parameter"].values[0]).sum())
    main = ds.attrs.get("report_observable") or str(ds["observable"].values[0])
    x, j = ds["parameter"].values[0, :n], list(ds["observable"].values).index(main)
    y = ds["amplitude_half_pp"].values[0, :n, j] * 1e6
    at = ds["event_parameter"].values[k]
    order = np.argsort(x)
    expected = np.interp(at, x[order], y[order])
    response = [f for f in branch_result.figures(ds, "bokeh") if f[1].startswith("response_")]
    sources = [r.data_source.data for _, plot in plots_of(response) for r in plot.renderers
               if "linked_orbit" in getattr(getattr(r, "data_source", None), "data", {})]
    assert len(sources) == 1
    marker_y, orbit_y = sources[0][main][0], sources[0]["linked_orbit"][0]
    assert marker_y == pytest.approx(expected, rel=1e-12)
    i = int(ds["event_point"].values[k])
    lo, hi = sorted(y[i:i + 2])
    assert lo <= marker_y <= hi
    assert orbit_y == pytest.approx(ds["event_amplitude_half_pp"].values[k, j] * 1e6, rel=1e-12)
    assert orbit_y <= marker_y * (1 + 2e-4) + (hi - lo)
    assert continuation_result.events_table(ds)["amplitudes_of"] == ["linked orbit at theta = 0"]
    hovers = [t for _, plot in plots_of(response) for tool in plot.tools if hasattr(tool, "tooltips")
              for t in (tool.tooltips or [])]
    assert any(str(label).startswith("linked orbit at θ = 0") for label, _ in hovers)
    assert_legend_hover_and_width(response)


def test_a_locked_marker_on_a_branch_that_turns_back_is_on_its_own_segment():
    """Past a fold the parameter is not monotone: the value comes from the event's segment (points
    2 and 3, y = 2 + 2 (2 - x) on the leg going back), not from the first leg at the same parameter
    (closed form: 2 + 2 * 0.25 = 2.5; the first leg, y = x, would read 1.75)."""
    from rotorsweep.pipeline.report.figures import locked_marks

    x, y = [0.0, 1.0, 2.0, 1.5], [0.0, 1.0, 2.0, 3.0]
    assert locked_marks.curve_value(x, y, 2, 1.75) == pytest.approx(2.5, rel=1e-15)
    assert locked_marks.curve_value(x, y, 3, 1.5) == 3.0      # the branch's last point: its own value

"""The scenes of Filipkovsky 2016, Figs. 3a, 3b, 4a, 4b (both forcings on, the bearing law as
printed): each validates with the law as printed and its bearing row, and one of them started on a
short range follows a torus whose half-swing a long scipy DOP853 run from its circle confirms."""
import pytest

from rotorsweep.pipeline import cli, config, continuation, continuation_result, torus_branches
from rotorsweep.pipeline import scene as scene_mod
from tests.reference import torus_half_swing

SCENES = {"3a": 15, "3b": 15, "4a": 26, "4b": 36}


@pytest.mark.parametrize("fig", sorted(SCENES))
def test_each_scene_is_the_paper_s_two_frequency_sweep_with_the_law_as_printed(fig):
    data = config.parse_config(open(f"configs/filipkovsky2016_fig{fig}.toml").read()).data
    assert data["bearing"]["preload_law"] == "as_printed" and data["bearing"]["table"] == "filipkovsky2016"
    assert data["sweep"]["nominal_angle"] == [SCENES[fig]] and data["sweep"]["speed"] == [250.0]
    assert data["forcing"]["support_acceleration"] > 0 and data["forcing"]["eccentricity"] > 0
    pl = continuation.plan(scene_mod.from_data(data))
    assert pl.parameter == "support_frequency"
    assert torus_branches.is_torus_line(scene_mod.from_data(data), pl.parameter, pl.start, pl.lines[0])


def test_fig4b_starts_a_stable_torus_confirmed_by_a_transient(tmp_path):
    """36 deg, 100 to 100.4 Hz: a torus branch, stable; its last point's half-swing of y_B against
    150 turns of DOP853 (rtol 1e-10) from its circle (as tests/test_torus_continue.py: both sample
    the sup from below, ~1e-3 relative at most)."""
    text = open("configs/filipkovsky2016_fig4b.toml").read().replace("stop = 1300.0", "stop = 100.4")
    (tmp_path / "fig4b.toml").write_text(text)
    assert cli.main(["continue", str(tmp_path / "fig4b.toml"), "-o", str(tmp_path / "fig4b.nc"), "--workers", "0"]) in (0, None)
    ds = continuation_result.open_result(tmp_path / "fig4b.nc")
    n = int(ds["branch_points"].values[0])
    assert ds["branch_kind"].values.tolist() == [1] and (ds["torus_status"].values[0, :n] == 1).all()
    j = list(ds["observable"].values).index("y_B")
    assert ds["amplitude_half_pp"].values[0, n - 1, j] == pytest.approx(
        torus_half_swing(config.parse_config(text).scene, ds, n - 1), rel=1e-3)


def test_a_branch_ending_in_breakdown_gives_event_rows_without_the_end(tmp_path):
    """Fig. 3a's full range once stopped with a KeyError: the branch ended torus_breakdown, and the
    ending event reached the event rows, which know only flags and locked ratios. The end is the
    branch's end reason and detail, never an event (duffing2, as tests/test_tori_continuation.py
    forces the breakdown: a decay tolerance no circle meets)."""
    import numpy as np

    from rotorsweep.kernels import integrators as ig, torus as tr
    from rotorsweep.kernels.continuation import engine, tori
    from rotorsweep.kernels.models import duffing2, get
    from rotorsweep.pipeline import torus_events

    model = get("duffing2")
    opts = ig.settings(rtol=1e-11, atol=1e-13)

    def params(w2):
        return np.array([2.0, 0.1, 0.5, 1.0, 0.5, w2, 0.0])
    fam = tori.TorusFamily(model.kernel, params, lambda w2: w2, duffing2.P_PHASE, opts, 7, decay_tol=1e-30)
    w2 = 2.0 * np.pi * 0.55
    circle = tr.solve_torus(model.kernel, np.zeros((7, 2)), params(w2), duffing2.P_PHASE, w2, opts, max_nodes=7)
    run = tori.follow_tori(fam, tori.start(fam, w2, circle.nodes), (w2, w2 + 0.5), engine.Settings(ds=0.2, max_steps=10))
    assert run.end == engine.TORUS_BREAKDOWN and run.found == []
    rows = torus_events.event_rows(model, fam, None, run, np.zeros((len(run.points), 2, 1)))
    assert rows["event_type"].size == 0 and rows["event_state"].shape == (0, 2) and rows["event_note"] == []


def test_a_sign_change_of_the_exponent_flags_even_between_undecided_points():
    """Next to the fold of configs/filipkovsky2016_torus_fold.toml over 380-420 Hz the largest
    normal exponent went -0.71 -> +0.31 1/s between two undecided points (within their error of 0):
    TS must flag there (the sign is what the flag means), and never where an exponent is NaN."""
    import numpy as np

    from rotorsweep.kernels import torus as tr
    from rotorsweep.kernels.continuation import tori

    def point(exponent, status):
        return tori.Point(None, 0.0, None, 0, 0.0, 0.0, tr.Stability(np.array([exponent, -5.0]), 1.0, status, ""), None)
    flag = tori.StabilityChange().detect
    assert flag(None, point(-0.71, tr.UNDECIDED), point(0.31, tr.UNDECIDED))
    assert flag(None, point(-3.0, tr.STABLE), point(2.0, tr.UNSTABLE))
    assert not flag(None, point(-3.0, tr.STABLE), point(-0.2, tr.UNDECIDED))
    assert not flag(None, point(np.nan, tr.UNDECIDED), point(2.0, tr.UNSTABLE))

"""The scenes of Filipkovsky 2016, Figs. 3a, 3b, 4a, 4b (both forcings on, the bearing law as
printed): each validates with the law as printed and its bearing row, and one of them started on a
short range follows a torus whose half-swing a long scipy DOP853 run from its circle confirms."""
import pytest

from rotorsweep.pipeline import cli, config, continuation, torus_branches
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
    ds = continuation.open_result(tmp_path / "fig4b.nc")
    n = int(ds["branch_points"].values[0])
    assert ds["branch_kind"].values.tolist() == [1] and (ds["torus_status"].values[0, :n] == 1).all()
    j = list(ds["observable"].values).index("y_B")
    assert ds["amplitude_half_pp"].values[0, n - 1, j] == pytest.approx(
        torus_half_swing(config.parse_config(text).scene, ds, n - 1), rel=1e-3)

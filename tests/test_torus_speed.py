"""`rotorsweep continue` of tori in the shaft speed Omega (the support frequency omega fixed, the
ratio omega / Omega moving) on the two-frequency scene: a short range through omega / Omega = 6/5,
the locked ratio found at Omega = omega * 5/6 (closed form), and the last point's half-swing against
a long scipy DOP853 run from its circle (a second method: the flow, not the collocation)."""
import numpy as np
import pytest

from rotorsweep.pipeline import cli, config, continuation_result
from rotorsweep.kernels.continuation import events as ev
from tests.reference import torus_half_swing

SCENE = "configs/filipkovsky2016_fig2b_tori.toml"
SUPPORT = 300.0     # omega [Hz], fixed on the line: 6/5 of Omega at 250 Hz


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    d = tmp_path_factory.mktemp("speed")
    text = open(SCENE).read().replace(
        'parameter = "support_frequency"\nstart = 305.0\nstop = 315.0', 'parameter = "speed"\nstart = 249.6\nstop = 250.4').replace(
        "support_frequency = [305.0]", f"support_frequency = [{SUPPORT}]")
    (d / "speed.toml").write_text(text)
    assert cli.main(["continue", str(d / "speed.toml"), "-o", str(d / "speed.nc"), "--workers", "0"]) in (0, None)
    return continuation_result.open_result(d / "speed.nc"), config.parse_config(text).scene


def test_tori_are_followed_in_the_shaft_speed_through_a_locked_ratio(result):
    ds, _ = result
    assert ds.attrs["parameter"] == "speed" and ds["branch_kind"].values.tolist() == [1]
    assert float(ds["support_frequency"].values[0]) == SUPPORT
    n = int(ds["branch_points"].values[0])
    lam = ds["parameter"].values[0, :n]
    assert lam[0] == pytest.approx(249.6) and lam[-1] == pytest.approx(250.4)
    assert (ds["torus_status"].values[0, :n] == 1).all() and (ds["torus_error"].values[0, :n] < 1e-6).all()
    k = np.flatnonzero(ds["event_type"].values == ev.LOCKED)
    assert len(k) == 1 and ds["event_parameter"].values[k[0]] == pytest.approx(SUPPORT * 5 / 6, rel=1e-12)
    assert str(ds["event_note"].values[k[0]]).startswith("6/5: torus stable; periodic orbit of 5 shaft turns linked")


def test_the_last_point_against_a_long_scipy_transient(result):
    """As tests/test_torus_continue.py: the half-swing of y_B over 150 turns of a DOP853 run (rtol
    1e-10) from the circle at phase 0 covers the torus (the ratio 300 / 250.4 is not one of small
    integers); both sample the sup from below, ~1e-3 relative at most."""
    ds, data = result
    k = int(ds["branch_points"].values[0]) - 1
    j = list(ds["observable"].values).index("y_B")
    assert ds["amplitude_half_pp"].values[0, k, j] == pytest.approx(torus_half_swing(data, ds, k), rel=1e-3)

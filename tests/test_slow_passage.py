"""Slow passage past a fold (issue 15, item 10): trajectories linger near the vanished orbit for
many periods, so a fixed 30-period transient left Newton outside its basin at 31.2 Hz / 15.2 um
(Bai 2006, Fig. 13) although a stable orbit exists there."""
from pathlib import Path

import numpy as np
import pytest

import rotorsweep.pipeline as pipeline
from rotorsweep.pipeline import compute, config, sweep
from rotorsweep.kernels import shooting

ROOT = Path(__file__).resolve().parents[1]
FIG13 = (ROOT / "configs" / "bai2006_fig13.toml").read_text()


def test_stable_orbit_just_past_the_fold_is_found_and_is_the_attractor():
    """The orbit the solver finds is confirmed independently: 2000 periods integrated from the
    cold start (the static equilibrium guess) end on it. The distance left after 2000 periods is
    the slow passage's remainder times max|lambda|^n (0.68 per period once it arrives), far below
    1e-6 um, plus the integration error (rtol 1e-10 over 2000 periods, ~1e-7 relative)."""
    cfg = config.parse_config(FIG13, allow_large=True)
    row = pipeline.point(speed=31.2, clearance=15.2e-6, config=cfg)
    assert row["orbit_status"] == 0 and row["stable"] == 1
    spec = cfg.model
    built = compute.point_params(cfg.scene, {**cfg.scene.fixed, "speed": 31.2, "clearance": 15.2e-6})
    opts = cfg.scene.integrator
    end, status, _ = shooting.settle(spec.kernel, spec.cold_guess(built.p), built.p, 2000.0, opts)
    assert status == 0
    np.testing.assert_allclose(end, row["orbit_state"], rtol=0, atol=1e-5 * np.abs(end).max())


@pytest.mark.slow
def test_no_point_of_fig13_lacks_an_orbit_that_a_longer_transient_finds(tmp_path):
    """Every point of the Fig. 13 grid where the sweep records no orbit is re-solved with a cold
    transient ten times longer (300 periods): it must not find one there either."""
    text = FIG13.replace("attractor = true", "attractor = false")
    cfg = config.parse_config(text, allow_large=True)
    ds = pipeline.open_cube(sweep.run(cfg, tmp_path / "fig13.nc", workers=2, progress=False))
    missing = np.argwhere(ds["orbit_status"].values != 0)
    longer = config.parse_config(text.replace("[numerics]", "[numerics]\ntransient_periods = 300"),
                                 allow_large=True)
    for i, j in missing:
        speed, clearance = float(ds["speed"].values[i]), float(ds["clearance"].values[j])
        row = pipeline.point(speed=speed, clearance=clearance, config=longer)
        assert row["orbit_status"] != 0, f"{speed} Hz, {clearance} m: a longer transient finds the orbit"

"""Attractor diagnostics inside sweeps: config keys, the derive-when-stable shortcut against the
integrated exponents, continuation of the attractor with up/down sweeps (hysteresis), and the
cube variables a sweep writes."""
import numpy as np
import pytest

from rotorsweep.pipeline import cli, compute, config, cube, query, schema, sweep
from rotorsweep.kernels import attractor as at

SCENE = """
[scene]
name = "attractor"
model = "jeffcott_clearance"

[bearing]
preset = "209"
stiffness = "bai2006"

[sweep]
speed = {{start = {start}, stop = {stop}, step = {step}}}
clearance = [{clearance}]

[analysis]
attractor = true
{analysis}

[numerics]
segment_length = 64
"""


def scene(start=60.0, stop=62.0, step=1.0, clearance="3.8e-6", analysis=""):
    return config.parse_config(SCENE.format(start=start, stop=stop, step=step, clearance=clearance,
                                            analysis=analysis))


def points(cfg):
    c = cfg.axes["clearance"][0]
    return [{"speed": s, "clearance": c, "contact_angle": None, "preload": 0.0} for s in cfg.axes["speed"]]


def test_analysis_keys_are_validated():
    cfg = scene()
    assert cfg.data["analysis"] == {
        "floquet": True, "attractor": True, "derive_when_stable": True, "sweep_direction": "up",
        "transient_periods": 200, "poincare_samples": 128, "max_period": 32,
        "lyapunov_max_periods": 2000, "lyapunov_rtol": 0.02, "stop_when_settled": True,
        "lyapunov_converged_stop": True}
    bad = {
        'sweep_direction = "sideways"': "analysis.sweep_direction",
        "poincare_samples = 64": "analysis.poincare_samples: must be >= 4 x analysis.max_period",
        "max_period = 0": "analysis.max_period",
        "lyapunov_max_periods = 5": "analysis.lyapunov_max_periods",
        "lyapunov_rtol = 0": "analysis.lyapunov_rtol",
        "lyapunov_rtol = 1.5": "analysis.lyapunov_rtol",
        'stop_when_settled = "yes"': "analysis.stop_when_settled",
        'lyapunov_converged_stop = 1': "analysis.lyapunov_converged_stop",
    }
    for line, message in bad.items():
        with pytest.raises(config.ConfigError, match=message.replace(".", r"\.")):
            scene(analysis=line)
    with pytest.raises(config.ConfigError, match="nothing to compute"):
        config.parse_config(SCENE.format(start=60, stop=61, step=1, clearance="3.8e-6", analysis="")
                            .replace("attractor = true", "attractor = false\nfloquet = false"))


def test_derived_exponents_of_stable_points_match_the_integrated_ones():
    """derive_when_stable = true (exponents from the multipliers, no Lyapunov run) against
    false (Benettin/QR for every point, stopped at the pipeline's 2 % standard error) on a stable
    stretch: largest exponent to 1e-3 relative (or its stated uncertainty), and the sum of the spectrum is the flow's
    divergence -2 D / M (D = 300 N s/m, M = 2 kg) in both."""
    cfg = scene(66.0, 70.0, 2.0, "19.0e-6")       # leading multiplier real (-0.88 at 66 Hz)
    fast = compute.solve_segment(cfg.scene, points(cfg))
    slow_cfg = scene(66.0, 70.0, 2.0, "19.0e-6", "derive_when_stable = false")
    slow = compute.solve_segment(slow_cfg.scene, points(slow_cfg))
    assert np.all(fast["stable"] == 1) and np.all(fast["attractor"] == at.PERIODIC)
    assert np.all(fast["lle_method"] == schema.LLE_METHOD.index("derived"))
    assert np.all(slow["lle_method"] == schema.LLE_METHOD.index("integrated"))
    assert np.all(fast["lyapunov_periods"] == 0) and np.all(slow["lyapunov_periods"] >= 100)
    # within 1e-3 relative, or within the integrated value's own uncertainty where the early
    # stop (2 % standard error) ends a run on a complex pair of equal-modulus multipliers
    assert np.all(np.abs(fast["lle"] - slow["lle"]) <= np.maximum(1e-3 * np.abs(fast["lle"]),
                                                                  3 * slow["lle_stderr"])), (fast["lle"], slow["lle"], slow["lle_stderr"])
    assert abs(fast["lle"][0] - slow["lle"][0]) < 1e-6 * abs(fast["lle"][0])      # real multiplier
    np.testing.assert_allclose(fast["lle"], np.log(fast["max_abs_multiplier"]) / fast["forcing_period"],
                               rtol=1e-12)
    for run in (fast, slow):
        np.testing.assert_allclose(run["lyapunov_exponents"].sum(axis=1), -300.0, rtol=1e-6)
    # the section of a stable period-1 attractor is the orbit's point
    np.testing.assert_allclose(fast["poincare_x"], np.repeat(fast["orbit_state"][:, :1] * 1e-6, 128, axis=1))


def test_lyapunov_run_stops_at_the_scenes_tolerance():
    """Chaos at 30 Hz, 19 um: a run stopped at lyapunov_rtol = 0.1 against one held to 0.01
    (it runs to its 2000-period cap): fewer periods, a standard error within the tolerance, the
    same class, and the exponents within 3 combined standard errors (block estimates of the
    statistical error of each run)."""
    runs = {}
    for rtol in (0.1, 0.01):
        cfg = scene(30.0, 30.0, 1.0, "19.0e-6", f"lyapunov_rtol = {rtol}\nmax_period = 8\npoincare_samples = 32")
        runs[rtol] = compute.solve_segment(cfg.scene, points(cfg))
    fast, long = runs[0.1], runs[0.01]
    assert fast["attractor"][0] == long["attractor"][0] == at.CHAOTIC
    assert 300 <= fast["lyapunov_periods"][0] < long["lyapunov_periods"][0]
    assert fast["lle_stderr"][0] <= 0.1 * fast["lle"][0]
    assert abs(fast["lle"][0] - long["lle"][0]) <= 3 * np.hypot(fast["lle_stderr"][0], long["lle_stderr"][0])


def test_up_and_down_sweeps_expose_coexisting_attractors():
    """19 um, 28.0-28.6 Hz: sweeping up, the rotor stays on the stable period-1 orbit until it
    vanishes; sweeping down from the chaotic attractor above, it stays chaotic (boundary crisis
    below ~27.6 Hz). Where the two differ, hysteresis = 1. Not 27.8 Hz: that close to the crisis
    a state on the chaotic attractor one step above may lie in the orbit's basin (measured: 3 of
    16 starts 1e-11 apart at 28.6 Hz ended on the orbit at 27.8 Hz, none of 16 at 28.0 Hz)."""
    cfg = scene(28.0, 28.6, 0.3, "19.0e-6", 'sweep_direction = "both"\nlyapunov_max_periods = 300')
    r = compute.solve_segment(cfg.scene, points(cfg))
    P, C = at.PERIODIC, at.CHAOTIC
    assert list(r["attractor"]) == [P, P, C] and list(r["period"]) == [1, 1, 0]
    assert list(r["attractor_down"]) == [C, C, C]
    assert list(r["hysteresis"]) == [1, 1, 0]
    assert r["stable"][0] == 1                                     # shooting sees only the orbit
    chaotic = r["attractor_down"] == C
    assert np.all(r["lle_down"][chaotic] > 3 * r["lle_stderr_down"][chaotic])
    assert np.all(np.isnan(r["attractor_multiplier_real_down"][chaotic]))


def test_sweep_writes_the_attractor_variables(tmp_path, capsys):
    cfg = scene(60.0, 64.0, 2.0, "3.8e-6, 19.0e-6", "poincare_samples = 32\nmax_period = 8")
    path = sweep.run(cfg, tmp_path / "a.nc", workers=2, progress=False)
    ds = cube.open_cube(path)
    assert ds["poincare_x"].dims == ("speed", "clearance", "sample") and ds.sizes["sample"] == 32
    assert ds["lyapunov_exponents"].dims == ("speed", "clearance", "exponent")
    assert ds["lle"].attrs["units"] == "s-1" and ds["poincare_x"].attrs["units"] == "m"
    assert list(ds["attractor"].attrs["flag_meanings"].split()) == list(schema.ATTRACTOR)
    assert "hysteresis" not in ds and "lle_down" not in ds
    assert np.all(ds["attractor"].values == at.PERIODIC)
    # 19 um, 60-64 Hz: period 2 after the period doubling at ~64.9 Hz (period-1 orbit unstable)
    line = ds.sel(clearance=19.0e-6)
    assert list(line["period"].values) == [2, 2, 2] and np.all(line["stable"].values == 0)
    assert np.all(np.abs(line["attractor_multiplier_real"].values + 1j * line["attractor_multiplier_imag"].values).max(axis=1) < 1)
    assert np.all(ds.sel(clearance=3.8e-6)["period"].values == 1)
    runs = query.attractor_intervals(ds)
    assert [(r["clearance"], r["start"], r["end"], r["attractor"]) for r in runs] == [
        (3.8e-6, 60.0, 64.0, "period-1"), (19.0e-6, 60.0, 64.0, "period-2")]
    with pytest.raises(ValueError, match="down sweep"):
        query.attractor_intervals(ds, "down")
    assert cli.main(["query", str(path), "--attractors", "--format", "csv"]) == 0
    assert capsys.readouterr().out.splitlines()[1:] == [
        "3.8e-06,60.0,64.0,3,period-1," + f"{runs[0]['max_lle']!r}",
        "1.9e-05,60.0,64.0,3,period-2," + f"{runs[1]['max_lle']!r}"]
    assert cli.main(["query", str(path), "--attractors", "down"]) == 2
    assert "no attractor diagnostics for the down sweep" in capsys.readouterr().err


@pytest.mark.slow    # a 441-speed up-and-down attractor sweep (~45 s on 2 cores)
def test_cascade_scene_period_doubling_to_chaos_and_coexistence(tmp_path):
    """The shipped configs/bai2006_cascade.toml (19 um, 26-70 Hz, up and down): sweeping down
    from 70 Hz the attractor has periods 1, 2, 4, 8 in this order, then chaos with a positive
    exponent beyond its error, with periodic windows (period 3, period 5) between chaotic runs;
    up and down sweeps differ where a stable orbit and a chaotic attractor coexist (~27.6-28.4 Hz)."""
    cfg = config.load_config("configs/bai2006_cascade.toml")
    ds = cube.open_cube(sweep.run(cfg, tmp_path / "cascade.nc", workers=2, progress=False))
    runs = query.attractor_intervals(ds)[::-1]                  # from 70 Hz down
    labels = [r["attractor"] for r in runs]
    first = {k: labels.index(f"period-{k}") for k in (1, 2, 4, 8)}
    first_chaos = labels.index("chaotic")
    assert first[1] < first[2] < first[4] < first[8] < first_chaos, labels
    chaotic = ds["attractor"].values.ravel() == at.CHAOTIC
    assert chaotic.sum() >= 40
    assert np.all(ds["lle"].values.ravel()[chaotic] > 3 * ds["lle_stderr"].values.ravel()[chaotic])
    last_chaos = len(labels) - 1 - labels[::-1].index("chaotic")
    for window in ("period-5", "period-3"):                   # periodic windows inside the chaos
        assert first_chaos < labels.index(window) < last_chaos, labels
    speed = ds["speed"].values
    hysteresis = speed[ds["hysteresis"].values.ravel() == 1]
    assert np.any((hysteresis > 27.6) & (hysteresis < 28.4))
    at28 = ds.sel(speed=28.0).squeeze()
    assert int(at28["attractor"]) == at.PERIODIC and int(at28["attractor_down"]) == at.CHAOTIC
    assert int(at28["stable"]) == 1

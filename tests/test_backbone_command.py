"""`rotorsweep backbone`: the pipeline around the invariant manifold (rotorsweep.kernels.nnm) and the
continuation backbones (rotorsweep.kernels.continuation.backbone) — the result file, the manifold vs
continuation agreement at the order the cubic theory predicts, info / query / report, and input
errors before any work."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from rotorsweep.pipeline import backbone, backbone_reader, cli, compute, config, result_kinds
from tests import browser, cfcheck
from tests.runlog_check import check_log
from tests.browser import assert_renders, needs_chromium
from tests.figure_checks import assert_legend_hover_and_width
from workflows import screenshots

AXIAL = "configs/filipkovsky2010_axial.toml"


def scene(**backbone_keys):
    """The axial paper's scene (asymmetric5) with a [backbone] section replaced."""
    text = open(AXIAL).read().split("[backbone]")[0]
    keys = "\n".join(f"{k} = {json.dumps(v)}" for k, v in backbone_keys.items())
    return text + f"[backbone]\n{keys}\n[numerics]\nrtol = 1e-12\natol = 1e-14\nnewton_tol = 1e-11\n"


@pytest.fixture(scope="module")
def axial_result(tmp_path_factory):
    """Mode 1 (axial, 390 Hz) over two decades of amplitude, one local worker, with its report
    (whose manifold figure shows mode 2, a whirl: the axial mode moves alone, its manifold is flat)."""
    out = tmp_path_factory.mktemp("bb")
    path = out / "scene.toml"
    path.write_text(scene(modes="1", amplitude_max=4e-6, amplitude_points=21, surface_mode=2))
    nc = out / "bb.nc"
    rc = cli.main(["backbone", str(path), "-o", str(nc), "--workers", "1", "--report", str(out / "report"), "-q"])
    assert rc == 0
    return nc, out / "report"


def test_backbone_logs_its_phases_even_when_quiet(axial_result):
    nc, _ = axial_result       # run with -q: nothing on stderr, the log file all the same
    check_log(nc, "backbone", ["backbones of asymmetric5 on 1 line", "starting 1 local Dask worker",
                               "compiling the kernels", "kernels ready", "[1/1]", "writing the result"], "lines")


def test_manifold_and_continuation_agree_at_fourth_order(axial_result):
    """The cubic manifold's backbone omega_0 + kappa A^2 is exact to O(A^2), so its difference from
    the continuation backbone is O(A^4): the log-log slope is 4, fitted over the decade that
    starts where the difference is 1e-12 relative. Below that the continuation's own error
    (rtol 1e-12, Newton tolerance 1e-11: about 1e-14 relative; changing the bearing constants by
    1e-15 moved its smallest-amplitude frequency by 8.5e-15) is a visible part of the difference
    (2.4e-14 there): the lowest decade's slope was 3.67-3.77. Tolerance +-0.1: the noise is <= 1 %
    of the difference in the fitted decade (slope error ~0.01 / ln 10) and the next order,
    O(A^6), is (A / z0)^2 <= 1e-3 relative to it."""
    ds = backbone_reader.open_result(axial_result[0]).isel(speed=0)
    a = ds["amplitude_grid"].values
    signed = ds["relative_difference"].values[0]
    d = np.abs(signed)
    assert np.all(np.isfinite(d)) and d.max() > 0
    start = a[np.argmax(d >= 1e-12)]
    fitted = (a >= start) & (a <= start * 10 * (1 + 1e-9))
    assert fitted.sum() >= 8 and start < 1e-6
    slope = np.polyfit(np.log(a[fitted]), np.log(d[fitted]), 1)[0]
    assert slope == pytest.approx(4.0, abs=0.1)
    # Below the fitted decade d is the quartic term C A^4 (< 1e-12) plus the noise of the two
    # frequencies relative to their scale f0: the continuation's ~1e-14 (measured above: 8.5e-15;
    # with E = 2e11 a constant offset of 2.5e-14 over the smallest amplitudes, where the shooting
    # period's and the eigenvalue's linear limits part) and the manifold's rounding (a few eps). So
    # |d - C A^4| <= NOISE = 1e-13 there (4x the offset seen), whatever the noise makes of d's sign
    # (the smallest |d| is 8.7e-16: quartic term and offset nearly cancel). C from the fitted decade
    # with the slope 4 of the theory: its O(A^6) part (<= 1e-3 relative) and the 1 % noise at the
    # decade's start move C A^4 by < 1e-14 below it. NOISE is 10x below the 1e-12 where the fitted
    # decade starts: small-amplitude frequencies that part by more (a drifting continuation, a
    # manifold whose linear frequency is off) fail here, which a floor on min |d| could not see.
    noise = 1e-13
    c = np.median(signed[fitted] / a[fitted] ** 4)
    below = a < start
    assert below.sum() >= 5
    assert np.abs(signed[below] - c * a[below] ** 4).max() <= noise
    # the linear limit: both backbones start at the eigenfrequency of the polynomial form
    f0 = float(ds["linear_frequency"].values[0])
    assert ds["frequency_manifold"].values[0, 0] == pytest.approx(f0, rel=1e-6)
    assert ds["frequency_continuation"].values[0, 0] == pytest.approx(f0, rel=1e-6)
    assert str(ds["mode_label"].values[0]) == "axial"


def test_result_holds_the_continued_orbits_conservative_and_cf_units(axial_result):
    ds = backbone_reader.open_result(axial_result[0]).isel(speed=0)
    assert ds.attrs["result_kind"] == "backbone"
    for name in ("frequency_manifold", "frequency_continuation", "point_frequency"):
        assert ds[name].attrs["units"] == "Hz"
    assert ds["amplitude_grid"].attrs["units"] == "m" and ds["parting_amplitude"].attrs["units"] == "m"
    drift = ds["point_energy_drift"].values[0]
    assert np.nanmax(drift) < 1e-10                          # rtol 1e-12 over one period
    assert np.nanmax(ds["point_unit_circle_error"].values[0]) < 1e-8
    assert str(ds["continuation_end"].values[0]) == "left_range"
    # the manifold figure's orbit of the full system stays on the surface: the cubic manifold's
    # error is O(A^4), relative to the slave's O(A) motion O((A / z0)^3) = 1.4 % at 4 um
    off = np.abs(ds["orbit_slave"].values - ds["orbit_on_surface"].values).max()
    assert off < 0.05 * np.abs(ds["orbit_slave"].values).max()


def test_info_query_and_report_of_a_backbone_result(axial_result, capsys):
    nc, report = axial_result
    assert cli.main(["info", str(nc)]) == 0
    assert "mode 1" in capsys.readouterr().out
    assert cli.main(["query", str(nc), "--format", "csv"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].startswith("speed,mode,label") and len(lines) == 2
    for name in ("report.html", "backbones.png", "backbone_difference.png", "manifold_surface.png", "modes.csv"):
        assert (report / name).stat().st_size > 0


@pytest.mark.parametrize("keys, message", [
    ({"modes": "0"}, "backbone.modes: mode numbers start at 1"),
    ({"modes": "one"}, "backbone.modes: 'one' is neither"),
    ({"modes": "9"}, "backbone.modes: mode 9 does not exist; the model has 5 modes"),
    ({"surface_mode": 7}, "backbone.surface_mode: mode 7 does not exist"),
    ({"amplitude_max": 2e-5}, "backbone.amplitude_max: 2e-05 m reaches the axial approach z0"),
    ({"amplitude_max": 1e-6, "amplitude_min": 2e-6}, "backbone.amplitude_min: 2e-06 m must be below"),
    ({"ds": 0.0}, "backbone.ds"),
])
def test_invalid_backbone_input_names_the_key_before_any_work(keys, message):
    with pytest.raises(config.ConfigError, match=message.replace("(", r"\(")):
        backbone.plan(config.parse_config(scene(**keys)).scene)


def test_a_forced_model_has_no_backbone_and_a_conservative_one_no_sweep():
    with pytest.raises(config.ConfigError, match="scene.model: rigid_preloaded is not a conservative"):
        backbone.plan(config.load_config("configs/filipkovsky2016_quick.toml").scene)
    with pytest.raises(config.ConfigError, match="symmetric4 is conservative.*rotorsweep backbone"):
        compute.require_forced(config.load_config("configs/filipkovsky2010_symmetric.toml").model, "run")
    done = subprocess.run([sys.executable, "-m", "rotorsweep.pipeline.cli", "run", AXIAL, "-o", "/nonexistent/x.nc"],
                          capture_output=True, text=True)
    assert done.returncode == 2 and "asymmetric5 is conservative" in done.stderr


def _forced_response(path, unit="Hz"):
    """A continuation result of the shape `rotorsweep continue` writes: one branch through the
    axial mode's frequency (the overlay's input; its physics is not what is tested here)."""
    import xarray as xr

    f = np.linspace(380.0, 410.0, 31)
    amp = np.zeros((1, f.size, 5))
    amp[0, :, 4] = 1e-6 / (1 + ((f - 395.0) / 3.0) ** 2)
    stable = np.where(np.abs(f - 395.0) < 2.0, 0, 1).astype("int8")[None]
    ds = xr.Dataset({"parameter": (("branch", "point"), f[None], {"units": unit}),
                     "amplitude_half_pp": (("branch", "point", "observable"), amp, {"units": "m"}),
                     "stable": (("branch", "point"), stable)},
                    coords={"observable": ["x_A", "y_A", "x_B", "y_B", "z"]},
                    attrs={"result_kind": "continuation", "parameter": "support_frequency",
                           "range": "[380.0, 410.0]"})
    sizes = {"branch": 1, "point": f.size, "observable": 5, "state": 10, "multiplier": 10, "event": 0}
    kind = result_kinds.KINDS[result_kinds.CONTINUATION]
    for name, (dims, _) in kind.variables.items():     # the rest of a complete file: zeros
        if name not in ds and name not in kind.optional:
            ds[name] = (dims, np.zeros([sizes[d] for d in dims]))
    ds.to_netcdf(path)
    return path


def test_backbones_drawn_over_a_forced_response(axial_result, tmp_path):
    import rotorsweep.pipeline as pipeline

    nc, _ = axial_result
    files = pipeline.make_report(nc, tmp_path / "over", over=_forced_response(tmp_path / "forced.nc"))
    assert "over the forced response" in files["html"].read_text()
    assert (tmp_path / "over" / "backbones.png").stat().st_size > 0
    with pytest.raises(ValueError, match="--over: the forced response must be continued along a frequency in Hz"):
        pipeline.make_report(nc, tmp_path / "bad", over=_forced_response(tmp_path / "bad.nc", unit="m"))


def test_cf_checkers_find_no_error_and_units_are_stated(axial_result, tmp_path):
    """The backbone file under cfchecker and the IOOS compliance-checker (tests/cfcheck.py,
    skipped where they are not installed): no error. cfchecker's only warnings are the string-
    valued label coordinates (monomial, state: text, not CF coordinate variables). Every float
    variable has UDUNITS units or, for the manifold's coefficients, whose units differ from
    element to element, a comment with the rule; the surface figure's slave coordinate has its own
    unit (it was "SI")."""
    nc, _ = axial_result
    messages = cfcheck.cfchecker_messages(nc, tmp_path)
    assert messages["FATAL"] == messages["ERROR"] == []
    assert sorted(messages["WARN"]) == [f"{n}: (5): Possible incorrect declaration of a coordinate variable."
                                        for n in ("monomial", "state")]
    assert cfcheck.ioos_failures(nc, tmp_path) == []
    ds = backbone_reader.open_result(nc)
    assert list(ds["state_units"].values) == ["m"] * 5 + ["m s-1"] * 5
    slave = list(ds["state"].values).index(json.loads(str(ds["surface_info"].values))["slave"])
    for name in ("surface_value", "orbit_slave", "orbit_on_surface"):
        assert ds[name].attrs["units"] == ds["state_units"].values[slave], name
    mixed = [n for n, v in ds.data_vars.items() if v.dtype.kind == "f" and "units" not in v.attrs]
    assert mixed == ["reduced_coefficient", "manifold_coefficient"]
    assert all(ds[n].attrs["comment"].startswith(result_kinds.MIXED_UNITS) for n in mixed)


@needs_chromium
def test_backbone_report_renders_in_a_browser(axial_result, tmp_path):
    assert_renders(axial_result[1], tmp_path / "shot.png", kind="backbone")


@needs_chromium
def test_the_screenshot_comparison_passes_a_window_1_px_off_and_fails_a_missing_plot(axial_result, tmp_path):
    """tests/browser.py's tolerance, on the backbone report (the smallest page): rendered 1 px
    narrower and wider it matches its reference, with its first figure (the one of its three
    whose loss changes the fewest cells, measured) drawn blank it does not."""
    reference = browser.REFERENCES / "backbone.png"
    if os.environ.get(browser.UPDATE) or not reference.is_file() or browser.helvetica() != browser.REFERENCE_FONT:
        pytest.skip("no reference to compare with on this machine (see tests/browser.py)")
    page = browser.masked_page(axial_result[1] / "report.html", tmp_path / "report.html")
    for width in (screenshots.WIDTH - 1, screenshots.WIDTH + 1):
        screenshots.capture(page, tmp_path / f"{width}.png", width=width)
        fraction, height = browser.difference(tmp_path / f"{width}.png", reference)
        assert fraction <= browser.FRACTION_TOL and height <= browser.HEIGHT_TOL, (width, fraction, height)
    screenshots.capture(browser.blank_figure(page, tmp_path / "blank.html", 0), tmp_path / "blank.png")
    fraction, _ = browser.difference(tmp_path / "blank.png", reference)
    assert fraction > 2 * browser.FRACTION_TOL, fraction


def test_every_plot_of_the_report_has_a_legend_and_a_hover(axial_result):
    from rotorsweep.pipeline.report import backbone_result
    assert_legend_hover_and_width(backbone_result.figures(backbone_reader.open_result(axial_result[0]), "bokeh"))

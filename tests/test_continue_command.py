"""`rotorsweep continue`: config checks before any work, the continuation result file, info,
query and report on it, and branch switching through the pipeline."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from rotorsweep.pipeline import coexistence, config, continuation, continuation_result
from tests import cfcheck
from tests.runlog_check import check_log
from tests.browser import assert_renders, needs_chromium
from tests.figure_checks import assert_legend_hover_and_width
from rotorsweep.kernels.continuation import arclength as al

CLI = [str(Path(sys.executable).with_name("rotorsweep"))]

DUFFING = """
[scene]
name = "duffing_hardening"
model = "duffing"

[duffing]
zeta = 0.05
gamma = 1.0
force = 0.1

[sweep]
omega = [0.5, 2.0]

[numerics]
rtol = 1e-12
atol = 1e-14
newton_tol = 1e-10
amplitude_limit = 100.0      # the Duffing oscillator is dimensionless (the default is bearing-scale, 1 mm)

[continuation]
ds = 0.02
"""


def rotorsweep(*args, check=True):
    proc = subprocess.run(CLI + [str(a) for a in args], capture_output=True, text=True, timeout=600)
    if check and proc.returncode != 0:
        raise AssertionError(f"rotorsweep {args} failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    return proc


def test_invalid_continuation_settings_stop_the_command_before_work(tmp_path):
    cfg_path = tmp_path / "bad.toml"
    cfg_path.write_text(DUFFING.replace("ds = 0.02", "ds = 0.0"))
    proc = rotorsweep("continue", cfg_path, "-o", tmp_path / "x.nc", check=False)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "continuation.ds" in proc.stderr and "continuing" not in proc.stderr
    assert not (tmp_path / "x.nc").exists()


def test_invalid_settings_messages():
    """The messages name the key and say what is wrong."""
    cases = {"ds = 0.0": "continuation.ds", 'parameter = "speed"': "is not a float parameter of model duffing",
             'parameter = "zeta"': "continuation.start: required", "start = 1.0\nstop = 1.0": "the range is empty",
             "ds_min = 0.1": "ds_min <= ds <= ds_max", 'parameter = "nonsense"': "continuable: omega, zeta, gamma, force"}
    for new, message in cases.items():
        with pytest.raises(config.ConfigError, match=message.replace("(", r"\(")):
            continuation.plan(config.parse_config(DUFFING.replace("ds = 0.02", new)).scene)


@pytest.fixture(scope="module")
def duffing_result(tmp_path_factory):
    d = tmp_path_factory.mktemp("cont")
    cfg_path = d / "duffing.toml"
    cfg_path.write_text(DUFFING)
    out = d / "duffing.nc"
    proc = rotorsweep("continue", cfg_path, "-o", out, "--workers", "2", "--report", d / "report")
    return out, d, proc


def test_continue_logs_the_phases_progress_and_time_of_run(duffing_result):
    out, d, proc = duffing_result
    phases = ["continuing omega", "starting 2 local Dask worker", "compiling the kernels", "kernels ready", "[1/1]",
              "writing the result"]
    check_log(out, "continue", phases, "lines")
    assert all(f"== {phase}" in proc.stderr for phase in phases)     # the same phase lines as `run` on stderr


def test_continue_writes_branches_and_folds(duffing_result):
    out, d, proc = duffing_result
    assert "[1/1]" in proc.stderr and "2 LP" in proc.stderr            # progress per line
    ds = continuation_result.open_result(out)
    assert ds.attrs["parameter"] == "omega" and ds.sizes["branch"] == 1
    assert ds["branch_end"].values.tolist() == [al.LEFT_RANGE]
    kinds = ds["event_type"].values
    assert kinds[kinds != al.PEAK].tolist() == [al.FOLD, al.FOLD] and (kinds == al.PEAK).sum() == 1
    folds = np.flatnonzero(kinds == al.FOLD)
    # the same folds as the kernels' continuation in this process (the file carries them intact)
    cfg = config.parse_config(DUFFING)
    pl = continuation.plan(cfg.scene)
    family, _ = continuation.line_family(cfg.scene, pl, {})
    direct = al.continue_orbit(family, 0.5, np.zeros(2), (0.5, 2.0), pl.settings)
    np.testing.assert_allclose(ds["event_parameter"].values, [e.point.lam for e in direct.events], rtol=1e-12)
    # stable, unstable between the folds, stable: as the multipliers say
    n = int(ds["branch_points"].values[0])
    mu = np.hypot(ds["multiplier_real"].values[0, :n], ds["multiplier_imag"].values[0, :n]).max(axis=1)
    assert ((ds["stable"].values[0, :n] == 1) == (mu < 1)).all()
    assert (ds["stable"].values[0, n:] == -1).all() and np.isnan(ds["parameter"].values[0, n:]).all()
    # the amplitude at the upper fold: the resonance peak, x ~ F / (2 zeta) = 1 scaled by the
    # cubic stiffness; the half peak-to-peak of a symmetric orbit equals its max |x| (to the
    # sampling, 64 per period: cos(pi / 64) ~ 1 - 1.2e-3)
    amp = ds["event_amplitude_max"].values[folds[0], 0]
    half = ds["amplitude_half_pp"].values[0, int(ds["event_point"].values[folds[0]])]
    assert 0.5 < amp < 2.0 and half == pytest.approx(ds["amplitude_max"].values[0, int(ds["event_point"].values[folds[0]]), 0], rel=2e-3)
    # the hardening resonance is bistable exactly between its folds (the outer branches stable)
    (iv,) = coexistence.bistable_intervals(ds)
    assert (iv["lo"], iv["hi"]) == tuple(sorted(ds["event_parameter"].values[folds]))
    # plain xarray keeps the flags integer
    import xarray as xr
    with xr.open_dataset(out) as raw:
        assert raw["event_type"].dtype.kind == "i" and raw["branch_end"].dtype.kind == "i"


def test_info_query_report_on_a_continuation_result(duffing_result):
    out, d, _ = duffing_result
    info = rotorsweep("info", out).stdout
    assert "parameter omega" in info and "ended left_range" in info and "two stable orbits coexist" in info
    rows = json.loads(rotorsweep("query", out, "--format", "json").stdout)
    assert sorted(r["type"] for r in rows) == ["LP", "LP", "PK"]
    assert all(abs(r["multiplier_real"] - 1.0) < 1e-6 for r in rows if r["type"] == "LP")
    html = (d / "report" / "report.html").read_text()
    assert "Branch diagram" in html and "Located points" in html and "bistable" in html
    assert (d / "report" / "branch_x.png").stat().st_size > 10_000


def test_branch_switching_through_the_pipeline():
    """Bai 2006, 19 um, from 29 down to 27 Hz (above the lower branch's fold at 28.40 Hz only the
    upper branch exists, so the start is on it): the line's task returns the period-1 branch,
    the period-2 branch switched at its period doubling (27.42 Hz) and the period-4 branch
    switched at the period-2 branch's, each parent recorded."""
    text = Path("configs/bai2006_fig13.toml").read_text()
    text = text.replace("speed = {start = 10.0, stop = 250.0, step = 0.1}", "speed = [27.0, 29.0]")
    text = text.replace("clearance = [3.8e-6, 7.6e-6, 11.4e-6, 15.2e-6, 19.0e-6]", "clearance = [19.0e-6]")
    cfg = config.parse_config(text + "\n[continuation]\nstart = 29.0\nstop = 27.0\nds_max = 0.5\n")
    (where,) = continuation.plan(cfg.scene).lines
    records = continuation.continue_line(cfg.scene, where)
    assert [r["periods"] for r in records][:3] == [1, 2, 4]
    assert [r["parent"] for r in records][:3] == [-1, 0, 1]
    pd1 = records[0]["event_parameter"][records[0]["event_type"] == al.PERIOD_DOUBLING]
    pd2 = records[1]["event_parameter"][records[1]["event_type"] == al.PERIOD_DOUBLING]
    assert pd1.size == 1 and pd2.size >= 1 and pd2[0] > pd1[0]


def test_a_boundary_curve_found_again_from_another_line_is_kept_once():
    """Two lines (nu = 1, 2) each locate a point of the same curve; the curve from the first line
    passes the second line's event, so the second line's curves are dropped; the two halves of
    one event's curve are both kept, and a curve through no kept mark stays."""
    def curve(start, marked, kind=al.PERIOD_DOUBLING):
        return {"kind": kind, "start": start, "marked": marked}
    first_up = curve((93.0, 1.0), [(1.0, 93.0), (2.0, 80.0), (2.0, 101.0), (1.0, 113.0)])
    first_down = curve((93.0, 1.0), [(1.0, 93.0)])
    again = curve((80.0 * (1 + 1e-9), 2.0 * (1 + 1e-15)), [(2.0, 80.0)])
    other_kind = curve((80.0, 2.0), [(2.0, 80.0)], kind=al.FOLD)
    elsewhere = curve((130.0, 2.0), [(2.0, 130.0)])
    kept = continuation.distinct_curves([first_up, first_down, again, other_kind, elsewhere])
    assert kept == [first_up, first_down, other_kind, elsewhere]


def test_boundary_curves_through_the_pipeline_match_the_sweep_boundaries():
    """Bai 2006, PD boundary from 3.8 um near 93 Hz continued in clearance through the pipeline:
    one curve (found from both lines, kept once) whose crossings of 7.6 um are the period
    doublings the 7.6 um line locates itself (1e-6 relative: both solve to ~1e-9)."""
    text = Path("configs/bai2006_fig13.toml").read_text()
    text = text.replace("speed = {start = 10.0, stop = 250.0, step = 0.1}", "speed = {start = 70.0, stop = 120.0, step = 1.0}")
    text = text.replace("clearance = [3.8e-6, 7.6e-6, 11.4e-6, 15.2e-6, 19.0e-6]", "clearance = [3.8e-6, 7.6e-6]")
    cfg = config.parse_config(text + '\n[continuation]\ncurves_in = "clearance"\nperiod_doubling_switches = 0\n')
    pl = continuation.plan(cfg.scene)
    lines = [(where, continuation.continue_line(cfg.scene, where)) for where in pl.lines]
    ds = continuation.to_dataset(cfg.scene, pl, lines, {})
    pds = ds["curve_type"].values == al.PERIOD_DOUBLING
    assert pds.any()
    events_76 = sorted(ds["event_parameter"].values[(ds["event_branch"].values == 1) & (ds["event_type"].values != al.PEAK)])
    for target in events_76:
        c, p = np.nonzero(np.isclose(ds["curve_second"].values, 7.6e-6, rtol=1e-12, atol=0))
        crossings = ds["curve_parameter"].values[c, p]
        assert np.min(np.abs(crossings - target)) <= 1e-6 * target


def test_cf_checkers_find_no_error(duffing_result, tmp_path):
    """The continuation file under cfchecker and the IOOS compliance-checker (tests/cfcheck.py,
    skipped where they are not installed): no error; text is stored as character arrays (cfchecker
    rejected netCDF-4 strings as an error). cfchecker's one warning is the string-valued label
    coordinate `observable` (text, not a CF coordinate variable)."""
    out = duffing_result[0]
    messages = cfcheck.cfchecker_messages(out, tmp_path)
    assert messages["FATAL"] == messages["ERROR"] == []
    assert messages["WARN"] == ["observable: (5): Possible incorrect declaration of a coordinate variable."]
    assert cfcheck.ioos_failures(out, tmp_path) == []


@needs_chromium
def test_continuation_report_renders_in_a_browser(duffing_result, tmp_path):
    assert_renders(duffing_result[1] / "report", tmp_path / "shot.png", kind="continuation")


def test_events_csv_has_units_in_every_numeric_header(duffing_result):
    header = (duffing_result[1] / "report" / "events.csv").read_text().splitlines()[0].split(",")
    assert header == ["type", "branch", "periods [1]", "omega [rad s-1]", "omega_error [rad s-1]",
                      "multiplier_real [1]", "multiplier_imag [1]", "stable", "amplitude_max_x [1]", "amplitude_half_pp_x [1]"]


def test_every_plot_of_the_report_has_a_legend_and_a_hover(duffing_result):
    from rotorsweep.pipeline.report import branch_result
    assert_legend_hover_and_width(branch_result.figures(continuation_result.open_result(duffing_result[0]), "bokeh"))


def test_the_branch_diagrams_show_the_report_s_observable_first_titled_as_plotted(duffing_result):
    """A result whose report observable is not the model's first (as y_B of rigid_preloaded's
    Filipkovsky scenes): Duffing's x with an observable u = 3 x put before it. The first max |o|
    panel is x's, as the response panel above it, then u's; each titled and labelled by the
    observable whose values it draws (x's own maximum, three times it for u: exact, a scaling)."""
    from rotorsweep.pipeline.report import branch_result

    ds = continuation_result.open_result(duffing_result[0])
    per_observable = [v for v in ds.data_vars if "observable" in ds[v].dims]
    with xr.set_options(keep_attrs=True):
        u = (ds[per_observable] * 3.0).assign_coords(observable=["u"])
    two = xr.merge([ds.drop_vars(per_observable + ["observable"]), xr.concat([u, ds[per_observable]], "observable")],
                   combine_attrs="override")
    assert two["observable"].values.tolist() == ["u", "x"] and two.attrs["report_observable"] == "x"
    panels = [(caption, fig) for caption, _, fig in branch_result.figures(two, "bokeh")
              if caption.startswith("Branch diagram")]
    assert [caption for caption, _ in panels] == ["Branch diagram: max |x| over the orbit",
                                                  "Branch diagram: max |u| over the orbit"]
    x_max = np.nanmax(ds["amplitude_max"].values)
    for (_, fig), name, factor in zip(panels, "xu", (1.0, 3.0)):
        curves = [el for el in fig if type(el).__name__ == "Curve"]
        assert {el.dimensions()[1].label for el in curves} == {f"max |{name}| [1]"}
        assert np.nanmax(np.concatenate([el.dimension_values(1) for el in curves])) == factor * x_max

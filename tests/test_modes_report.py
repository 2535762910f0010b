"""`rotorsweep modes --report DIR` (pipeline/report/modes_report.py): the page's files and tables,
its bokeh figures (legends, hover, the critical speeds listed as `modes --json` gives them), and
the page in headless Chromium against its reference screenshot."""
import csv
import json
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import cli, config, modes
from rotorsweep.pipeline.report import modes_report
from tests.browser import assert_renders, needs_chromium
from tests.figure_checks import assert_legend_hover_and_width, plots_of

ROOT_CONFIGS = Path(__file__).resolve().parents[1] / "configs"
# rigid_preloaded, damped, with a support-frequency line: five modes, every whirl kind
QUICK = str(ROOT_CONFIGS / "filipkovsky2016_quick.toml")


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    """The report of the quick scene and its `modes --json` records, made once."""
    out = tmp_path_factory.mktemp("modes") / "report"
    assert cli.main(["modes", QUICK, "--report", str(out)]) == 0
    cfg = config.load_config(QUICK, whole_grid=False)
    point = modes.at_point(cfg, {})
    return out, modes.records(cfg.model, modes.scene_values(cfg.scene, point))


def test_report_writes_the_page_pngs_and_the_modes_table(quick_report):
    """modes.csv holds the --json modes with units in every numeric header; its log decrement
    is the closed form 2 pi zeta / sqrt(1 - zeta^2) of its damping ratio (rounding: 1e-12)."""
    out, rec = quick_report
    assert {p.name for p in out.iterdir()} == {"report.html", "mode_campbell.png", "mode_shapes.png", "modes.csv"}
    with open(out / "modes.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == list(modes_report.MODE_COLUMNS)
    assert len(rows) == len(rec["modes"]) == 5
    for row, mode in zip(rows, rec["modes"]):
        assert float(row["damped frequency [Hz]"]) == pytest.approx(mode["damped_frequency_hz"], rel=1e-12)
        assert float(row["undamped frequency [Hz]"]) == pytest.approx(mode["undamped_frequency_hz"], rel=1e-12)
        zeta = float(row["damping ratio [1]"])
        assert zeta == pytest.approx(mode["damping_ratio"], rel=1e-12) and zeta > 0
        assert float(row["log decrement [1]"]) == pytest.approx(2 * np.pi * zeta / np.sqrt(1 - zeta ** 2), rel=1e-12)
        assert (row["whirl"], row["label"]) == (mode["whirl"], mode["label"])
    page = (out / "report.html").read_text(encoding="utf-8")
    assert page.index("<h2>Modes</h2>") < page.index("Campbell diagram") < page.index("Mode shapes")
    assert "damped frequency [Hz]" in page and "<script src=" not in page      # offline: bokeh inlined


def _figures():
    cfg = config.load_config(QUICK, whole_grid=False)
    point = modes.at_point(cfg, {})
    values = modes.scene_values(cfg.scene, point)
    scene = modes_report.scene_at(cfg.scene, point)
    return modes_report.figures(scene, [250.0], modes_report.campbell_speeds(cfg.model, values), "bokeh")


def test_every_plot_has_a_legend_and_a_hover_and_the_critical_speeds_are_listed(quick_report):
    """The Campbell diagram (its colour bar, the 1x and support lines in the legend) and one
    mode-shape panel per mode; its table lists the critical speeds `modes --json` gives (the same
    bracketing grid and root solve; the table rounds to 1e-6 Hz)."""
    from bokeh.models import ColorBar, ColumnDataSource, DataTable, Legend

    _, rec = quick_report
    figs = _figures()
    assert [f for _, f, _ in figs] == ["mode_campbell.png", "mode_shapes.png"]
    assert_legend_hover_and_width(figs)
    plots = plots_of(figs)
    campbell = [p for caption, p in plots if caption == figs[0][0]]
    shapes = [p for caption, p in plots if caption == figs[1][0]]
    assert len(campbell) == 1 and len(shapes) == len(rec["modes"])
    assert campbell[0].select({"type": ColorBar})
    names = {item.label["value"] for legend in campbell[0].select({"type": Legend}) for item in legend.items}
    assert {"1x (shaft speed)", "support 150 Hz", "critical speed"} <= names
    from rotorsweep.pipeline.report import style
    with style.backend("bokeh"):
        model = style.holoviews().render(figs[0][2], backend="bokeh")
    (table,) = model.select({"type": DataTable})
    assert isinstance(table.source, ColumnDataSource)
    field = {column.title: column.field for column in table.columns}["shaft speed [Hz]"]
    speeds = [c["speed_hz"] for c in rec["critical_speeds"]]
    assert len(speeds) == 4
    np.testing.assert_allclose(table.source.data[field], speeds, rtol=1e-6)


def test_a_model_without_a_linearization_is_one_line_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "report"
    assert cli.main(["modes", str(ROOT_CONFIGS / "bai2006_fig13.toml"), "--report", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "model jeffcott_clearance has no linearization" in err
    assert not out.exists()


def test_a_model_without_shaft_speed_or_stations_gets_the_table_alone(tmp_path):
    """Duffing's declared linearization x'' + 2 zeta x' + x = 0 (zeta 0.05): a page with no
    figures and no script, the table's damped frequency the closed form sqrt(1 - zeta^2) / 2 pi."""
    out = tmp_path / "report"
    assert cli.main(["modes", str(ROOT_CONFIGS / "duffing_resonance.toml"), "--report", str(out)]) == 0
    assert {p.name for p in out.iterdir()} == {"report.html", "modes.csv"}
    assert "<script" not in (out / "report.html").read_text(encoding="utf-8")
    with open(out / "modes.csv") as fh:
        (row,) = list(csv.DictReader(fh))
    assert float(row["damped frequency [Hz]"]) == pytest.approx(np.sqrt(1 - 0.05 ** 2) / (2 * np.pi), rel=1e-12)


def test_at_moves_the_table_and_the_mode_shapes_to_the_point(tmp_path):
    """--at speed=500 (off the scene's grid): the table and every mode-shape title give the
    modes of the point, as the text summary there does."""
    out = tmp_path / "report"
    assert cli.main(["modes", QUICK, "--at", "speed=500", "--report", str(out)]) == 0
    cfg = config.load_config(QUICK, whole_grid=False)
    rec = modes.records(cfg.model, modes.scene_values(cfg.scene, modes.at_point(cfg, {"speed": 500.0})))
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "at speed = 500" in page
    for k, mode in enumerate(rec["modes"]):
        assert f"mode {k}: {mode['damped_frequency_hz']:.4g} Hz" in page
    with open(out / "modes.csv") as fh:
        got = [float(row["damped frequency [Hz]"]) for row in csv.DictReader(fh)]
    np.testing.assert_allclose(got, [m["damped_frequency_hz"] for m in rec["modes"]], rtol=1e-12)


def test_the_json_and_a_campbell_range_go_with_the_report(tmp_path, capsys):
    """--json prints only the JSON; --campbell sets the diagram's speeds (no -o needed)."""
    out = tmp_path / "report"
    assert cli.main(["modes", QUICK, "--json", "--campbell", "1:600:21", "--report", str(out)]) == 0
    assert json.loads(capsys.readouterr().out)["model"] == "rigid_preloaded"
    assert (out / "mode_campbell.png").is_file()


@needs_chromium
def test_modes_report_renders_in_a_browser(quick_report, tmp_path):
    assert_renders(quick_report[0], tmp_path / "shot.png", kind="modes")


@needs_chromium
def test_the_reference_catches_a_missing_mode_shapes_plot(quick_report, tmp_path):
    """The page with its mode-shape figure drawn blank (its slot kept) differs from the reference."""
    from tests import browser
    from workflows import screenshots

    if browser.helvetica() != browser.REFERENCE_FONT:
        pytest.skip(f"the references are drawn with {browser.REFERENCE_FONT}")
    page = browser.blank_figure(quick_report[0] / "report.html", tmp_path / "blank.html", 1)
    screenshots.capture(page, tmp_path / "blank.png")
    assert browser.difference(tmp_path / "blank.png", browser.REFERENCES / "modes.png")[0] > browser.FRACTION_TOL


def _contents(directory):
    return {p.name: p.read_bytes() for p in directory.iterdir()}


def test_an_interrupted_report_leaves_the_earlier_one_or_none(tmp_path, monkeypatch, capsys):
    """Ctrl-C after modes.csv is written and before report.html: the directory is as it was
    (absent, or the earlier report byte for byte) and no temp directory is left next to it."""
    from rotorsweep.pipeline.report import page

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    out, duffing = tmp_path / "report", str(ROOT_CONFIGS / "duffing_resonance.toml")
    monkeypatch.setattr(page, "save_html", interrupted)
    assert cli.main(["modes", duffing, "--report", str(out)]) == 130
    assert "report directory is as it was" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    assert cli.main(["modes", duffing, "--report", str(out)]) == 0
    before = _contents(out)
    monkeypatch.setattr(page, "save_html", interrupted)
    assert cli.main(["modes", duffing, "--at", "omega=1.3", "--report", str(out)]) == 130
    assert _contents(out) == before and [p.name for p in tmp_path.iterdir()] == ["report"]


def test_a_modes_report_never_goes_into_a_foreign_directory(tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    assert cli.main(["modes", str(ROOT_CONFIGS / "duffing_resonance.toml"), "--report", str(mine)]) == 2
    assert "holds no rotorsweep report" in capsys.readouterr().err
    assert _contents(mine) == {"thesis.tex": b"precious"}

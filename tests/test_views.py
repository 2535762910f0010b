"""The rotordynamics views of the reports (issue 34): the Campbell diagram with critical speeds,
checked on the bokeh models the HTML page embeds."""
from pathlib import Path

import numpy as np
import pytest

from pipeline import compute, config, modes
from pipeline.report import style
from pipeline.report.figures import mode_campbell

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
WINDOW = 1400     # px: every figure fits a window this wide


def _render(fig):
    hv = style.holoviews()
    with style.backend("bokeh"):
        return hv.render(fig, backend="bokeh")


def _plots(model):
    from bokeh.models import Plot
    return list(model.select({"type": Plot}))


@pytest.fixture(scope="module")
def symmetric():
    return config.load_config(CONFIGS / "filipkovsky2010_symmetric.toml").data


def test_campbell_diagram_marks_and_lists_the_critical_speeds(symmetric):
    """Damping as a colour bar, whirl styles and the 1x line in the legend, hover everywhere, the
    critical speeds of modes.scene_critical_speeds as markers and table rows, within 1400 px."""
    from bokeh.models import ColorBar, DataTable, HoverTool, Legend
    speeds = mode_campbell.campbell_speeds(symmetric, top=1500.0)   # past the first critical speeds (713 Hz)
    model = _render(mode_campbell.fig_mode_campbell(symmetric, "bokeh", speeds))
    (plot,) = _plots(model)
    (bar,) = plot.select({"type": ColorBar})
    assert bar.title == "damping ratio ζ [1]"
    labels = {item.label["value"] for legend in plot.select({"type": Legend}) for item in legend.items}
    assert {"forward whirl (solid)", "backward whirl (dashed)", "1x (shaft speed)", "critical speed"} <= labels
    assert plot.select({"type": HoverTool})
    spec = compute.model_of(symmetric)
    first = {name: float(v[0]) for name, v in symmetric["sweep"].items()}
    fine = np.linspace(0.0, speeds[-1], modes.CRITICAL_GRID + 1)[1:]
    found = modes.scene_critical_speeds(spec, modes.scene_values(symmetric, first), fine)
    assert found and all(c.line == "1x" for c in found)
    (table,) = model.select({"type": DataTable})
    field = {column.title: column.field for column in table.columns}
    np.testing.assert_allclose(table.source.data[field["shaft speed [Hz]"]], [round(c.speed_hz, 6) for c in found])
    assert plot.width + 200 <= WINDOW      # the legend and colour bar beside it


def test_support_frequency_adds_its_line_and_crossings():
    """A support excitation frequency (rigid_preloaded's [forcing] support_frequency) is a
    horizontal line whose crossings are critical speeds too, at the line's frequency."""
    from rotorkernels import models
    spec = models.REGISTRY["rigid_preloaded"]
    assert spec.support_frequency == "support_frequency"
    lines = modes.excitation_lines(spec, {"support_frequency": 500.0})
    assert [(ln.slope, ln.offset) for ln in lines] == [(1.0, 0.0), (0.0, 500.0)]
    assert len(modes.excitation_lines(spec, {"support_frequency": 0.0})) == 1

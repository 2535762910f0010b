"""The rotordynamics views of the reports (issue 34): the Campbell diagram with critical speeds,
checked on the bokeh models the HTML page embeds."""
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import config, modes
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.figures import mode_campbell
from tests.figure_checks import WINDOW

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def _render(fig):
    hv = style.holoviews()
    with style.backend("bokeh"):
        return hv.render(fig, backend="bokeh")


def _plots(model):
    from bokeh.models import Plot
    return list(model.select({"type": Plot}))


@pytest.fixture(scope="module")
def symmetric():
    return config.load_config(CONFIGS / "filipkovsky2010_symmetric.toml").scene


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
    spec = symmetric.model
    first = {name: float(v[0]) for name, v in symmetric.axes.items()}
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
    from rotorsweep.kernels import models
    spec = models.REGISTRY["rigid_preloaded"]
    assert spec.support_frequency == "support_frequency"
    lines = modes.excitation_lines(spec, {"support_frequency": 500.0})
    assert [(ln.slope, ln.offset) for ln in lines] == [(1.0, 0.0), (0.0, 500.0)]
    assert len(modes.excitation_lines(spec, {"support_frequency": 0.0})) == 1


LINEAR_DUFFING = """
[scene]
name = "linear_oscillator"
model = "duffing"
[duffing]
zeta = 0.05
gamma = 0.0
force = 0.1
[sweep]
omega = [0.6, 0.95, 1.0, 1.05, 1.6]
[numerics]
rtol = 1e-12
atol = 1e-14
newton_tol = 1e-12
amplitude_limit = 100.0
"""


@pytest.fixture(scope="module")
def linear_cube():
    """A real sweep cube of the forced linear oscillator x'' + 2 zeta x' + x = F cos(omega t)
    (duffing with gamma = 0), built in-process as tests/conftest.py builds its tiny cube."""
    from rotorsweep.pipeline import cube, sweep
    cfg = config.parse_config(LINEAR_DUFFING)
    ids, index, results, _ = sweep.compute_chunk(cfg.scene, sweep.segments(cfg.scene))
    return cfg, cube.assemble(cfg.axes, sweep.fixed_coords(cfg.scene), [(ids, index, results, None)],
                              sweep.provenance(cfg), n_multipliers=2)


def test_first_harmonic_is_exact_for_a_band_limited_signal():
    """o = 2 cos(t + 0.3) + 0.5 cos(3 t) - 0.2 sin(2 t) sampled at 64 points per period: X = 2 e^{0.3 i}
    to rounding (the DFT's aliases of the other harmonics are at indices 64 apart)."""
    from rotorsweep.pipeline.report import harmonics
    t = 2 * np.pi * np.arange(64) / 64
    o = 2 * np.cos(t + 0.3) + 0.5 * np.cos(3 * t) - 0.2 * np.sin(2 * t)
    assert harmonics.first_harmonic(o[:, None])[0] == pytest.approx(2 * np.exp(0.3j), abs=1e-13)
    two = np.tile(o, 2)[:, None]       # a period-2 sample of the same orbit: the forcing frequency is index 2
    assert harmonics.first_harmonic(two, periods=2)[0] == pytest.approx(2 * np.exp(0.3j), abs=1e-13)


def test_bode_of_the_linear_oscillator_against_the_closed_form(linear_cube):
    """X = F / (1 - w^2 + 2 i zeta w): amplitude and phase of the first harmonic of the re-integrated
    orbits. The orbit is shot to newton_tol 1e-12 and integrated at rtol 1e-12; 1e-8 relative
    leaves room for the error growth over a period near resonance (amplification 1 / 2 zeta = 10)."""
    from rotorsweep.pipeline.report import harmonics
    from rotorsweep.pipeline.report.figures import bode
    cfg, ds = linear_cube
    lines = harmonics.sweep_lines(ds, cfg.scene, "x")
    (w,), (x,) = lines.x, lines.harmonic
    expected = 0.1 / (1 - w ** 2 + 2j * 0.05 * w)
    np.testing.assert_allclose(np.abs(x), np.abs(expected), rtol=1e-8)
    np.testing.assert_allclose(bode.unwrapped_phase(x), np.degrees(np.angle(expected)), atol=1e-6)
    assert bode.unwrapped_phase(x)[-1] < -90 < bode.unwrapped_phase(x)[0] < 0     # the lag passes -90 deg
    assert lines.stable[0].all()


def test_bode_figure_has_legends_hover_and_fits_the_window(linear_cube):
    from bokeh.models import HoverTool, Legend
    from rotorsweep.pipeline.report.figures import bode
    cfg, ds = linear_cube
    plots = _plots(_render(bode.fig_bode(*_bode_inputs(cfg, ds), "bokeh")))
    assert len(plots) == 3
    for plot in plots:
        assert plot.select({"type": HoverTool}) and plot.select({"type": Legend})
    assert all(_width(plot) <= WINDOW / 2 for plot in plots)      # two a row


def _width(plot):
    """A bokeh plot's width [px]; a plot sized by its frame: the frame plus axes and legend room."""
    return plot.width if plot.width is not None else plot.frame_width + 250


def _bode_inputs(cfg, ds):
    from rotorsweep.pipeline.report import harmonics
    return harmonics.sweep_lines(ds, cfg.scene, "x"), "x", "1", "omega [rad s-1]"


def test_accessor_draws_bode_and_says_why_no_campbell(linear_cube):
    """ds.rotorsweep.bode() on a sweep cube; campbell() refuses a model without a shaft speed."""
    import holoviews as hv
    import rotorsweep  # noqa: F401  (registers the accessor)
    cfg, ds = linear_cube
    ds = ds.assign_attrs(config_toml=cfg.source)
    plot = ds.rotorsweep.bode()
    assert isinstance(plot, hv.Layout) and len(plot) == 3
    from rotorsweep.pipeline.report.cubeinfo import continued_axis
    from rotorsweep.pipeline.report.plan import axis_label
    xlabel = hv.renderer("bokeh").get_plot(plot).state.children[0][0].xaxis[0].axis_label
    assert xlabel == axis_label(ds, continued_axis(ds))          # the report's label, in display units
    with pytest.raises(ValueError, match="no Campbell diagram"):
        ds.rotorsweep.campbell()
    with pytest.raises(ValueError, match="no mode shapes"):
        ds.rotorsweep.mode_shapes()


def test_special_points_at_one_place_share_one_label():
    """Two PDs at one point (a branch and the branch switched there) give one "PD"; an LP beside
    them too: one text "PD/LP"; a PD elsewhere keeps its own."""
    from rotorsweep.pipeline.report.branches import Special, merged_labels
    special = [Special(30.0, 2.0, "PD"), Special(30.0 + 1e-6, 2.0, "PD"), Special(30.0, 2.0 + 1e-6, "LP"),
               Special(40.0, 1.0, "PD")]
    assert [label for _, _, label in merged_labels(special)] == ["PD/LP", "PD"]

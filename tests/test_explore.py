"""The hvplot functions and the `rotorsweep` accessor on a cube: each figure kind is an hvplot
(HoloViews) object that renders with bokeh."""
import holoviews as hv
import numpy as np
import pytest

import rotorsweep
from rotorsweep.pipeline import explore
from tests.synthetic import synthetic_cube

KINDS = ("max_multiplier", "stability_map", "branches", "response", "multiplier_frequency", "bifurcation", "lle",
         "multipliers")


@pytest.fixture(scope="module")
def ds():
    return synthetic_cube(speed=np.arange(60.0, 140.0, 4.0), attractor=True, boundaries=True, n_samples=64)


@pytest.mark.parametrize("kind", KINDS)
def test_every_figure_kind_is_an_hvplot_object(ds, kind):
    where = {"where": {"clearance": float(ds.clearance[0])}} if kind == "multipliers" else {}
    plot = getattr(ds.rotorsweep, kind)(**where)
    assert isinstance(plot, hv.core.Dimensioned)
    hv.renderer("bokeh").get_plot(plot)


def test_accessor_and_facade(ds):
    assert rotorsweep.explore is explore
    curves = explore.max_multiplier(ds)
    assert len(curves.get(0)) == ds.sizes["clearance"]                # one line per clearance
    branches = explore.branches(ds, "amplitude_x")
    stable, unstable = branches.get(0), branches.get(1)
    assert unstable.last.opts.get("style").kwargs["line_dash"] == "dashed"
    # the unstable points are gaps of the solid lines, the stable ones of the dashed lines
    n_unstable = int((ds["stable"] != 1).sum())
    assert sum(np.isnan(c.dimension_values(1)).sum() for c in stable) == n_unstable > 0
    assert sum(np.isfinite(c.dimension_values(1)).sum() for c in unstable) == n_unstable


def test_to_frame_is_one_row_per_grid_point_in_um_and_hz(ds):
    table = ds.rotorsweep.to_frame(["max_abs_multiplier", "amplitude_x"])
    assert list(table.columns) == ["speed_Hz", "clearance_um", "max_abs_multiplier", "amplitude_x_um"]
    assert len(table) == ds.sizes["speed"] * ds.sizes["clearance"]
    np.testing.assert_allclose(np.unique(table["clearance_um"]), ds["clearance"].values * 1e6)
    at = ds.isel(speed=3, clearance=2)
    row = table[(table["speed_Hz"] == float(at.speed)) & np.isclose(table["clearance_um"], float(at.clearance) * 1e6)]
    np.testing.assert_allclose(row["amplitude_x_um"], float(at["amplitude_x"]) * 1e6)
    assert "max_abs_multiplier" in ds.rotorsweep.to_frame().columns              # default: every per-point variable
    with pytest.raises(ValueError, match="poincare_x not a variable with one value per row"):
        ds.rotorsweep.to_frame(["poincare_x"])


def _figure(plot):
    state = hv.renderer("bokeh").get_plot(plot).state
    return state if hasattr(state, "xaxis") else state.children[0]


@pytest.mark.parametrize("kind", KINDS)
def test_figures_show_um_and_no_selected_dimension_in_the_title(ds, kind):
    where = {"where": {"clearance": float(ds.clearance[0])}} if kind == "multipliers" else {}
    fig = _figure(getattr(ds.rotorsweep, kind)(**where))
    assert "=" not in fig.title.text                      # no `multiplier = 0`, `preload = 0.0 [N]`
    labels = [fig.xaxis[0].axis_label, fig.yaxis[0].axis_label]
    assert not any(label.endswith("(m)") for label in labels)
    if kind in ("branches", "response", "bifurcation"):
        assert labels[1].endswith("(µm)") and labels[0] == "shaft speed (Hz)"
    if kind == "stability_map":
        assert labels[1] == "radial internal clearance (µm)"


def test_dashed_lines_have_the_colour_of_their_solid_lines(ds):
    from bokeh.models import GlyphRenderer

    fig = _figure(ds.rotorsweep.branches("amplitude_x"))
    renderers = fig.select(GlyphRenderer)
    solid = {r.name: r.glyph.line_color for r in renderers if not r.glyph.line_dash}
    dashed = {r.name: r.glyph.line_color for r in renderers if r.glyph.line_dash}
    assert solid == dashed and len(set(solid.values())) == ds.sizes["clearance"]     # keyed by legend label

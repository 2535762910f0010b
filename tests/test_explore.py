"""The hvplot functions and the `rotorsweep` accessor on a cube: each figure kind is an hvplot
(HoloViews) object that renders with bokeh."""
import holoviews as hv
import numpy as np
import pytest

import rotorsweep
from pipeline import explore
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

"""The report of a cube of tori (issue 38 item 5): a sweep with quasi-periodic forcing at every
point gets its response figure (the half-swing over the torus, stable solid, unstable or undecided
dashed, failed tori marked on the axis), no multiplier figures, and the unstable and failed tori
in its unstable-interval table. Bokeh model checks (tests/figure_checks.py), no browser."""
import csv
import importlib

import numpy as np
import pytest

from rotorsweep.pipeline.report import registry
from rotorsweep.pipeline.report.figures import response
from tests.figure_checks import assert_legend_hover_and_width, plots_of
from tests.synthetic import synthetic_cube, with_tori

report = importlib.import_module("rotorsweep.pipeline.report")

SPEED = np.arange(300.0, 320.0, 1.0)
LINE0 = ["stable"] * 5 + ["unstable"] * 5 + ["failed"] * 2 + ["undecided"] * 3 + ["stable"] * 5


def tori_cube():
    kinds = np.array([LINE0, ["stable"] * SPEED.size], object).T
    return with_tori(synthetic_cube(speed=SPEED, clearance=[3.8e-6, 19e-6]), kinds)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    out = tmp_path_factory.mktemp("tori_report")
    return report.make_report(tori_cube(), out), out


def test_a_cube_of_tori_gets_the_response_figure_and_no_multiplier_figures(made):
    files, out = made
    assert [p.name for p in files["png"]] == ["stability_map.png", "response.png"]
    rows = list(csv.DictReader(open(files["csv"])))
    assert [(r["start [Hz]"], r["end [Hz]"], r["type"], r["torus failed: status"]) for r in rows] == [
        ("305", "309", "quasi_periodic_unstable", "-"), ("310", "311", "torus_failed", "fourier_decay_failed")]
    assert "quasi-periodic unstable" in (out / "report.html").read_text()


def test_a_cube_without_tori_or_orbits_gets_no_response_figure():
    ds = with_tori(synthetic_cube(speed=SPEED, clearance=[3.8e-6]), np.full((SPEED.size, 1), "failed", object))
    ds["torus_status"][:] = -1          # not_applicable without a torus attempted (no [analysis] floquet)
    assert "response" not in [f.name for f in registry.figures_for(ds)]
    assert "response" in [f.name for f in registry.figures_for(tori_cube())]


def test_the_response_draws_tori_stable_solid_unstable_dashed_and_marks_the_failed():
    ds = tori_cube()
    fig = response.fig_response(ds, "bokeh")
    figures = [("response", "response.png", fig)]
    assert_legend_hover_and_width(figures)
    plots = [p for _, p in plots_of(figures)]
    assert len(plots) == 2                                    # x and y
    for plot in plots:
        lines = [r for r in plot.renderers if type(r.glyph).__name__ == "Line"]
        first = [r for r in lines if r.glyph.line_color == lines[0].glyph.line_color]    # clearance 3.8 um
        solid, dashed = (next(r for r in first if bool(r.glyph.line_dash) == d) for d in (False, True))

        def drawn(r):
            data = r.data_source.data
            x, y = np.asarray(data["speed"], float), np.asarray(data[next(k for k in data if k.startswith("amplitude"))], float)
            return set(x[np.isfinite(y)].tolist())
        # stable runs reach one point into the next run (no gap); undecided tori are dashed
        assert drawn(solid) == set(SPEED[:6].tolist()) | set(SPEED[15:].tolist())
        assert drawn(dashed) == set(SPEED[5:10].tolist()) | set(SPEED[12:16].tolist())
        (marks,) = [r for r in plot.renderers if type(r.glyph).__name__ == "Scatter"
                    and r.glyph.marker == "square" and not r.glyph.fill_alpha]
        data = marks.data_source.data
        assert list(data["speed"]) == [310.0, 311.0] and list(data[next(k for k in data if k != "speed")]) == [0.0, 0.0]
        legend = [i.label["value"] for legend in plot.legend for i in legend.items]
        assert response.FAILED in legend

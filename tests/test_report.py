"""Report: HTML + PNG + CSV from synthetic cubes. Rendering is slow (seconds per report), so each
report is made once per module and shared by the tests."""
import csv
import importlib

import matplotlib.image as mpimg
import numpy as np
import pytest
import xarray as xr

from pipeline import query, schema
from tests.synthetic import synthetic_cube

# `from pipeline import report` can return the function of that name in pipeline/__init__.py
report = importlib.import_module("pipeline.report")

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def all_stable_cube():
    ds = synthetic_cube()
    ds["stable"][:] = 1
    ds["bifurcation"][:] = 0
    ds["max_abs_multiplier"][:] = 0.5
    ds["multiplier_real"][:] = ds["multiplier_real"] * 0.4
    ds["multiplier_imag"][:] = ds["multiplier_imag"] * 0.4
    return ds


def cube_4d(angles=(15.0, 40.0), preloads=(0.0, 200.0), step=6.0):
    """synthetic_cube expanded over contact_angle and preload. Preloaded facets are stable; the
    largest clearance has no periodic orbit (NaN multipliers) at the top speeds."""
    ds = synthetic_cube(speed=np.arange(10.0, 250.01, step))
    ds = ds.drop_vars(["contact_angle", "preload"])
    ds = ds.expand_dims(contact_angle=np.asarray(angles, float), preload=np.asarray(preloads, float))
    ds = ds.transpose(*schema.AXES, ...).copy(deep=True)
    for a in ("contact_angle", "preload"):
        ds[a].attrs.update(units=schema.AXES[a][0], long_name=schema.AXES[a][1])
    preloaded = ds["preload"] > 0
    ds["max_abs_multiplier"] = ds["max_abs_multiplier"].where(~preloaded, 0.5 * ds["max_abs_multiplier"])
    ds["stable"] = xr.where(preloaded, 1, ds["stable"]).astype("int8")
    ds["bifurcation"] = xr.where(preloaded, 0, ds["bifurcation"]).astype("int8")
    diverged = (ds["speed"] > 230) & (ds["clearance"] == ds["clearance"].max())
    ds["orbit_status"] = xr.where(diverged, 2, ds["orbit_status"]).astype("int8")
    for v in ("multiplier_real", "multiplier_imag", "max_abs_multiplier"):
        ds[v] = ds[v].where(~diverged)
    ds["stable"] = xr.where(diverged, schema.INT_FILL, ds["stable"]).astype("int8")
    ds["bifurcation"] = xr.where(diverged, schema.INT_FILL, ds["bifurcation"]).astype("int8")
    return ds.transpose(*schema.AXES, ...)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """{name: (cube, make_report result)} for the base, all-stable and 4-D cubes."""
    hv = report._hv()   # importing the plotting backends itself sets one
    before = hv.Store.current_backend
    cubes = {"base": synthetic_cube(), "stable": all_stable_cube(), "4d": cube_4d()}
    out = {k: (ds, report.make_report(ds, tmp_path_factory.mktemp(k) / "rep")) for k, ds in cubes.items()}
    assert hv.Store.current_backend == before, "make_report must restore the HoloViews backend"
    return out


def _read_html(res):
    return res["html"].read_text(encoding="utf-8")


def _colour_pixels(img, hex_colour, tol=0.02):
    rgb = np.array([int(hex_colour[i:i + 2], 16) for i in (1, 3, 5)]) / 255.0
    return int((np.abs(img[..., :3] - rgb).max(axis=-1) < tol).sum())


def test_writes_all_files(made):
    for _, res in made.values():
        assert res["html"].name == "report.html" and res["html"].stat().st_size > 100_000
        assert [p.name for p in res["png"]] == [name for name, _ in report.FIGURES]
        assert res["csv"].name == "unstable_intervals.csv"
        assert all(p.parent == res["html"].parent for p in [*res["png"], res["csv"]])


def test_pngs_are_real_images_of_sane_size(made):
    for _, res in made.values():
        for p in res["png"]:
            assert p.read_bytes()[:8] == PNG_MAGIC
            h, w = mpimg.imread(p).shape[:2]
            assert 600 <= w <= 1600, (p.name, w)
            assert 200 <= h <= 1600, (p.name, h)
            # not a blank canvas
            assert len(np.unique(mpimg.imread(p)[..., :3].reshape(-1, 3), axis=0)) > 10


def test_stability_map_shows_the_classes(made):
    base = mpimg.imread(made["base"][1]["png"][0])
    stable = mpimg.imread(made["stable"][1]["png"][0])
    assert not (base.shape == stable.shape and np.allclose(base, stable))
    # the synthetic cube has period-doubling, Neimark-Sacker and fold bands: their cells add
    # many pixels of the class colour beyond the colorbar swatch both maps share
    for cls in ("fold", "period doubling", "Neimark-Sacker"):
        colour = report.PALETTE[report.CLASSES.index(cls)]
        n_base, n_stable = _colour_pixels(base, colour), _colour_pixels(stable, colour)
        assert n_stable > 0, cls  # legend swatch
        assert n_base > 2 * n_stable, (cls, n_base, n_stable)
    stable_colour = report.PALETTE[0]
    assert _colour_pixels(stable, stable_colour) > _colour_pixels(base, stable_colour)


def test_html_is_offline_and_has_header_table_and_config(made):
    ds, res = made["base"]
    text = _read_html(res)
    assert '<script src="http' not in text and "<script src=" not in text
    assert '<link rel="stylesheet" href="http' not in text
    assert ds.attrs["config_hash"] in text
    assert "synthetic" in text
    assert '<pre class="config">[scene]\nname = &quot;synthetic&quot;' in text
    by_status, by_class = report.counts(ds)
    assert f"<li>converged: {by_status['converged']}</li>" in text
    assert f"<li>stable: {by_class['stable']}</li>" in text
    intervals = query.unstable_intervals(ds)
    assert intervals
    for iv in intervals:
        row = (f"<tr><td>{iv['clearance'] * 1e6:.6g}</td><td>{iv['start']:.6g}</td>"
               f"<td>{iv['end']:.6g}</td><td>-</td><td>-</td><td>{iv['n_points']}</td>")
        assert row in text, row
    # table after the figures, config last
    assert text.index("Stability-region map") < text.index("Unstable speed intervals") < text.index("Configuration")


def test_csv_is_the_unstable_interval_table(made):
    ds, res = made["base"]
    with open(res["csv"], newline="") as f:
        rows = list(csv.DictReader(f))
    intervals = query.unstable_intervals(ds)
    assert len(rows) == len(intervals)
    for row, iv in zip(rows, intervals):
        assert float(row["radial clearance [um]"]) == pytest.approx(iv["clearance"] * 1e6)
        assert float(row["start [Hz]"]) == iv["start"] and float(row["end [Hz]"]) == iv["end"]
        assert int(row["points"]) == iv["n_points"] and row["type"] == iv["type"]
        assert float(row["max abs multiplier"]) == pytest.approx(iv["max_abs_multiplier"], rel=1e-3)


def test_all_stable_cube(made):
    _, res = made["stable"]
    assert "no unstable intervals" in _read_html(res)
    with open(res["csv"], newline="") as f:
        rows = list(csv.reader(f))
    assert len(rows) == 1 and "start [Hz]" in rows[0]


def test_4d_cube_gets_facets(made):
    ds, res = made["4d"]
    plan = report.axes_plan(ds)
    assert plan["y"] == "clearance" and plan["facets"] == ["contact_angle", "preload"]
    assert len(plan["shown"]) == 4 and not plan["omitted"]
    fig = report.fig_stability_map(ds, "matplotlib")
    assert len(fig) == 4
    text = _read_html(res)
    for title in ("contact angle 15 deg, preload 0 N", "contact angle 40 deg, preload 200 N"):
        assert title in text
    # a 2 x 2 grid of panels is taller than the single 2-D map
    h4 = mpimg.imread(res["png"][0]).shape[0]
    h2 = mpimg.imread(made["base"][1]["png"][0]).shape[0]
    assert h4 > 1.4 * h2
    with open(res["csv"], newline="") as f:
        header = next(csv.reader(f))
    assert header[:3] == ["radial clearance [um]", "contact angle [deg]", "preload [N]"]
    # the no-orbit points are counted, and their NaN multipliers never reach a figure
    assert report.counts(ds)[1]["no periodic orbit"] == int((ds["orbit_status"] != 0).sum()) > 0
    paths = report.fig_multiplier_paths(ds, "matplotlib")
    points = [el for panel in paths for el in panel if type(el).__name__ == "Points"]
    assert points and all(np.isfinite(p.array()).all() for p in points)


def test_facet_count_is_capped_and_omissions_are_named():
    ds = cube_4d(angles=(15.0, 25.0, 40.0), preloads=(0.0, 50.0, 100.0, 150.0, 200.0), step=20.0)
    plan = report.axes_plan(ds)
    assert len(plan["shown"]) == report.MAX_PANELS and len(plan["omitted"]) == 3
    fig = report.fig_stability_map(ds, "matplotlib")
    assert len(fig) == report.MAX_PANELS
    assert "3 omitted" in report._figure_title("x", plan)
    header = report._header_html(ds, "t", plan)
    for where in plan["omitted"]:
        assert report._where_label(where) in header


def test_boundaries_are_capped_deterministic_and_inside_the_grid():
    ds = synthetic_cube()
    b1, b2 = report.stability_boundaries(ds), report.stability_boundaries(ds)
    assert b1 == b2
    assert 0 < len(b1) <= report.MAX_BOUNDARIES
    assert {b["type"] for b in b1} >= {"fold", "period_doubling", "neimark_sacker"}
    # a run that starts at the first grid speed has no onset boundary
    ds2 = synthetic_cube(speed=np.arange(84.0, 120.0, 2.0), clearance=[3.8e-6])
    (iv,) = query.unstable_intervals(ds2)
    assert iv["start"] == 84.0
    kinds = [b["kind"] for b in report.stability_boundaries(ds2)]
    assert kinds == ["end"]

"""Report: HTML + PNG + CSV from synthetic cubes. Rendering is slow (seconds per report), so each
report is made once per module and shared by the tests."""
import csv
import importlib
import re

import matplotlib.image as mpimg
import numpy as np
import pytest
import xarray as xr

from rotorsweep.pipeline import cube, query, schema
from tests.synthetic import synthetic_cube

# `from rotorsweep.pipeline import report` can return the function of that name in pipeline/__init__.py
report = importlib.import_module("rotorsweep.pipeline.report")

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
BASE_PNGS = ("stability_map.png", "branches.png", "max_multiplier.png", "response.png", "multiplier_frequency.png",
             "multiplier_paths.png")


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
    ds = ds.drop_vars(["preload"])
    del ds.attrs[cube.DERIVED_ATTR]             # contact_angle is swept here
    ds = ds.expand_dims(contact_angle=np.asarray(angles, float), preload=np.asarray(preloads, float))
    ds = ds.transpose(*schema.axes_of(schema.model_of({})), ...).copy(deep=True)
    for a in ("contact_angle", "preload"):
        ds[a].attrs.update(units=schema.axes_of(schema.model_of({}))[a][0], long_name=schema.axes_of(schema.model_of({}))[a][1])
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
    return ds.transpose(*schema.axes_of(schema.model_of({})), ...)


def attractor_cube():
    """Attractor diagnostics of both sweep directions, a boundary table (tests/synthetic.py)."""
    return synthetic_cube(attractor=True, sweep_direction="both", boundaries=True)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """{name: (cube, make_report result)} for the base, all-stable, 4-D and attractor cubes."""
    hv = report.holoviews()   # importing the plotting backends itself sets one
    before = hv.Store.current_backend
    cubes = {"base": synthetic_cube(), "stable": all_stable_cube(), "4d": cube_4d(),
             "attractor": attractor_cube()}
    out = {k: (ds, report.make_report(ds, tmp_path_factory.mktemp(k) / "rep")) for k, ds in cubes.items()}
    assert hv.Store.current_backend == before, "make_report must restore the HoloViews backend"
    return out


def _read_html(res):
    return res["html"].read_text(encoding="utf-8")


def _colour_pixels(img, hex_colour, tol=0.02):
    rgb = np.array([int(hex_colour[i:i + 2], 16) for i in (1, 3, 5)]) / 255.0
    return int((np.abs(img[..., :3] - rgb).max(axis=-1) < tol).sum())


ATLAS_PNGS = ("atlas_onset.png", "atlas_stable_fraction.png", "atlas_boundaries.png")


def expected_pngs(name):
    """The report's figures: the base set, the attractor figures after it, the atlas summaries
    (cubes with more than two varying axes) right after the stability map."""
    if name == "4d":
        return [BASE_PNGS[0], *ATLAS_PNGS, *BASE_PNGS[1:]]
    return list(BASE_PNGS) + (["bifurcation.png", "lle.png"] if name == "attractor" else [])


def test_writes_all_files(made):
    for name, (ds, res) in made.items():
        assert res["html"].name == "report.html" and res["html"].stat().st_size > 100_000
        pngs = expected_pngs(name)
        assert [p.name for p in res["png"]] == pngs
        assert [f.filename for f in report.figures_for(ds)] == pngs
        assert res["csv"].name == "unstable_intervals.csv"
        assert res["points"] == []
        assert all(p.parent == res["html"].parent for p in [*res["png"], res["csv"]])


def test_cubes_without_attractor_variables_keep_the_old_figure_set(made):
    for name in ("base", "stable", "4d"):
        ds, res = made[name]
        assert not report.has_attractor(ds)
        assert [p.name for p in res["png"]] == expected_pngs(name)
        text = _read_html(res)
        assert "Bifurcation diagram" not in text and "Lyapunov" not in text
        assert "attractor (" not in text


def _not_blank(img, min_colours=10):
    return len(np.unique(img[::3, ::3, :3].reshape(-1, 3), axis=0)) > min_colours


def test_pngs_are_real_images_of_sane_size(made):
    for _, res in made.values():
        for p in res["png"]:
            assert p.read_bytes()[:8] == PNG_MAGIC
            img = mpimg.imread(p)
            h, w = img.shape[:2]
            assert 600 <= w <= 1600, (p.name, w)
            assert 200 <= h <= 1800, (p.name, h)
            assert _not_blank(img), p.name


def test_stability_map_shows_the_classes(made):
    base = mpimg.imread(made["base"][1]["png"][0])
    stable = mpimg.imread(made["stable"][1]["png"][0])
    assert not (base.shape == stable.shape and np.allclose(base, stable))
    # the synthetic cube has period-doubling, Neimark-Sacker and fold bands; the all-stable cube
    # has none, and its legend names only the classes it has
    for cls in ("fold", "period doubling", "Neimark-Sacker"):
        colour = report.PALETTE[report.CLASSES.index(cls)]
        n_base, n_stable = _colour_pixels(base, colour), _colour_pixels(stable, colour)
        assert n_stable == 0, cls
        assert n_base > 2000, (cls, n_base)
    stable_colour = report.PALETTE[0]
    assert _colour_pixels(stable, stable_colour) > _colour_pixels(base, stable_colour)


def _elements(fig, kind):
    """Elements of one type in a figure (an overlay, or a layout of overlays)."""
    panels = list(fig) if type(fig).__name__ == "Layout" else [fig]
    return [el for panel in panels for el in panel if type(el).__name__ == kind]


def _interior_edges(rects):
    """Speed edges where two rectangles of one band meet."""
    edges = set()
    for r in rects:
        for x0, y0, x1, y1 in r.array(["x0", "y0", "x1", "y1"]):
            if x1 > x0:
                edges.update({(round(y0, 6), x0), (round(y0, 6), x1)})
    return edges


def test_map_edges_are_the_refined_boundaries():
    """The stability map draws runs of one class as rectangles whose speed edges are the
    boundary table's refined speeds, not the grid (the data drawn, not pixels)."""
    ds = synthetic_cube(boundaries=True)
    assert ds.sizes["boundary"] == 10
    fig = report.fig_stability_map(ds, "matplotlib")
    rects = _elements(fig, "Rectangles")
    assert {r.label for r in rects} == {"stable", "fold", "period doubling", "Neimark-Sacker"}
    edges = _interior_edges(rects)
    clearances = list(ds["clearance"].values)
    for k in range(ds.sizes["boundary"]):
        band = clearances.index(ds["boundary_clearance"].values[k])
        speed = float(ds["boundary_speed"].values[k])
        assert (round(band - report.RECT_HALF, 6), speed) in edges, (band, speed)
        # strictly between the grid speeds: not a staircase edge
        assert ds["boundary_grid_low"].values[k] < speed < ds["boundary_grid_high"].values[k]
    # every interior edge (outside the grid ends) is a refined boundary
    first, last = report.axis_edges(ds["speed"].values)
    inner = {x for _, x in edges if first < x < last}
    assert inner == set(ds["boundary_speed"].values.tolist())
    # the refined edges are also drawn as segments (legend: refined boundary)
    (segs,) = _elements(fig, "Segments")
    assert sorted(segs.array(["x0"])[:, 0]) == sorted(ds["boundary_speed"].values)
    # same data for bokeh
    bk = _interior_edges(_elements(report.fig_stability_map(ds, "bokeh"), "Rectangles"))
    assert bk == edges


def test_figures_run_along_the_cubes_continued_axis():
    """The x axis of every figure is the cube's continued_axis attribute; cubes written before it
    fall back to the first swept dimension (speed)."""
    ds = synthetic_cube()
    assert "continued_axis" not in ds.attrs and report.continued_axis(ds) == "speed"
    assert [f.caption(ds) for f in report.figures_for(ds)][2] == "Largest Floquet multiplier vs shaft speed"
    ds.attrs["continued_axis"] = "clearance"
    plan = report.axes_plan(ds)
    assert (plan["x"], plan["y"]) == ("clearance", "speed")
    assert report.figures_for(ds)[2].caption(ds) == "Largest Floquet multiplier vs radial clearance"
    segments, _ = report.line_segments(ds, {"speed": 100.0})
    assert segments[0][0] < ds["clearance"].values[0] and segments[-1][1] > ds["clearance"].values[-1]
    assert segments[-1][1] < 1e-4       # clearance units, not speeds
    fig = report.fig_stability_map(ds, "matplotlib")
    assert {round(y0 + report.RECT_HALF) for r in _elements(fig, "Rectangles")
            for _, y0, _, _ in r.array(["x0", "y0", "x1", "y1"])} == set(range(ds.sizes["speed"]))


def test_map_without_boundary_table_puts_edges_midway():
    ds = synthetic_cube(speed=np.arange(70.0, 110.0, 2.0), clearance=[3.8e-6])
    segments, refined = report.line_segments(ds, {})
    assert refined == []
    (iv,) = query.unstable_intervals(ds)
    assert [s[2] for s in segments] == [0.0, 2.0, 0.0]
    assert segments[1][:2] == (iv["start"] - 1.0, iv["end"] + 1.0)
    assert segments[0][0] == 69.0 and segments[-1][1] == 109.0
    # with a table: the same runs, edges moved to the refined speeds
    ds_b = synthetic_cube(speed=np.arange(70.0, 110.0, 2.0), clearance=[3.8e-6], boundaries=True)
    seg_b, refined_b = report.line_segments(ds_b, {"clearance": 3.8e-6})
    (iv_b,) = query.unstable_intervals(ds_b)
    assert seg_b[1][:2] == (iv_b["onset"], iv_b["offset"]) and refined_b == [iv_b["onset"], iv_b["offset"]]


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
    assert "3 omitted" in report.figure_title(ds, "x", plan)
    header = report.header_html(ds, "t", plan)
    for where in plan["omitted"]:
        assert report.where_label(ds, where) in header


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


# ----------------------------------------------------------------------------- attractor figures

def test_attractor_figures_are_nontrivial_pngs_in_the_html(made):
    ds, res = made["attractor"]
    pngs = {p.name: p for p in res["png"]}
    for name in ("bifurcation.png", "lle.png"):
        img = mpimg.imread(pngs[name])
        assert pngs[name].stat().st_size > 50_000, name
        assert _not_blank(img, 50), name
        assert img.shape[0] > 5 * 150       # one panel per clearance, stacked
    text = _read_html(res)
    for caption in ("Bifurcation diagram", "Largest Lyapunov exponent vs shaft speed"):
        assert f"<h2>{caption}</h2>" in text
    assert text.count('<div class="figure">') == len(BASE_PNGS) + 2
    # bifurcation dots: both sweep colours and the shading of the unstable intervals
    img = mpimg.imread(pngs["bifurcation.png"])
    for colour in report.SWEEP_COLOURS:
        assert _colour_pixels(img, colour, tol=0.08) > 200, colour


def test_header_counts_attractor_classes(made):
    ds, res = made["attractor"]
    text = _read_html(res)
    up, down = report.attractor_counts(ds), report.attractor_counts(ds, schema.DOWN_SUFFIX)
    assert up["chaotic"] > 0 and up["quasi-periodic"] > 0 and up["diverged"] == 0
    assert up["periodic, period 1"] > 0 and up["periodic, period 2"] > 0
    assert sum(up.values()) == ds.sizes["speed"] * ds.sizes["clearance"]
    assert "<b>attractor (sweep up)</b>" in text and "<b>attractor (sweep down)</b>" in text
    for key, n in up.items():
        assert f"<li>{key}: {n}</li>" in text
    n_hyst = int((ds["hysteresis"] == 1).sum())
    assert n_hyst > 0
    assert f"<li>hysteresis (sweeps end on different attractors): {n_hyst}</li>" in text
    assert down["periodic, period 2"] > up["periodic, period 2"]


def test_bifurcation_shading_uses_the_refined_onsets_and_offsets():
    ds = attractor_cube()
    fig = report.fig_bifurcation(ds, "matplotlib")
    assert len(fig) == ds.sizes["clearance"]
    intervals = query.unstable_intervals(ds)
    for panel, c in zip(fig, ds["clearance"].values):
        spans = sorted((x0, x1) for r in _elements(panel, "Rectangles")
                       for x0, _, x1, _ in r.array(["x0", "y0", "x1", "y1"]) if x1 > x0)
        want = sorted((iv["onset"], iv["offset"]) for iv in intervals if iv["clearance"] == c)
        assert spans == want
        labels = {el.label for el in panel}
        assert {"sweep up", "sweep down", "hysteresis (up and down differ)"} <= labels


def test_poincare_points_are_thinned_per_speed():
    rng = np.random.default_rng(0)
    speed = np.arange(5.0)
    values = np.empty((5, 128))
    values[0] = 1.0                                     # period 1
    values[1] = np.tile([1.0, 2.0], 64)                 # period 2
    values[2] = rng.uniform(0, 1, 128)                  # chaos
    values[3] = np.nan                                  # diverged
    values[4] = np.tile([0.0, 1.0, 1.0 + 1e-9, 3.0], 32)   # period 4, two values within resolution
    sp, val = report.thin_points(speed, values, cap=16, resolution=1e-6)
    per = {s: np.sort(val[sp == s]) for s in speed}
    assert list(per[0.0]) == [1.0] and list(per[1.0]) == [1.0, 2.0]
    assert per[3.0].size == 0 and per[4.0].size == 3
    assert 8 <= per[2.0].size <= 16
    # the thinning keeps the spread of the cloud
    assert per[2.0].min() < 0.1 and per[2.0].max() > 0.9


def test_bifurcation_of_a_fig13_size_cube_stays_small():
    """2401 speeds x 5 clearances x 128 samples (1.5 M points, both directions 3 M): the figure
    draws at most BIF_POINTS per panel."""
    ds = synthetic_cube(speed=np.round(np.arange(10.0, 250.01, 0.1), 6), attractor=True,
                        sweep_direction="both")
    for backend in ("bokeh", "matplotlib"):
        fig = report.fig_bifurcation(ds, backend)
        for panel in fig:
            n = sum(len(p) for p in _elements(panel, "Points") if p.label.startswith("sweep"))
            assert 2401 <= n <= report.BIF_POINTS[backend], (backend, n)


def test_lle_figure_marks_methods_and_chaos():
    ds = attractor_cube()
    fig = report.fig_lle(ds, "matplotlib")
    assert len(fig) == ds.sizes["clearance"]
    for panel, c in zip(fig, ds["clearance"].values):
        line = ds.sel(clearance=c)
        pts = {p.label: p for p in _elements(panel, "Points")}
        integ, derived, chaos = (pts[k] for k in ("integrated (Benettin/QR)", "derived ln|λ|/(kT)",
                                                  "chaotic attractor"))
        finite = lambda p: p.array()[np.isfinite(p.array()[:, 0])]   # noqa: E731
        assert len(finite(integ)) == int((line["lle_method"] == 0).sum())
        assert len(finite(derived)) == int((line["lle_method"] == 1).sum())
        assert len(finite(chaos)) == int((line["attractor"] == 3).sum())
        assert np.all(finite(chaos)[:, 1] > 0)
        (spread,) = _elements(panel, "Spread")
        assert len(spread) == int(np.isfinite(line["lle"]).sum())
        assert len(_elements(panel, "HLine")) == 1


# ----------------------------------------------------------------------------- --point

def test_parse_and_resolve_points():
    ds = synthetic_cube()
    assert report.parse_point(["speed=36", "clearance=19e-6"]) == {"speed": 36.0, "clearance": 1.9e-5}
    assert report.parse_point("speed=36,clearance=19e-6") == {"speed": 36.0, "clearance": 1.9e-5}
    r = report.resolve_point(ds, {"speed": 36.9, "clearance": 12e-6})
    assert r["values"] == {"speed": 36.0, "clearance": 1.14e-5}
    assert report.point_filename(ds, r) == "point_36Hz_11.4um.png"
    # a trailing comma is harmless; values between grid points take the nearest one
    assert report.resolve_point(ds, "speed=50 clearance=1e-5,")["values"] == {"speed": 50.0,
                                                                                "clearance": 1.14e-5}
    bad = {"speed=500 clearance=3.8e-6": "speed=500 is outside the cube's grid: speed spans 10 .. 250 Hz (121 values)",
           "speed=50": "give clearance=VALUE too; the cube sweeps clearance over 3.8e-06 .. 1.9e-05 m",
           "speed=50 clearance=40e-6": "clearance=4e-05 is outside",
           "speed=50 clearance=4e-6 preload=10": "preload is not swept",
           "clearance=4e-6": "give speed=VALUE too",
           "speed=fast": "bad number 'fast'",
           "speed": "expected AXIS=VALUE",
           "speed=1 speed=2": "speed is given twice",
           "sped=40": "unknown axis 'sped'"}
    for spec, message in bad.items():
        with pytest.raises(query.QueryError, match=re.escape(message)):
            report.resolve_point(ds, spec)


def _cli(args, capsys):
    from rotorsweep.pipeline import cli
    code = cli.main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_point_outside_the_grid_exits_2_before_drawing(tmp_path, capsys):
    path = cube.write_cube(synthetic_cube(), tmp_path / "syn.nc")
    code, out, err = _cli(["report", path, "-o", tmp_path / "rep", "--point", "speed=500",
                           "clearance=3.8e-6"], capsys)
    assert code == 2
    assert "rotorsweep report: error: point speed=500 is outside the cube's grid: speed spans 10 .. 250 Hz" in err
    assert "Traceback" not in err and not (tmp_path / "rep").exists()
    # a synthetic cube has no usable scene to recompute a point from
    code, _, err = _cli(["report", path, "-o", tmp_path / "rep", "--point", "speed=50",
                         "clearance=3.8e-6"], capsys)
    assert code == 2 and "config_toml" in err


def test_point_detail_on_a_real_attractor_cube(tiny_cube, tmp_path, capsys):
    out = tmp_path / "rep"
    code, stdout, err = _cli(["report", tiny_cube, "-o", out, "--point", "speed=63.4",
                              "clearance=19e-6"], capsys)
    assert code == 0, err
    phases = [line for line in err.splitlines() if line.startswith("== ")]
    # a real cube stores its scene: the Bode plot (orbits integrated again) joins the synthetic cubes' set
    assert phases[0].startswith("== drawing the figures (9) and the points in detail (1): ")
    assert sorted(p.split(" (")[0] for p in phases[1:]) == ["== HTML page written", "== PNGs written"]
    png = out / "point_64Hz_19um.png"
    assert f"figure: {png}" in stdout
    img = mpimg.imread(png)
    assert png.stat().st_size > 50_000 and _not_blank(img, 50)
    assert 800 <= img.shape[1] <= 1800 and 600 <= img.shape[0] <= 1600
    text = (out / "report.html").read_text(encoding="utf-8")
    assert "<h2>Points in detail</h2>" in text
    assert "<h3>Point shaft speed 64 Hz, radial clearance 19 µm</h3>" in text
    assert "(nearest grid point to speed=63.4)" in text
    # the cube's attractor at 64 Hz: period 2 (the period-1 orbit is unstable there)
    assert "<tr><th>attractor (sweep up, cube)</th><td>periodic</td></tr>" in text
    assert "<tr><th>  period</th><td>2 forcing periods</td></tr>" in text
    assert "from the cube&#x27;s attractor_state" in text
    assert text.count('<div class="figure">') == len(BASE_PNGS) + 4      # + bode, bifurcation, lle, point
    # the real boundary table drives the map: its refined speed is a rectangle edge
    ds = cube.open_cube(tiny_cube)
    (speed,) = ds["boundary_speed"].values
    assert 64.0 < speed < 66.0
    segments, refined = report.line_segments(ds, {"clearance": 19e-6})
    assert refined == [speed] and segments[0][1] == speed


def test_point_attractor_flag(capsys):
    import json
    code, out, err = _cli(["point", "--speed", "45", "--clearance", "19e-6", "--attractor", "--json"], capsys)
    assert code == 0, err
    a = json.loads(out)["attractor"]
    assert a["class"] == "periodic" and a["period"] == 2 and a["lle_method"] == "derived"
    assert a["lle"] < 0 and a["lle_stderr"] == 0.0 and a["max_abs_multiplier"] < 1
    assert len(a["multipliers"]) == 4 and len(a["lyapunov_exponents"]) == 4
    code, out, _ = _cli(["point", "--speed", "45", "--clearance", "19e-6", "--attractor"], capsys)
    assert code == 0
    assert "attractor         periodic" in out and "attractor period  2 forcing periods" in out
    assert "(derived)" in out and "periodic orbit    unstable (period_doubling)" in out


# ----------------------------------------------------------------------------- bokeh models

def _bokeh_plots(fig):
    """The bokeh figures (plots) of a figure rendered for the HTML page."""
    from bokeh.models import Plot
    hv = report.holoviews()
    with report.style.backend("bokeh"):
        return list(hv.render(fig, backend="bokeh").select({"type": Plot}))


def _tooltips(plot):
    from bokeh.models import HoverTool
    return [dict(h.tooltips) for h in plot.select({"type": HoverTool})]


def test_multiplier_panels_are_square_with_units_on_the_colour_bar():
    """Round unit circles: bokeh keeps data_aspect=1 only with frame_width == frame_height."""
    from bokeh.models import ColorBar
    plots = _bokeh_plots(report.fig_multiplier_paths(synthetic_cube(), "bokeh"))
    assert plots
    for plot in plots:
        assert plot.frame_width == plot.frame_height and plot.width is None and plot.height is None
        (bar,) = plot.select({"type": ColorBar})
        assert bar.title == "shaft speed [Hz]"
        (tips,) = _tooltips(plot)
        assert set(tips) == {"Re λ", "Im λ", "shaft speed [Hz]"}


@pytest.mark.slow    # 17-41 s: the default suite stays under 15 min on 2 cores (make test-slow)
def test_every_line_plot_has_a_hover_with_the_parameter_and_the_value():
    ds = attractor_cube()
    from rotorsweep.pipeline.report.figures import branch_diagram, multiplier_frequency, response
    values = {report.fig_max_multiplier: "max |multiplier|", report.fig_bifurcation: "Poincaré x [µm]",
              report.fig_lle: "largest Lyapunov exp. [1/s]", multiplier_frequency.fig_multiplier_frequency: "frequency [Hz]",
              response.fig_response: "amplitude of",
              branch_diagram.fig_branches: "Poincaré x of the orbit [µm]"}
    for make, value in values.items():
        plots = _bokeh_plots(make(ds, "bokeh"))
        assert plots, make.__name__
        for plot in plots:
            tips = _tooltips(plot)
            assert any("shaft speed [Hz]" in t and any(k.startswith(value) for k in t) for t in tips), \
                (make.__name__, tips)


def test_stability_map_hover_reads_interval_line_and_class():
    (plot,) = _bokeh_plots(report.fig_stability_map(synthetic_cube(boundaries=True), "bokeh"))
    tips = _tooltips(plot)
    assert tips and all(t == {"shaft speed [Hz] interval": "@{start}{0.[0000]} to @{end}{0.[0000]}",
                              "radial clearance": "@{line}", "orbit": "@{class}"} for t in tips)
    from bokeh.models import ColumnDataSource
    lines = {v for s in plot.select({"type": ColumnDataSource}) for v in s.data.get("line", [])}
    assert {"3.8 µm", "19 µm"} <= lines


def _glyphs(plot, kind):
    """The plot's own glyph renderers of a kind (select() would also reach the other panels')."""
    return [r for r in plot.renderers if type(r.glyph).__name__ == kind]


def test_branch_diagram_draws_stable_solid_unstable_dashed_and_labels_special_points():
    from rotorsweep.pipeline.report.figures import branch_diagram
    ds = attractor_cube()
    plots = _bokeh_plots(branch_diagram.fig_branches(ds, "bokeh", observable="amplitude_x"))
    assert len(plots) == ds.sizes["clearance"]
    titles = {report.where_label(ds, {"clearance": c}): c for c in ds["clearance"].values}
    for plot in plots:
        c = titles[plot.title.text]
        dashes = {r.name: list(r.glyph.line_dash) for r in _glyphs(plot, "Line")}
        assert dashes == {"periodic orbit, stable": [], "periodic orbit, unstable": [6]}
        (text,) = _glyphs(plot, "Text")
        rows = [b for b in range(ds.sizes["boundary"]) if ds["boundary_clearance"].values[b] == c]
        names = {1: "LP", 2: "PD", 3: "NS"}
        want = sorted((float(ds["boundary_speed"].values[b]), names[int(ds["boundary_type"].values[b])])
                      for b in rows)
        data = text.data_source.data
        assert sorted(zip(data["speed"], data["label"])) == want


def test_branch_segments_follow_the_branch_order_through_a_fold():
    """A branch that turns back (x not monotonic): runs are cut along the branch, not by x."""
    x = np.array([0.0, 1.0, 2.0, 1.5, 1.0, 0.5])
    stable = np.array([True, True, True, False, False, False])
    solid, dashed, marks, text = report.branch_elements(x, x ** 2, stable, [(2.0, 4.0, "LP")],
                                                           "matplotlib", dims=("p", "a"))
    np.testing.assert_array_equal(solid.dimension_values("p"), [0.0, 1.0, 2.0, 1.5])
    np.testing.assert_array_equal(dashed.dimension_values("p"), [1.5, 1.0, 0.5])
    assert solid.opts.get("style", "matplotlib").kwargs["linestyle"] == "-"
    assert dashed.opts.get("style", "matplotlib").kwargs["linestyle"] == "--"
    assert list(text.dimension_values("label")) == ["LP"]
    assert report.stability_runs([True, False, False, True]) == [(0, 2, True), (1, 4, False), (3, 4, True)]

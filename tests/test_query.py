"""Queries: selections, tables in three formats, unstable speed intervals."""
import csv
import io
import json
import math

import numpy as np
import pytest

from rotorsweep.pipeline import cube, query, schema
from tests.synthetic import synthetic_cube


@pytest.fixture(scope="module")
def ds():
    return synthetic_cube()


def test_parse_where():
    assert query.parse_where(["speed=80:120", "clearance=3.8e-6", "preload=0,100", "contact_angle=:15"]) == {
        "speed": slice(80.0, 120.0), "clearance": [3.8e-6], "preload": [0.0, 100.0],
        "contact_angle": slice(None, 15.0)}
    for bad, message in [("speed", "expected AXIS=SEL"), ("speed=", "expected AXIS=SEL"),
                         ("speed=fast", "bad number 'fast'"), ("speed=1:2:3", "bad range")]:
        with pytest.raises(query.QueryError, match=message):
            query.parse_where([bad])
    with pytest.raises(query.QueryError, match="speed is selected twice"):
        query.parse_where(["speed=1", "speed=2"])


def test_select_range_is_inclusive_and_keeps_dimensions(ds):
    sel = query.select(ds, query.parse_where(["speed=80:120", "clearance=7.6e-6"]))
    np.testing.assert_array_equal(sel.speed.values, np.arange(80.0, 120.1, 2.0))
    assert sel.sizes["clearance"] == 1
    assert query.select(ds, {"speed": slice(245.0, None)}).speed.values.tolist() == [246.0, 248.0, 250.0]


def test_select_values_match_the_grid_within_tolerance(ds):
    sel = query.select(ds, query.parse_where(["clearance=3.8000000001e-6,19e-6"]))
    assert sel.clearance.values.tolist() == [3.8e-6, 19.0e-6]           # the grid's own values


@pytest.mark.parametrize("where, message", [
    (["preload=0"], "preload is not a swept axis of this cube; its axes are speed, clearance"),
    (["temperature=20"], "its axes are speed, clearance"),
    (["clearance=4e-6"], r"clearance=4e-06 is not on the grid; available: 3.8e-06, 7.6e-06"),
    (["speed=300:400"], "selects no grid value; the grid spans 10 .. 250"),
    (["speed=120:80"], "selects no grid value"),
])
def test_bad_selections(ds, where, message):
    with pytest.raises(query.QueryError, match=message):
        query.select(ds, query.parse_where(where))


def small(ds):
    return query.select(ds, query.parse_where(["speed=80:84", "clearance=3.8e-6,19e-6"]))


def test_csv_table_parses_back_with_flag_names(ds):
    rows = list(csv.DictReader(io.StringIO(query.to_table(small(ds), fmt="csv"))))
    assert list(rows[0]) == ["speed", "clearance", "orbit_status", "max_abs_multiplier", "stable", "bifurcation"]
    assert len(rows) == 6
    assert [float(r["speed"]) for r in rows[:3]] == [80.0, 82.0, 84.0]    # speed varies fastest
    assert {r["orbit_status"] for r in rows} == {"converged"}
    assert rows[1]["stable"] == "unstable" and rows[1]["bifurcation"] == "period_doubling"
    at = small(ds).sel(speed=82.0, clearance=3.8e-6)
    assert float(rows[1]["max_abs_multiplier"]) == float(at.max_abs_multiplier)   # full precision


def test_json_records_with_nulls_and_multiplier_columns(ds):
    sel = small(ds).copy(deep=True)
    sel["max_abs_multiplier"][0, 0] = np.nan
    sel["stable"][0, 0] = schema.INT_FILL
    records = json.loads(query.to_table(sel, ["max_abs_multiplier", "stable", "multiplier_real"], fmt="json"))
    assert len(records) == 6
    assert records[0]["max_abs_multiplier"] is None and records[0]["stable"] is None
    assert [k for k in records[1] if k.startswith("multiplier_real")] == [f"multiplier_real_{k}" for k in range(4)]
    assert records[1]["multiplier_real_1"] == float(sel.multiplier_real.sel(speed=82.0, clearance=3.8e-6)[1])


def test_plain_table_is_aligned(ds):
    lines = query.to_table(small(ds)).splitlines()
    assert lines[0].split() == ["speed", "clearance", "orbit_status", "max_abs_multiplier", "stable", "bifurcation"]
    assert len(lines) == 7 and len({len(line) for line in lines}) == 1
    assert lines[2].split()[:2] == ["82", "3.8e-06"] and lines[2].split()[-1] == "period_doubling"


def test_unknown_variable_and_format(ds):
    with pytest.raises(query.QueryError, match="unknown variable 'lle'; this cube has orbit_status, "):
        query.to_table(ds, ["lle"])
    with pytest.raises(query.QueryError, match="unknown format 'xml'"):
        query.to_table(ds, fmt="xml")


def tiny_cube():
    """8 speeds x 2 clearances with known runs: clearance 1e-5 has a period-doubling run and a
    Neimark-Sacker run reaching the last speed; 2e-5 starts with no orbit, then one fold point."""
    U, S, F = 0, 1, schema.INT_FILL
    stable = [[S, U, U, S, S, U, U, U], [F, F, S, S, U, S, S, S]]
    bif = [[0, 2, 2, 0, 0, 3, 3, 3], [F, F, 0, 0, 1, 0, 0, 0]]
    status = [[0] * 8, [1, 2, 0, 0, 0, 0, 0, 0]]
    mu = [[0.9, 1.1, 1.3, 0.9, 0.8, 1.05, 1.2, 1.4], [np.nan, np.nan, 0.9, 0.9, 1.01, 0.9, 0.9, 0.9]]
    results = {"orbit_status": status, "stable": stable, "bifurcation": bif, "max_abs_multiplier": mu}
    results = {k: np.array(v).T for k, v in results.items()}
    return cube.build_dataset({"speed": np.arange(10.0, 90.0, 10.0), "clearance": np.array([1e-5, 2e-5])},
                              {"preload": 0.0}, results, {})


def test_unstable_intervals_on_known_runs():
    got = query.unstable_intervals(tiny_cube())
    nan = float("nan")
    expected = [
        {"clearance": 1e-5, "start": 20.0, "end": 30.0, "n_points": 2, "type": "period_doubling", "max_abs_multiplier": 1.3},
        {"clearance": 1e-5, "start": 60.0, "end": 80.0, "n_points": 3, "type": "neimark_sacker", "max_abs_multiplier": 1.4},
        {"clearance": 2e-5, "start": 10.0, "end": 20.0, "n_points": 2, "type": "no_orbit", "max_abs_multiplier": nan},
        {"clearance": 2e-5, "start": 50.0, "end": 50.0, "n_points": 1, "type": "fold", "max_abs_multiplier": 1.01},
    ]
    assert len(got) == len(expected)
    for g, e in zip(got, expected):
        assert np.isnan(g["onset"]) and np.isnan(g["offset"])     # no boundary table in this cube
        skip = ("max_abs_multiplier", "onset", "offset")
        assert {k: v for k, v in g.items() if k not in skip} == {k: v for k, v in e.items() if k not in skip}
        m = e["max_abs_multiplier"]
        assert math.isnan(g["max_abs_multiplier"]) if math.isnan(m) else g["max_abs_multiplier"] == m


def test_intervals_table_formats():
    intervals = query.unstable_intervals(tiny_cube())
    rows = list(csv.DictReader(io.StringIO(query.intervals_table(intervals, "csv"))))
    assert [r["type"] for r in rows] == ["period_doubling", "neimark_sacker", "no_orbit", "fold"]
    assert rows[2]["max_abs_multiplier"] == "" and float(rows[1]["end"]) == 80.0
    records = json.loads(query.intervals_table(intervals, "json"))
    assert records[2]["max_abs_multiplier"] is None and records[3]["n_points"] == 1
    table = query.intervals_table(intervals).splitlines()
    assert table[0].split() == ["clearance", "start", "end", "onset", "offset", "n_points", "type",
                                "max_abs_multiplier"]
    assert table[3].split() == ["2e-05", "10", "20", "-", "-", "2", "no_orbit", "-"]
    assert query.intervals_table([], "json") == "[]"
    assert query.intervals_table([], "table") == "no unstable intervals"


def test_not_applicable_points_are_never_unstable_intervals():
    """Quasi-periodic forcing has no periodic orbit by design: such points end a run and start none
    (issue 32 item 5)."""
    ds = tiny_cube()
    status = ds["orbit_status"].values.copy()
    speed_axis = ds["orbit_status"].dims.index("speed")
    na = np.take(status, [0, 1, 2], axis=speed_axis) * 0 + schema.ORBIT_STATUS.index("not_applicable")
    status[(slice(None),) * speed_axis + (slice(0, 3),)] = na
    ds["orbit_status"].values = status
    got = query.unstable_intervals(ds)
    assert [(g["clearance"], g["start"], g["end"], g["type"]) for g in got] == [
        (1e-5, 60.0, 80.0, "neimark_sacker"), (2e-5, 50.0, 50.0, "fold")]


def test_map_header_and_query_class_every_interval_alike():
    """One vocabulary (issue 32 item 5): every point of every unstable interval has the
    interval's type as its map class, and the header counts are those classes' sizes."""
    from rotorsweep.pipeline.report import stability

    ds = tiny_cube()
    classes = stability.stability_class(ds)
    dims = ds["orbit_status"].dims
    for iv in query.unstable_intervals(ds):
        line = {"clearance": iv["clearance"]}
        speeds = ds["speed"].values
        for i in np.flatnonzero((speeds >= iv["start"]) & (speeds <= iv["end"])):
            idx = tuple(i if d == "speed" else list(ds[d].values).index(line[d]) for d in dims)
            assert stability.CLASSES[int(classes[idx])].replace(" ", "_").replace("-", "_").lower() in (
                iv["type"], "no_periodic_orbit" if iv["type"] == "no_orbit" else iv["type"])
    _, by_class = stability.counts(ds)
    names = [t for iv in query.unstable_intervals(ds) for t in [iv["type"]] * iv["n_points"]]
    assert by_class["fold"] == names.count("fold") and by_class["period doubling"] == names.count("period_doubling")


@pytest.fixture(scope="module")
def fig13_slice(tmp_path_factory):
    """A real Fig. 13 sweep (configs/bai2006_fig13.toml, orbits only) at 15.2 and 19 um over
    28.2-32.6 Hz in 0.05 Hz steps: stable, bistable (15.2 um's fold pair near 31.1 Hz), period
    doubling (15.2 um, 32.4 Hz) and fold (19 um, 28.40159 Hz) intervals."""
    from pathlib import Path

    from rotorsweep.pipeline import config, sweep

    text = Path("configs/bai2006_fig13.toml").read_text()
    text = text.replace("speed = {start = 10.0, stop = 250.0, step = 0.1}", "speed = {start = 28.2, stop = 32.6, step = 0.05}")
    text = text.replace("clearance = [3.8e-6, 7.6e-6, 11.4e-6, 15.2e-6, 19.0e-6]", "clearance = [15.2e-6, 19.0e-6]")
    text = text.replace("attractor = true ", "attractor = false")
    out = tmp_path_factory.mktemp("fig13") / "slice.nc"
    sweep.run(config.parse_config(text), str(out), workers=0)
    return cube.open_cube(str(out))


def test_fig13_slice_map_header_query_and_info_class_every_interval_alike(fig13_slice):
    """One vocabulary on a real cube (issue 32 item 5): for every interval `info` lists, the map
    draws each of its points in that class, `query --unstable` / `--bistable` put them in an
    interval of that type (a stable one in none), and the header counts are the intervals' sizes."""
    from rotorsweep.pipeline.report import stability

    ds = fig13_slice
    runs = query.class_runs(ds)
    assert {r["class"] for r in runs} >= {"stable", "bistable", "period_doubling", "fold"}
    info = cube.describe(ds)
    drawn = stability.stability_class(ds)
    dims = ds["orbit_status"].dims
    speeds = ds["speed"].values
    unstable, bistable = query.unstable_intervals(ds), query.bistable_intervals(ds)

    def covering(intervals, run):
        return [iv for iv in intervals if iv["clearance"] == run["clearance"]
                and iv["start"] <= run["start"] and run["end"] <= iv["end"]]
    for run in runs:
        assert f"clearance={run['clearance']:g} {run['start']:g} .. {run['end']:g}  {run['class']} " in info
        for i in np.flatnonzero((speeds >= run["start"]) & (speeds <= run["end"])):
            idx = tuple(i if d == "speed" else list(ds[d].values).index(run["clearance"]) for d in dims)
            assert drawn[idx] == stability.NAME_CLASS[run["class"]]
        if run["class"] in ("stable", "bistable"):
            assert not covering(unstable, run)
            assert bool(covering(bistable, run)) == (run["class"] == "bistable")
        else:
            assert [iv["type"] for iv in covering(unstable, run)] == [run["class"]]
    _, by_class = stability.counts(ds)
    for k, shown in enumerate(stability.CLASSES):      # "no periodic orbit": no_orbit and not_applicable
        names = [name for name, c in stability.NAME_CLASS.items() if c == k]
        assert by_class.get(shown, 0) == sum(r["n_points"] for r in runs if r["class"] in names)  # torus classes: cubes with tori

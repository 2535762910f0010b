"""`query --unstable` with tori (issue 38 item 4): a sweep cube's runs of unstable and failed tori
listed with the periodic orbits' unstable intervals, in the classes of query.point_classes (one
vocabulary with the map, the report's counts and `info`), and a continuation result's unstable
stretches of its orbit and torus branches."""
import json

import numpy as np
import pytest

from rotorsweep.pipeline import cli, query
from tests.synthetic import synthetic_cube, with_tori

SPEED = np.arange(100.0, 120.0, 1.0)
# clearance 0: orbits, then tori stable, unstable, failed, undecided, unstable; clearance 1: orbits only
LINE0 = ["orbit"] * 4 + ["stable"] * 3 + ["unstable"] * 4 + ["failed"] * 2 + ["undecided"] * 2 + ["unstable"] + ["orbit"] * 4


@pytest.fixture(scope="module")
def ds():
    kinds = np.array([LINE0, ["orbit"] * SPEED.size], object).T
    return with_tori(synthetic_cube(speed=SPEED, clearance=[3.8e-6, 19e-6]), kinds)


def torus_rows(intervals):
    return [iv for iv in intervals if iv["type"] in query.TORUS_UNSTABLE]


def test_unstable_and_failed_tori_are_listed_like_unstable_orbits(ds):
    rows = torus_rows(query.unstable_intervals(ds))
    got = [(iv["clearance"], iv["start"], iv["end"], iv["n_points"], iv["type"], iv["reason"]) for iv in rows]
    assert got == [(3.8e-6, 107.0, 110.0, 4, "quasi_periodic_unstable", ""),
                   (3.8e-6, 111.0, 112.0, 2, "torus_failed", "fourier_decay_failed"),
                   (3.8e-6, 115.0, 115.0, 1, "quasi_periodic_unstable", "")]
    # the run's largest normal exponent: the helper's 3 (1 + speed / 1000) at its last point
    assert rows[0]["max_torus_exponent"] == pytest.approx(3.0 * 1.110)
    assert np.isnan(rows[1]["max_torus_exponent"]) and all(np.isnan(iv["onset"]) for iv in rows)


def test_every_entry_has_the_same_columns_and_runs_are_ordered(ds):
    intervals = query.unstable_intervals(ds)
    assert len({tuple(iv) for iv in intervals}) == 1 and "reason" in intervals[0]
    for c in (3.8e-6, 19e-6):
        starts = [iv["start"] for iv in intervals if iv["clearance"] == c]
        assert starts == sorted(starts)
    # the orbits' own intervals are those of the cube without tori wherever the line has no torus
    plain = synthetic_cube(speed=SPEED, clearance=[3.8e-6, 19e-6])
    orbits = [{k: v for k, v in iv.items() if k not in ("reason", "max_torus_exponent")}
              for iv in intervals if iv["clearance"] == 19e-6]
    assert orbits == [iv for iv in query.unstable_intervals(plain) if iv["clearance"] == 19e-6]


def test_the_intervals_and_the_classes_are_one_vocabulary(ds):
    """Each class run of point_classes (what the map and info show) of a torus class that --unstable
    lists lies in exactly one torus interval of that type, and no stable or undecided torus does."""
    intervals = query.unstable_intervals(ds)
    runs = [r for r in query.class_runs(ds) if r["class"].startswith(("quasi_periodic", "torus"))]
    assert {r["class"] for r in runs} == {"quasi_periodic_stable", "quasi_periodic_unstable",
                                         "quasi_periodic_undecided", "torus_failed"}
    for run in runs:
        covering = [iv["type"] for iv in intervals if iv["clearance"] == run["clearance"]
                    and iv["start"] <= run["start"] and run["end"] <= iv["end"]]
        assert covering == ([run["class"]] if run["class"] in query.TORUS_UNSTABLE else [])


def test_query_unstable_prints_the_torus_runs(ds, tmp_path, capsys):
    path = tmp_path / "tori.nc"
    ds.to_netcdf(path)
    assert cli.main(["query", str(path), "--unstable", "--format", "json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["type"] for r in torus_rows(rows)] == ["quasi_periodic_unstable", "torus_failed", "quasi_periodic_unstable"]
    assert torus_rows(rows)[1]["reason"] == "fourier_decay_failed" and torus_rows(rows)[1]["max_abs_multiplier"] is None
    assert cli.main(["query", str(path), "--unstable"]) == 0
    assert "torus_failed" in capsys.readouterr().out


def continuation_result():
    """A continuation result (the variables branch_unstable_stretches reads) of an orbit branch
    (stable, unstable between a fold and a period doubling, stable) and a torus branch (stable,
    unstable, undecided, unstable; its TS flags are not located events)."""
    import xarray as xr
    from rotorsweep.kernels.continuation import events as ev

    lam = np.array([[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], [10.0, 9.0, 8.0, 7.0, 6.0, 5.0]])
    stable = np.array([[1, 1, 0, 0, 0, 1], [1, 1, 0, 0, 0, 0]], "int8")
    status = np.array([[-1] * 6, [1, 1, 0, 0, 2, 0]], "int8")
    mu = np.array([[0.5, 0.9, 1.2, 1.5, 1.1, 0.8], [np.nan] * 6])
    exponent = np.array([[np.nan] * 6, [-1.0, -0.5, 0.5, 2.0, 0.0, 4.0]])
    bp = ("branch", "point")
    return xr.Dataset({
        "parameter": (bp, lam), "stable": (bp, stable), "torus_status": (bp, status), "max_abs_multiplier": (bp, mu),
        "torus_exponent": (bp, exponent), "branch_points": ("branch", [6, 6]), "branch_kind": ("branch", [0, 1]),
        "event_branch": ("event", [0, 0, 1]), "event_point": ("event", [1, 4, 1]),
        "event_parameter": ("event", [2.5, 5.5, np.nan]),     # the TS flag not located: NaN
        "event_type": ("event", [ev.FOLD, ev.PERIOD_DOUBLING, ev.TORUS_STABILITY])},
        coords={"speed": ("branch", [250.0, 250.0])})


def test_a_continuation_lists_the_unstable_stretches_of_orbit_and_torus_branches():
    rows = query.branch_unstable_stretches(continuation_result())
    got = [(r["branch"], r["kind"], r["start"], r["end"], r["n_points"], r["type"]) for r in rows]
    assert got == [(0, "periodic_orbit", 3.0, 5.0, 3, "fold"), (1, "torus", 8.0, 7.0, 2, "quasi_periodic_unstable"),
                   (1, "torus", 5.0, 5.0, 1, "quasi_periodic_unstable")]
    assert (rows[0]["onset"], rows[0]["offset"], rows[0]["max_abs_multiplier"]) == (2.5, 5.5, 1.5)
    assert np.isnan(rows[1]["onset"]) and np.isnan(rows[1]["offset"])        # a TS flag is not located
    assert (rows[1]["max_torus_exponent"], rows[2]["max_torus_exponent"]) == (2.0, 4.0)
    assert all(r["speed"] == 250.0 for r in rows)


def test_info_explains_the_torus_classes_in_its_legend(ds):
    from rotorsweep.pipeline import cube
    text = cube.describe(ds)
    legend = next(line for line in text.splitlines() if line.startswith("points per stability class"))
    for name in ("quasi_periodic_stable", "quasi_periodic_unstable", "quasi_periodic_undecided", "torus_failed"):
        assert name in legend


def test_a_located_stability_change_is_the_torus_stretch_onset_and_offset():
    """Torus branch 1 (statuses 1 1 0 0 2 0): its located TS on the step 1 -> 2 is the first unstable
    stretch's onset; a located TF on the step 3 -> 4, beside the undecided point 4, is both that
    stretch's offset and the next one's onset (TF stands in where no TS is located), which runs to
    the branch's end (no offset); a TS not located (NaN) is never an onset."""
    from rotorsweep.kernels.continuation import events as ev
    result = continuation_result()
    result = result.assign(event_branch=("event", [0, 0, 1, 1, 1]), event_point=("event", [1, 4, 1, 3, 3]),
                           event_parameter=("event", [2.5, 5.5, 8.5, np.nan, 6.75]),
                           event_type=("event", [ev.FOLD, ev.PERIOD_DOUBLING, ev.TORUS_STABILITY,
                                                 ev.TORUS_STABILITY, ev.TORUS_FOLD]))
    rows = query.branch_unstable_stretches(result)
    assert [(r["onset"], r["offset"]) for r in rows[1:2]] == [(8.5, 6.75)]
    assert rows[2]["onset"] == 6.75 and np.isnan(rows[2]["offset"])     # the branch ends unstable
    assert (rows[0]["onset"], rows[0]["offset"]) == (2.5, 5.5)


def test_info_names_a_torus_stretch_onset_and_offset_or_says_not_located():
    from rotorsweep.pipeline import continuation_result as cr
    line = cr.stretch_line({"start": 8.0, "end": 7.0, "n_points": 2, "onset": 8.5, "offset": np.nan}, "speed", "Hz")
    assert line.strip() == "unstable from speed 8 to 7 Hz (2 points): onset 8.5 Hz, offset not located"

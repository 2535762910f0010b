"""Hysteresis in sweeps: a jump between neighbouring points of a swept line is handed to the
continuation engine in the chunk's task, which locates both folds of the pair (boundary table,
typed fold) and the bistable interval between them (`query --bistable`)."""
import json

import numpy as np
import pytest

from rotorsweep.pipeline import boundaries, cli, compute, config, continuation, cube, query, schema, sweep
from rotorsweep.kernels.continuation import arclength as al

# Bai 2006 (configs/bai2006_fold.toml): the natural sweep jumps over a fold pair near 40.8 Hz at
# 7.6 um and near 31.1 Hz at 15.2 um.
BAI = """
[scene]
name = "jump"
model = "jeffcott_clearance"

[bearing]
preset = "209"
stiffness = "bai2006"
cage_rotation = true

[rotor]
mass = 2.0
damping = 300.0
radial_load = "gravity"
gravity = 9.8

[sweep]
speed = {{start = {start}, stop = {stop}, step = 0.05}}
clearance = [{clearance}]

[continuation]
parameter = "speed"

[numerics]
rtol = 1e-10
atol = 1e-12
newton_tol = 1e-9
"""

CASES = {"7.6um": (40.5, 41.0, 7.6e-6), "15.2um": (30.9, 31.3, 15.2e-6)}


@pytest.fixture(scope="module", params=sorted(CASES))
def jump_sweep(request, tmp_path_factory):
    start, stop, clearance = CASES[request.param]
    cfg = config.parse_config(BAI.format(start=start, stop=stop, clearance=clearance))
    out = tmp_path_factory.mktemp("jump") / "jump.nc"
    sweep.run(cfg, str(out), workers=0)
    return cfg, cube.open_cube(str(out)), clearance


def _reference_folds(cfg, clearance):
    """The folds of `rotorsweep continue` on the same scene: the branch from the range's lower
    end, followed through the fold pair (another start and other steps than the sweep's)."""
    (first, *_) = continuation.continue_line(cfg.scene, {"clearance": clearance})
    return np.sort(first["event_parameter"][first["event_type"] == al.FOLD])


def test_both_folds_of_a_jump_are_in_the_boundary_table(jump_sweep):
    cfg, ds, clearance = jump_sweep
    rows = boundaries.boundary_frame(ds)
    folds = [r for r in rows if r["direction"] >= schema.BOUNDARY_DIRECTION.index("enters_bistable")]
    assert len(folds) == 2 and all(r["type"] == schema.BIFURCATION.index("fold") and r["status"] == 0
                                   for r in folds)
    # both are located by Brent's method on the branch to the events' tolerance (~1e-10
    # relative): two continuations from different starts agree to far below 1e-8
    reference = _reference_folds(cfg, clearance)
    assert len(reference) == 2
    np.testing.assert_allclose([r["speed"] for r in folds], reference, rtol=1e-8)
    # the jump lies within the bistable interval, between the two grid points either side of it
    low, high = folds[0]["grid_low"], folds[0]["grid_high"]
    assert reference[0] < high and low < reference[1]


def test_query_bistable_lists_the_interval_between_the_folds(jump_sweep, capsys):
    cfg, ds, clearance = jump_sweep
    (iv,) = query.bistable_intervals(ds)
    reference = _reference_folds(cfg, clearance)
    np.testing.assert_allclose([iv["start"], iv["end"]], reference, rtol=1e-8)
    assert iv["clearance"] == clearance
    assert cli.main(["query", ds.encoding["source"], "--bistable", "--format", "json"]) == 0
    (row,) = json.loads(capsys.readouterr().out)
    assert row["start"] == iv["start"] and row["end"] == iv["end"]
    # the unstable-interval view is unaffected: every grid point here is stable
    assert query.unstable_intervals(ds) == []


def test_smooth_branches_make_no_jump():
    """A steep smooth branch (x ~ sqrt(1 - lambda) sampled up to its fold at a grid point, the
    steepest step 2.41 times the one before) is no jump; a step change is."""
    grid = np.linspace(0.0, 1.0, 11)
    pos = np.arange(11)
    status, stable = np.zeros(11, int), np.ones(11, int)
    near = np.full(11, 0.1)                         # a multiplier near +1 everywhere
    smooth = np.sqrt(1.0 - grid)[:, None] * np.ones((1, 4))
    assert boundaries.jump_brackets((), grid, pos, status, stable, smooth, near) == []
    jumped = smooth + 5.0 * (grid > 0.55)[:, None]
    (b,) = boundaries.jump_brackets((), grid, pos, status, stable, jumped, near)
    assert b.i == 5 and b.grid == (grid[5], grid[6])
    # without a multiplier near +1 the same step is not a jump over a fold
    assert boundaries.jump_brackets((), grid, pos, status, stable, jumped, np.full(11, 0.9)) == []


def test_the_map_draws_the_bistable_band_as_its_own_class(jump_sweep):
    from rotorsweep.pipeline.report import stability

    _, ds, _ = jump_sweep
    (iv,) = query.bistable_intervals(ds)
    grid = ds["speed"].values
    classes = query.point_classes(ds).values.ravel()
    inside = (grid >= iv["start"]) & (grid <= iv["end"])
    assert inside.any() and (classes[inside] == "bistable").all() and (classes[~inside] == "stable").all()
    cls = stability.stability_class(ds).ravel()
    assert stability.CLASSES[int(cls[inside][0])] == "bistable"


@pytest.mark.parametrize("start, stop, step, clearance, kind", [
    (28.2, 28.6, 0.05, 19.0e-6, "fold"),                # the lower branch's fold at 28.40159 Hz
    (32.2, 32.6, 0.1, 15.2e-6, "period_doubling"),      # the period-1 orbit's first doubling above the jump
])
def test_stability_changes_next_to_jumps_are_unchanged(tmp_path, start, stop, step, clearance, kind):
    """A stability change is refined as before (one row, its own type, at the continuation's
    event) and no jump is reported there: the 19 um fold ends the branch the sweep was on (its
    jump is the stability change's bracket), and a period doubling is no jump at all."""
    cfg = config.parse_config(BAI.format(start=start, stop=stop, clearance=clearance).replace(
        "step = 0.05", f"step = {step}"))
    sweep.run(cfg, str(tmp_path / "c.nc"), workers=0)
    ds = cube.open_cube(str(tmp_path / "c.nc"))
    (row,) = boundaries.boundary_frame(ds)
    assert schema.BIFURCATION[row["type"]] == kind and row["direction"] == 0 and row["status"] == 0
    assert query.bistable_intervals(ds) == []
    (first, *_) = continuation.continue_line(cfg.scene, {"clearance": clearance})
    code = al.FOLD if kind == "fold" else al.PERIOD_DOUBLING
    (reference,) = first["event_parameter"][first["event_type"] == code][:1]
    assert row["speed"] == pytest.approx(reference, rel=1e-8)


def test_the_map_draws_a_narrow_bistable_band_at_least_its_minimum_width(jump_sweep, monkeypatch):
    """The bistable band lies over the interval between the folds (query --bistable), is in the
    legend, and a band narrower than MIN_BAND_FRACTION of the axis (the demo's 7.6 um pair: 0.1 Hz
    of 240, half a pixel) is drawn that wide about its middle."""
    from rotorsweep.pipeline.report import axes_plan, map_rectangles, stability

    _, ds, _ = jump_sweep
    (iv,) = query.bistable_intervals(ds)
    assert float(stability.BISTABLE) in stability.class_keys(ds)
    plan = axes_plan(ds)
    bands = [r for r in map_rectangles(ds, plan, {}, query.bistable_intervals(ds))[0][float(stability.BISTABLE)]
             if r[0] <= iv["start"] and iv["end"] <= r[2]]
    assert bands
    span = float(np.ptp(ds["speed"].values))
    monkeypatch.setattr(stability, "MIN_BAND_FRACTION", 2.0 * (iv["end"] - iv["start"]) / span)
    (lo, hi), = stability.bistable_bands(ds, {}, query.bistable_intervals(ds))
    assert hi - lo == pytest.approx(2.0 * (iv["end"] - iv["start"]), rel=1e-12)
    assert 0.5 * (lo + hi) == pytest.approx(0.5 * (iv["start"] + iv["end"]), rel=1e-12)


def test_the_bistable_interval_names_its_two_coexisting_orbits(jump_sweep):
    """query --bistable and the report's table give the two stable orbits that coexist in the
    middle of the fold pair (issue 32 item 4, gap d). Independently: Newton at that speed from
    the cube's orbits either side of the jump (one on each branch), amplitudes by
    rotorsweep.kernels.extrema; both sides converge to 1e-9 (newton_tol), so the amplitudes agree to
    1e-6 relative with room, and each orbit is stable."""
    from rotorsweep.pipeline.report.tables import bistable_rows
    from rotorsweep.kernels import extrema
    from rotorsweep.kernels.continuation import solve_orbit

    cfg, ds, clearance = jump_sweep
    (iv,) = query.bistable_intervals(ds)
    assert iv["start"] < iv["orbits_at"] < iv["end"]
    scene = cfg.scene
    model = scene.model
    built = compute.builder(scene)({**scene.fixed, "clearance": clearance, "speed": iv["orbits_at"]})
    opts = scene.integrator
    speeds = ds["speed"].values
    found = []
    for grid in (iv["grid_low"], iv["grid_high"]):
        state = ds["orbit_state"].values.reshape(speeds.size, -1)[int(np.argmin(abs(speeds - grid)))]
        sol = solve_orbit(model, built.p, opts, [state], **scene.newton.solve_orbit_args(model))
        assert sol.status == 0 and sol.stable
        found.append(extrema.amplitudes(model, sol.state, built.p, 1.0, opts, built.period)[1])
    found.sort(key=lambda a: a[0])
    for j, ref in zip((1, 2), found):
        got = [iv[f"orbit{j}_amplitude_{o.name}"] for o in model.observables]
        np.testing.assert_allclose(got, ref, rtol=1e-6)
        assert iv[f"orbit{j}_max_abs_multiplier"] < 1.0 and iv[f"orbit{j}_periods"] == 1
    header, (row,) = bistable_rows(ds, [iv])
    assert len(header) == len(row) and "-" not in row

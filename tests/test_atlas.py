"""The 4-D atlas: its config's points are physical, the guided chunk plan, the boundary table's
per-line map, and the summary figures of cubes with more than two varying axes."""
import itertools
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import boundaries, compute, config, cube, scene, schema, sweep
from rotorsweep.pipeline.report.figures import atlas
from tests.test_pipeline import SMALL

ROOT = Path(__file__).resolve().parents[1]
SPEEDS = np.array([10.0, 11.0, 12.0, 13.0, 14.0, 15.0])
AXES = {"speed": SPEEDS, "clearance": np.array([5e-6, 1e-5]),
        "contact_angle": np.array([15.0, 25.0, 40.0]), "preload": np.array([0.0, 100.0])}


def test_atlas_config_is_the_fig13_grid_and_every_point_builds():
    """768,320 points; the preload turns the free contact angle towards the axis (loaded angle >
    free angle, growing with the preload: static equilibrium N K dn^1.5 sin(a) = P0) and every
    (clearance, angle, preload) builds finite kernel parameters."""
    cfg = config.parse_config((ROOT / "configs" / "atlas4d_fig13.toml").read_text(), allow_large=True)
    assert cfg.n_points == 2401 * 5 * 8 * 8 and cfg.data["analysis"]["attractor"] is False
    build, fixed = compute.builder(cfg.scene), cfg.scene.fixed
    for c, a in itertools.product(cfg.axes["clearance"], cfg.axes["contact_angle"]):
        used = []
        for p in cfg.axes["preload"]:
            built = build({**fixed, "speed": 100.0, "clearance": c, "contact_angle": a, "preload": p})
            assert np.all(np.isfinite(built.p)) and built.period > 0
            used.append(float(built.derived["contact_angle_used"]))
        assert used[0] == pytest.approx(a) and np.all(np.diff(used) > 0) and used[-1] < 90.0


def test_segments_tile_the_grid_and_each_builds_from_its_id_alone():
    """The atlas's segments (24,320) cover every grid point once, runs of at most segment_length
    along speed on one line; a chunk task's worker builds any of them from its id (SegmentGrid)."""
    cfg = config.parse_config((ROOT / "configs" / "atlas4d_fig13.toml").read_text(), allow_large=True)
    segs = sweep.segments(cfg.scene)
    grid = sweep.SegmentGrid(cfg.scene)
    assert [s.id for s in segs] == list(range(len(grid)))
    seen = np.zeros(tuple(len(v) for v in cfg.axes.values()), int)
    for seg in segs:
        seen[tuple(seg.index.T)] += 1
        assert len(seg) <= cfg.data["numerics"]["segment_length"]
        assert np.array_equal(seg.values, cfg.axes["speed"][seg.index[:, 0]])
        assert (seg.index[:, 1:] == seg.index[0, 1:]).all()
        assert all(seg.line[n] == cfg.axes[n][j] for n, j in zip(list(cfg.axes)[1:], seg.index[0, 1:]))
    assert (seen == 1).all()
    for i in (0, 75, 76, 12345, len(segs) - 1):
        built = grid[i]
        assert (built.id, built.line) == (segs[i].id, segs[i].line)
        assert np.array_equal(built.index, segs[i].index) and np.array_equal(built.values, segs[i].values)
    with pytest.raises(IndexError):
        grid[len(segs)]


def _segments(lengths):
    return [sweep.Segment(i, np.zeros((n, 1), int), {}, "speed", np.zeros(n)) for i, n in enumerate(lengths)]


def test_guided_chunks_shrink_cover_every_segment_once_and_keep_a_floor():
    segs = _segments([32] * 375 + [5])
    total = 375 * 32 + 5
    plans = {share: sweep.plan_chunks(segs, n_workers=2, share=share) for share in (2, 4)}
    for share, chunks in plans.items():
        sizes = [sum(len(s) for s in c) for c in chunks]
        assert [s.id for c in chunks for s in c] == list(range(len(segs)))
        assert sizes[0] >= total // (share * 2)                          # a first chunk of ~1/(2 share)
        assert all(b <= a + 32 for a, b in zip(sizes, sizes[1:-1]))      # shrinking (to a segment)
        assert sizes[-1] < sizes[-2] + sweep.MIN_CHUNK_POINTS             # the last takes the rest
        assert min(sizes) >= sweep.MIN_CHUNK_POINTS                      # the 5-point rest is no task
        assert len(chunks) < total // sweep.MIN_CHUNK_POINTS             # fewer tasks than equal 64s
    assert len(plans[2]) < len(plans[4])
    assert [len(c) for c in sweep.plan_chunks(segs, 2, chunk_points=64)][:3] == [2, 2, 2]
    assert sum(len(s) for s in sweep.plan_chunks(segs, 2, chunk_points=64)[-1]) == 37  # as asked: no merge
    big = [sum(len(s) for s in c) for c in sweep.plan_chunks(_segments([32] * 24010), 2)]
    assert max(big) <= sweep.MAX_CHUNK_POINTS + 32 and big[0] > sweep.MAX_CHUNK_POINTS - 32


def test_guided_share_is_larger_where_attractor_diagnostics_make_point_costs_uneven():
    data = config.parse_config((ROOT / "configs" / "bai2006_fig13.toml").read_text(), allow_large=True).data
    assert data["analysis"]["attractor"] is True
    orbits = {**data, "analysis": {**data["analysis"], "attractor": False}}
    assert (sweep.guided_share(scene.from_data(data)) == sweep.GUIDED_SHARE_ATTRACTORS
            > sweep.guided_share(scene.from_data(orbits)) == sweep.GUIDED_SHARE)


def test_boundary_rows_are_the_same_for_any_map_and_rows_refined_during_the_sweep(tiny_cube):
    """The driver's serial map, another order of evaluation (reversed, as workers may finish) and
    rows refined earlier (as a sweep refines them while it computes) give the same rows in the
    same order; only the brackets not refined yet reach the map."""
    ds = cube.open_cube(tiny_cube)
    data = config.parse_config(ds.attrs["config_toml"]).scene
    plain = ds.drop_dims("boundary")

    def backwards(data, axis, tasks):
        return [boundaries.refine_brackets(data, axis, task) for task in tasks[::-1]][::-1]
    serial = boundaries.boundary_rows(data, plain)
    assert serial and boundaries.boundary_rows(data, plain, backwards) == serial
    first = boundaries.cube_brackets(plain, "speed")[0]
    done = {(first[1].line, first[1].i): boundaries.refine_brackets(data, "speed", [first])[0]}
    mapped = []

    def recording(data, axis, tasks):
        mapped.extend(b for task in tasks for _, b in task)
        return boundaries.refine_serially(data, axis, tasks)
    assert boundaries.boundary_rows(data, plain, recording, done) == serial
    assert (first[1].line, first[1].i) not in {(b.line, b.i) for b in mapped}
    assert len(mapped) == len(serial) - 1


def test_a_chunk_refines_the_stability_changes_between_its_own_points_only(tmp_path):
    """Solved as one chunk, the small scene's one stability change (between its first two
    segments) is refined by the chunk, to the row the cube's table gives it; with the chunks cut
    between those segments, by neither (the driver's tracker gives it a task of its own). The rows
    survive a part file's JSON meta, from which a resumed sweep takes them."""
    cfg = config.parse_config(SMALL)
    segs = sweep.segments(cfg.scene)
    ids, index, results, inside = sweep.compute_chunk(cfg.scene, segs)
    assert [(tuple(line), i) for line, i, _ in inside] == [((0,), 3)]
    ds = cube.assemble(cfg.axes, sweep.fixed_coords(cfg.scene), [(ids, index, results, None)],
                       sweep.provenance(cfg), n_multipliers=4)
    (row,) = boundaries.boundary_rows(cfg.scene, ds)
    assert inside[0][2].items() <= row.items()
    assert sweep.compute_chunk(cfg.scene, segs[:1])[3] == []
    assert sweep.compute_chunk(cfg.scene, segs[1:])[3] == []
    cube.write_part(tmp_path, "seg000000", index, results, {"config_hash": "h", "segments": ids, "boundaries": inside})
    assert sweep.earlier_parts(tmp_path, "h") == (set(ids), boundaries.keyed(inside))


def test_tracker_finds_each_stability_change_once_in_any_chunk_order():
    """Chunks of a 7 x 3 grid (random statuses and stabilities) fed in random orders and sizes:
    the tracker yields every pair of neighbours along speed where both orbits converged and their
    stability differs, each once, with both points' values; compared with a plain double loop."""
    axes = {"speed": np.arange(7.0), "clearance": np.array([1e-6, 2e-6, 3e-6])}
    rng = np.random.default_rng(7)
    index = np.array([(s, c) for c in range(3) for s in range(7)])
    results = {"orbit_status": rng.choice([0, 0, 0, 1], len(index)), "stable": rng.integers(0, 2, len(index)),
               "orbit_state": rng.normal(size=(len(index), 4)), "multiplier_real": rng.normal(size=(len(index), 4)),
               "multiplier_imag": rng.normal(size=(len(index), 4))}
    at = {tuple(ix): k for k, ix in enumerate(index)}
    expected = {((c,), s) for c in range(3) for s in range(6)
                if results["orbit_status"][at[s, c]] == 0 == results["orbit_status"][at[s + 1, c]]
                and results["stable"][at[s, c]] != results["stable"][at[s + 1, c]]}
    assert expected
    for trial in range(5):
        order = rng.permutation(len(index))
        cuts = np.sort(rng.choice(np.arange(1, len(index)), size=trial + 2, replace=False))
        tracker, found = boundaries.Tracker(axes, "speed"), []
        for rows in np.split(order, cuts):
            found += tracker.add(index[rows], {k: v[rows] for k, v in results.items()})
        assert sorted((b.line, b.i) for _, b in found) == sorted(expected)
        for where, b in found:
            low, high = at[b.i, b.line[0]], at[b.i + 1, b.line[0]]
            assert where == {"clearance": axes["clearance"][b.line[0]]} and b.grid == (b.i, b.i + 1.0)
            assert b.stable == (results["stable"][low], results["stable"][high])
            assert np.array_equal(b.states[0], results["orbit_state"][low])
            assert b.lead == complex(results["multiplier_real"][high, 0], results["multiplier_imag"][high, 0])
        assert not tracker.lines


def _atlas_cube(onset_index, refined=None):
    """A 4-D cube whose line (c, a, p) is stable below SPEEDS[onset_index[c, a, p]] (never when
    the index is len(SPEEDS)) and unstable from there on; refined: {(c, a, p): value} boundary
    rows of those lines."""
    shape = tuple(len(v) for v in AXES.values())
    k = np.arange(len(SPEEDS)).reshape(-1, 1, 1, 1)
    stable = (k < onset_index[None]).astype("int8")
    results = {"orbit_status": np.zeros(shape, "int8"), "stable": stable,
               "bifurcation": np.where(stable == 1, 0, 2).astype("int8")}
    ds = cube.build_dataset(AXES, {}, results, {"model": "jeffcott_clearance", "continued_axis": "speed"})
    rows = [dict(speed=v, c=AXES["clearance"][c], a=AXES["contact_angle"][a], p=AXES["preload"][p],
                 low=SPEEDS[onset_index[c, a, p] - 1], high=SPEEDS[onset_index[c, a, p]])
            for (c, a, p), v in (refined or {}).items()]
    table = {"boundary_speed": [r["speed"] for r in rows], "boundary_clearance": [r["c"] for r in rows],
             "boundary_contact_angle": [r["a"] for r in rows], "boundary_preload": [r["p"] for r in rows],
             "boundary_grid_low": [r["low"] for r in rows], "boundary_grid_high": [r["high"] for r in rows],
             "boundary_status": [0] * len(rows), "boundary_direction": [0] * len(rows),
             "boundary_type": [2] * len(rows)}
    for name, values in table.items():
        ds[name] = ("boundary", np.asarray(values))
    return ds


def test_onset_and_stable_share_per_line():
    """Onset = the refined boundary where the table has one inside the line's first stable ->
    unstable bracket, else the first unstable grid speed, NaN when stable throughout;
    stable share = stable points / points."""
    rng = np.random.default_rng(1)
    onset_index = rng.integers(0, len(SPEEDS) + 1, size=(2, 3, 2))
    onset_index[0, 0, 0], onset_index[1, 2, 1], onset_index[0, 1, 1], onset_index[1, 0, 0] = 3, len(SPEEDS), 0, 2
    ds = _atlas_cube(onset_index, refined={(0, 0, 0): 12.4, (1, 0, 0): 99.0})   # 99: outside [11, 12]
    onset, share = atlas.line_summary(ds)
    assert onset.dims == ("clearance", "contact_angle", "preload")
    for idx in itertools.product(range(2), range(3), range(2)):
        n = onset_index[idx]
        expect = 12.4 if idx == (0, 0, 0) else np.nan if n == len(SPEEDS) else SPEEDS[n]
        np.testing.assert_equal(onset.values[idx], expect)
        assert share.values[idx] == pytest.approx(n / len(SPEEDS))


@pytest.mark.parametrize("builder", [atlas.fig_onset, atlas.fig_stable_fraction, atlas.fig_boundary_surfaces])
def test_atlas_figures_build_in_both_backends_one_panel_per_clearance(builder):
    from rotorsweep.pipeline.report import style

    ds = _atlas_cube(np.full((2, 3, 2), 3), refined={(1, 2, 0): 12.5})
    for backend in ("bokeh", "matplotlib"):
        with style.backend(backend):
            fig = builder(ds, backend)
        assert len(fig) == 2            # a layout of one panel per clearance


def test_atlas_figures_apply_only_with_more_than_two_varying_axes():
    from rotorsweep.pipeline.report import figures_for

    four = _atlas_cube(np.full((2, 3, 2), 3))
    names = {f.name for f in figures_for(four)}
    assert {"atlas_onset", "atlas_stable_fraction", "atlas_boundaries"} <= names
    two = four.isel(contact_angle=[0], preload=[0])      # size-1 axes do not count
    assert not atlas.is_atlas(two) and atlas.is_atlas(four.isel(preload=[0]))
    assert schema.point_axes(two) == list(AXES)

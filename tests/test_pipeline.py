"""End to end: the CLI as a user runs it (subprocesses), and sweep invariances."""
import gc
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import cluster, config, cube, sweep
from tests.runlog_check import check_log

SMALL = """
[scene]
name = "small"
model = "jeffcott_clearance"

[bearing]
preset = "209"
stiffness = "bai2006"

[sweep]
speed = {start = 70.0, stop = 100.0, step = 3.0}
clearance = [7.6e-6, 19.0e-6]

[numerics]
segment_length = 4
"""

CLI = [str(Path(sys.executable).with_name("rotorsweep"))]


def rotorsweep(*args, check=True):
    proc = subprocess.run(CLI + [str(a) for a in args], capture_output=True, text=True, timeout=600)
    if check and proc.returncode != 0:
        raise AssertionError(f"rotorsweep {args} failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    return proc


@pytest.fixture(scope="module")
def small_config(tmp_path_factory):
    path = tmp_path_factory.mktemp("cfg") / "small.toml"
    path.write_text(SMALL)
    return path


@pytest.fixture(scope="module")
def small_cube(small_config, tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "small.nc"
    proc = rotorsweep("run", small_config, "-o", out, "--workers", "2")
    assert "points" in proc.stderr          # the progress bar
    return out


def test_run_writes_its_phases_progress_and_time_into_a_log_file(small_cube):
    check_log(small_cube, "run", ["starting 2 local Dask workers", "compiling the kernels", "kernels ready",
                                  "sweeping 22 points", "assembling the cube", "writing the cube"], "points")


def data_vars(path):
    ds = cube.open_cube(path)
    return ds.drop_vars("compute_time")     # the only variable that measures the machine


def test_run_writes_a_cube_with_the_grid_and_provenance(small_cube):
    ds = cube.open_cube(small_cube)
    assert dict(ds.sizes)["speed"] == 11 and dict(ds.sizes)["clearance"] == 2
    assert ds.attrs["config_hash"] == config.parse_config(SMALL).hash()
    assert "[scene]" in ds.attrs["config_toml"]
    assert (ds["orbit_status"].values == 0).all()
    assert not os.path.exists(cube.parts_dir(small_cube))        # parts cleaned up after assembly


def test_cube_values_match_the_point_command(small_cube):
    ds = cube.open_cube(small_cube)
    proc = rotorsweep("point", "--speed", 85.0, "--clearance", 19.0e-6, "--json")
    point = json.loads(proc.stdout)
    assert set(point) >= {"status", "multipliers", "max_abs_multiplier", "bifurcation", "period"}
    at = ds.sel(speed=85.0, clearance=19.0e-6)
    assert point["status"] == "converged"
    # the sweep continues the orbit from neighbours, the point solves cold: same orbit, to Newton tol
    assert abs(point["max_abs_multiplier"] - float(at["max_abs_multiplier"])) < 1e-7
    assert abs(point["period"] - float(at["forcing_period"])) < 1e-15


def test_results_do_not_depend_on_workers_or_chunking(small_config, small_cube, tmp_path):
    cfg = config.load_config(small_config)
    one = sweep.run(cfg, tmp_path / "one.nc", workers=1, chunk_points=1, progress=False)
    reference = data_vars(small_cube)
    other = data_vars(one)
    for name in reference.data_vars:
        np.testing.assert_array_equal(reference[name].values, other[name].values, err_msg=name)


def test_the_driver_reads_no_part_back_and_leaves_its_heap_out_of_gc_during_a_sweep_only(
        small_config, tmp_path, monkeypatch):
    frozen, unfrozen, write_part, compile_scene = [], [], cube.write_part, sweep.warmup.compile_scene

    def recording(*args, **kwargs):
        frozen.append(gc.get_freeze_count())
        return write_part(*args, **kwargs)

    def compiling(*args, **kwargs):
        unfrozen.append(len(gc.get_objects()))      # what a full collection would walk
        return compile_scene(*args, **kwargs)
    monkeypatch.setattr(cube, "write_part", recording)
    monkeypatch.setattr(sweep.warmup, "compile_scene", compiling)
    monkeypatch.setattr(cube, "_read_part", lambda path: pytest.fail(f"{path} read back"))
    assert gc.get_freeze_count() == 0
    out = sweep.run(config.load_config(small_config), tmp_path / "f.nc", workers=1, progress=False)
    assert frozen and min(frozen) > 10_000          # the imported modules' objects, at least
    # the local cluster started inside the run is frozen too before the kernels compile (its
    # objects in every collection cost the demo's cold compile 8 s of CPU)
    assert unfrozen and unfrozen[0] < 1_000, unfrozen
    assert gc.get_freeze_count() == 0               # the caller's heap as it was
    assert (cube.open_cube(out)["orbit_status"].values == 0).all()     # every point, from memory


def test_a_nested_heap_freeze_adds_what_was_made_since_and_only_the_outermost_unfreezes(monkeypatch):
    assert gc.get_freeze_count() == 0
    asked, count = [], gc.get_freeze_count
    with cluster.heap_frozen():
        before = gc.get_freeze_count()
        made = [[] for _ in range(1000)]            # tracked by gc, made inside the outer block
        monkeypatch.setattr(gc, "get_freeze_count", lambda: asked.append(1) or count())
        with cluster.heap_frozen():                   # does not walk the frozen heap to count it
            assert count() >= before + len(made)
        assert not asked
        monkeypatch.undo()
        assert gc.get_freeze_count() >= before + len(made)     # the inner block left them frozen
    assert gc.get_freeze_count() == 0


def test_query_and_info_and_report(small_cube, tmp_path):
    table = rotorsweep("query", small_cube, "--where", "speed=80:90", "--where", "clearance=7.6e-6").stdout
    assert "82" in table and "70" not in table.split("\n", 1)[1]
    as_json = json.loads(rotorsweep("query", small_cube, "--format", "json").stdout)
    assert len(as_json) == 22
    intervals = rotorsweep("query", small_cube, "--unstable", "--format", "json").stdout
    assert isinstance(json.loads(intervals), list)
    info = rotorsweep("info", small_cube).stdout
    assert "speed" in info and "clearance" in info
    quiet = rotorsweep("report", small_cube, "-o", tmp_path / "rep", "-q")
    assert "==" not in quiet.stderr                     # -q: no phase lines
    assert (tmp_path / "rep" / "report.html").exists()
    assert (tmp_path / "rep" / "stability_map.png").exists()


@pytest.mark.parametrize("args, fragment", [
    (["point", "--speed", "-5", "--clearance", "7.6e-6"], "speed"),
    (["point", "--speed", "80", "--clearance", "-1e-6"], "clearance"),
    (["point", "--speed", "80", "--clearance", "7.6e-6", "--contact-angle", "95"], "contact_angle"),
    (["point", "--speed", "80", "--clearance", "7.6e-6", "--preload", "-3"], "preload"),
    (["query", "does-not-exist.nc"], "does-not-exist.nc"),
    (["info", __file__], "test_pipeline.py"),
])
def test_user_errors_exit_2_without_traceback(args, fragment):
    proc = rotorsweep(*args, check=False)
    assert proc.returncode == 2, proc.stderr
    assert fragment in proc.stderr
    assert "Traceback" not in proc.stderr


def test_bad_config_exits_2(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(SMALL.replace('preset = "209"', 'preset = "208"'))
    proc = rotorsweep("run", bad, "-o", tmp_path / "x.nc", check=False)
    assert proc.returncode == 2 and "bearing.preset" in proc.stderr and "Traceback" not in proc.stderr


def test_boundary_table_refines_each_stability_change(small_cube):
    import rotorsweep.pipeline as pipeline
    from rotorsweep.pipeline import boundaries

    ds = cube.open_cube(small_cube)
    table = boundaries.boundary_frame(ds)
    assert table, "the small sweep crosses the period-doubling boundary at 7.6 um"
    for row in table:
        assert row["status"] == 0 and row["grid_low"] < row["speed"] < row["grid_high"]
        # independent of the refinement: a cold solve at the refined speed sits on |lambda| = 1
        at = pipeline.point(row["speed"], row["clearance"])
        assert abs(at["max_abs_multiplier"] - 1.0) < 1e-5
    intervals = json.loads(rotorsweep("query", small_cube, "--unstable", "--format", "json").stdout)
    onsets = [iv["onset"] for iv in intervals if iv["onset"] is not None]
    assert any(abs(o - table[0]["speed"]) < 1e-12 for o in onsets)
    # refined on the workers (one task per line) as the driver would refine it alone
    from rotorsweep.pipeline import config
    plain = ds.drop_dims("boundary")
    serial = boundaries.add_boundary_table(config.parse_config(ds.attrs["config_toml"]).scene, plain)
    assert boundaries.boundary_frame(serial) == table


PHASES = ("starting 1 local Dask worker (127.0.0.1)", "1 worker; Dask dashboard: http://127.0.0.1:",
          "compiling the kernels of jeffcott_clearance", "kernels ready", "sweeping 2 points in 1 chunk",
          "assembling the cube and its boundary table", "writing the cube", "writing the report into",
          "drawing the figures (7)")
# the report's last two, in either order (the PNGs drawn in a second process or all before the HTML)
LAST_PHASES = ["HTML page written", "PNGs written"]


def test_run_prints_its_phases_before_the_progress_lines(tmp_path, capsys):
    """In a non-interactive log (captured stderr) each phase is a line of its own, in order, and
    the progress lines come after the sweep starts."""
    from rotorsweep.pipeline import cli
    cfg = tmp_path / "phases.toml"
    # 79 and 82 Hz at 7.6 um: two points either side of the period doubling at 80.88 Hz
    cfg.write_text(SMALL.replace("start = 70.0, stop = 100.0", "start = 79.0, stop = 82.0")
                   .replace("7.6e-6, 19.0e-6", "7.6e-6"))
    code = cli.main(["run", str(cfg), "-o", str(tmp_path / "p.nc"), "--workers", "1",
                     "--report", str(tmp_path / "rep")])
    err = capsys.readouterr().err
    assert code == 0, err
    lines = err.splitlines()
    phases = [line for line in lines if line.startswith(sweep.PHASE)]
    assert len(phases) == len(PHASES) + 2 and all(p[len(sweep.PHASE):].startswith(w) for p, w in zip(phases, PHASES)), err
    assert sorted(p[len(sweep.PHASE):].split(" (")[0] for p in phases[len(PHASES):]) == LAST_PHASES, err
    progress = [i for i, line in enumerate(lines) if " points " in line and line.startswith("[")]
    assert progress and lines.index(phases[4]) < progress[0] < lines.index(phases[5])
    # the stability changes were refined on the worker while the sweep ran: none is left for the
    # refinement phase (which would show its own progress lines)
    assert cube.open_cube(tmp_path / "p.nc").sizes["boundary"] == 1
    assert not [line for line in lines if " boundary lines " in line], err
    assert "\r" not in err                         # not a terminal: whole lines only


def test_every_cli_argument_has_help():
    """Every argument of every subcommand says what it is (`rotorsweep CMD --help`)."""
    import argparse

    from rotorsweep.pipeline import cli
    parser = cli.build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    missing = [f"{name} {a.dest}" for name, p in sub.choices.items() for a in p._actions
               if not a.help and not isinstance(a, argparse._HelpAction)]
    assert missing == []


def test_import_rotorsweep_gives_the_public_api():
    from importlib import metadata

    import rotorsweep
    assert rotorsweep.__version__ == cluster.VERSION == metadata.version("rotorsweep")   # pyproject reads it
    assert all(hasattr(rotorsweep, name) for name in rotorsweep.__all__)
    assert all(callable(getattr(rotorsweep, name)) for name in ("run", "open_cube", "unstable_intervals",
                                                                "make_report", "point", "load_config"))

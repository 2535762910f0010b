"""Reliability of the file side of a sweep (issue 15): one run per output, parts of one config
only, the umask's file modes, OS errors as one line, argument and config checks that come
before any work."""
import logging
import os
import subprocess
import time

import numpy as np
import pytest

from rotorsweep.pipeline import cli, config, cube, fileio, gridsize, sweep
from tests.test_cube import AXES4, PROVENANCE, random_results, _write_random_parts
from tests.faults import disk_full_after_one_part
from tests.harness import run_cli, wait_for_parts
from tests.test_pipeline import CLI, SMALL, rotorsweep


# --- item 1: one run per output, parts of one config ------------------------------------------

def test_a_second_run_on_a_locked_output_is_refused_naming_the_first(small_config, tmp_path):
    out = tmp_path / "cd.nc"
    with fileio.output_lock(out, "first.toml"):
        proc = rotorsweep("run", small_config, "-o", out, "--workers", "1", check=False)
        assert proc.returncode == 2, proc.stderr
        assert f"pid {os.getpid()}" in proc.stderr and "first.toml" in proc.stderr, proc.stderr
        assert "Traceback" not in proc.stderr
        assert not cube.parts_dir(out).exists()          # the refused run touched nothing
    assert not fileio.lock_path(out).exists()             # released on exit


def test_the_lock_of_a_killed_run_does_not_block(tmp_path):
    """A lock file whose holder died (here: a child killed by SIGKILL) is free again: the kernel
    drops the flock with the process, whatever pid and host the file names."""
    out = tmp_path / "k.nc"
    holder = subprocess.Popen(["python3", "-c", "import fcntl, os, time; "
                               f"fd = os.open({str(fileio.lock_path(out))!r}, os.O_RDWR | os.O_CREAT); "
                               "fcntl.flock(fd, fcntl.LOCK_EX); print('locked', flush=True); time.sleep(60)"],
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "locked"
    with pytest.raises(fileio.FileIOError, match="another rotorsweep run"):
        with fileio.output_lock(out, "x"):
            pass
    holder.kill()
    holder.wait()
    with fileio.output_lock(out, "x") as path:
        assert path.exists()


def test_assemble_refuses_parts_of_another_config(tmp_path):
    shape = (3, 2, 2, 2)
    _write_random_parts(tmp_path, random_results(shape), shape)          # config_hash "x"
    read = cube.read_parts(tmp_path)
    cube.assemble(AXES4, {}, read, PROVENANCE, n_multipliers=4, config_hash="x")
    chunk_id, index, results, meta = read[1]
    mixed = read[:1] + [(chunk_id, index, results, {**meta, "config_hash": "y"})] + read[2:]
    with pytest.raises(cube.CubeError, match=r"1 of 6 part files \(first: c001.npz\) belong to another config"):
        cube.assemble(AXES4, {}, mixed, PROVENANCE, n_multipliers=4, config_hash="x")


# --- item 3: files get the umask's mode -------------------------------------------------------

@pytest.mark.parametrize("umask", [0o022, 0o002, 0o077])
def test_cubes_and_parts_get_the_umask_mode(tmp_path, umask):
    shape = (3, 2, 2, 2)
    results = random_results(shape)
    old = os.umask(umask)
    try:
        path = cube.write_cube(cube.build_dataset(AXES4, {}, results, PROVENANCE), tmp_path / "c.nc")
        part = cube.write_part(tmp_path / "p", "c000", np.argwhere(np.ones(shape, bool)),
                               {n: v.reshape((-1,) + v.shape[4:]) for n, v in results.items()}, {})
    finally:
        os.umask(old)
    for written in (path, part):
        assert oct(written.stat().st_mode & 0o777) == oct(0o666 & ~umask), written


# --- item 4: OS errors as one line, checks before any work -------------------------------------

@pytest.mark.parametrize("args", [["--workers", "-3"], ["--chunk-points", "0"],
                                  ["--chunk-points", "-5"], ["--workers", "two"]])
def test_worker_and_chunk_counts_are_checked_at_parsing(small_config, tmp_path, args):
    proc = rotorsweep("run", small_config, "-o", tmp_path / "w.nc", *args, check=False)
    assert proc.returncode == 2 and "must be an integer >= " in proc.stderr, proc.stderr   # 0 workers: in-process
    assert not cube.parts_dir(tmp_path / "w.nc").exists()


def _free_port():
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_an_unreachable_scheduler_fails_fast_before_any_work(small_config, tmp_path):
    out = tmp_path / "s.nc"
    address = f"tcp://127.0.0.1:{_free_port()}"          # nothing listens there
    t0 = time.monotonic()
    proc = rotorsweep("run", small_config, "-o", out, "--scheduler", address, check=False)
    assert proc.returncode == 2 and address in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert time.monotonic() - t0 < 20          # not Dask's 30 s connect timeout
    assert not cube.parts_dir(out).exists() and not fileio.lock_path(out).exists()


def test_a_read_only_output_directory_is_one_line(small_config, tmp_path, monkeypatch, capsys):
    def read_only(path):
        raise OSError(30, "Read-only file system", str(path))

    monkeypatch.setattr(fileio, "_lock_fd", read_only)
    rc, err = run_cli(capsys, "run", small_config, "-o", tmp_path / "ro.nc", "--workers", "1")
    assert rc == 2 and "ro.nc.lock: Read-only file system" in err and len(err.strip().splitlines()) == 1


def test_a_full_disk_keeps_the_finished_chunks_and_resume_finishes(small_config, tmp_path, monkeypatch, capsys):
    out = tmp_path / "full.nc"
    args = ("run", small_config, "-o", out, "--workers", "1", "--chunk-points", "8", "-q")
    disk_full_after_one_part(monkeypatch)
    rc, err = run_cli(capsys, *args)
    assert rc == 2 and "No space left on device" in err and "the 1 finished chunk(s) are kept" in err, err
    assert "--resume" in err and len(err.strip().splitlines()) == 1
    monkeypatch.undo()

    def hdf_error(*_, **__):
        raise RuntimeError("NetCDF: HDF error")          # what netCDF-C says when the disk fills

    monkeypatch.setattr("xarray.Dataset.to_netcdf", hdf_error)
    rc, err = run_cli(capsys, *args, "--resume")
    assert rc == 2 and "NetCDF: HDF error" in err and "--resume" in err, err
    assert not out.exists() and len(list(cube.parts_dir(out).glob("*.npz"))) > 1
    monkeypatch.undo()
    rc, err = run_cli(capsys, *args, "--resume")
    assert rc == 0 and cube.open_cube(out)["orbit_status"].size == 22


# --- item 2: the grid size is checked before any axis is built --------------------------------

def _speed_axis(definition):
    return SMALL.replace("speed = {start = 70.0, stop = 100.0, step = 3.0}", f"speed = {definition}")


@pytest.mark.parametrize("definition, points", [
    ("{start = 1.0, stop = 1e5, num = 300000}", 600_000),
    ("{start = 1.0, stop = 4.0, step = 1e-5}", 600_002)])
def test_max_points_is_checked_without_building_the_axes(definition, points):
    import tracemalloc

    text = _speed_axis(definition)
    tracemalloc.start()
    try:
        with pytest.raises(config.ConfigError, match="numerics.max_points") as err:
            config.parse_config(text)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert err.value.grid_points == points
    assert peak < 8 * points / 4      # building the axis as floats would take >= 8 bytes a point


@pytest.mark.parametrize("definition", ["{start = 1.0, stop = 1e5, num = 1000000000000}",
                                        "{start = 1.0, stop = 1e5, step = 1e-9}"])
def test_a_grid_beyond_memory_is_refused_even_with_yes(definition):
    with pytest.raises(config.ConfigError, match="fit in this machine's memory.*even with --yes") as err:
        config.parse_config(_speed_axis(definition), allow_large=True)
    assert err.value.grid_points is None          # nothing to confirm


def test_the_memory_cap_follows_the_bytes_per_point(monkeypatch):
    monkeypatch.setattr(gridsize, "memory_bytes", lambda: 3 * 512 * 1000)     # room for 1000 points
    config.parse_config(_speed_axis("{start = 1.0, stop = 1e3, num = 500}"), allow_large=True)
    with pytest.raises(config.ConfigError, match="at most 1000 fit"):
        config.parse_config(_speed_axis("{start = 1.0, stop = 1e3, num = 501}"), allow_large=True)


# --- item 7: a cube without its required variables is one clear error ---------------------------

@pytest.mark.parametrize("command", [["report"], ["query", "--unstable"], ["query"], ["info"]])
def test_a_cube_missing_a_required_variable_is_refused(tmp_path, command):
    shape = (3, 2, 2, 2)
    ds = cube.build_dataset(AXES4, {}, random_results(shape), PROVENANCE).drop_vars("orbit_status")
    path = cube.write_cube(ds, tmp_path / "broken.nc")
    proc = rotorsweep(command[0], path, *command[1:], check=False)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert "missing orbit_status" in proc.stderr and "broken.nc" in proc.stderr


# --- item 8: the clearance bound is the preset's, with the key, rounded ----------------------

@pytest.mark.parametrize("preset, where, edit, bound", [
    ("209", "sweep.clearance", "clearance = [7.6e-6, 6e-4]", "0.0005"),
    ("209", "sweep.clearance", "clearance = [7.6e-6, 2e-3]", "0.0005"),
    ("209", "bearing.clearance", "[bearing]\nclearance = 6e-4", "0.0005"),
    ("angular_contact_medium", "sweep.clearance", "clearance = [4e-4]", "0.00035")])
def test_the_clearance_bound_is_the_presets(preset, where, edit, bound):
    text = SMALL.replace('preset = "209"', f'preset = "{preset}"')
    if where == "bearing.clearance":
        text = text.replace("clearance = [7.6e-6, 19.0e-6]\n", "").replace("[bearing]", edit)
    else:
        text = text.replace("clearance = [7.6e-6, 19.0e-6]", edit)
    with pytest.raises(config.ConfigError) as err:
        config.parse_config(text)
    assert f"{where}: must be <= {bound} m for bearing.preset \"{preset}\"" in str(err.value)
    assert "0.001" not in str(err.value) and "0000000" not in str(err.value)
    text = text.replace("6e-4", "5e-4").replace("4e-4", "3.5e-4")            # at the bound: fine
    config.parse_config(text.replace("2e-3", "5e-4"))


def test_the_point_command_states_the_presets_clearance_bound():
    proc = rotorsweep("point", "--speed", "80", "--clearance", "6e-4", check=False)
    assert proc.returncode == 2 and "clearance: must be <= 0.0005 m" in proc.stderr, proc.stderr


# --- item 5: a report directory holds the report of one cube -----------------------------------

@pytest.fixture(scope="module")
def two_cubes(tmp_path_factory):
    from tests.synthetic import synthetic_cube

    where = tmp_path_factory.mktemp("cubes")
    speed, clearance = np.arange(10.0, 60.0, 5.0), [3.8e-6, 19e-6]
    first = synthetic_cube(speed, clearance, attractor=True)     # more figures than the second
    second = synthetic_cube(speed, clearance)
    second.attrs["config_hash"] = "1" * 64
    return cube.write_cube(first, where / "first.nc"), cube.write_cube(second, where / "second.nc")


def _files(directory):
    return sorted(p.name for p in directory.iterdir())


@pytest.mark.slow    # 17-41 s: the default suite stays under 15 min on 2 cores (make test-slow)
def test_a_report_of_another_cube_is_refused_then_replaced_cleanly(two_cubes, tmp_path):
    import rotorsweep.pipeline as pipeline

    first, second = two_cubes
    out, fresh = tmp_path / "rep", tmp_path / "fresh"
    pipeline.make_report(first, out)
    before = _files(out)
    pipeline.make_report(first, out)                  # the same cube again: fine
    proc = rotorsweep("report", second, "-o", out, check=False)
    assert proc.returncode == 2 and "first.nc" in proc.stderr and "--overwrite" in proc.stderr, proc.stderr
    assert _files(out) == before and "report.json" in before
    files = pipeline.make_report(second, out, overwrite=True)
    pipeline.make_report(second, fresh)
    assert _files(out) == _files(fresh) != before      # nothing of the first report is left
    assert files["html"] == out.absolute() / "report.html" and files["html"].exists()
    assert str(second.absolute()) in (out / "report.json").read_text()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []   # no temp dirs left


def test_a_report_never_goes_into_a_file_or_a_foreign_directory(two_cubes, tmp_path):
    first, _ = two_cubes
    a_file = tmp_path / "notes.txt"
    a_file.write_text("mine")
    proc = rotorsweep("report", first, "-o", a_file, check=False)
    assert proc.returncode == 2 and "not a directory" in proc.stderr and "Traceback" not in proc.stderr
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    proc = rotorsweep("report", first, "-o", mine, "--overwrite", check=False)
    assert proc.returncode == 2 and "holds no rotorsweep report" in proc.stderr, proc.stderr
    assert _files(mine) == ["thesis.tex"] and a_file.read_text() == "mine"


def test_ctrl_c_between_the_two_renames_of_a_report_keeps_the_old_one(tmp_path, monkeypatch):
    """replaced_dir sets the old report aside, then renames the new one into place: interrupted
    in between, the old one comes back; uninterrupted, only the new one is left."""
    out = tmp_path / "rep"
    out.mkdir()
    (out / "report.html").write_text("old")
    rename, calls = os.rename, []

    def interrupted_second(src, dst):
        calls.append(dst)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return rename(src, dst)

    monkeypatch.setattr(os, "rename", interrupted_second)
    with pytest.raises(KeyboardInterrupt), fileio.replaced_dir(out) as tmp:
        (tmp / "report.html").write_text("new")
    assert _files(out) == ["report.html"] and (out / "report.html").read_text() == "old"
    assert _files(tmp_path) == ["rep"]
    monkeypatch.undo()
    with fileio.replaced_dir(out) as tmp:
        (tmp / "modes.csv").write_text("new")
    assert _files(out) == ["modes.csv"] and _files(tmp_path) == ["rep"]


# --- item 6: Ctrl-C is one line -----------------------------------------------------------------

def test_ctrl_c_prints_one_line_and_no_worker_traceback(tmp_path):
    import signal

    from tests.test_reliability import LONG

    cfg = tmp_path / "long.toml"
    # 9604 points: seconds of sweeping left after the first part file, so the interrupt cannot
    # come after the run has finished, however the machine schedules this test's polling
    cfg.write_text(LONG.replace("step = 0.5", "step = 0.1"))
    out = tmp_path / "long.nc"
    # SIGINT at its default, as under a terminal: a CI job started in the background of a
    # non-interactive shell inherits it ignored, and so would the CLI (which then rightly
    # ignores Ctrl-C)
    proc = subprocess.Popen(CLI + ["run", str(cfg), "-o", str(out), "--workers", "2", "--chunk-points", "16"],
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    wait_for_parts(cube.parts_dir(out), proc)
    os.killpg(proc.pid, signal.SIGINT)            # what a terminal's Ctrl-C does: the whole group
    err = proc.communicate(timeout=120)[1]
    assert proc.returncode == 130, err
    lines = [line for line in err.splitlines()                 # not the phase and progress lines
             if " points " not in line and not line.startswith(sweep.PHASE)]
    assert lines == ["rotorsweep: interrupted; finished chunks are kept, rerun with --resume"], err



def test_a_closing_worker_logs_nothing_more(caplog):
    """A worker's teardown (the start of its close) silences Dask's loggers in that process: a
    heartbeat in flight when the worker closes its connections would log an ERROR traceback
    after Ctrl-C (seen once in a fresh-clone CI run of the test above)."""
    from rotorsweep.pipeline import workerinit

    dask_logger = logging.getLogger("distributed")
    level = dask_logger.level
    try:
        workerinit.dask_teardown(None)
        with caplog.at_level(logging.NOTSET):
            logging.getLogger("distributed.worker").error("Failed to communicate with scheduler during heartbeat.")
        assert not caplog.records
    finally:
        dask_logger.setLevel(level)


def test_ctrl_c_is_an_interrupt_where_a_library_turns_it_into_another_error(tmp_path, monkeypatch, capsys):
    """numpy's structured comparison (np.unique(axis=0), in the boundary tracker) reports a
    KeyboardInterrupt raised inside it as a TypeError; the CLI still ends as interrupted."""
    import signal

    import rotorsweep.pipeline as pipeline

    def run_hit_inside_numpy(*args, **kwargs):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)                                  # the handler runs before this ends
        except BaseException:
            raise TypeError("Cannot compare structured arrays unless they have a common dtype.") from None
        raise AssertionError("SIGINT was not delivered")

    cfg = tmp_path / "small.toml"
    cfg.write_text(SMALL)
    monkeypatch.setattr(pipeline, "run", run_hit_inside_numpy)
    before = signal.getsignal(signal.SIGINT)
    assert cli.main(["run", str(cfg), "-o", str(tmp_path / "x.nc")]) == 130
    assert capsys.readouterr().err == "rotorsweep: interrupted; finished chunks are kept, rerun with --resume\n"
    assert signal.getsignal(signal.SIGINT) is before               # the caller's handler is back


def test_after_ctrl_c_the_event_loop_logs_nothing_and_main_restores_the_loggers(tmp_path, monkeypatch, caplog):
    """What Dask's event-loop thread logs once Ctrl-C came is teardown racing the interrupt: seen
    in a fresh-clone CI run, its sync() cancel callback raised NameError (the interrupt came
    before its future existed) and tornado.application logged the traceback after the one line.
    The CLI turns logging off from the interrupt on (distributed.client has a level of its own,
    which silencing "distributed" would miss) and back on when main returns."""
    import signal

    import rotorsweep.pipeline as pipeline

    def interrupted_run(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(5)
        raise AssertionError("SIGINT was not delivered")

    def logged_late(*args, **kwargs):
        try:
            interrupted_run()
        finally:        # what the loop thread logs while the KeyboardInterrupt propagates
            logging.getLogger("tornado.application").error("Exception in callback sync.<locals>.cancel")
            logging.getLogger("distributed.client").error("heartbeat failed")

    cfg = tmp_path / "small.toml"
    cfg.write_text(SMALL)
    monkeypatch.setattr(pipeline, "run", logged_late)
    import distributed  # noqa: F401  (sets distributed.client's own level, as a run does)

    with caplog.at_level(logging.NOTSET):
        assert cli.main(["run", str(cfg), "-o", str(tmp_path / "x.nc")]) == 130
    assert not caplog.records
    assert logging.root.manager.disable == logging.NOTSET
    logging.getLogger("distributed.client").error("after main")
    assert [r.getMessage() for r in caplog.records] == ["after main"]

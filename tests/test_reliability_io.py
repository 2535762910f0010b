"""Reliability of the file side of a sweep (issue 15): one run per output, parts of one config
only, the umask's file modes, OS errors as one line, argument and config checks that come
before any work."""
import os
import subprocess
import time

import numpy as np
import pytest

from pipeline import cli, cube, fileio
from tests.test_cube import AXES4, PROVENANCE, random_results, _write_random_parts
from tests.test_pipeline import CLI, SMALL, rotorsweep


@pytest.fixture
def small_config(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    return path


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

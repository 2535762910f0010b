"""What the reliability tests (tests/test_reliability*.py) share, written once: a config file, the
CLI in this process, waiting for a run's part files, bitwise cube comparison, stopping processes."""
import subprocess
import time

import numpy as np

from rotorsweep.pipeline import cli
from tests.test_pipeline import data_vars


def config_file(directory, name, text):
    path = directory / name
    path.write_text(text)
    return path


def run_cli(capsys, *args):
    """(exit status, stderr) of `rotorsweep args` in this process; never a traceback."""
    rc = cli.main([str(a) for a in args])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return rc, err


def wait_for_parts(parts, proc, minimum=1, timeout=300):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if parts.is_dir() and len([p for p in parts.iterdir() if p.suffix == ".npz"]) >= minimum:
            return
        assert proc.poll() is None, "the sweep ended before it could be interrupted"
        time.sleep(0.05)
    raise AssertionError("no part file appeared")


def wait_for_file(path, timeout=60):
    """Until `path` exists (a scheduler file the Dask CLI writes) or `timeout` s have passed."""
    deadline = time.monotonic() + timeout
    while not path.exists() and time.monotonic() < deadline:
        time.sleep(0.1)


def assert_same_cube(reference, other):
    """Every data variable bitwise equal but compute_time, the one that measures the machine."""
    a, b = data_vars(reference), data_vars(other)
    assert set(a.data_vars) == set(b.data_vars)
    for name in a.data_vars:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


def stop(procs, timeout=30):
    """Terminate the processes, then kill those still there after `timeout` s."""
    for proc in procs:
        proc.terminate()
    for proc in procs:
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()

"""Sweeps on a real distributed cluster: a `dask scheduler` and `dask worker` processes started
with the distributed CLI on 127.0.0.1, `rotorsweep run --scheduler`, workers (and the driver)
killed mid-run. The cube must be bitwise the one of an undisturbed local run."""
import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import cube
from tests.harness import assert_same_cube, stop, wait_for_file, wait_for_parts
from tests.test_pipeline import CLI, SMALL, rotorsweep

DASK = str(Path(sys.executable).with_name("dask"))


def grid_config(tmp_path, speed, clearance, segment_length):
    path = tmp_path / "grid.toml"
    path.write_text(SMALL.replace("speed = {start = 70.0, stop = 100.0, step = 3.0}", f"speed = {speed}")
                    .replace("clearance = [7.6e-6, 19.0e-6]", f"clearance = {clearance}")
                    .replace("segment_length = 4", f"segment_length = {segment_length}"))
    return path


@contextlib.contextmanager
def dask_cluster(tmp_path, n_workers, nanny):
    """A scheduler and n single-thread workers as separate processes, bound to 127.0.0.1 (free
    ports picked by the OS; the address travels in a scheduler file). Yields (address, client)."""
    from dask.distributed import Client

    sched_file = tmp_path / "scheduler.json"
    local = ["--host", "127.0.0.1"]
    procs = [subprocess.Popen([DASK, "scheduler", *local, "--port", "0", "--dashboard-address", "127.0.0.1:0",
                               "--scheduler-file", str(sched_file)], stderr=subprocess.DEVNULL)]
    try:
        wait_for_file(sched_file)
        env = {**os.environ, "NUMBA_NUM_THREADS": "1"}
        procs += [subprocess.Popen([DASK, "worker", *local, "--nthreads", "1", "--scheduler-file", str(sched_file),
                                    "--nanny" if nanny else "--no-nanny"], stderr=subprocess.DEVNULL, env=env)
                  for _ in range(n_workers)]
        with Client(scheduler_file=str(sched_file), timeout="30s") as client:
            client.wait_for_workers(n_workers, timeout=120)
            yield json.loads(sched_file.read_text())["address"], client
    finally:
        stop(procs[::-1])


def worker_pids(client):
    """pid of each worker process (the one that computes; under a nanny, the nanny's child)."""
    return list(client.run(os.getpid).values())


@pytest.mark.slow    # 17-41 s: the default suite stays under 15 min on 2 cores (make test-slow)
def test_a_sweep_on_a_dask_cli_cluster_survives_a_killed_worker(tmp_path):
    cfg = grid_config(tmp_path, "{start = 60.0, stop = 250.0, step = 4.0}", "[7.6e-6, 19.0e-6]", 4)
    local = tmp_path / "local.nc"
    rotorsweep("run", cfg, "-o", local, "--workers", "2", "-q")
    out = tmp_path / "cluster.nc"
    with dask_cluster(tmp_path, n_workers=2, nanny=False) as (address, client):
        victim = worker_pids(client)[0]
        proc = subprocess.Popen(CLI + ["run", str(cfg), "-o", str(out), "--scheduler", address,
                                       "--chunk-points", "4", "-q"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        wait_for_parts(cube.parts_dir(out), proc)
        os.kill(victim, signal.SIGKILL)              # no nanny: this worker is gone for good
        stdout, stderr = proc.communicate(timeout=300)
        assert proc.returncode == 0, stderr
        assert len(client.scheduler_info()["workers"]) == 1
    assert_same_cube(local, out)


class Killer:
    """SIGKILLs a random worker process (its nanny starts a new one) each time `every` more part
    files have appeared in `parts`: deaths keep pace with the sweep however fast the machine runs
    it (at every 3 s a quiet machine finished the whole chaos run after 2 kills), and each one
    lets the sweep advance."""

    def __init__(self, client, parts, every, seed=0):
        import threading

        self.client, self.parts, self.every, self.kills = client, parts, every, 0
        self.rng = np.random.default_rng(seed)
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _count(self):
        return len(list(self.parts.glob("*.npz"))) if self.parts.is_dir() else 0

    def _run(self):
        last = 0
        while not self.stop.wait(0.05):
            done = self._count()
            if done < last + self.every:
                last = min(last, done)                      # the run's end removes the parts
                continue
            with contextlib.suppress(Exception):          # a worker just restarting: next round
                pids = worker_pids(self.client)
                os.kill(int(self.rng.choice(pids)), signal.SIGKILL)
                self.kills += 1
                last = done

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join()


def driver_killed_then_resumed(run, address, parts, minimum, timeout, resume_timeout):
    """The command `run` started on the cluster at `address`, SIGKILLed once `minimum` part files
    are in `parts` (its stderr the error if they never come), then run again with --resume:
    (the resumed run's finished process, the part files there were when the driver died)."""
    driver = subprocess.Popen(run + ["--scheduler", address], stderr=subprocess.PIPE, text=True)
    try:
        wait_for_parts(parts, driver, minimum=minimum, timeout=timeout)
    except AssertionError:
        raise AssertionError(driver.communicate()[1]) from None
    driver.kill()                                                # the driver, once
    driver.wait()
    parts_at_kill = len(list(parts.glob("*.npz")))
    resumed = subprocess.run(run + ["--scheduler", address, "--resume"], capture_output=True, text=True,
                             timeout=resume_timeout)
    return resumed, parts_at_kill


@pytest.mark.slow
def test_chaos_workers_killed_every_few_chunks_and_the_driver_once(tmp_path):
    """A few thousand points (orbits only) while a worker dies every 8 finished chunks and the
    driver once,
    then --resume: the cube is bitwise the undisturbed one. Figures in docs/reliability.md."""
    cfg = grid_config(tmp_path, "{start = 100.0, stop = 250.0, step = 0.1}", "[7.6e-6, 19.0e-6]", 8)
    reference = tmp_path / "reference.nc"
    t0 = time.monotonic()
    rotorsweep("run", cfg, "-o", reference, "--workers", "2", "-q")
    undisturbed_s = time.monotonic() - t0
    out = tmp_path / "chaos.nc"
    run = CLI + ["run", str(cfg), "-o", str(out), "--chunk-points", "16", "-q"]
    with dask_cluster(tmp_path, n_workers=2, nanny=True) as (address, client), Killer(client, cube.parts_dir(out), every=8) as killer:
        t0 = time.monotonic()
        resumed, parts_at_driver_kill = driver_killed_then_resumed(run, address, cube.parts_dir(out), minimum=40,
                                                                   timeout=1200, resume_timeout=3600)
        chaos_s = time.monotonic() - t0
        assert resumed.returncode == 0, resumed.stderr
    n_points = cube.open_cube(out)["orbit_status"].size
    print(f"\nchaos: {n_points} points, {killer.kills} worker kills + 1 driver kill (after "
          f"{parts_at_driver_kill} parts), {chaos_s:.0f} s; undisturbed local run {undisturbed_s:.0f} s")
    assert killer.kills >= 3
    assert_same_cube(reference, out)


@pytest.mark.slow
def test_chaos_continue_a_line_worker_killed_and_the_driver_once(tmp_path):
    """`continue` on twelve lines while a worker dies every 3 finished lines and the driver once,
    then --resume: the result is bitwise the undisturbed local one."""
    from tests.test_reliability_results import LINES, assert_same_result

    cfg = tmp_path / "lines.toml"
    cfg.write_text(LINES.replace("clearance = [7.6e-6, 11.4e-6, 19.0e-6]",
                                 f"clearance = [{', '.join(f'{c:.2e}' for c in np.linspace(6e-6, 19e-6, 12))}]"))
    reference = tmp_path / "reference.nc"
    rotorsweep("continue", cfg, "-o", reference, "--workers", "2", "-q")
    out = tmp_path / "chaos.nc"
    run = CLI + ["continue", str(cfg), "-o", str(out), "-q"]
    with dask_cluster(tmp_path, n_workers=2, nanny=True) as (address, client), Killer(client, cube.parts_dir(out), every=3) as killer:
        resumed, _ = driver_killed_then_resumed(run, address, cube.parts_dir(out), minimum=7, timeout=600,
                                                resume_timeout=1200)
        assert resumed.returncode == 0, resumed.stderr
    assert killer.kills >= 2
    assert_same_result(reference, out)

"""Reliability: resume after SIGKILL, worker loss, refusal of a changed config, numerical
faults as data, localhost-only cluster, no silent overwrite."""
import gc
import os
import re
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

from rotorsweep.pipeline import compute, config, cube, scene, schema, sweep
from rotorsweep.pipeline.cluster import connect
from tests.harness import assert_same_cube, config_file, wait_for_parts
from tests.test_pipeline import CLI, SMALL, rotorsweep

LONG = SMALL.replace("speed = {start = 70.0, stop = 100.0, step = 3.0}",
                     "speed = {start = 10.0, stop = 250.0, step = 0.5}").replace(
    "clearance = [7.6e-6, 19.0e-6]", "clearance = [3.8e-6, 7.6e-6, 15.2e-6, 19.0e-6]").replace(
    "segment_length = 4", "segment_length = 16")


@pytest.fixture(scope="module")
def long_config(tmp_path_factory):
    return config_file(tmp_path_factory.mktemp("cfg"), "long.toml", LONG)


@pytest.fixture(scope="module")
def uninterrupted(long_config, tmp_path_factory):
    out = tmp_path_factory.mktemp("ref") / "long.nc"
    rotorsweep("run", long_config, "-o", out, "--workers", "2", "-q")
    return out


def test_resume_after_sigkill_gives_the_uninterrupted_cube(long_config, uninterrupted, tmp_path):
    out = tmp_path / "long.nc"
    proc = subprocess.Popen(CLI + ["run", str(long_config), "-o", str(out), "--workers", "2",
                                   "--chunk-points", "32"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    wait_for_parts(cube.parts_dir(out), proc, minimum=3)
    os.killpg(proc.pid, signal.SIGKILL)           # the driver and its local workers, no cleanup
    proc.wait()
    assert not out.exists()
    resumed = rotorsweep("run", long_config, "-o", out, "--workers", "2", "--resume")
    first = re.search(r"\] (\d+)/(\d+) points", resumed.stderr)
    assert first and 0 < int(first.group(1)) < int(first.group(2)), resumed.stderr  # only missing work
    assert_same_cube(uninterrupted, out)


def test_resume_refuses_parts_of_a_changed_config(long_config, tmp_path):
    out = tmp_path / "c.nc"
    parts = cube.parts_dir(out)
    cfg = config.load_config(long_config)
    seg = sweep.segments(cfg.scene)[0]
    cube.write_part(parts, "seg000000", seg.index, compute.solve_segment(cfg.scene, list(seg.points)),
                    {"config_hash": cfg.hash(), "segments": [seg.id]})
    changed = tmp_path / "changed.toml"
    changed.write_text(LONG.replace('stiffness = "bai2006"', 'stiffness = "hertz"'))
    proc = rotorsweep("run", changed, "-o", out, "--resume", check=False)
    assert proc.returncode == 2 and "different config" in proc.stderr, proc.stderr
    proc = rotorsweep("run", long_config, "-o", out, check=False)
    assert proc.returncode == 2 and "--resume" in proc.stderr


def test_sweep_survives_the_loss_of_a_worker(long_config, uninterrupted, tmp_path):
    from dask.distributed import Client, LocalCluster

    cfg = config.load_config(long_config)
    out = tmp_path / "lost.nc"
    with LocalCluster(n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None) as cluster, \
            Client(cluster) as client:
        pids = client.run(os.getpid)
        runner = threading.Thread(target=sweep.run, args=(cfg, out),
                                  kwargs=dict(scheduler=cluster.scheduler_address, chunk_points=32,
                                              progress=False))
        runner.start()
        parts = cube.parts_dir(out)
        deadline = time.monotonic() + 300
        while not (parts.is_dir() and any(parts.iterdir())) and time.monotonic() < deadline:
            time.sleep(0.05)
        os.kill(next(iter(pids.values())), signal.SIGKILL)     # one worker dies mid-sweep
        runner.join(timeout=600)
    assert_same_cube(uninterrupted, out)


def test_numerical_faults_are_statuses_not_crashes():
    cfg = config.parse_config(SMALL)
    data = cfg.data
    data["rotor"]["damping"] = 0.0                        # undamped: no transient decay
    data["numerics"]["max_newton_iter"] = 2               # too few iterations: not_converged
    data["numerics"]["amplitude_limit"] = 1e-9            # 1 nm: every orbit 'diverges'
    pts = [{"speed": s, "clearance": 19e-6, "contact_angle": None, "preload": 0.0} for s in (40.0, 120.0)]
    rows = compute.solve_segment(scene.from_data(data), pts)
    statuses = {schema.ORBIT_STATUS[s] for s in rows["orbit_status"]}
    assert statuses <= {"not_converged", "diverged"} and statuses
    assert np.isnan(rows["max_abs_multiplier"]).all()
    assert (rows["stable"] == schema.INT_FILL).all()


def test_existing_cube_is_not_overwritten_without_flag(tmp_path):
    cfg_path = tmp_path / "s.toml"
    cfg_path.write_text(SMALL)
    out = tmp_path / "exists.nc"
    out.write_text("precious")
    proc = rotorsweep("run", cfg_path, "-o", out, check=False)
    assert proc.returncode == 2 and "--overwrite" in proc.stderr
    assert out.read_text() == "precious"


def test_local_cluster_binds_to_localhost_and_its_workers_keep_their_imports_out_of_gc():
    client, cluster = connect(2, None)
    try:
        assert client.scheduler.address.startswith("tls://127.0.0.1:")
        assert "127.0.0.1" in client.dashboard_link
        for addr in client.scheduler_info()["workers"]:
            assert addr.startswith("tls://127.0.0.1:")
        # the preload froze what the imports left (a fresh process: nothing frozen otherwise)
        assert all(n > 10_000 for n in client.run(gc.get_freeze_count).values())
        # the relaxed housekeeping reached the worker processes (they get the nannies' settings)
        monitor_ms = client.run(lambda dask_worker: dask_worker.periodic_callbacks["monitor"].callback_time)
        assert set(monitor_ms.values()) == {5000}
    finally:
        client.close()
        cluster.close()

"""How many tasks per second a Dask scheduler sustains, measured through the distributed CLI on
127.0.0.1 (`dask scheduler --host 127.0.0.1` + `dask worker ... --nthreads 1`), and the cluster
size at which it would saturate for a sweep's per-chunk cost.

    python -m workflows.bench.scheduler_throughput      # prints the JSON (about 1 min)

The scaling benchmark (workflows.bench.scaling) runs it and puts the numbers into scaling.md.

A task here is a no-op (`_noop(i)`, a few bytes each way), so the rate is the scheduler's (and
the client's) cost per task: submit, assign, run, report, release. A sweep whose chunk takes
`c` seconds of compute keeps the scheduler below saturation while workers / c < rate, i.e.
up to about rate x c workers; beyond that, chunks must grow.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from workflows.bench.common import ROOT, loadavg, log

N_TASKS = 2000
START_TIMEOUT_S = 60


def _noop(i):
    return i


def _dask_cli():
    here = Path(sys.executable).with_name("dask")
    return str(here) if here.exists() else shutil.which("dask") or "dask"


def _start(args, log_path):
    # the tasks (_noop) are this module's: workflows/ is not installed, so the checkout goes on the
    # path of the CLI's processes (a console script does not put the working directory there)
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    return subprocess.Popen([_dask_cli(), *args], stdout=open(log_path, "w"), stderr=subprocess.STDOUT,
                            env={**os.environ, "NUMBA_NUM_THREADS": "1", "PYTHONPATH": path})


def _wait_for(path, timeout):
    t0 = time.monotonic()
    while not Path(path).exists():
        if time.monotonic() - t0 > timeout:
            raise RuntimeError(f"no {path} after {timeout} s")
        time.sleep(0.1)


def _rate(client, n, batch):
    """Tasks per second of n no-op tasks: submitted all at once (batch) or one at a time,
    each waited for before the next (the round trip: submit -> result)."""
    t0 = time.perf_counter()
    if batch:
        client.gather(client.map(_noop, range(n), pure=False))
    else:
        for i in range(n):
            client.submit(_noop, i, pure=False).result()
    return n / (time.perf_counter() - t0)


def measure(worker_counts=(1, 2), n_tasks=N_TASKS):
    """{n workers: {"batch_tasks_per_s", "round_trip_ms", "load"}} through a CLI-started
    scheduler and `dask worker` processes on 127.0.0.1."""
    from dask.distributed import Client

    out = {}
    work = Path(tempfile.mkdtemp(prefix="bench_sched_"))
    try:
        for k in worker_counts:
            out[k] = _measure_cluster(Client, work / f"w{k}", k, n_tasks)
            log(f"  scheduler, {k} worker(s): {out[k]['batch_tasks_per_s']:.0f} tasks/s in a batch, "
                f"round trip {out[k]['round_trip_ms']:.2f} ms; load {out[k]['loadavg'][0]}")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return out


def _measure_cluster(client_class, work, n_workers, n_tasks):
    work.mkdir(parents=True)
    sched_file = work / "scheduler.json"
    procs = [_start(["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                     "--scheduler-file", str(sched_file)], work / "scheduler.log")]
    try:
        _wait_for(sched_file, START_TIMEOUT_S)
        procs.append(_start(["worker", "--scheduler-file", str(sched_file), "--nworkers", str(n_workers),
                             "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"], work / "worker.log"))
        with client_class(scheduler_file=str(sched_file), timeout="60s") as client:
            client.wait_for_workers(n_workers, timeout=START_TIMEOUT_S)
            _rate(client, 200, True)                     # warm: imports, connections
            load = loadavg()
            batch = max(_rate(client, n_tasks, True) for _ in range(3))
            single = max(_rate(client, n_tasks // 10, False) for _ in range(3))
            return {"workers": n_workers, "n_tasks": n_tasks, "batch_tasks_per_s": round(batch, 1),
                    "round_trip_ms": round(1e3 / single, 3), "loadavg": load}
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in reversed(procs):
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()


def saturation(rate, chunk_compute_s):
    """Workers at which `rate` tasks/s are used up by chunks of chunk_compute_s seconds each."""
    return rate * chunk_compute_s


if __name__ == "__main__":
    print(json.dumps(measure(), indent=1))

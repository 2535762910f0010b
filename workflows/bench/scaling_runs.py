"""One timed sweep of the scaling benchmark on a fresh local Dask cluster, and the warm-up before
any timed run: wall time, phases, task stream, memory and CPU time."""
import contextlib
import os
import time
from pathlib import Path

import numpy as np

from workflows.bench.common import loadavg, peak_rss_kib, since, steal_seconds
from workflows.bench.scaling_scene import chunk_plan, first_point, scene_config


# --- instrumentation ----------------------------------------------------------------------------

# (phase, module, function). The first five follow one another in rotorsweep.pipeline.sweep.run, except that
# driver_warmup runs inside compute (after the cluster has started); the last two run inside the
# compute phase (in the driver, while the workers compute).
PHASES = (("driver_warmup", "rotorsweep.pipeline.warmup", "compile_scene"),
          ("compute", "rotorsweep.pipeline.sweep", "_run_chunks"),
          ("assemble", "rotorsweep.pipeline.cube", "Assembly.dataset"),
          ("boundaries", "rotorsweep.pipeline.boundaries", "add_boundary_table"),
          ("write", "rotorsweep.pipeline.cube", "write_cube"),
          ("connect", "rotorsweep.pipeline.cluster", "connect"),
          ("part_files", "rotorsweep.pipeline.cube", "write_part"))
TOP_PHASES = ("driver_warmup", "compute", "assemble", "boundaries", "write")


@contextlib.contextmanager
def phase_timers():
    """Time the pipeline's phases by wrapping its functions for the duration (module attributes
    are looked up at call time, so rotorsweep.pipeline.sweep.run sees the wrappers). Yields a dict of
    seconds per phase (and the wall-clock epoch at which the compute phase started); a phase
    whose function does not exist (the pipeline changed) is left out."""
    import importlib

    times, patched = {}, []

    def wrap(phase, fn):
        def timed(*args, **kwargs):
            if phase == "compute":
                times["compute_epoch"] = time.time()
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                times[phase] = times.get(phase, 0.0) + time.perf_counter() - t0
        return timed

    for phase, module_name, attr in PHASES:
        owner = importlib.import_module(module_name)
        *path, attr = attr.split(".")           # a method: "Class.method"
        for name in path:
            owner = getattr(owner, name, None)
        fn = getattr(owner, attr, None)
        if fn is None:
            continue
        setattr(owner, attr, wrap(phase, fn))
        patched.append((owner, attr, fn))
    try:
        yield times
    finally:
        for owner, attr, fn in patched:
            setattr(owner, attr, fn)


def task_summary(records, n_workers, phase_start_epoch, phase_seconds):
    """Busy time per worker, span, tail and utilization of the compute phase from the records
    of dask's task stream (worker clocks are the machine's wall clock): chunk tasks and the
    boundary refinement tasks that run between them."""
    tasks, refining = [], []
    for rec in records:
        key = str(rec.get("key", "")).lstrip("('")
        kind = tasks if key.startswith("compute_segments") else refining if key.startswith("refine_brackets") else None
        for ss in rec.get("startstops", ()) if kind is not None else ():
            if ss.get("action") == "compute":
                kind.append((rec["worker"], ss["start"], ss["stop"]))
    if not tasks:
        return dict(n_tasks=0)
    n_chunks, chunk_busy = len(tasks), sum(b - a for _, a, b in tasks)
    tasks += refining          # the boundary table's tasks run between the chunks: worker work too
    workers = sorted({w for w, _, _ in tasks})
    busy = {w: sum(b - a for ww, a, b in tasks if ww == w) for w in workers}
    last = {w: max(b for ww, _, b in tasks if ww == w) for w in workers}
    first = min(a for _, a, _ in tasks)
    end = max(last.values())
    drain = None if phase_start_epoch is None or not phase_seconds else phase_start_epoch + phase_seconds - end
    # a worker that got no task at all finished 'at the start'
    lasts = list(last.values()) + [first] * (n_workers - len(workers))
    busy_list = [busy[w] for w in workers] + [0.0] * (n_workers - len(workers))
    timeline = [dict(worker=workers.index(w), start=round(a - first, 4), stop=round(b - first, 4))
                for w, a, b in sorted(tasks, key=lambda t: t[1])]
    return dict(
        n_tasks=n_chunks, chunk_busy_s=round(chunk_busy, 3), n_refine_tasks=len(refining),
        refine_busy_s=round(sum(b - a for _, a, b in refining), 3),
        busy_s=[round(b, 3) for b in busy_list],
        busy_total_s=round(sum(busy_list), 3),
        span_s=round(end - first, 3),
        tail_s=round(end - min(lasts), 3),
        dispatch_s=None if phase_start_epoch is None else round(first - phase_start_epoch, 3),
        drain_s=None if drain is None else round(drain, 3),
        utilization=None if not phase_seconds else round(sum(busy_list) / (n_workers * phase_seconds), 4),
        timeline=timeline,
    )


# --- one run ------------------------------------------------------------------------------------

def start_cluster(n_workers):
    from distributed import Client

    from rotorsweep.pipeline import cluster as runtime

    cluster = runtime.local_cluster(n_workers)      # the cluster every command starts
    client = Client(cluster)
    client.wait_for_workers(n_workers)
    return cluster, client


def worker_calls():
    """Functions run on the workers: warm and cpu_seconds are closures, which cloudpickle ships by
    value (the workers need not import this module); peak_rss_kib is imported there from
    workflows.bench.common (worker processes start with the driver's sys.path)."""
    def warm(scene, point):
        from rotorsweep.pipeline import compute, sweep  # noqa: F401  (what a real run's worker preload imports)
        compute.solve_segment(scene, [point])
        return True

    def cpu_seconds():
        import resource as r
        u = r.getrusage(r.RUSAGE_SELF)
        return u.ru_utime + u.ru_stime

    return warm, peak_rss_kib, cpu_seconds


def measure_run(cfg, n_workers, chunk_points, work_dir, label, repeat=0):
    """One timed sweep on a fresh cluster of n_workers processes; returns the run's record."""
    import rotorsweep.pipeline as pipeline
    from distributed import get_task_stream

    warm, max_rss, cpu_seconds = worker_calls()
    before = loadavg()
    t0 = time.perf_counter()
    cluster, client = start_cluster(n_workers)
    cluster_start = time.perf_counter() - t0
    try:
        t0 = time.perf_counter()
        client.run(warm, cfg.scene, first_point(cfg))
        worker_warmup = time.perf_counter() - t0
        rss_before = list(client.run(max_rss).values())
        cpu_before = client.run(cpu_seconds)
        out = Path(work_dir) / f"{label}_r{repeat}.nc"
        driver_cpu = time.process_time()
        with phase_timers() as phases, get_task_stream(client) as stream:
            steal = steal_seconds()
            t0 = time.perf_counter()
            path = pipeline.run(cfg, str(out), scheduler=cluster,
                                chunk_points=chunk_points, overwrite=True, progress=False)
            wall = time.perf_counter() - t0
            steal = since(steal, steal_seconds())
        driver_cpu = time.process_time() - driver_cpu
        cpu_after = client.run(cpu_seconds)
        rss_after = list(client.run(max_rss).values())
        records = list(stream.data)
    finally:
        client.close()
        cluster.close()
    ds = pipeline.open_cube(path)
    try:
        point_compute = float(np.nansum(ds["compute_time"].values)) if "compute_time" in ds else None
        n_failed = int(np.sum(ds["orbit_status"].values != 0)) if "orbit_status" in ds else None
    finally:
        ds.close()
    os.remove(path)
    epoch = phases.pop("compute_epoch", None)
    phase_s = {k: round(v, 3) for k, v in phases.items()}
    phase_s["other"] = round(wall - sum(v for k, v in phases.items() if k in TOP_PHASES), 3)
    n_chunks, used = chunk_plan(cfg, n_workers, chunk_points)
    tasks = task_summary(records, n_workers, epoch, phases.get("compute"))
    return dict(
        label=label, workers=n_workers, chunk_points=chunk_points, chunk_points_used=used,
        n_chunks=n_chunks, repeat=repeat,
        cluster_start_s=round(cluster_start, 3), worker_warmup_s=round(worker_warmup, 3),
        wall_s=round(wall, 3), points_per_s=round(cfg.n_points / wall, 2), phases=phase_s,
        tasks=tasks, point_compute_s=round(point_compute, 3), n_not_converged=n_failed,
        worker_max_rss_kib=rss_after, worker_rss_before_kib=rss_before,
        driver_max_rss_kib=peak_rss_kib(), driver_cpu_s=round(driver_cpu, 3), steal_s=steal,
        worker_cpu_s=[round(cpu_after[w] - cpu_before[w], 3) for w in cpu_after],
        loadavg_before=before, loadavg_after=loadavg(),
    )


def warm_up(work_dir):
    """Compile (or load from Numba's on-disk cache) every kernel a sweep uses and import the
    driver's modules with a tiny one-worker sweep, before any timed run."""
    import rotorsweep.pipeline as pipeline
    from rotorsweep.pipeline import compute

    cfg = scene_config(speed=(100.0, 101.0, 0.5), clearances=(7.6e-6,), name="bench_warmup")
    t0 = time.perf_counter()
    compute.solve_segment(cfg.scene, [first_point(cfg)])
    kernels = time.perf_counter() - t0
    t0 = time.perf_counter()
    cluster, client = start_cluster(1)
    try:
        path = pipeline.run(cfg, str(Path(work_dir) / "warmup.nc"), scheduler=cluster,
                            overwrite=True, progress=False)
    finally:
        client.close()
        cluster.close()
    os.remove(path)
    return dict(driver_kernels_s=round(kernels, 3), tiny_sweep_s=round(time.perf_counter() - t0, 3))

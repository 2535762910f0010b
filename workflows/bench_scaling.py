"""Scaling benchmark of a distributed sweep: the Bai 2006 Fig. 13 grid on a local Dask cluster.

    python -m workflows.bench_scaling            # full: Fig. 13, 12005 points (about 7 min on
                                                 #   2 quiet cores) -> docs/benchmarks/scaling.*
    python -m workflows.bench_scaling --quick    # reduced grid, 242 points (about 1 min)
                                                 #   -> build/bench_scaling_quick/

Writes scaling.json (every measured number), scaling.md (machine, tables, what limits the
speed-up, verdict against the target) and scaling.png (wall time against chunk size and the task
timeline of the two-worker run).

What is measured, every run through the public API `pipeline.run(cfg, output,
scheduler=<address>, chunk_points=..., overwrite=True)` on a fresh
`distributed.LocalCluster(n_workers=k, threads_per_worker=1, processes=True)`:

* wall time of the sweep (`pipeline.run`, from the call to the written cube), separately from
  the cluster start-up and from the workers' warm-up (import + loading Numba's on-disk cache:
  paid once per worker process, in parallel, by every real run too);
* its phases, timed by wrapping the pipeline's own functions (nothing in pipeline/ changes):
  driver warm-up, the distributed compute phase (scatter, tasks, part files), cube assembly,
  boundary table (every stability change refined to 1e-8 in the driver, serially), cube write;
* from Dask's task stream: busy time per worker, the span of the compute phase, its tail (how
  long the first worker to finish waits for the last), and worker utilization;
* points per second, the sum of the per-point compute times stored in the cube;
* peak memory: max RSS (ru_maxrss, KiB on Linux) of each worker process after the sweep and of
  the driver process (a high-water mark over the whole benchmark, as the driver runs them all);
* CPU seconds of the driver and the workers during the sweep, load average before and after.

Runs: 1 worker and 2 workers with the pipeline's default chunking (speed-up, efficiency; target:
2 workers >= 1.8x faster than 1), then 2 workers with other chunk sizes, from one continuation
segment per chunk to one chunk per worker. Numba compilation is excluded: a tiny warm-up sweep
fills the on-disk cache and imports everything in the driver before any timed run.
"""
import argparse
import contextlib
import datetime
import json
import math
import os
import platform
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FIG13 = ROOT / "configs" / "bai2006_fig13.toml"
DOCS = ROOT / "docs" / "benchmarks"
QUICK_OUT = ROOT / "build" / "bench_scaling_quick"
TARGET_SPEEDUP = 1.8
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
              "MKL_NUM_THREADS": "1"}
QUICK_SPEED = (10.0, 250.0, 2.0)            # Hz: the Fig. 13 range, 2 Hz steps
QUICK_CLEARANCES = (7.6e-6, 19.0e-6)         # m: the most and the least regular Fig. 13 lines

RUN_KEYS = ("label", "workers", "chunk_points", "chunk_points_used", "n_chunks", "repeat",
            "cluster_start_s", "worker_warmup_s", "wall_s", "points_per_s", "phases", "tasks",
            "point_compute_s", "n_not_converged", "worker_max_rss_kib", "worker_rss_before_kib", "driver_max_rss_kib",
            "driver_cpu_s", "worker_cpu_s", "loadavg_before", "loadavg_after")
RESULT_KEYS = ("benchmark", "mode", "created", "git", "scene", "machine", "load_average",
               "warmup", "runs", "scaling", "chunk_sensitivity", "limits", "verdict", "command")


def log(msg):
    print(msg, file=sys.stderr, flush=True)


# --- scenes -------------------------------------------------------------------------------------

def scene_config(speed=None, clearances=None, name=None, segment_length=None):
    """The Fig. 13 scene, optionally with another speed axis (start, stop, step) [Hz], other
    clearances [m], name or segment length, attractor diagnostics off: built by editing the TOML text of
    configs/bai2006_fig13.toml and validated by pipeline.config.parse_config."""
    from pipeline import config

    # orbits + Floquet only: the scaling of the paper's map, not of the attractor diagnostics
    text = re.sub(r"(?m)^attractor\s*=.*$", "attractor = false", FIG13.read_text())
    if speed is not None:
        start, stop, step = speed
        text, n = re.subn(r"(?m)^speed\s*=.*$",
                          f"speed = {{start = {start!r}, stop = {stop!r}, step = {step!r}}}", text)
        assert n == 1, "configs/bai2006_fig13.toml: no speed axis line"
    if clearances is not None:
        values = ", ".join(repr(float(c)) for c in clearances)
        text, n = re.subn(r"(?m)^clearance\s*=.*$", f"clearance = [{values}]", text)
        assert n == 1, "configs/bai2006_fig13.toml: no clearance axis line"
    if name is not None:
        text, n = re.subn(r'(?m)^name\s*=.*$', f'name = "{name}"', text)
        assert n == 1
    if segment_length is not None:
        text = re.sub(r"(?m)^segment_length\s*=.*$", "", text)
        text = text.replace("[numerics]", f"[numerics]\nsegment_length = {int(segment_length)}", 1)
    return config.parse_config(text, path=f"{FIG13.name} (bench_scaling)", allow_large=True)


def quick_config():
    return scene_config(speed=QUICK_SPEED, clearances=QUICK_CLEARANCES, name="bai2006_fig13_quick")


def full_config():
    return scene_config()


def scene_info(cfg):
    from pipeline import sweep

    segs = sweep.segments(cfg)
    return dict(name=cfg.data["scene"]["name"], n_points=cfg.n_points,
                axes={k: len(v) for k, v in cfg.axes.items()},
                speed_range=[float(cfg.axes["speed"][0]), float(cfg.axes["speed"][-1])],
                clearances=[float(c) for c in cfg.axes.get("clearance", [])],
                segment_length=cfg.data["numerics"]["segment_length"], n_segments=len(segs),
                config_hash=cfg.hash())


def chunk_plan(cfg, n_workers, chunk_points):
    """(number of chunks, median points per chunk) that pipeline.sweep.plan_chunks makes of the
    scene's segments for n_workers (chunk_points None: the pipeline's default)."""
    from pipeline import sweep

    chunks = sweep.plan_chunks(sweep.segments(cfg), n_workers, chunk_points)
    sizes = [sum(len(seg.points) for seg in chunk) for chunk in chunks]
    return len(chunks), int(statistics.median(sizes)) if sizes else 0


def chunk_sizes_for(cfg, n_workers=2):
    """Chunk sizes for the sensitivity runs: one continuation segment per chunk, 8 and 24
    segments per chunk (when that still leaves >= 4 chunks per worker), and one chunk per
    worker; the pipeline's default (None) is measured by the default run."""
    n = cfg.n_points
    seg = cfg.data["numerics"]["segment_length"]
    sizes = [seg]
    sizes += [k * seg for k in (8, 24) if k * seg <= n / (4 * n_workers)]
    sizes.append(int(math.ceil(n / n_workers)))
    return sorted(set(sizes))


# --- machine ------------------------------------------------------------------------------------

def machine_info():
    import dask
    import distributed
    import numba
    import scipy

    cpu = platform.processor() or "unknown"
    mem_kib = None
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    with contextlib.suppress(OSError, ValueError, IndexError):
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                mem_kib = int(line.split()[1])
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    return dict(cpu=cpu, cores=os.cpu_count(), usable_cores=usable,
                memory_gib=None if mem_kib is None else round(mem_kib / 2 ** 20, 1),
                platform=platform.platform(), python=platform.python_version(),
                numpy=np.__version__, scipy=scipy.__version__, numba=numba.__version__,
                dask=dask.__version__, distributed=distributed.__version__)


def git_info():
    def git(*args):
        try:
            out = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, timeout=30)
            return out.stdout.strip() if out.returncode == 0 else None
        except (OSError, subprocess.SubprocessError):
            return None
    status = git("status", "--porcelain", "--", "rotorkernels", "pipeline", "configs")
    return dict(commit=git("rev-parse", "--short", "HEAD"),
                kernels_or_pipeline_modified=None if status is None else bool(status))


def loadavg():
    return [round(x, 2) for x in os.getloadavg()]


def driver_max_rss_kib():
    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)


# --- instrumentation ----------------------------------------------------------------------------

# (phase, module, function). The first five follow one another in pipeline.sweep.run; the last
# two run inside the compute phase (in the driver, while the workers compute).
PHASES = (("driver_warmup", "pipeline.sweep", "_warm_up"),
          ("compute", "pipeline.sweep", "_run_chunks"),
          ("assemble", "pipeline.cube", "assemble"),
          ("boundaries", "pipeline.boundaries", "add_boundary_table"),
          ("write", "pipeline.cube", "write_cube"),
          ("connect", "pipeline.sweep", "_client"),
          ("part_files", "pipeline.cube", "write_part"))
TOP_PHASES = ("driver_warmup", "compute", "assemble", "boundaries", "write")


@contextlib.contextmanager
def phase_timers():
    """Time the pipeline's phases by wrapping its functions for the duration (module attributes
    are looked up at call time, so pipeline.sweep.run sees the wrappers). Yields a dict of
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
        module = importlib.import_module(module_name)
        fn = getattr(module, attr, None)
        if fn is None:
            continue
        setattr(module, attr, wrap(phase, fn))
        patched.append((module, attr, fn))
    try:
        yield times
    finally:
        for module, attr, fn in patched:
            setattr(module, attr, fn)


def task_summary(records, n_workers, phase_start_epoch, phase_seconds):
    """Busy time per worker, span, tail and utilization of the compute phase from the records
    of dask's task stream (worker clocks are the machine's wall clock)."""
    tasks = []
    for rec in records:
        if not str(rec.get("key", "")).startswith(("compute_chunk", "('compute_chunk")):
            continue
        for ss in rec.get("startstops", ()):
            if ss.get("action") == "compute":
                tasks.append((rec["worker"], ss["start"], ss["stop"]))
    if not tasks:
        return dict(n_tasks=0)
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
        n_tasks=len(tasks),
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
    from distributed import Client, LocalCluster

    # worker_dashboard_address=None: no per-worker HTTP server (nothing here reads it, and on a
    # shared machine the default port 8787 is often taken, which only produces warnings)
    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                           host="127.0.0.1", dashboard_address=None, worker_dashboard_address=None,
                           env=dict(WORKER_ENV))
    client = Client(cluster)
    client.wait_for_workers(n_workers)
    return cluster, client


def _worker_calls():
    """Functions run on the workers; closures so that cloudpickle ships them by value (the
    workers need not import this module)."""
    def warm(data, point):
        from pipeline import compute
        compute.solve_segment(data, [point])
        return True

    def max_rss():
        import resource as r
        return int(r.getrusage(r.RUSAGE_SELF).ru_maxrss)

    def cpu_seconds():
        import resource as r
        u = r.getrusage(r.RUSAGE_SELF)
        return u.ru_utime + u.ru_stime

    return warm, max_rss, cpu_seconds


def first_point(cfg):
    from pipeline import sweep

    return dict(sweep.segments(cfg)[0].points[0])


def measure_run(cfg, n_workers, chunk_points, work_dir, label, repeat=0):
    """One timed sweep on a fresh cluster of n_workers processes; returns the run's record."""
    import pipeline
    from distributed import get_task_stream

    warm, max_rss, cpu_seconds = _worker_calls()
    before = loadavg()
    t0 = time.perf_counter()
    cluster, client = start_cluster(n_workers)
    cluster_start = time.perf_counter() - t0
    try:
        t0 = time.perf_counter()
        client.run(warm, cfg.data, first_point(cfg))
        worker_warmup = time.perf_counter() - t0
        rss_before = list(client.run(max_rss).values())
        cpu_before = client.run(cpu_seconds)
        out = Path(work_dir) / f"{label}_r{repeat}.nc"
        driver_cpu = time.process_time()
        with phase_timers() as phases, get_task_stream(client) as stream:
            t0 = time.perf_counter()
            path = pipeline.run(cfg, str(out), scheduler=cluster.scheduler_address,
                                chunk_points=chunk_points, overwrite=True, progress=False)
            wall = time.perf_counter() - t0
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
        driver_max_rss_kib=driver_max_rss_kib(), driver_cpu_s=round(driver_cpu, 3),
        worker_cpu_s=[round(cpu_after[w] - cpu_before[w], 3) for w in cpu_after],
        loadavg_before=before, loadavg_after=loadavg(),
    )


def warm_up(work_dir):
    """Compile (or load from Numba's on-disk cache) every kernel a sweep uses and import the
    driver's modules with a tiny one-worker sweep, before any timed run."""
    import pipeline
    from pipeline import compute

    cfg = scene_config(speed=(100.0, 101.0, 0.5), clearances=(7.6e-6,), name="bench_warmup")
    t0 = time.perf_counter()
    compute.solve_segment(cfg.data, [first_point(cfg)])
    kernels = time.perf_counter() - t0
    t0 = time.perf_counter()
    cluster, client = start_cluster(1)
    try:
        path = pipeline.run(cfg, str(Path(work_dir) / "warmup.nc"), scheduler=cluster.scheduler_address,
                            overwrite=True, progress=False)
    finally:
        client.close()
        cluster.close()
    os.remove(path)
    return dict(driver_kernels_s=round(kernels, 3), tiny_sweep_s=round(time.perf_counter() - t0, 3))


# --- the benchmark ------------------------------------------------------------------------------

def _median_run(runs, workers, chunk_points):
    sel = [r for r in runs if r["workers"] == workers and r["chunk_points"] == chunk_points]
    if not sel:
        return None
    walls = [r["wall_s"] for r in sel]
    med = statistics.median(walls)
    return min(sel, key=lambda r: abs(r["wall_s"] - med)), sel


def _amdahl(serial, parallel_1):
    """Largest 2-worker speed-up with `serial` seconds not divided: (S + P) / (S + P / 2)."""
    if not parallel_1:
        return float("nan")
    return (serial + parallel_1) / (serial + parallel_1 / 2)


def analyse(runs, worker_counts):
    """Speed-up, efficiency, chunk sensitivity and the budget of what limits the speed-up."""
    one = _median_run(runs, 1, None) if 1 in worker_counts else None
    two = _median_run(runs, 2, None) if 2 in worker_counts else None
    scaling, limits = {}, {}
    if one and two:
        r1, r2 = one[0], two[0]
        s = r1["wall_s"] / r2["wall_s"]
        c1, c2 = r1["phases"].get("compute"), r2["phases"].get("compute")
        serial1 = r1["wall_s"] - (c1 or 0.0)
        serial2 = r2["wall_s"] - (c2 or 0.0)
        scaling = dict(
            wall_1_worker_s=r1["wall_s"], wall_2_workers_s=r2["wall_s"],
            speedup=round(s, 3), efficiency=round(s / 2, 3), target=TARGET_SPEEDUP,
            meets_target=bool(s >= TARGET_SPEEDUP),
            compute_speedup=None if not (c1 and c2) else round(c1 / c2, 3),
            span_speedup=None if not (r1["tasks"].get("span_s") and r2["tasks"].get("span_s"))
            else round(r1["tasks"]["span_s"] / r2["tasks"]["span_s"], 3),
            points_per_s_1=r1["points_per_s"], points_per_s_2=r2["points_per_s"],
            repeats_1=[r["wall_s"] for r in one[1]], repeats_2=[r["wall_s"] for r in two[1]],
        )
        b1 = r1["tasks"].get("busy_total_s")
        b2 = r2["tasks"].get("busy_total_s")
        ideal = r1["wall_s"] / 2
        in_compute2 = (r2["tasks"].get("dispatch_s") or 0.0) + (r2["tasks"].get("drain_s") or 0.0)
        in_compute1 = (r1["tasks"].get("dispatch_s") or 0.0) + (r1["tasks"].get("drain_s") or 0.0)
        serial1_all = serial1 + in_compute1
        serial2_all = serial2 + in_compute2
        limits = dict(
            ideal_2_workers_s=round(ideal, 3),
            excess_s=round(r2["wall_s"] - ideal, 3),
            serial_1_worker_s=round(serial1_all, 3), serial_2_workers_s=round(serial2_all, 3),
            outside_compute_2_s=round(serial2, 3),
            serial_phases_2_workers={k: v for k, v in r2["phases"].items()
                                     if k in TOP_PHASES + ("other",) and k != "compute"},
            dispatch_s=r2["tasks"].get("dispatch_s"), drain_s=r2["tasks"].get("drain_s"),
            connect_s=r2["phases"].get("connect"), part_files_s=r2["phases"].get("part_files"),
            # the same serial work in both runs: the smaller measurement is the less disturbed
            serial_s=round(min(serial1_all, serial2_all), 3),
            amdahl_limit=round(_amdahl(min(serial1_all, serial2_all), r1["tasks"].get("span_s")), 3),
            serial_cost_s=round(serial2_all - serial1_all / 2, 3),
            tail_s=r2["tasks"].get("tail_s"),
            tail_cost_s=None if r2["tasks"].get("tail_s") is None else round(r2["tasks"]["tail_s"] / 2, 3),
            busy_total_1_s=b1, busy_total_2_s=b2,
            busy_ratio=None if not (b1 and b2) else round(b2 / b1, 4),
            slowdown_cost_s=None if not (b1 and b2) else round((b2 - b1) / 2, 3),
            utilization_2=r2["tasks"].get("utilization"),
            driver_cpu_2_s=r2["driver_cpu_s"],
        )
        known = [limits["serial_cost_s"], limits["tail_cost_s"], limits["slowdown_cost_s"]]
        limits["gaps_cost_s"] = round(limits["excess_s"] - sum(x or 0.0 for x in known), 3)
    sens = []
    for size in sorted({r["chunk_points"] for r in runs if r["workers"] == 2},
                       key=lambda s: -1 if s is None else s):
        med, sel = _median_run(runs, 2, size)
        sens.append(dict(chunk_points=size, chunk_points_used=med["chunk_points_used"],
                         n_chunks=med["n_chunks"], wall_s=med["wall_s"],
                         compute_s=med["phases"].get("compute"), tail_s=med["tasks"].get("tail_s"),
                         utilization=med["tasks"].get("utilization"),
                         points_per_s=med["points_per_s"], repeats=[r["wall_s"] for r in sel]))
    sens.sort(key=lambda d: d["chunk_points_used"])
    return scaling, sens, limits


def verdict_text(scaling, limits, sens, mode):
    if not scaling:
        return "No 1- and 2-worker pair was measured: no speed-up to judge."
    s = scaling["speedup"]
    parts = [f"2 workers are {s:.2f}x faster than 1 (efficiency {100 * scaling['efficiency']:.0f} %): "
             + ("the 1.8x target is met." if scaling["meets_target"] else
                f"below the {TARGET_SPEEDUP}x target.")]
    if scaling.get("compute_speedup"):
        parts.append(f"The distributed compute phase alone scales {scaling['compute_speedup']:.2f}x; "
                     f"the serial driver work ({limits['serial_s']:.1f} s) caps the whole sweep at "
                     f"{limits['amdahl_limit']:.2f}x (Amdahl).")
        if scaling["speedup"] > limits["amdahl_limit"] * 1.02:
            parts.append("The measured speed-up exceeds that cap: the runs were disturbed by other load.")
    best = min(sens, key=lambda d: d["wall_s"]) if sens else None
    if best:
        parts.append(f"Fastest chunking on 2 workers: {best['chunk_points_used']} points per chunk "
                     f"({best['n_chunks']} chunks, {best['wall_s']:.1f} s).")
    if mode == "quick":
        parts.append("QUICK run on a reduced grid: start-up, warm-up and serial phases weigh far "
                     "more than on the full Fig. 13 sweep, so these numbers do not judge the target.")
    return " ".join(parts)


def run_benchmark(cfg, out_dir, *, worker_counts=(1, 2), chunk_sizes="auto", repeats=1,
                  mode="full", plot=True, work_dir=None, command=None):
    """Measure cfg's sweep (see the module docstring); write scaling.json and scaling.md (and
    scaling.png when plot) into out_dir. Returns the results dict."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    own_work = work_dir is None
    work_dir = Path(tempfile.mkdtemp(prefix="bench_scaling_")) if own_work else Path(work_dir)
    work_dir.mkdir(parents=True, exist_ok=True)
    load_start = loadavg()
    t_all = time.perf_counter()
    try:
        log(f"bench_scaling ({mode}): {cfg.data['scene']['name']}, {cfg.n_points} points; "
            f"load average {load_start}")
        warm = warm_up(work_dir)
        log(f"  warm-up: kernels {warm['driver_kernels_s']:.1f} s, tiny sweep {warm['tiny_sweep_s']:.1f} s")
        plan = [(k, None, f"w{k}_default") for k in worker_counts]
        if 2 in worker_counts:
            sizes = chunk_sizes_for(cfg, 2) if chunk_sizes == "auto" else list(chunk_sizes)
            plan += [(2, s, f"w2_chunk{s}") for s in sizes]
        runs = []
        for rep in range(repeats):
            for k, size, label in plan:
                r = measure_run(cfg, k, size, work_dir, label, rep)
                runs.append(r)
                log(f"  {label:>14} rep {rep}: wall {r['wall_s']:7.2f} s  {r['points_per_s']:7.1f} pts/s  "
                    f"chunks {r['n_chunks']:4d}  compute {r['phases'].get('compute', float('nan')):7.2f} s  "
                    f"start {r['cluster_start_s']:.1f} s  warm {r['worker_warmup_s']:.1f} s  "
                    f"rss {[round(x / 1024) for x in r['worker_max_rss_kib']]} MiB  load {r['loadavg_after'][0]}")
    finally:
        if own_work:
            shutil.rmtree(work_dir, ignore_errors=True)
    scaling, sens, limits = analyse(runs, worker_counts)
    results = dict(
        benchmark="scaling", mode=mode,
        created=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        git=git_info(), scene=scene_info(cfg), machine=machine_info(),
        load_average=dict(start=load_start, end=loadavg()),
        warmup=warm, runs=runs, scaling=scaling, chunk_sensitivity=sens, limits=limits,
        verdict=verdict_text(scaling, limits, sens, mode),
        command=command or "python -m workflows.bench_scaling" + (" --quick" if mode == "quick" else ""),
        total_s=round(time.perf_counter() - t_all, 1),
    )
    (out_dir / "scaling.json").write_text(json.dumps(results, indent=1) + "\n")
    png = None
    if plot:
        png = write_plot(results, out_dir / "scaling.png")
    (out_dir / "scaling.md").write_text(markdown(results, png))
    log(results["verdict"])
    log(f"wrote {out_dir / 'scaling.md'} ({results['total_s']:.0f} s in all)")
    return results


# --- outputs ------------------------------------------------------------------------------------

def write_plot(results, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    sens = results["chunk_sensitivity"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    ax = axes[0]
    if sens:
        x = [d["chunk_points_used"] for d in sens]
        ax.plot(x, [d["wall_s"] for d in sens], "o-", label="2 workers: sweep wall")
        ax.plot(x, [d["compute_s"] for d in sens], "s--", label="2 workers: compute phase")
    sc = results["scaling"]
    if sc:
        ax.axhline(sc["wall_1_worker_s"], color="k", lw=1, label="1 worker (default chunks)")
        ax.axhline(sc["wall_1_worker_s"] / TARGET_SPEEDUP, color="r", lw=1, ls=":",
                   label=f"target: 1 worker / {TARGET_SPEEDUP}")
    if sens:
        ax.set_xscale("log")
        ax.set_xticks(x)
        ax.set_xticklabels([str(v) for v in x])
        ax.minorticks_off()
    ax.set_xlabel("points per chunk (2 workers)")
    ax.set_ylabel("seconds")
    ax.set_ylim(bottom=0)
    ax.set_title(f"{results['scene']['name']}: {results['scene']['n_points']} points")
    ax.legend(fontsize=8)
    ax = axes[1]
    two = _median_run(results["runs"], 2, None)
    if two:
        r = two[0]
        for w in range(r["workers"]):
            bars = [(t["start"], t["stop"] - t["start"]) for t in r["tasks"].get("timeline", [])
                    if t["worker"] == w]
            ax.broken_barh(bars, (w - 0.35, 0.7), facecolors="tab:blue", edgecolors="white", linewidth=0.5)
        ax.set_yticks(range(r["workers"]))
        ax.set_yticklabels([f"worker {i}" for i in range(r["workers"])])
        ax.set_xlabel("seconds since the first task")
        ax.set_title(f"2 workers, default chunks: {r['n_chunks']} tasks, tail {_f(r['tasks'].get('tail_s'))} s",
                     fontsize=10)
        ax.set_ylim(-0.5, r["workers"] - 0.5)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _mib(kib):
    return f"{kib / 1024:.0f}"


def _f(v, fmt="{:.2f}"):
    return "-" if v is None else fmt.format(v)


def markdown(res, png=None):
    m, sc, lim, scene = res["machine"], res["scaling"], res["limits"], res["scene"]
    r1 = (_median_run(res["runs"], 1, None) or [None])[0]
    r2 = (_median_run(res["runs"], 2, None) or [None])[0]
    quick = res["mode"] == "quick"
    lines = [
        "# Scaling benchmark: the Fig. 13 sweep on a local Dask cluster" + (" (QUICK, reduced grid)" if quick else ""),
        "",
        f"Generated by `{res['command']}` on {res['created']} (git {res['git'].get('commit')}"
        + (", kernels/pipeline modified in the working tree" if res["git"].get("kernels_or_pipeline_modified") else "")
        + f"); {res['total_s']:.0f} s in all. Every number is in `scaling.json`.",
        "",
    ]
    if quick:
        lines += ["**Quick run**: a reduced grid to check the benchmark itself. Cluster start-up, warm-up and",
                  "the serial driver phases weigh far more here than in the full sweep: do not judge the",
                  "speed-up target from it. The final numbers come from `python -m workflows.bench_scaling`.", ""]
    lines += [
        "## Scene and machine",
        "",
        f"- scene `{scene['name']}`: {scene['n_points']} points ({' x '.join(f'{v} {k}' for k, v in scene['axes'].items())}), "
        f"speed {scene['speed_range'][0]:g}-{scene['speed_range'][1]:g} Hz, "
        f"{scene['n_segments']} continuation segments of up to {scene['segment_length']} speeds",
        f"- CPU: {m['cpu']}, {m['cores']} cores ({m['usable_cores']} usable), {m['memory_gib']} GiB memory",
        f"- {m['platform']}, Python {m['python']}, numpy {m['numpy']}, numba {m['numba']}, "
        f"dask {m['dask']}, distributed {m['distributed']}",
        f"- load average (1, 5, 15 min) at start {res['load_average']['start']}, at end {res['load_average']['end']}"
        " (on 2 cores anything above ~0.3 at the start means another process competed for the CPU)",
        f"- warm-up before timing: kernels in the driver {res['warmup']['driver_kernels_s']:.1f} s "
        f"(Numba cache load or compile), tiny 1-worker sweep {res['warmup']['tiny_sweep_s']:.1f} s",
        "",
        "## Runs",
        "",
        "`wall`: `pipeline.run` from call to written cube (cluster already started and warmed). Phases: "
        "`compute` = scatter + chunk tasks + part files, `bound.` = boundary table refinement "
        "(driver, serial), `asm+wr` = cube assembly and write. Tail: time the first worker to finish "
        "waits for the last. Util.: worker busy time / (workers x compute phase). RSS: max resident "
        "set size (peak) per worker process after the sweep, and of the driver process (a high-water "
        "mark over the whole benchmark).",
        "",
        "| run | workers | pts/chunk | chunks | start [s] | warm [s] | wall [s] | pts/s | compute [s] | bound. [s] | asm+wr [s] | tail [s] | util. | worker RSS [MiB] | driver RSS [MiB] | load after |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in res["runs"]:
        ph, t = r["phases"], r["tasks"]
        lines.append(
            f"| {r['label']}{' #' + str(r['repeat']) if r['repeat'] else ''} | {r['workers']} | "
            f"{r['chunk_points_used']}{' (default)' if r['chunk_points'] is None else ''} | {r['n_chunks']} | "
            f"{r['cluster_start_s']:.1f} | {r['worker_warmup_s']:.1f} | **{r['wall_s']:.2f}** | {r['points_per_s']:.0f} | "
            f"{_f(ph.get('compute'))} | {_f(ph.get('boundaries'))} | "
            f"{_f((ph.get('assemble') or 0) + (ph.get('write') or 0))} | {_f(t.get('tail_s'))} | "
            f"{_f(t.get('utilization'), '{:.0%}')} | {' / '.join(_mib(x) for x in r['worker_max_rss_kib'])} | "
            f"{_mib(r['driver_max_rss_kib'])} | {r['loadavg_after'][0]} |")
    lines += [""]
    if sc:
        lines += [
            "## Speed-up (default chunking)",
            "",
            "| | 1 worker | 2 workers | ratio |",
            "| --- | ---: | ---: | ---: |",
            f"| sweep wall [s] | {sc['wall_1_worker_s']:.2f} | {sc['wall_2_workers_s']:.2f} | **{sc['speedup']:.2f}x** (efficiency {sc['efficiency']:.0%}) |",
            f"| points per second | {sc['points_per_s_1']:.0f} | {sc['points_per_s_2']:.0f} | |",
            f"| compute phase (scatter, tasks, part files) [s] | {_f(r1['phases'].get('compute'))} | "
            f"{_f(r2['phases'].get('compute'))} | {_f(sc.get('compute_speedup'))}x |",
            f"| task span (first task start to last task end) [s] | {_f(r1['tasks'].get('span_s'))} | "
            f"{_f(r2['tasks'].get('span_s'))} | {_f(sc.get('span_speedup'))}x |",
            f"| serial: outside the compute phase + before the first / after the last task [s] | "
            f"{_f(lim.get('serial_1_worker_s'))} | {_f(lim.get('serial_2_workers_s'))} | |",
            f"| worker busy time, all workers [s] | {_f(lim.get('busy_total_1_s'))} | {_f(lim.get('busy_total_2_s'))} | {_f(lim.get('busy_ratio'), '{:.3f}')} |",
            "",
            f"Target: 2 workers >= {TARGET_SPEEDUP}x faster than 1 -> "
            + ("**met**." if sc["meets_target"] else "**not met**."),
            "",
            "## What limits the speed-up",
            "",
            f"The ideal 2-worker wall time is half the 1-worker one, {lim['ideal_2_workers_s']:.2f} s; the "
            f"measured one is {lim['excess_s']:+.2f} s off it. Approximate budget of that difference:",
            "",
            "| cause | cost [s] | measured as |",
            "| --- | ---: | --- |",
            f"| serial driver work | {lim['serial_cost_s']:.2f} | {lim['serial_2_workers_s']:.2f} s of the "
            f"2-worker run is not divided by the workers: "
            + ", ".join(f"{k} {v:.2f}" for k, v in lim["serial_phases_2_workers"].items())
            + f" s outside the compute phase, plus {_f(lim.get('dispatch_s'))} s from its start to the first "
            f"task (client connection {_f(lim.get('connect_s'))} s, scatter, submit) and "
            f"{_f(lim.get('drain_s'))} s after the last task (last part file, client close) |",
            f"| load imbalance (tail) | {_f(lim.get('tail_cost_s'))} | one worker idles {_f(lim.get('tail_s'))} s "
            "at the end, waiting for the other's last chunk (half of it counts against the ideal) |",
            f"| slower points with both cores busy | {_f(lim.get('slowdown_cost_s'))} | summed worker busy time "
            f"{_f(lim.get('busy_total_2_s'), '{:.1f}')} s vs {_f(lim.get('busy_total_1_s'), '{:.1f}')} s with 1 "
            f"worker (x{_f(lim.get('busy_ratio'), '{:.3f}')}): the driver (results, part files: "
            f"{_f(lim.get('part_files_s'))} s writing them, {lim['driver_cpu_2_s']:.1f} CPU s in all), nannies and "
            "scheduler share the 2 cores; shared caches, clock boost |",
            f"| gaps between tasks, rest | {_f(lim.get('gaps_cost_s'))} | the remainder: scheduler round trips, "
            "result transfer, idle time between chunks |",
            "",
            f"The serial work alone ({_f(lim.get('serial_s'))} s, the smaller of the two runs' "
            f"measurements) caps the speed-up at {lim['amdahl_limit']:.2f}x (Amdahl: (S + P) / (S + P / 2), "
            "P the 1-worker task span). Utilization of the 2 workers over the compute phase: "
            f"{_f(lim.get('utilization_2'), '{:.0%}')}.",
            "",
        ]
        if sc["speedup"] > lim["amdahl_limit"] * 1.02:
            lines += [f"**Inconsistent**: the measured speed-up exceeds that cap, i.e. the runs were "
                      f"disturbed (the serial time was {lim['serial_1_worker_s']:.2f} s in the 1-worker "
                      f"run and {lim['serial_2_workers_s']:.2f} s in the 2-worker one for the same work). "
                      "Repeat on a quiet machine (`--repeats 3`).", ""]
    sens = res["chunk_sensitivity"]
    if sens:
        lines += ["## Chunk size (2 workers)", "",
                  "| points per chunk | chunks | wall [s] | compute [s] | tail [s] | util. | pts/s |",
                  "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
        for d in sens:
            lines.append(f"| {d['chunk_points_used']}{' (default)' if d['chunk_points'] is None else ''} | "
                         f"{d['n_chunks']} | {d['wall_s']:.2f} | {_f(d['compute_s'])} | {_f(d['tail_s'])} | "
                         f"{_f(d['utilization'], '{:.0%}')} | {d['points_per_s']:.0f} |")
        lines += ["", "Small chunks pay the per-task costs (a scheduler round trip, a result message and a "
                  "part file written by the driver) once per chunk; one chunk per worker leaves the whole "
                  "cost difference between the two halves of the grid as tail. The pipeline's default "
                  "(about 32 chunks per worker, at least 64 points each) sits between.", ""]
    if png:
        lines += [f"![wall time against chunk size and the 2-worker task timeline]({Path(png).name})", ""]
    lines += ["## Verdict", "", res["verdict"], "",
              "## Method", "",
              "Each run starts a fresh `distributed.LocalCluster(n_workers=k, threads_per_worker=1, "
              "processes=True, host=\"127.0.0.1\", dashboard_address=None)` with NUMBA_NUM_THREADS=1, "
              "warms its workers (each imports the kernels and solves one point: Numba's on-disk cache "
              "is loaded, nothing compiles), then calls `pipeline.run(cfg, out, "
              "scheduler=cluster.scheduler_address, chunk_points=..., overwrite=True)`. Phases are "
              "timed by wrapping the pipeline's functions in the benchmark process; task times come "
              "from `distributed.get_task_stream`; memory from `client.run(getrusage(RUSAGE_SELF)."
              "ru_maxrss)` on every worker after the sweep. Runs are single measurements unless "
              "`--repeats` is given (then the median run is reported and all walls are in the JSON). "
              "A busy machine (load average well above 0 at the start) inflates every number, and "
              "the 2-worker runs most.", ""]
    return "\n".join(lines)


# --- command line -------------------------------------------------------------------------------

def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m workflows.bench_scaling", description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="reduced grid (Fig. 13 scene, 2 Hz speed step, 2 clearances) -> build/bench_scaling_quick/")
    ap.add_argument("--out", type=Path, default=None, help="output directory (default: docs/benchmarks "
                    "or build/bench_scaling_quick with --quick)")
    ap.add_argument("--repeats", type=int, default=1, help="timed repeats of every run (median reported)")
    ap.add_argument("--workers", default="1,2", help="worker counts with default chunking (default 1,2)")
    ap.add_argument("--chunks", default="auto",
                    help="comma-separated chunk sizes [points] for 2 workers, or 'auto' (default): one "
                         "segment per chunk, 8 segments, the default and one chunk per worker")
    ap.add_argument("--no-plot", action="store_true")
    args = ap.parse_args(argv)
    cfg = quick_config() if args.quick else full_config()
    out = args.out or (QUICK_OUT if args.quick else DOCS)
    workers = tuple(int(x) for x in args.workers.split(","))
    chunks = "auto" if args.chunks == "auto" else [int(x) for x in args.chunks.split(",")]
    command = "python -m workflows.bench_scaling " + " ".join(sys.argv[1:] if argv is None else argv)
    run_benchmark(cfg, out, worker_counts=workers, chunk_sizes=chunks, repeats=args.repeats,
                  mode="quick" if args.quick else "full", plot=not args.no_plot, command=command.strip())
    return 0


if __name__ == "__main__":
    sys.exit(main())

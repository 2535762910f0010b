"""Scaling benchmark of a distributed sweep: the Bai 2006 Fig. 13 grid on a local Dask cluster.

    python -m workflows.bench.scaling                # full: Fig. 13, 12005 points (about 7 min
                                                     #   on 2 quiet cores) -> docs/benchmarks/scaling.*
    python -m workflows.bench.scaling --quick        # reduced grid, 242 points (about 1 min)
                                                     #   -> build/bench_scaling_quick/
    python -m workflows.bench.scaling --render-only  # scaling.md and .png again from scaling.json

Writes scaling.json (every measured number), scaling.md (templates/scaling.md filled from it:
machine, tables, what limits the speed-up, verdict against the target) and scaling.png (wall
time against chunk size and the task timeline of the two-worker run).

What is measured, every run through the public API `rotorsweep.pipeline.run(cfg, output,
scheduler=<the cluster>, chunk_points=..., overwrite=True)` on a fresh local cluster of k
single-threaded worker processes, the one `rotorsweep run` starts (`rotorsweep.pipeline.cluster.local_cluster`,
with its relaxed housekeeping settings; `scaling_runs`):

* wall time of the sweep (`rotorsweep.pipeline.run`, from the call to the written cube), separately from
  the cluster start-up and from the workers' warm-up (import + loading Numba's on-disk cache:
  paid once per worker process, in parallel, by every real run too);
* its phases, timed by wrapping the pipeline's own functions (nothing in pipeline/ changes):
  driver warm-up, the distributed compute phase (scatter, tasks, part files), cube assembly,
  what is left of the boundary table after it (each chunk task refines the stability changes
  between its own points; one between two chunks gets a task of its own as soon as both are
  computed, ahead of the queued chunks), cube write;
* from Dask's task stream: busy time per worker, the span of the compute phase, its tail (how
  long the first worker to finish waits for the last), and worker utilization;
* points per second, the sum of the per-point compute times stored in the cube;
* peak memory: peak RSS (VmHWM, KiB) of each worker process after the sweep and of
  the driver process (a high-water mark over the whole benchmark, as the driver runs them all);
* CPU seconds of the driver and the workers during the sweep, load average before and after;
  from them the speed-up in CPU time, which other load on a shared machine does not inflate;
* what a task carries: pickled size and (de)serialization time of the median chunk's arguments,
  its result's size;
* tasks per second through a scheduler started with the distributed CLI on 127.0.0.1
  (workflows.bench.scheduler_throughput) and the cluster size at which it would saturate.

Runs: 1 worker and 2 workers with the pipeline's default chunking (speed-up, efficiency; target:
2 workers >= 1.85x faster than 1), then 2 workers with other chunk sizes, from one continuation
segment per chunk to one chunk per worker (`scaling_analysis`). Numba compilation is excluded: a
tiny warm-up sweep fills the on-disk cache and imports everything in the driver before any timed run.
"""
import argparse
import datetime
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from workflows.bench.common import DOCS, ROOT, add_render_options, log, loadavg, machine_info
from workflows.bench import scaling_ceiling
from workflows.bench.scaling_analysis import analyse, verdict_text
from workflows.bench.scaling_md import markdown
from workflows.bench.scaling_plots import write_plot
from workflows.bench.scaling_runs import measure_run, warm_up
from workflows.bench.scaling_scene import chunk_sizes_for, full_config, quick_config, scene_info

QUICK_OUT = ROOT / "build" / "bench_scaling_quick"
RUN_KEYS = ("label", "workers", "chunk_points", "chunk_points_used", "n_chunks", "repeat",
            "cluster_start_s", "worker_warmup_s", "wall_s", "points_per_s", "phases", "tasks",
            "point_compute_s", "n_not_converged", "worker_max_rss_kib", "worker_rss_before_kib", "driver_max_rss_kib",
            "driver_cpu_s", "worker_cpu_s", "steal_s", "loadavg_before", "loadavg_after")
RESULT_KEYS = ("benchmark", "mode", "created", "git", "scene", "machine", "load_average",
               "warmup", "runs", "scaling", "ceiling", "chunk_sensitivity", "limits", "task_costs", "scheduler",
               "verdict", "command")


def scaling_machine_info():
    """machine_info plus the memory and the Dask versions."""
    import dask
    import distributed

    mem_kib = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                mem_kib = int(line.split()[1])
    except (OSError, ValueError, IndexError):
        pass
    return dict(machine_info(), memory_gib=None if mem_kib is None else round(mem_kib / 2 ** 20, 1),
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


def _measure_runs(cfg, work_dir, worker_counts, chunk_sizes, repeats):
    """Every planned run, `repeats` times: default chunking per worker count, then chunk sizes on 2."""
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
    return runs


def task_costs(cfg, n_workers=2):
    """What one task of the default plan carries and costs to (de)serialize in the driver: the
    pickled arguments (config + the chunk's segment ids) and result of the median chunk, the result
    measured on one segment solved here and scaled by points."""
    import pickle
    import statistics

    from rotorsweep.pipeline import sweep

    chunks = sweep.chunks_for(cfg.scene, sweep.segments(cfg.scene), n_workers)
    chunk = sorted(chunks, key=lambda c: sum(len(s) for s in c))[len(chunks) // 2]
    n = sum(len(s) for s in chunk)
    t0 = time.perf_counter()
    args = pickle.dumps((cfg.scene, tuple(s.id for s in chunk)), protocol=5)
    dumps_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    pickle.loads(args)
    loads_s = time.perf_counter() - t0
    one = sweep.compute_chunk(cfg.scene, chunk[:1])
    result_per_point = len(pickle.dumps(one, protocol=5)) / len(chunk[0])
    sizes = [sum(len(s) for s in c) for c in chunks]
    return dict(n_chunks=len(chunks), chunk_points_first=sizes[0], chunk_points_median=int(statistics.median(sizes)),
                chunk_points_last=sizes[-1], median_chunk_points=n, args_bytes=len(args),
                args_dumps_ms=round(1e3 * dumps_s, 3), args_loads_ms=round(1e3 * loads_s, 3),
                result_bytes=round(result_per_point * n))


def scheduler_section(runs, n_tasks):
    """Tasks per second through a CLI-started scheduler (scheduler_throughput) and the cluster
    size at which it saturates for the mean chunk of the 2-worker default run."""
    from workflows.bench import scheduler_throughput

    rates = scheduler_throughput.measure(n_tasks=n_tasks)
    two = [r for r in runs if r["workers"] == 2 and r["chunk_points"] is None and r["tasks"].get("n_tasks")]
    chunk_s = (statistics.median(r["tasks"].get("chunk_busy_s", r["tasks"]["busy_total_s"]) / r["tasks"]["n_tasks"] for r in two)
               if two else None)
    best = max(v["batch_tasks_per_s"] for v in rates.values())
    return dict(by_workers={str(k): v for k, v in rates.items()}, chunk_compute_s=chunk_s,
                saturation_workers=None if chunk_s is None else round(scheduler_throughput.saturation(best, chunk_s)))


def run_benchmark(cfg, out_dir, *, worker_counts=(1, 2), chunk_sizes="auto", repeats=1,
                  mode="full", plot=True, work_dir=None, command=None, scheduler_tasks=2000):
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
        log(f"bench scaling ({mode}): {cfg.data['scene']['name']}, {cfg.n_points} points; "
            f"load average {load_start}")
        warm = warm_up(work_dir)
        log(f"  warm-up: kernels {warm['driver_kernels_s']:.1f} s, tiny sweep {warm['tiny_sweep_s']:.1f} s")
        runs = _measure_runs(cfg, work_dir, worker_counts, chunk_sizes, repeats)
        ceiling = scaling_ceiling.measure(cfg, repeats=max(3, repeats))
        log(f"  without Dask: 1 process {ceiling['wall_1_s']:.2f} s, 2 processes {ceiling['wall_2_s']:.2f} s "
            f"({ceiling['speedup']:.2f}x)")
        costs = task_costs(cfg)
        sched = scheduler_section(runs, scheduler_tasks)
    finally:
        if own_work:
            shutil.rmtree(work_dir, ignore_errors=True)
    scaling, sens, limits = analyse(runs, worker_counts)
    results = dict(
        benchmark="scaling", mode=mode,
        created=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        git=git_info(), scene=scene_info(cfg), machine=scaling_machine_info(),
        load_average=dict(start=load_start, end=loadavg()),
        warmup=warm, runs=runs, scaling=scaling, ceiling=ceiling, chunk_sensitivity=sens, limits=limits,
        task_costs=costs, scheduler=sched,
        verdict=verdict_text(scaling, limits, sens, mode, ceiling),
        command=command or "python -m workflows.bench.scaling" + (" --quick" if mode == "quick" else ""),
        total_s=round(time.perf_counter() - t_all, 1),
    )
    (out_dir / "scaling.json").write_text(json.dumps(results, indent=1) + "\n")
    render(results, out_dir, plot)
    log(results["verdict"])
    log(f"wrote {out_dir / 'scaling.md'} ({results['total_s']:.0f} s in all)")
    return results


def render(results, out_dir, plot=True):
    """scaling.md (and scaling.png when plot and matplotlib is there) in out_dir."""
    png = write_plot(results, Path(out_dir) / "scaling.png") if plot else None
    (Path(out_dir) / "scaling.md").write_text(markdown(results, png))


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m workflows.bench.scaling", description=__doc__.split("\n\n")[0])
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
    add_render_options(ap, "scaling.md (and .png)", "scaling.json", QUICK_OUT)
    args = ap.parse_args(argv)
    default_dir = QUICK_OUT if args.quick else DOCS
    out = args.out or default_dir
    if args.render_only:
        out.mkdir(parents=True, exist_ok=True)
        render(json.loads(((args.data or default_dir) / "scaling.json").read_text()), out, not args.no_plot)
        log(f"wrote {out / 'scaling.md'}")
        return 0
    cfg = quick_config() if args.quick else full_config()
    workers = tuple(int(x) for x in args.workers.split(","))
    chunks = "auto" if args.chunks == "auto" else [int(x) for x in args.chunks.split(",")]
    command = "python -m workflows.bench.scaling " + " ".join(sys.argv[1:] if argv is None else argv)
    run_benchmark(cfg, out, worker_counts=workers, chunk_sizes=chunks, repeats=args.repeats,
                  mode="quick" if args.quick else "full", plot=not args.no_plot, command=command.strip())
    return 0


if __name__ == "__main__":
    sys.exit(main())

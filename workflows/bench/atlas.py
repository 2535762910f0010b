"""The 4-D atlas benchmark: configs/atlas4d_fig13.toml (2401 speeds x 5 clearances x 8 contact
angles x 8 preloads = 768,320 points, orbits + Floquet multipliers) on a local 2-worker cluster.

    python -m workflows.bench.atlas                      # the full atlas (~5 min on 2 quiet
                                                         #   cores, 10.5 min under load) -> docs/benchmarks/atlas.*
    python -m workflows.bench.atlas --clearances 1 --angles 2 --preloads 3 --out build/bench_atlas
                                                         # a reduced grid (every speed, n values of
                                                         #   each other axis, spread evenly), with
                                                         #   the full atlas extrapolated from it

Measured through the public `rotorsweep.pipeline.run` (phases timed by wrapping the pipeline's functions,
as workflows.bench.scaling does): wall time per phase, points per second, part-file bytes, cube
size and write time, read times of one speed line, one (contact angle, preload) slice and the
whole cube, the report's time on the cube (PNGs in a second process, and all in one), peak
memory (driver and workers), CPU seconds and the load average. atlas.md is templates/atlas.md
filled from atlas.json.
"""
import argparse
import datetime
import json
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

from workflows.bench.common import DOCS, ROOT, log, loadavg, peak_rss_kib
from workflows.bench.render import fill, table
from workflows.bench.scaling import git_info, scaling_machine_info
from workflows.bench.scaling_runs import phase_timers, start_cluster, task_summary

CONFIG = ROOT / "configs" / "atlas4d_fig13.toml"
FULL = {"clearance": 5, "contact_angle": 8, "preload": 8}


def atlas_config(counts=None):
    """The atlas scene, each of clearance / contact_angle / preload cut to `counts[axis]` of its
    values spread evenly from the first to the last (None: the full atlas), by editing the TOML."""
    import numpy as np

    from rotorsweep.pipeline import config

    text = CONFIG.read_text()
    for axis, n in (counts or {}).items():
        line = re.search(rf"(?m)^{axis}\s*=\s*\[(.*?)\]", text)
        values = [v.strip() for v in line.group(1).split(",")]
        values = [values[i] for i in sorted(set(np.linspace(0, len(values) - 1, n).round().astype(int)))]
        text = text.replace(line.group(0), f"{axis} = [{', '.join(values)}]")
    return config.parse_config(text, path=CONFIG.name, allow_large=True)


def _worker_stats():
    def stats():
        import resource as r
        u = r.getrusage(r.RUSAGE_SELF)
        return peak_rss_kib(), u.ru_utime + u.ru_stime
    return stats


def run_atlas(cfg, work_dir, n_workers=2):
    """One timed sweep of cfg into work_dir/atlas.nc; the run's record (the cube is kept)."""
    import rotorsweep.pipeline as pipeline
    from distributed import get_task_stream

    from rotorsweep.pipeline import cube

    part_bytes = []
    write_part = cube.write_part

    def counting(*args, **kwargs):
        path = write_part(*args, **kwargs)
        part_bytes.append(os.path.getsize(path))
        return path

    stats = _worker_stats()
    before = loadavg()
    cluster, client = start_cluster(n_workers)
    try:
        cpu0 = dict(client.run(stats))
        out = Path(work_dir) / "atlas.nc"
        driver_cpu = time.process_time()
        cube.write_part = counting
        with phase_timers() as phases, get_task_stream(client) as stream:
            t0 = time.perf_counter()
            pipeline.run(cfg, str(out), scheduler=cluster, overwrite=True, progress=False)
            wall = time.perf_counter() - t0
        cube.write_part = write_part
        driver_cpu = time.process_time() - driver_cpu
        after = client.run(stats)
        records = list(stream.data)
    finally:
        cube.write_part = write_part
        client.close()
        cluster.close()
    epoch = phases.pop("compute_epoch", None)
    tasks = task_summary(records, n_workers, epoch, phases.get("compute"))
    tasks.pop("timeline", None)
    return dict(points=cfg.n_points, lines=cfg.n_points // len(cfg.axes["speed"]), wall_s=round(wall, 2),
                points_per_s=round(cfg.n_points / wall, 1), phases={k: round(v, 3) for k, v in phases.items()},
                tasks=tasks, part_files=len(part_bytes), part_bytes=sum(part_bytes),
                cube_bytes=out.stat().st_size, driver_cpu_s=round(driver_cpu, 2),
                worker_cpu_s=[round(after[w][1] - cpu0[w][1], 2) for w in after],
                worker_max_rss_kib=[after[w][0] for w in after], driver_max_rss_kib=peak_rss_kib(),
                loadavg_before=before, loadavg_after=loadavg(), cube=str(out))


def read_times(path):
    """Seconds to read one speed line (every variable), one (contact angle, preload) slice at
    one speed and clearance, and the whole cube."""
    import xarray as xr

    def timed(fn):
        t0 = time.perf_counter()
        with xr.open_dataset(path, engine="netcdf4") as ds:
            fn(ds)
        return round(time.perf_counter() - t0, 4)
    mid = {"clearance": 0, "contact_angle": 0, "preload": 0}
    return dict(speed_line_s=timed(lambda ds: ds.isel(mid).load()),
                angle_preload_slice_s=timed(lambda ds: ds.isel(speed=ds.sizes["speed"] // 2, clearance=0).load()),
                whole_cube_s=timed(lambda ds: ds.load()))


def full_size_io(path, work_dir):
    """Write and read times of a cube of the full atlas's size made from a reduced run's cube:
    its lines repeated over the full clearance x contact angle x preload grid, every float
    scaled by 1 + 1e-6 N(0, 1) so that no two lines are bitwise equal (neighbouring lines of a
    real atlas differ in their low bits too; exact copies would compress away). Written by
    rotorsweep.pipeline.cube.write_cube (the pipeline's encoding); read as read_times does."""
    import numpy as np
    import xarray as xr

    from rotorsweep.pipeline import cube

    small = cube.open_cube(path)
    small = small.drop_dims("boundary") if "boundary" in small.dims else small
    axes = atlas_config().axes
    rng = np.random.default_rng(0)
    data = {}
    for name, var in small.data_vars.items():
        reps = [-(-len(axes[a]) // small.sizes[a]) if a in axes and a != "speed" else 1 for a in var.dims]
        cut = tuple(slice(0, len(axes[a])) if a in axes else slice(None) for a in var.dims)
        values = np.tile(var.values, reps)[cut]
        if values.dtype.kind == "f":
            values = values * (1 + 1e-6 * rng.standard_normal(values.shape))
        data[name] = (var.dims, values, var.attrs)
    big = xr.Dataset(data, coords={**{a: axes[a] for a in small.dims if a in axes},
                                   **{d: small[d].values for d in small.dims if d not in axes}}, attrs=small.attrs)
    out = Path(work_dir) / "full_size.nc"
    t0, c0 = time.perf_counter(), time.process_time()
    cube.write_cube(big, out, overwrite=True)
    write = dict(write_s=round(time.perf_counter() - t0, 2), write_cpu_s=round(time.process_time() - c0, 2),
                 bytes=out.stat().st_size, points=int(np.prod([len(axes[a]) for a in axes])))
    return {**write, **read_times(out)}


def report_time(path, out_dir, parallel):
    """Seconds of make_report on the cube (parallel: the PNGs in a second process, the default on
    2 cores) and the PNGs' names."""
    from rotorsweep.pipeline import cube
    from rotorsweep.pipeline.report import make_report

    t0 = time.perf_counter()
    res = make_report(cube.open_cube(path), out_dir, parallel=parallel)
    return round(time.perf_counter() - t0, 2), [p.name for p in res["png"]]


def extrapolate(run):
    """The full atlas from a reduced run: per-point and per-line costs times the full counts
    (its write and read times are measured instead by full_size_io)."""
    full_points = 2401 * 5 * 8 * 8
    scale = full_points / run["points"]
    ph = run["phases"]
    lines = 5 * 8 * 8
    return dict(points=full_points, compute_s=round(ph.get("compute", 0) * scale, 1),
                boundaries_s=round(ph.get("boundaries", 0) * lines / run["lines"], 1),
                assemble_s=round(ph.get("assemble", 0) * scale, 1), wall_s=round(run["wall_s"] * scale, 1),
                cube_mb=round(run["cube_bytes"] * scale / 1e6, 1), part_mb=round(run["part_bytes"] * scale / 1e6, 1),
                # what the workers' CPU time (compute and boundary tasks) makes of it with a core each
                quiet_wall_s=round(sum(run["worker_cpu_s"]) * scale / len(run["worker_cpu_s"])
                                   + (ph.get("assemble", 0) + ph.get("write", 0)) * scale, 1))


def markdown(res):
    run, reads = res["run"], res["reads"]
    ph = run["phases"]
    rows = [(k, f"{ph[k]:.2f}") for k in ("connect", "driver_warmup", "compute", "assemble", "boundaries", "write")
            if k in ph] + [("part files (in compute)", f"{ph.get('part_files', 0):.2f}"), ("**run**", f"**{run['wall_s']:.1f}**")]
    ext = res.get("extrapolated")
    ext_text = "" if not ext else table(
        ("full atlas (extrapolated)", "value"),
        [("points", ext["points"]), ("wall [s], at this run's load", ext["wall_s"]),
         ("wall [s] on 2 cores of its own (worker CPU s / 2 + assemble + write)", ext["quiet_wall_s"]),
         ("compute [s]", ext["compute_s"]),
         ("boundary table after the compute phase [s]", ext["boundaries_s"]), ("assemble [s]", ext["assemble_s"]),
         ("cube [MB]", ext["cube_mb"]), ("part files [MB]", ext["part_mb"])])
    io = res.get("full_size_io")
    io_text = "" if not io else table(
        ("cube of the full atlas's size (768,320 points, from this run's lines)", "value"),
        [("size [MB]", f"{io['bytes'] / 1e6:.1f} ({io['bytes'] / io['points']:.0f} bytes per point)"),
         ("write [s] (CPU s)", f"{io['write_s']:.2f} ({io['write_cpu_s']:.2f})"),
         ("read one speed line, every variable [ms]", f"{1e3 * io['speed_line_s']:.0f}"),
         ("read one (contact angle x preload) slice [ms]", f"{1e3 * io['angle_preload_slice_s']:.0f}"),
         ("read the whole cube [s]", f"{io['whole_cube_s']:.2f}")])
    return fill("atlas", command=res["command"], created=res["created"], commit=res["git"]["commit"],
                grid=" x ".join(f"{n} {a}" for a, n in res["axes"].items()), points=run["points"], lines=run["lines"],
                mode=res["mode"], cpu=res["machine"]["cpu"], cores=res["machine"]["cores"],
                versions=f"Python {res['machine']['python']}, numpy {res['machine']['numpy']}, numba "
                         f"{res['machine']['numba']}, dask {res['machine']['dask']}",
                load_before=run["loadavg_before"], load_after=run["loadavg_after"],
                phases=table(("phase", "wall [s]"), rows), pps=f"{run['points_per_s']:.0f}",
                cube_mb=f"{run['cube_bytes'] / 1e6:.1f}", cube_bpp=f"{run['cube_bytes'] / run['points']:.0f}",
                part_mb=f"{run['part_bytes'] / 1e6:.1f}", n_parts=run["part_files"],
                write_s=f"{ph.get('write', 0):.2f}", line_s=f"{1e3 * reads['speed_line_s']:.0f}",
                slice_s=f"{1e3 * reads['angle_preload_slice_s']:.0f}", whole_s=f"{reads['whole_cube_s']:.2f}",
                report_s=res["report_s"], report_serial_s=res.get("report_serial_s", "(not measured)"),
                driver_rss=f"{run['driver_max_rss_kib'] / 1024:.0f}",
                worker_rss=" / ".join(f"{k / 1024:.0f}" for k in run["worker_max_rss_kib"]),
                driver_cpu=run["driver_cpu_s"], worker_cpu=" / ".join(map(str, run["worker_cpu_s"])),
                utilization=f"{100 * (run['tasks'].get('utilization') or 0):.0f}",
                tail=run["tasks"].get("tail_s"), n_tasks=run["tasks"].get("n_tasks"),
                extrapolated=ext_text, full_size_io=io_text, verdict=res["verdict"])


def verdict(res):
    ext, run = res.get("extrapolated"), res["run"]
    load = f"load {run['loadavg_before'][0]}-{run['loadavg_after'][0]} on {res['machine']['cores']} cores"
    if not ext:
        return (f"Full atlas measured: {run['wall_s']:.0f} s against the 900 s (15 min) target: "
                f"{'met' if run['wall_s'] <= 900 else 'not met'} ({load}).")
    return (f"Full atlas extrapolated from this reduced grid: {ext['wall_s']:.0f} s at this run's {load}, "
            f"{ext['quiet_wall_s']:.0f} s from the workers' CPU time on 2 cores of their own; target 900 s "
            f"(15 min): {'met' if ext['quiet_wall_s'] <= 900 else 'not met'} by the CPU-time estimate, "
            f"{'met' if ext['wall_s'] <= 900 else 'not met'} at this load. `make bench-atlas` runs the full grid.")


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m workflows.bench.atlas", description=__doc__.split("\n\n")[0])
    for axis, flag in (("clearance", "--clearances"), ("contact_angle", "--angles"), ("preload", "--preloads")):
        ap.add_argument(flag, dest=axis, type=int, default=FULL[axis], help=f"n values of {axis}, spread evenly")
    ap.add_argument("--out", type=Path, default=DOCS)
    ap.add_argument("--work", type=Path, default=None, help="where the cube goes (default: a temp dir, removed)")
    args = ap.parse_args(argv)
    counts = {a: getattr(args, a) for a in FULL}
    cfg = atlas_config(counts)
    work = args.work or Path(tempfile.mkdtemp(prefix="bench_atlas_"))
    work.mkdir(parents=True, exist_ok=True)
    try:
        log(f"bench atlas: {cfg.n_points} points; load {loadavg()}")
        run = run_atlas(cfg, work)
        log(f"  run {run['wall_s']} s, {run['points_per_s']} pts/s, phases {run['phases']}")
        reads = read_times(run["cube"])
        report_s, pngs = report_time(run["cube"], work / "report", parallel=True)
        report_serial_s, _ = report_time(run["cube"], work / "report_serial", parallel=False)
        log(f"  reads {reads}; report {report_s} s (in one process {report_serial_s} s)")
        full_io = full_size_io(run["cube"], work) if counts != FULL else None
        log(f"  full-size cube I/O {full_io}")
    finally:
        if args.work is None:
            shutil.rmtree(work, ignore_errors=True)
    reduced = counts != FULL
    res = dict(benchmark="atlas", mode="reduced" if reduced else "full",
               created=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
               git=git_info(), machine=scaling_machine_info(), axes={k: len(v) for k, v in cfg.axes.items()},
               run=run, reads=reads, report_s=report_s, report_serial_s=report_serial_s, report_figures=pngs, full_size_io=full_io,
               extrapolated=extrapolate(run) if reduced else None,
               command="python -m workflows.bench.atlas " + " ".join(sys.argv[1:] if argv is None else argv))
    res["verdict"] = verdict(res)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "atlas.json").write_text(json.dumps(res, indent=1) + "\n")
    (args.out / "atlas.md").write_text(markdown(res))
    log(res["verdict"])
    return 0


if __name__ == "__main__":
    sys.exit(main())

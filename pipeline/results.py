"""What `rotorsweep continue` and `rotorsweep backbone` share: writing their result files (netCDF
with a `result_kind` attribute, see pipeline.result_kinds) and running a task per line of the
swept axes on a Dask cluster or, for small work, in this process (pipeline.cluster), the
scene's kernels compiled first in the driver."""
import contextlib
import os

from pipeline import cluster, compute, cube, fileio, warmup, workload


def write(ds, path):
    """Atomic netCDF write: compressed numbers, integers without a fill value (so a plain
    xarray.open_dataset keeps the flags integer; padding has its own flag value), text as UTF-8
    character arrays, which every netCDF reader and the CF checker know (netCDF-4 variable-length
    strings are valid CF-1.8 but cfchecker 4.1 rejects them, and HDF5 filters skip them)."""
    enc = {name: {"_FillValue": None, **_text(var)} for name, var in ds.coords.items()}
    for name, var in ds.data_vars.items():
        if var.dtype.kind in "OU":
            enc[name] = _text(var)
        else:
            enc[name] = {**cube.COMPRESSION, **({"_FillValue": None} if var.dtype.kind in "iu" else {})}
    with fileio.atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4", encoding=enc)
    return path


def _text(var):
    return {"dtype": "S1"} if var.dtype.kind in "OU" else {}


@contextlib.contextmanager
def result_output(cfg, output, overwrite, scheduler):
    """The absolute output path, locked for the run (refused if it exists without `overwrite`;
    the scheduler checked first)."""
    output = os.path.abspath(output)
    if os.path.exists(output) and not overwrite:
        raise cube.CubeError(f"{output} exists; pass --overwrite (overwrite=True from Python) to replace it")
    with fileio.output_lock(output, cfg.path or "<default scene>"):
        if scheduler:
            cluster.check_scheduler(scheduler)
        yield output


def run_lines(cfg, task, lines, workers, scheduler, stream, summary, unit="continuation_line"):
    """task(cfg.data, where) for every line {axis: value}, after compiling the scene's kernels in
    the driver (workers load them from the cache): in this process when the lines' estimated
    work (pipeline.workload, `unit`) is small or workers == 0, else as Dask tasks; a progress
    line per line done (`summary(result)`); the results in line order."""
    model = compute.model_of(cfg.data).name
    in_process = cluster.runs_in_process(workers, scheduler, workload.estimate(unit, model, len(lines)), len(lines))
    executor = cluster.executor(0 if in_process else workers, scheduler)
    try:
        with cluster.heap_frozen():     # the imports' and the cluster's objects (see cluster.heap_frozen)
            warmup.compile_scene(cfg.data, lambda text: say(stream, text))
            with workload.Meter() as meter:
                results = _run_tasks(executor, cfg, task, lines, stream, summary)
    finally:
        executor.close()
    if in_process:
        workload.record(unit, model, len(lines), meter.seconds)
    return results


def _run_tasks(executor, cfg, task, lines, stream, summary):
    submit = executor.submitter(task, cfg.data)
    futures = {submit(where): k for k, where in enumerate(lines)}
    results = [None] * len(lines)
    for done, future in enumerate(executor.as_completed(futures), 1):
        k = futures[future]
        results[k] = future.result()
        say(stream, f"[{done}/{len(lines)}] {_line_label(lines[k])}: {summary(results[k])}")
    return results


def say(stream, text):
    if stream:
        print(text, file=stream, flush=True)


def _line_label(where):
    return ", ".join(f"{k}={v:g}" for k, v in where.items()) or "the scene"



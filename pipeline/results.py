"""What `rotorsweep continue` and `rotorsweep backbone` share: writing their result files (netCDF
with a `result_kind` attribute, see pipeline.result_kinds) and running a task per line of the
swept axes on a Dask cluster (pipeline.cluster), the scene's kernels compiled first in the
driver."""
import contextlib
import os

from pipeline import cluster, cube, fileio, runlog, warmup


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
        raise cube.CubeError(f"{output} exists; pass --overwrite to replace it")
    with fileio.output_lock(output, cfg.path or "<default scene>"):
        if scheduler:
            cluster.check_scheduler(scheduler)
        yield output


def run_lines(cfg, task, lines, workers, scheduler, stream, summary):
    """task(cfg.data, where) for every line {axis: value} as Dask tasks, after compiling the
    scene's kernels in the driver (workers load them from the cache); a progress line per line
    done (`summary(result)`); the results in line order."""
    from dask.distributed import as_completed

    say(stream, f"connecting to the Dask scheduler at {scheduler}" if scheduler else
        f"starting {cluster.local_workers(workers)} local Dask worker(s) (127.0.0.1)")
    client, local = cluster.connect(workers, scheduler)
    try:
        with cluster.heap_frozen():     # the imports' and the cluster's objects (see cluster.heap_frozen)
            warmup.compile_scene(cfg.data, lambda text: say(stream, text))
            submit = cluster.submitter(client, task, cfg.data)
            futures = {submit(where): k for k, where in enumerate(lines)}
            results = [None] * len(lines)
            bar = runlog.Progress(len(lines), stream=stream, unit="lines")
            for done, future in enumerate(as_completed(futures), 1):
                k = futures[future]
                results[k] = future.result()
                say(stream, f"[{done}/{len(lines)}] {_line_label(lines[k])}: {summary(results[k])}")
                bar.update(1)
    finally:
        cluster.close(client, local)
    return results


def say(stream, text):
    """A phase line on `stream` and in the log (pipeline.runlog)."""
    runlog.phase_printer(stream)(text)


def _line_label(where):
    return ", ".join(f"{k}={v:g}" for k, v in where.items()) or "the scene"



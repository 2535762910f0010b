"""What `rotorsweep continue` and `rotorsweep backbone` share: writing their result files (netCDF
with a `result_kind` attribute, see rotorsweep.pipeline.result_kinds) and running a task per line of the
swept axes on a Dask cluster or, for small work, in this process (rotorsweep.pipeline.cluster), the
scene's kernels compiled first in the driver.

Like `run`'s chunks, every finished line is saved at once as a part file (rotorsweep.pipeline.cube's
write_part, in `<output>.parts/`): a run stopped by a full disk, a kill or Ctrl-C keeps its
finished lines, and `--resume` computes only the lines no part holds. A line's result (nested
dicts, lists and tuples of arrays, numbers and text) goes into a part as its arrays and a JSON
skeleton (to_part / from_part), read back exactly: a resumed result is bitwise the
uninterrupted one."""
import contextlib
import errno
import os

import numpy as np

from rotorsweep.pipeline import cluster, cube, fileio, plainnc, result_kinds, runlog, warmup, workload


def write(result, path):
    """Atomic netCDF write of a result (plainnc.Plain, or an xarray.Dataset taken as its plain
    variables): compressed numbers, integers without a fill value (so a plain
    xarray.open_dataset keeps the flags integer; padding has its own flag value), text as UTF-8
    character arrays, which every netCDF reader and the CF checker know (netCDF-4 variable-length
    strings are valid CF-1.8 but cfchecker 4.1 rejects them, and HDF5 filters skip them); written
    with the netCDF4 library directly, without importing xarray (rotorsweep.pipeline.plainnc)."""
    plain = result if isinstance(result, plainnc.Plain) else plainnc.of_dataset(result)
    with fileio.atomic_path(path) as tmp:
        try:
            plainnc.write(plain, tmp)
        except RuntimeError as exc:   # netCDF-C reports a full disk as "NetCDF: HDF error"
            raise OSError(errno.EIO, f"netCDF write failed ({exc}; is the disk full?)", str(path)) from None
    return path


@contextlib.contextmanager
def result_output(cfg, output, overwrite, scheduler, resume=False):
    """(absolute output path, its parts directory), locked for the run: refused if the output
    exists without `overwrite`, or parts of an interrupted run are there without `resume`
    (`overwrite` alone discards them); the scheduler checked first. An OS error inside (a full
    disk) becomes one CubeError naming the path and the finished lines kept."""
    output = os.path.abspath(output)
    if os.path.exists(output) and not overwrite:
        raise cube.CubeError(f"{output} exists; pass --overwrite (overwrite=True from Python) to replace it")
    with fileio.output_lock(output, cfg.path or "<default scene>"):
        if scheduler:
            cluster.check_scheduler(scheduler)
        parts = _prepare_parts(output, resume, overwrite)
        try:
            yield output, parts
        except OSError as exc:
            raise cube.CubeError(_write_failure(exc, output, parts)) from None
        finally:
            if parts.is_dir() and not any(parts.iterdir()):
                parts.rmdir()       # nothing finished: leave no empty parts directory behind


def _prepare_parts(output, resume, overwrite):
    parts = cube.parts_dir(output)
    if parts.is_dir() and any(parts.iterdir()) and not resume:
        if not overwrite:
            raise cube.CubeError(f"{parts} holds the finished lines of an interrupted run; pass --resume to "
                                 "finish it or --overwrite to start again")
        remove_parts(parts)
    parts.mkdir(parents=True, exist_ok=True)
    return parts


def remove_parts(parts):
    for path in parts.iterdir():
        path.unlink()
    parts.rmdir()


def _write_failure(exc, output, parts):
    n = len(list(parts.glob("*.npz"))) if parts.is_dir() else 0
    kept = (f"the {n} finished line(s) are kept in {parts}; fix the cause and rerun with --resume"
            if n else "no finished line was kept")
    return f"the run into {output} stopped: {fileio.os_error_text(exc)}; {kept}"


def run_result(cfg, kind, output, dataset, stream, overwrite=False, scheduler=None, resume=False):
    """The frame of a command that writes a result line by line (rotorsweep continue, backbone):
    the output locked with its parts (result_output), the run logged into `<output>.log` (appended
    to on a resume), `dataset(parts)` -> the result's Dataset, written and its parts dropped;
    returns the absolute output path."""
    command = result_kinds.KINDS[kind].command
    with (result_output(cfg, output, overwrite, scheduler, resume) as (output, parts),
          runlog.log_file(output, command, append=resume)):
        ds = dataset(parts)
        say(stream, f"writing the result: {output}")
        return finish(ds, output, parts)


def finish(ds, output, parts):
    """Write the result, then drop the parts it was assembled from."""
    write(ds, output)
    remove_parts(parts)
    return output


def run_lines(cfg, task, lines, workers, scheduler, stream, summary, parts, unit="continuation_line"):
    """task(cfg.scene, where) for every line {axis: value}: in this process (its kernels loaded on
    first use) when the estimated work of the lines to compute (rotorsweep.pipeline.workload,
    `unit`) is small or workers == 0, else as Dask tasks after compiling the scene's kernels in the
    driver (workers load them from the cache). The lines that part files in `parts` hold already
    are read, not computed; each line done is saved as a part and gets a progress line
    (`summary(result)`). The results in line order; the in-process cost per line is recorded
    unless a kernel had to be compiled."""
    config_hash = cfg.hash()
    results = earlier_lines(parts, config_hash, len(lines))
    todo = [k for k, r in enumerate(results) if r is None]
    if len(todo) < len(lines):
        say(stream, f"{len(lines) - len(todo)} of {len(lines)} line(s) read from {parts}")
    if not todo:
        return results
    model = cfg.scene.model_name
    in_process = cluster.runs_in_process(workers, scheduler, workload.estimate(unit, model, len(todo)), len(todo),
                                         cfg.scene.in_process_below)
    say(stream, "computing in this process (small work: no cluster)" if in_process else
        f"connecting to the Dask scheduler at {scheduler}" if scheduler else
        f"starting {cluster.local_workers(workers)} local Dask worker(s) (127.0.0.1)")
    executor = cluster.executor(0 if in_process else workers, scheduler)
    try:
        with cluster.heap_frozen():     # the imports' and the cluster's objects (see cluster.heap_frozen)
            with _kernels_ready(cfg.scene, in_process, lambda text: say(stream, text)) as kernels:
                with workload.Meter() as meter:
                    _run_tasks(executor, cfg.scene, task, lines, todo, results, stream, summary,
                               lambda k: save_line(parts, config_hash, k, results[k]))
    finally:
        executor.close()
    if in_process and not kernels.exclusive:
        workload.record(unit, model, len(todo), meter.seconds)
    return results


def _kernels_ready(scene, in_process, say):
    """The context the tasks run in: in this process the kernels load on first use
    (warmup.kernels_on_first_use); for a cluster the driver compiles (or loads) them all first, so
    that the workers load them from the cache instead of each compiling them (compile_scene)."""
    if in_process:
        return warmup.kernels_on_first_use(scene, say)
    warmup.compile_scene(scene, say)
    return contextlib.nullcontext()


def _run_tasks(executor, scene, task, lines, todo, results, stream, summary, saved):
    """results[k] = task(scene, lines[k]) for k in todo, each `saved(k)` and reported as it ends."""
    submit = executor.submitter(task, scene)
    futures = {submit(lines[k]): k for k in todo}
    bar = runlog.Progress(len(todo), stream=stream, unit="lines")
    for done, future in enumerate(executor.as_completed(futures), len(lines) - len(todo) + 1):
        k = futures[future]
        results[k] = future.result()
        saved(k)
        say(stream, f"[{done}/{len(lines)}] {_line_label(lines[k])}: {summary(results[k])}")
        bar.update(1)


# --- a line's result as a part file -----------------------------------------------------------

def save_line(parts, config_hash, k, result):
    arrays, skeleton = to_part(result)
    cube.write_part(parts, f"line{k:06d}", [k], arrays, {"config_hash": config_hash, "line": k, "result": skeleton})


def earlier_lines(parts, config_hash, n_lines):
    """[result or None] per line: the lines part files of this config hold; parts of another
    config are refused."""
    out = [None] * n_lines
    for _, _, arrays, meta in cube.iter_parts(parts):
        if meta.get("config_hash") != config_hash or not 0 <= meta.get("line", -1) < n_lines:
            raise cube.CubeError(f"{parts} holds lines of a different config (hash {str(meta.get('config_hash'))[:12]}, "
                                 f"this config {config_hash[:12]}); use another output path or pass --overwrite "
                                 "to discard them")
        out[meta["line"]] = from_part(meta["result"], arrays)
    return out


def to_part(value):
    """(arrays {"k": array}, JSON skeleton) of a nested value: dicts with text keys, lists, tuples,
    text, ints, bools and None in the skeleton; floats, complex numbers, numpy scalars and arrays
    as arrays (exact, unlike decimal text). from_part(skeleton, arrays) gives the value back."""
    arrays = {}

    def walk(v):
        if isinstance(v, dict):
            return {"d": {str(k): walk(x) for k, x in v.items()}}
        if isinstance(v, (list, tuple)):
            return {"l" if isinstance(v, list) else "t": [walk(x) for x in v]}
        if v is None or isinstance(v, (str, bool, int)) and not isinstance(v, np.generic):
            return {"v": v}
        tag = "a" if isinstance(v, np.ndarray) else "g" if isinstance(v, np.generic) else "p"
        arrays[str(len(arrays))] = np.asarray(v)
        return {tag: len(arrays) - 1}
    return arrays, walk(value)


def from_part(node, arrays):
    (tag, v), = node.items()
    if tag == "d":
        return {k: from_part(x, arrays) for k, x in v.items()}
    if tag in "lt":
        items = [from_part(x, arrays) for x in v]
        return items if tag == "l" else tuple(items)
    if tag == "v":
        return v
    a = arrays[str(v)]
    return a if tag == "a" else a[()] if tag == "g" else a[()].item()


def say(stream, text):
    """A phase line on `stream` and in the log (rotorsweep.pipeline.runlog)."""
    runlog.phase_printer(stream)(text)


def _line_label(where):
    return ", ".join(f"{k}={v:g}" for k, v in where.items()) or "the scene"

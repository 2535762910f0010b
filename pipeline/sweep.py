"""Distributed sweeps: grid -> continuation segments -> chunks on Dask workers -> part files ->
one result cube.

Segments (fixed by the config) carry the numerics; chunks (groups of whole segments, sized for
scheduling) carry only the work distribution, so the cube is the same for any worker count or
chunk size. Every finished chunk is written at once as a part file next to the output; a
re-run with `resume` computes only the segments no part holds. The cube's arrays take the
earlier parts and then each chunk as it arrives; the cube is written (atomically) at the end.
"""
import os
import sys
from dataclasses import dataclass

import numpy as np

from rotorsweep.pipeline import boundaries, cluster, compute, cube, fileio, result_kinds, warmup, workload
from rotorsweep.pipeline.runlog import PHASE, Progress, log_file, phase_printer  # noqa: F401 (PHASE: the phase lines' mark)
from rotorsweep.pipeline.cluster import SweepError


@dataclass(frozen=True)
class Segment:
    id: int
    index: np.ndarray      # (n, n_axes) grid indices of its points, the continued axis varying fastest
    line: dict             # the parameters its points share: fixed values, the other axes' values
    along: str             # the continued axis
    values: np.ndarray     # (n,) its points' values on it

    def __len__(self):
        return len(self.values)

    @property
    def points(self):
        """One parameter dict per point, built where they are solved (the driver of a 768k-point
        atlas would otherwise build, hold and ship 768k dicts)."""
        return tuple({**self.line, self.along: float(v)} for v in self.values)


class SegmentGrid:
    """The continuation segments of a grid, in a fixed order (the other axes' index combinations,
    the last varying fastest, then runs of segment_length values along the continued axis), each
    built from its id alone: a chunk task carries its segments' ids and its worker builds them
    (Fig. 13's 17 chunks pickled ~760 numpy arrays out of band otherwise: ~8 ms of submitting in
    the driver, and more frames for the scheduler and worker to pass before the first task ran)."""

    def __init__(self, scene):
        axes, along = scene.axes, scene.along
        self.axes, self.along = axes, along
        self.names = list(axes)
        self.at = self.names.index(along)
        self.others = [n for n in self.names if n != along]
        self.shape = tuple(len(axes[n]) for n in self.others)
        self.fixed = scene.fixed
        self.length = scene.segment_length
        self.values = np.asarray(axes[along], float)
        self.per_line = -(-len(self.values) // self.length)

    def __len__(self):
        return self.per_line * self.n_lines

    @property
    def n_lines(self):
        return int(np.prod(self.shape, dtype=np.int64))

    def __getitem__(self, i):
        if not 0 <= i < len(self):
            raise IndexError(f"segment {i} of {len(self)}")
        line_no, k = divmod(int(i), self.per_line)
        return self._segment(line_no, k, *self._line(line_no))

    def line_segments(self, line_no):
        """The segments of one line (one other-axes combination), in order."""
        line, row = self._line(line_no)
        return [self._segment(line_no, k, line, row) for k in range(self.per_line)]

    def _line(self, line_no):
        """(the parameters a line's points share, its grid index with 0 on the continued axis)."""
        where = dict(zip(self.others, (int(j) for j in np.unravel_index(line_no, self.shape))))
        line = {**self.fixed, **{n: float(self.axes[n][j]) for n, j in where.items()}}
        return line, np.array([where.get(n, 0) for n in self.names])

    def _segment(self, line_no, k, line, row):
        steps = np.arange(k * self.length, min((k + 1) * self.length, len(self.values)))
        index = np.repeat(row[None], len(steps), axis=0)
        index[:, self.at] = steps
        return Segment(line_no * self.per_line + k, index, line, self.along, self.values[steps])


def segments(scene):
    """The continuation segments of a scene's grid, in a fixed order (SegmentGrid's)."""
    grid = SegmentGrid(scene)
    return [seg for line_no in range(grid.n_lines) for seg in grid.line_segments(line_no)]


MIN_CHUNK_POINTS = 64
# Default chunks shrink towards the end (guided self-scheduling): each takes about a
# 1 / (share * workers) share of the points still unplanned, at least MIN_CHUNK_POINTS and at
# most MAX_CHUNK_POINTS (seconds of work orbits-only, a minute with attractors: progress lines,
# part files and what a lost worker takes with it stay small on a 768k-point atlas). The share
# follows how unevenly points cost (docs/benchmarks/chunk_plans.md: list schedules of the plans
# on the per-point times of Fig. 13 sweeps, over 40 orders of its lines): orbits-only segments
# cost within ~5x of each other, and share 2 has the best worst case on 2, 4 and 8 workers and
# the best mean on 4 and 8 (half the tasks of share 4, ~10 ms of CPU each, balance as good);
# attractor diagnostics make a segment cost up to ~23x the mean one, where share 4 is within 1%
# of the best mean on 2 workers and the best on 8.
GUIDED_SHARE = 2
GUIDED_SHARE_ATTRACTORS = 4
MAX_CHUNK_POINTS = 4096


def guided_share(scene):
    """The guided plan's share for a scene (see GUIDED_SHARE)."""
    return GUIDED_SHARE_ATTRACTORS if scene.analysis.attractor else GUIDED_SHARE


def chunks_for(scene, segs, n_workers, chunk_points=None):
    """The chunks a sweep of a scene makes of segs: plan_chunks with the scene's guided share."""
    return plan_chunks(segs, n_workers, chunk_points, guided_share(scene))


def plan_chunks(segs, n_workers, chunk_points=None, share=GUIDED_SHARE):
    """Group segments into chunks: of about chunk_points points each when given, else guided
    chunks that shrink from about total / (share * n_workers) (at most MAX_CHUNK_POINTS)
    to MIN_CHUNK_POINTS (~0.05 s of orbits-only work; a task costs ~10 ms of CPU besides its own
    work, about 6 in the driver's scheduler and client and 4 in the worker's event loop, measured
    with no-op tasks of 50 ms on 2 cores); a remainder below that joins the last chunk. Point
    costs vary 100-fold (a stable orbit ~5 ms, a chaotic attractor ~400 ms) and cluster along
    speed, so the last chunks must be small for balance: Fig. 13 with attractors on 2 workers
    took 115 s with 8 equal chunks per worker (one chunk held a quarter of the work) and 93 s
    with 47; large first chunks save tasks (scheduler and driver time) where balance does not
    need them."""
    workers = max(1, n_workers)
    remaining = sum(len(s) for s in segs)
    chunks, current, size = [], [], 0
    for seg in segs:
        current.append(seg)
        size += len(seg)
        target = chunk_points or min(MAX_CHUNK_POINTS, max(MIN_CHUNK_POINTS, remaining // (share * workers)))
        if size >= target:
            chunks.append(current)
            remaining -= size
            current, size = [], 0
    if current and chunks and not chunk_points and size < MIN_CHUNK_POINTS:
        chunks[-1].extend(current)      # not a task of its own: Fig. 13's last line ends in 1 point
    elif current:
        chunks.append(current)
    return chunks


def compute_segments(scene, ids):
    """Worker task of a sweep: compute_chunk of the scene's segments with these ids (SegmentGrid).
    A plain function of an importable module so Dask ships it by reference and workers reuse
    Numba's on-disk cache."""
    grid = SegmentGrid(scene)
    return compute_chunk(scene, [grid[i] for i in ids])


def compute_chunk(scene, chunk):
    """Solve every segment of a chunk and refine the stability changes between two of its points
    along the continued axis (boundaries.refine_within; those between two chunks are left to the
    driver, which sees both)."""
    index = np.concatenate([seg.index for seg in chunk])
    parts = [compute.solve_segment(scene, list(seg.points)) for seg in chunk]
    results = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    return [seg.id for seg in chunk], index, results, boundaries.refine_within(scene, index, results)


def earlier_parts(parts_dir, config_hash):
    """(segment ids, {(line, i): refined boundary row}) that part files of the same config hold
    already; refuse parts of another config."""
    done, refined = set(), {}
    for meta in cube.part_metas(parts_dir):
        if meta.get("config_hash") != config_hash:
            raise SweepError(
                f"{parts_dir} holds partial results of a different config (hash "
                f"{meta.get('config_hash', '?')[:12]}, this config {config_hash[:12]}); "
                "use another output path or pass --overwrite to discard them")
        done.update(meta["segments"])
        refined.update(boundaries.keyed(meta.get("boundaries", ())))
    return done, refined


def _prepare_output(output, cfg, resume, overwrite):
    output = os.path.abspath(output)
    parts = cube.parts_dir(output)
    if os.path.exists(output) and not overwrite:
        raise SweepError(f"{output} exists; pass --overwrite (overwrite=True from Python) to replace it")
    if os.path.isdir(parts) and os.listdir(parts):
        if overwrite and not resume:
            for name in os.listdir(parts):
                os.remove(os.path.join(parts, name))
        elif not resume:
            raise SweepError(f"{parts} holds partial results of an interrupted run; pass --resume to "
                             "finish it or --overwrite to start again")
    os.makedirs(parts, exist_ok=True)
    return output, parts


def provenance(cfg):
    """The global attributes of a sweep cube of cfg (cluster.provenance)."""
    return cluster.provenance(cfg, result_kinds.SWEEP)


def fixed_coords(scene):
    """The cube's scalar coordinates: the fixed values of the axis parameters not swept (NaN
    where a value is derived per point)."""
    return {k: (np.nan if v is None else float(v)) for k, v in scene.fixed.items() if k not in scene.axes}


def run(cfg, output, workers=None, scheduler=None, resume=False, overwrite=False, chunk_points=None,
        progress=True, stream=None):
    """Run a sweep from a validated config into a netCDF cube at `output`; returns its path.
    The output is locked for the whole run, so two runs never share part files. Phase and
    progress lines go to `stream` (default: sys.stderr at the time of the call; progress=False:
    none) and to the log file `<output>.log` (rotorsweep.pipeline.runlog)."""
    compute.require_forced(cfg.model, "run")
    output = os.path.abspath(output)
    with fileio.output_lock(output, cfg.path or "<default scene>"), cluster.heap_frozen():
        if scheduler:
            cluster.check_scheduler(scheduler)
        output, parts = _prepare_output(output, cfg, resume, overwrite)
        try:
            with log_file(output, "run", append=resume):
                return _run_locked(cfg, output, parts, workers, scheduler, chunk_points,
                                   (stream or sys.stderr) if progress else None)
        except OSError as exc:
            raise SweepError(_write_failure(exc, output, parts)) from None
        finally:
            if os.path.isdir(parts) and not os.listdir(parts):
                os.rmdir(parts)       # nothing finished: leave no empty parts directory behind


def _run_locked(cfg, output, parts, workers, scheduler, chunk_points, stream):
    say = phase_printer(stream)
    config_hash = cfg.hash()
    scene = cfg.scene
    segs = segments(scene)
    done, refined = earlier_parts(parts, config_hash)
    todo = [s for s in segs if s.id not in done]
    # the cube's arrays take each chunk as it arrives (the parts of an earlier run first): no
    # part file is read back at the end (Fig. 13: 0.04-0.06 s; the 4-D atlas: 186 MB)
    assembly = cube.Assembly(scene.axes, scene.model_name, scene.model.n_state, config_hash)
    for part in cube.iter_parts(parts):
        assembly.add(*part)
    executor = None
    try:
        if todo:
            executor = _connect(scene, workers, scheduler, sum(len(s) for s in todo), say)
            total = sum(len(s) for s in segs)
            bar = Progress(total, total - sum(len(s) for s in todo), stream)
            refined.update(_run_chunks(executor, scene, todo, parts, assembly, chunk_points, bar, say))
        say("assembling the cube and its boundary table")
        ds = assembly.dataset(fixed_coords(scene), provenance(cfg))
        on_cluster = isinstance(executor, cluster.DaskExecutor)
        ds = boundaries.add_boundary_table(scene, ds, _map_tasks_on(executor.client, stream) if on_cluster else None,
                                           refined)
    finally:
        if executor is not None:
            executor.close()
    say(f"writing the cube: {output}")
    path = cube.write_cube(ds, output, overwrite=True)
    _remove_parts(parts)
    return path


def _map_tasks_on(client, stream=None):
    """boundaries' map_tasks on the sweep's workers: one task per line of brackets the sweep did
    not refine while it computed (those of part files from an earlier run, of a chunk whose
    refinement task was lost), with a progress line on `stream`. A task that keeps killing
    workers is refined here instead."""
    from dask.distributed import KilledWorker

    def map_tasks(scene, axis, tasks):
        if not client.scheduler_info()["workers"]:      # an external cluster scaled to nothing
            return [boundaries.refine_brackets(scene, axis, task) for task in tasks]
        refine = cluster.submitter(client, boundaries.refine_brackets, scene, axis)
        futures = [refine(task) for task in tasks]
        bar = Progress(len(tasks), stream=stream, unit="boundary lines") if tasks else None
        out = []
        for task, future in zip(tasks, futures):
            try:
                out.append(future.result())
            except KilledWorker:
                out.append(boundaries.refine_brackets(scene, axis, task))
            if bar:
                bar.update(1)
        return out
    return map_tasks


def _count(n, noun):
    return f"{n} {noun}{'' if n == 1 else 's'}"


def _write_failure(exc, output, parts):
    """One line for an OS error during a run (disk full, read-only, lost scheduler): what
    failed, what is kept, how to go on."""
    n = len([p for p in os.listdir(parts) if p.endswith(".npz")]) if os.path.isdir(parts) else 0
    kept = (f"the {n} finished chunk(s) are kept in {parts}; fix the cause and rerun with --resume"
            if n else "no finished chunk was kept")
    return f"the run into {output} stopped: {fileio.os_error_text(exc)}; {kept}"


# Dask gives up on a task after its workers died `allowed-failures` (3) times (KilledWorker), as
# it may be what kills them. Our chunks are plain numerics, so worker deaths are far more likely
# the machine's doing (OOM killer, preemption): resubmit a chunk that many more times.
RESUBMITS = 3


def point_unit(scene):
    """The unit of a sweep's work (rotorsweep.pipeline.workload): a point, with or without attractors."""
    return "point_attractor" if scene.analysis.attractor else "point"


def _connect(scene, workers, scheduler, n_points, say):
    """The executor of a sweep of n_points (rotorsweep.pipeline.cluster.executor: this process for small
    work or workers=0, else a cluster), with the scene's kernels compiled (or loaded) here."""
    estimate = workload.estimate(point_unit(scene), scene.model_name, n_points)
    if cluster.runs_in_process(workers, scheduler, estimate, below=scene.in_process_below):
        say(f"computing in this process (about {estimate:.1f} s of work; a local cluster pays from "
            f"{cluster.in_process_below_s(scene.in_process_below):g} s)" if workers != 0 else "computing in this process (--workers 0)")
        executor = cluster.executor(0, None)
    else:
        say(f"connecting to the Dask scheduler at {scheduler}" if scheduler else
            f"starting {_count(cluster.local_workers(workers), 'local Dask worker')} (127.0.0.1)")
        executor = cluster.executor(workers, scheduler)
    try:
        if isinstance(executor, cluster.DaskExecutor):
            say(f"{_count(executor.n_workers, 'worker')}; Dask dashboard: {executor.client.dashboard_link}")
        # the cluster just started joins the frozen heap: with its objects in every full
        # collection, compiling the demo scene's kernels took 27.9 s of CPU instead of 19.6
        with cluster.heap_frozen():
            warmup.compile_scene(scene, say)
    except BaseException:
        executor.close()
        raise
    return executor


# Refinement tasks (of the stability changes between two chunks) run before the chunks still
# queued: the boundary table is then done when the last chunk is, instead of after it.
REFINE_PRIORITY = 1


def _run_chunks(executor, scene, todo, parts, assembly, chunk_points, bar, say):
    """Compute the chunks into part files and `assembly`, each refining the stability changes
    between its own points; one between two chunks is refined by a task of its own as soon as
    both are done (a task and its result's round trip cost ~10 ms of CPU on the driver and the
    worker: Fig. 13 on 2 workers had 11 refinement tasks besides 31 chunks when every finished
    chunk's changes were one): {(line, i): boundary row}. An in-process run records its cost per
    point (rotorsweep.pipeline.workload)."""
    chunks = chunks_for(scene, todo, executor.n_workers, chunk_points)
    say(f"sweeping {_count(sum(len(s) for s in todo), 'point')} in {_count(len(chunks), 'chunk')}")
    bar.restart()
    with workload.Meter() as meter:
        refined = _solve_chunks(executor, scene, chunks, parts, assembly, bar)
    if isinstance(executor, cluster.InProcess):
        workload.record(point_unit(scene), scene.model_name, sum(len(s) for s in todo),
                        meter.seconds)
    return refined


def _solve_chunks(executor, scene, chunks, parts, assembly, bar):
    solve = executor.submitter(compute_segments, scene)

    def submit(chunk):
        return solve(tuple(seg.id for seg in chunk))
    refine = executor.submitter(boundaries.refine_brackets, scene, scene.along, priority=REFINE_PRIORITY)
    tracker = boundaries.Tracker(scene.axes, scene.along)
    futures = {submit(chunk): (chunk, 0) for chunk in chunks}
    refining, refined = {}, {}
    pending = executor.as_completed(futures)
    for future in pending:
        if future in refining:
            _collect_refined(future, refining.pop(future), refined, executor.lost)
            continue
        chunk, resubmits = futures.pop(future)
        try:
            seg_ids, index, results, inside = future.result()
        except executor.lost:
            if resubmits == RESUBMITS:
                raise SweepError(_killed_chunk(chunk, parts)) from None
            retry = submit(chunk)
            futures[retry] = (chunk, resubmits + 1)
            pending.add(retry)
            continue
        chunk_id, meta = f"seg{seg_ids[0]:06d}", {"config_hash": assembly.config_hash, "segments": seg_ids,
                                                  "boundaries": inside}
        cube.write_part(parts, chunk_id, index, results, meta)
        assembly.add(chunk_id, index, results, meta)
        inside = boundaries.keyed(inside)
        refined.update(inside)
        found = [(where, b) for where, b in tracker.add(index, results) if (b.line, b.i) not in inside]
        if found:
            task = refine(found)
            refining[task] = found
            pending.add(task)
        bar.update(len(index))
        future.release()
    return refined


def _collect_refined(future, found, refined, lost):
    """Add a refinement task's rows to `refined`; a task lost with its workers (`lost`: the
    executor's exception for that) leaves its brackets to the refinement after the sweep."""
    try:
        rows = future.result()
    except lost:
        return
    refined.update({(b.line, b.i): row for (_, b), row in zip(found, rows)})
    future.release()


def _killed_chunk(chunk, parts):
    first = chunk[0].points[0]
    return (f"the chunk starting at speed={first['speed']:g} Hz, clearance={first['clearance']:g} m "
            f"killed {RESUBMITS + 1} x 3 workers; finished chunks are kept in {parts}: look for what "
            "ends the workers (memory?), then rerun with --resume")


def _remove_parts(parts):
    for name in os.listdir(parts):
        os.remove(os.path.join(parts, name))
    os.rmdir(parts)

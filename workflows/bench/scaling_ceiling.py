"""What two busy cores give on this machine without Dask: the sweep's chunks solved by a
`multiprocessing` pool of 1 and of 2 processes (a bare queue: each chunk solved and the stability
changes between its own points refined, as in a sweep's chunk task; no scheduler, part files,
refinement between chunks or cube). Shared caches, clock boost and the hypervisor slow each process when both cores
are busy; the pool's speed-up is the ceiling of any scheduler here, the yardstick for the
2-worker Dask sweep."""
import multiprocessing
import statistics
import time

from workflows.bench.common import since, steal_seconds


def _warm(scene, point):
    """Pool initializer: imports and Numba's on-disk cache loaded once per process, untimed."""
    from rotorsweep.pipeline import compute

    compute.solve_segment(scene, [point])


def _solve(args):
    from rotorsweep.pipeline import sweep

    start = time.process_time()
    sweep.compute_segments(*args)
    return time.process_time() - start


def _timed(pool, cfg, chunks):
    """(wall, CPU seconds of the pool's processes, hypervisor steal or None) of solving every
    chunk, the next chunk going to whichever process is free."""
    steal, start = steal_seconds(), time.perf_counter()
    cpu = sum(pool.imap_unordered(_solve, [(cfg.scene, [s.id for s in c]) for c in chunks], chunksize=1))
    return time.perf_counter() - start, cpu, since(steal, steal_seconds())


def measure(cfg, repeats=3):
    """Median wall and CPU seconds with 1 and with 2 processes (their pools started and warmed
    first, the runs interleaved so that a drift of the machine's speed hits both), each on the
    pipeline's default chunk plan for that many workers."""
    from rotorsweep.pipeline import sweep

    segs = sweep.segments(cfg.scene)
    # spawn: the benchmark process runs Dask's threads, which a forked child would inherit locked
    ctx = multiprocessing.get_context("spawn")
    point = segs[0].points[0]
    pools = {k: ctx.Pool(k, initializer=_warm, initargs=(cfg.scene, point)) for k in (1, 2)}
    try:
        runs = {k: [] for k in pools}
        for _ in range(repeats):
            for k, pool in pools.items():
                runs[k].append(_timed(pool, cfg, sweep.chunks_for(cfg.scene, segs, k)))
    finally:
        for pool in pools.values():
            pool.terminate()
    wall = {k: statistics.median(w for w, _, _ in r) for k, r in runs.items()}
    cpu = {k: statistics.median(c for _, c, _ in r) for k, r in runs.items()}
    steals = {k: [s for _, _, s in r] for k, r in runs.items()}
    steal = {k: None if None in s else round(statistics.median(s), 2) for k, s in steals.items()}
    return dict(repeats=repeats, wall_1_s=round(wall[1], 4), wall_2_s=round(wall[2], 4),
                cpu_1_s=round(cpu[1], 4), cpu_2_s=round(cpu[2], 4), speedup=round(wall[1] / wall[2], 3),
                steal_1_s=steal[1], steal_2_s=steal[2],
                speedup_net_of_steal=net_of_steal(wall[1], wall[2], steal[1], steal[2]),
                walls_1_s=[round(w, 4) for w, _, _ in runs[1]], walls_2_s=[round(w, 4) for w, _, _ in runs[2]],
                steals_1_s=steals[1], steals_2_s=steals[2])


def net_of_steal(wall_1, wall_2, steal_1, steal_2):
    """The 2-over-1 speed-up had the hypervisor taken nothing: each run's wall less the steal on
    its critical path, all of it with one busy vCPU, half of it with two (the two share it), to
    3 decimals; None where steal is not reported."""
    if steal_1 is None or steal_2 is None:
        return None
    return round((wall_1 - steal_1) / (wall_2 - steal_2 / 2), 3)

"""How unevenly points cost, and what that asks of the sweep's chunk plan: the guided share of
rotorsweep.pipeline.sweep (GUIDED_SHARE, GUIDED_SHARE_ATTRACTORS) chosen on measured costs.

    python -m workflows.bench.chunk_plans      # -> docs/benchmarks/chunk_plans.{json,md} (~1 min)

Sweeps the Bai 2006 Fig. 13 grid (2401 speeds x 5 clearances) twice on 2 local workers, orbits
and Floquet multipliers only and with the attractor diagnostics, and keeps each point's measured
time (the cube's compute_time). Then simulates the guided plans of shares 1-4 on those times for
1, 2, 4 and 8 workers: a list schedule (each worker takes the next chunk when it is free), a chunk
lasting the sum of its points' times plus TASK_OVERHEAD_S. Costs cluster along the speed line, so
each plan is scheduled on ORDERS orders of the grid's lines (shuffled, each line forwards or
backwards; seeded): the makespan over the ideal (total work / workers), mean and worst.
"""
import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

from workflows.bench import render
from workflows.bench.common import DOCS, loadavg, log, provenance
from workflows.bench.scaling_scene import FIG13, scene_config

SHARES = (1, 2, 3, 4)
WORKERS = (1, 2, 4, 8)
ORDERS = 40
# CPU a task costs besides its work (~6 ms in the driver's scheduler and client, ~4 ms in the
# worker; no-op tasks of 50 ms on 2 workers, 2 cores): on busy cores it delays the workers.
TASK_OVERHEAD_S = 0.010


def swept_costs(cfg, work_dir):
    """[(segment, its points' summed compute_time [s])] of a sweep of cfg on 2 local workers,
    warmed first (the first point a worker solves would count the kernels' loading), in plan order."""
    import rotorsweep.pipeline as pipeline
    from rotorsweep.pipeline import sweep
    from workflows.bench.scaling_runs import worker_calls, first_point, start_cluster

    cluster, client = start_cluster(2)
    try:
        client.run(worker_calls()[0], cfg.scene, first_point(cfg))
        path = pipeline.run(cfg, str(Path(work_dir) / "costs.nc"), scheduler=cluster,
                            overwrite=True, progress=False)
    finally:
        client.close()
        cluster.close()
    with pipeline.open_cube(path) as ds:
        times = ds["compute_time"].transpose(*cfg.axes).values
    return [(seg, float(times[tuple(seg.index.T)].sum())) for seg in sweep.segments(cfg.scene)]


def lines_of(costs):
    """The segments grouped by line (the same fixed values off the continued axis), in order."""
    lines = []
    for seg, cost in costs:
        if not lines or lines[-1][0][0].line != seg.line:
            lines.append([])
        lines[-1].append((seg, cost))
    return lines


def makespan(chunk_costs, workers):
    free = np.zeros(workers)
    for cost in chunk_costs:
        i = int(np.argmin(free))
        free[i] += cost + TASK_OVERHEAD_S
    return float(free.max())


def simulate(lines, rng):
    """{workers: {share: {"mean", "worst": makespan / ideal, "chunks"}}} over ORDERS orders of
    the lines."""
    from rotorsweep.pipeline import sweep

    cost = {seg.id: c for line in lines for seg, c in line}
    total = sum(cost.values())
    orders = []
    for _ in range(ORDERS):
        order = [lines[i] if rng.random() < 0.5 else lines[i][::-1] for i in rng.permutation(len(lines))]
        orders.append([sc for line in order for sc in line])
    out = {}
    for p in WORKERS:
        out[p] = {}
        for share in SHARES:
            ratios, n = [], None
            for segs in orders:
                chunks = sweep.plan_chunks([seg for seg, _ in segs], p, share=share)
                ratios.append(makespan([sum(cost[s.id] for s in ch) for ch in chunks], p) / (total / p))
                n = n or len(chunks)
            out[p][share] = {"mean": round(float(np.mean(ratios)), 4), "worst": round(float(np.max(ratios)), 4),
                             "chunks": n}
    return out


def scene_record(name, cfg, work_dir, rng):
    from rotorsweep.pipeline import sweep

    log(f"{name}: sweeping {cfg.n_points} points on 2 workers")
    lines = lines_of(swept_costs(cfg, work_dir))
    seg_costs = np.array([c for line in lines for _, c in line])
    line_totals = np.array([sum(c for _, c in line) for line in lines])
    return {"scene": name, "attractor": bool(cfg.data["analysis"]["attractor"]),
            "share": sweep.guided_share(cfg.scene), "points": cfg.n_points, "segments": len(seg_costs),
            "lines": len(lines), "work_s": round(float(seg_costs.sum()), 3),
            "segment_mean_s": round(float(seg_costs.mean()), 4),
            "segment_max_over_mean": round(float(seg_costs.max() / seg_costs.mean()), 2),
            "line_spread": round(float(line_totals.max() / line_totals.min() - 1.0), 4),
            "plans": simulate(lines, rng)}


def _table(scene):
    header = ["workers"] + [f"share {s}" + (" (pipeline)" if s == scene["share"] else "") for s in SHARES]
    rows = []
    for p, by_share in scene["plans"].items():
        cells = [f"{v['mean']:.3f} / {v['worst']:.3f} ({v['chunks']})" for v in by_share.values()]
        rows.append([str(p)] + cells)
    return render.table(header, rows)


def markdown(result):
    parts = []
    for s in result["scenes"]:
        parts.append(render.part("chunk_plans", "scene", title=s["scene"], points=s["points"],
                                 segments=s["segments"], lines=s["lines"], work=f"{s['work_s']:.1f}",
                                 seg_mean=f"{s['segment_mean_s'] * 1e3:.0f}", seg_max=f"{s['segment_max_over_mean']:.1f}",
                                 spread=f"{s['line_spread'] * 100:.1f}", share=s["share"], table=_table(s)))
    return render.fill("chunk_plans", date=result["date"], command=result["command"],
                       machine=json.dumps(result["machine"]), load=result["load"], orders=result["orders"],
                       overhead_ms=f"{result['task_overhead_s'] * 1e3:.0f}", scenes="\n\n".join(parts))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=DOCS)
    ap.add_argument("--render-only", action="store_true", help="measure nothing: the .md from the .json in --out")
    args = ap.parse_args(argv)
    if args.render_only:
        result = json.loads((args.out / "chunk_plans.json").read_text())
    else:
        from rotorsweep.pipeline import config

        load = loadavg()
        rng = np.random.default_rng(1)
        attractors = config.parse_config(FIG13.read_text(), path=FIG13.name, allow_large=True)
        with tempfile.TemporaryDirectory() as work:
            scenes = [scene_record("Fig. 13, orbits and Floquet multipliers", scene_config(), work, rng),
                      scene_record("Fig. 13 with attractor diagnostics", attractors, work, rng)]
        result = {"scenes": scenes, "orders": ORDERS, "task_overhead_s": TASK_OVERHEAD_S,
                  **provenance(load, "workflows.bench.chunk_plans", argv)}
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "chunk_plans.json").write_text(json.dumps(result, indent=1) + "\n")
    (args.out / "chunk_plans.md").write_text(markdown(result))
    log(f"wrote {args.out / 'chunk_plans.md'}")
    return result


if __name__ == "__main__":
    main()

"""Speed-up, chunk-size sensitivity and the budget of what limits the speed-up, from the runs;
the verdict against the target."""
import statistics

from workflows.bench.scaling_ceiling import net_of_steal
from workflows.bench.scaling_runs import TOP_PHASES

TARGET_SPEEDUP = 1.85


def median_run(runs, workers, chunk_points):
    """(the run with the median wall time, all runs) of a worker count and chunk size, or None."""
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


def cpu_speedup(r1, r2, serial):
    """The speed-up the two runs would show with a core per worker and no other load: worker CPU
    seconds (what the workers did, not how long other processes kept them waiting) of the
    1-worker run against half of the 2-worker run's, plus the serial driver work S outside the
    boundary table (whose refinement runs on the workers, so its CPU is in theirs):
    (S + W1) / (S + W2 / 2)."""
    w1, w2 = sum(r1.get("worker_cpu_s") or []), sum(r2.get("worker_cpu_s") or [])
    if not (w1 and w2):
        return {}
    s = max(0.0, serial - (r2["phases"].get("boundaries") or 0.0))
    return dict(worker_cpu_1_s=round(w1, 3), worker_cpu_2_s=round(w2, 3), cpu_serial_s=round(s, 3),
                cpu_speedup=round((s + w1) / (s + w2 / 2), 3))


def analyse(runs, worker_counts):
    """Speed-up, efficiency, chunk sensitivity and the budget of what limits the speed-up."""
    one = median_run(runs, 1, None) if 1 in worker_counts else None
    two = median_run(runs, 2, None) if 2 in worker_counts else None
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
            speedup_net_of_steal=net_of_steal(r1["wall_s"], r2["wall_s"], r1.get("steal_s"), r2.get("steal_s")),
        )
        b1 = r1["tasks"].get("busy_total_s")
        b2 = r2["tasks"].get("busy_total_s")
        st1, st2 = r1.get("steal_s"), r2.get("steal_s")
        # the steal on the 2-worker run's critical path (half of it: two vCPUs share it) beyond
        # what the ideal, half the 1-worker wall, holds already
        steal_cost = None if st1 is None or st2 is None else round((st2 - st1) / 2, 3)
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
            steal_1_s=st1, steal_2_s=st2, steal_cost_s=steal_cost,
            # busy times hold the steal too: the slowdown is what is left of it
            slowdown_cost_s=None if not (b1 and b2) else round((b2 - b1) / 2 - (steal_cost or 0.0), 3),
            utilization_2=r2["tasks"].get("utilization"),
            driver_cpu_2_s=r2["driver_cpu_s"],
        )
        limits.update(cpu_speedup(r1, r2, limits["serial_s"]))
        known = [limits["serial_cost_s"], limits["tail_cost_s"], limits["slowdown_cost_s"], steal_cost]
        limits["gaps_cost_s"] = round(limits["excess_s"] - sum(x or 0.0 for x in known), 3)
    sens = []
    for size in sorted({r["chunk_points"] for r in runs if r["workers"] == 2},
                       key=lambda s: -1 if s is None else s):
        med, sel = median_run(runs, 2, size)
        sens.append(dict(chunk_points=size, chunk_points_used=med["chunk_points_used"],
                         n_chunks=med["n_chunks"], wall_s=med["wall_s"],
                         compute_s=med["phases"].get("compute"), tail_s=med["tasks"].get("tail_s"),
                         utilization=med["tasks"].get("utilization"),
                         points_per_s=med["points_per_s"], repeats=[r["wall_s"] for r in sel]))
    sens.sort(key=lambda d: d["chunk_points_used"])
    return scaling, sens, limits


def ratio_text(s):
    """A speed-up to 2 decimals, or 3 where 2 would round a miss of the target up to it."""
    text = f"{s:.2f}"
    return f"{s:.3f}" if s < TARGET_SPEEDUP <= float(text) else text


def verdict_text(scaling, limits, sens, mode, ceiling=None):
    if not scaling:
        return "No 1- and 2-worker pair was measured: no speed-up to judge."
    s = scaling["speedup"]
    parts = [f"2 workers are {ratio_text(s)}x faster than 1 (efficiency {100 * scaling['efficiency']:.0f} %): "
             + (f"the {TARGET_SPEEDUP}x target is met." if scaling["meets_target"] else
                f"below the {TARGET_SPEEDUP}x target.")]
    if scaling.get("compute_speedup"):
        parts.append(f"The distributed compute phase alone scales {scaling['compute_speedup']:.2f}x; "
                     f"the serial driver work ({limits['serial_s']:.1f} s) caps the whole sweep at "
                     f"{limits['amdahl_limit']:.2f}x (Amdahl).")
        if scaling["speedup"] > limits["amdahl_limit"] * 1.02:
            parts.append("The measured speed-up exceeds that cap: the runs were disturbed by other load.")
    if ceiling:
        parts.append(f"Without Dask (a multiprocessing pool, the same chunks) two processes reach "
                     f"{ceiling['speedup']:.2f}x on this machine; the sweep reaches "
                     f"{s / ceiling['speedup']:.0%} of that.")
    if scaling.get("speedup_net_of_steal"):
        parts.append(f"The hypervisor took {limits['steal_2_s']:.2f} CPU s from the two vCPUs during the "
                     f"2-worker run ({limits['steal_1_s']:.2f} s during the 1-worker one); net of it the "
                     f"speed-up is {scaling['speedup_net_of_steal']:.2f}x"
                     + (f" (the pool's: {ceiling['speedup_net_of_steal']:.2f}x)."
                        if ceiling and ceiling.get("speedup_net_of_steal") else "."))
    if limits.get("cpu_speedup"):
        parts.append(f"Counted in CPU seconds (the workers' own work, which other processes on the machine "
                     f"do not inflate) the speed-up is {limits['cpu_speedup']:.2f}x.")
    best = min(sens, key=lambda d: d["wall_s"]) if sens else None
    if best:
        parts.append(f"Fastest chunking on 2 workers: {best['chunk_points_used']} points per chunk "
                     f"({best['n_chunks']} chunks, {best['wall_s']:.1f} s).")
    if mode == "quick":
        parts.append("QUICK run on a reduced grid: start-up, warm-up and serial phases weigh far "
                     "more than on the full Fig. 13 sweep, so these numbers do not judge the target.")
    return " ".join(parts)

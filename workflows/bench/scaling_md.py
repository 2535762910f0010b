"""scaling.md from scaling.json, through templates/scaling.md and templates/scaling_parts.md."""
from pathlib import Path

from workflows.bench.render import fill, part
from workflows.bench.scaling_analysis import TARGET_SPEEDUP, median_run, ratio_text


def _mib(kib):
    return f"{kib / 1024:.0f}"


def fmt(v, spec="{:.2f}"):
    """v formatted, '-' where it was not measured."""
    return "-" if v is None else spec.format(v)


def _pct(v):
    return fmt(v, "{:.0%}")


def _default(d):
    return " (default)" if d["chunk_points"] is None else ""


def run_rows(runs):
    rows = []
    for r in runs:
        ph, t = r["phases"], r["tasks"]
        rows.append(
            f"| {r['label']}{' #' + str(r['repeat']) if r['repeat'] else ''} | {r['workers']} | "
            f"{r['chunk_points_used']}{_default(r)} | {r['n_chunks']} | "
            f"{r['cluster_start_s']:.1f} | {r['worker_warmup_s']:.1f} | **{r['wall_s']:.2f}** | "
            f"{r['points_per_s']:.0f} | "
            f"{fmt(ph.get('compute'))} | {fmt(ph.get('boundaries'))} | "
            f"{fmt((ph.get('assemble') or 0) + (ph.get('write') or 0))} | {fmt(t.get('tail_s'))} | "
            f"{_pct(t.get('utilization'))} | {fmt(r.get('steal_s'))} | "
            f"{' / '.join(_mib(x) for x in r['worker_max_rss_kib'])} | "
            f"{_mib(r['driver_max_rss_kib'])} | {r['loadavg_after'][0]} |")
    return "\n".join(rows)


def speedup_section(res):
    """The speed-up table and the budget of what limits it ('' without a 1- and 2-worker pair)."""
    sc, lim = res["scaling"], res["limits"]
    if not sc:
        return ""
    r1, r2 = median_run(res["runs"], 1, None)[0], median_run(res["runs"], 2, None)[0]
    text = part(
        "scaling", "speedup", wall_1=f"{sc['wall_1_worker_s']:.2f}", wall_2=f"{sc['wall_2_workers_s']:.2f}",
        speedup=ratio_text(sc["speedup"]), efficiency=f"{sc['efficiency']:.0%}",
        pps_1=f"{sc['points_per_s_1']:.0f}", pps_2=f"{sc['points_per_s_2']:.0f}",
        compute_1=fmt(r1["phases"].get("compute")), compute_2=fmt(r2["phases"].get("compute")),
        compute_speedup=fmt(sc.get("compute_speedup")), span_1=fmt(r1["tasks"].get("span_s")),
        span_2=fmt(r2["tasks"].get("span_s")), span_speedup=fmt(sc.get("span_speedup")),
        serial_1=fmt(lim.get("serial_1_worker_s")), serial_2=fmt(lim.get("serial_2_workers_s")),
        busy_1=fmt(lim.get("busy_total_1_s")), busy_2=fmt(lim.get("busy_total_2_s")),
        busy_ratio=fmt(lim.get("busy_ratio"), "{:.3f}"), target=TARGET_SPEEDUP,
        target_met="**met**." if sc["meets_target"] else "**not met**.",
        ideal=f"{lim['ideal_2_workers_s']:.2f}", excess=f"{lim['excess_s']:+.2f}",
        serial_cost=f"{lim['serial_cost_s']:.2f}",
        serial_phases=", ".join(f"{k} {v:.2f}" for k, v in lim["serial_phases_2_workers"].items()),
        dispatch=fmt(lim.get("dispatch_s")), connect=fmt(lim.get("connect_s")), drain=fmt(lim.get("drain_s")),
        tail_cost=fmt(lim.get("tail_cost_s")), tail=fmt(lim.get("tail_s")),
        slowdown_cost=fmt(lim.get("slowdown_cost_s")), busy_2_total=fmt(lim.get("busy_total_2_s"), "{:.1f}"),
        busy_1_total=fmt(lim.get("busy_total_1_s"), "{:.1f}"), part_files=fmt(lim.get("part_files_s")),
        driver_cpu=f"{lim['driver_cpu_2_s']:.1f}", gaps_cost=fmt(lim.get("gaps_cost_s")),
        serial=fmt(lim.get("serial_s")), amdahl=f"{lim['amdahl_limit']:.2f}",
        utilization=_pct(lim.get("utilization_2")), pairs=_pair_ratios(res["runs"]),
        steal_1=fmt(lim.get("steal_1_s")), steal_2=fmt(lim.get("steal_2_s")), steal_cost=fmt(lim.get("steal_cost_s")),
        net_speedup=fmt(sc.get("speedup_net_of_steal")))
    text += "\n\n" + ceiling_section(res)
    if sc["speedup"] > lim["amdahl_limit"] * 1.02:
        text += part("scaling", "inconsistent", serial_1=f"{lim['serial_1_worker_s']:.2f}",
                     serial_2=f"{lim['serial_2_workers_s']:.2f}") + "\n\n"
    return text


def _pair_ratios(runs):
    """The speed-up repeat by repeat (its default 1- and 2-worker runs ran back to back), which
    shows how far the machine moved between repeats; '' for a single repeat."""
    walls = {}
    for r in runs:
        if r["chunk_points"] is None and r["workers"] in (1, 2):
            walls.setdefault(r.get("repeat", 0), {})[r["workers"]] = r["wall_s"]
    ratios = [f"{w[1] / w[2]:.2f}" for _, w in sorted(walls.items()) if 1 in w and 2 in w]
    if len(ratios) < 2:
        return ""
    return (f" Repeat by repeat (its 1- and 2-worker runs back to back): {', '.join(ratios)}x; the "
            "verdict takes the ratio of the median walls.")


def ceiling_section(res):
    """The same chunks on a bare multiprocessing pool ('' for a JSON written before it was measured)."""
    c = res.get("ceiling")
    if not c:
        return ""
    return part("scaling", "ceiling", repeats=c["repeats"], wall_1=f"{c['wall_1_s']:.2f}",
                wall_2=f"{c['wall_2_s']:.2f}", speedup=f"{c['speedup']:.2f}", cpu_1=f"{c['cpu_1_s']:.2f}",
                cpu_2=f"{c['cpu_2_s']:.2f}", cpu_ratio=f"{c['cpu_2_s'] / c['cpu_1_s']:.3f}",
                share=f"{res['scaling']['speedup'] / c['speedup']:.0%}", steal_1=fmt(c.get("steal_1_s")),
                steal_2=fmt(c.get("steal_2_s")), net_speedup=fmt(c.get("speedup_net_of_steal"))) + "\n\n"


def chunk_section(sens):
    if not sens:
        return ""
    rows = "\n".join(f"| {d['chunk_points_used']}{_default(d)} | {d['n_chunks']} | {d['wall_s']:.2f} | "
                     f"{fmt(d['compute_s'])} | {fmt(d['tail_s'])} | {_pct(d['utilization'])} | "
                     f"{d['points_per_s']:.0f} |" for d in sens)
    return part("scaling", "chunk_sizes", rows=rows) + "\n\n"


def tasks_section(res):
    """Task size, serialization, the CPU-time speed-up and the scheduler's throughput ('' for a
    JSON written before they were measured)."""
    costs, sched, lim = res.get("task_costs"), res.get("scheduler"), res.get("limits") or {}
    if not (costs and sched):
        return ""
    rows = "\n".join(f"| {k} | {v['batch_tasks_per_s']:.0f} | {v['round_trip_ms']:.2f} | {v['loadavg'][0]} |"
                     for k, v in sched["by_workers"].items())
    return part("scaling", "tasks", **{k: v for k, v in costs.items()},
                args_kb=f"{costs['args_bytes'] / 1024:.1f}", result_kb=f"{costs['result_bytes'] / 1024:.1f}",
                cpu_speedup=fmt(lim.get("cpu_speedup")), worker_cpu_1=fmt(lim.get("worker_cpu_1_s")),
                worker_cpu_2=fmt(lim.get("worker_cpu_2_s")), cpu_serial=fmt(lim.get("cpu_serial_s")),
                rows=rows, chunk_ms=fmt(None if sched["chunk_compute_s"] is None else 1e3 * sched["chunk_compute_s"], "{:.0f}"),
                saturation=fmt(sched["saturation_workers"], "{:.0f}")) + "\n\n"


def markdown(res, png=None):
    """The text of scaling.md (png: the plot's path, linked when given)."""
    m, scene, quick = res["machine"], res["scene"], res["mode"] == "quick"
    return fill(
        "scaling", quick_title=" (QUICK, reduced grid)" if quick else "", command=res["command"],
        created=res["created"], commit=res["git"].get("commit"),
        modified=(", kernels/pipeline modified in the working tree"
                  if res["git"].get("kernels_or_pipeline_modified") else ""),
        total_s=f"{res['total_s']:.0f}", quick_note=part("scaling", "quick_note") + "\n\n" if quick else "",
        scene_name=scene["name"], n_points=scene["n_points"],
        axes=" x ".join(f"{v} {k}" for k, v in scene["axes"].items()),
        speed_lo=f"{scene['speed_range'][0]:g}", speed_hi=f"{scene['speed_range'][1]:g}",
        n_segments=scene["n_segments"], segment_length=scene["segment_length"],
        cpu=m["cpu"], cores=m["cores"], usable_cores=m["usable_cores"], memory_gib=m["memory_gib"],
        platform=m["platform"], python=m["python"], numpy=m["numpy"], numba=m["numba"], dask=m["dask"],
        distributed=m["distributed"], load_start=res["load_average"]["start"], load_end=res["load_average"]["end"],
        warm_kernels=f"{res['warmup']['driver_kernels_s']:.1f}", warm_sweep=f"{res['warmup']['tiny_sweep_s']:.1f}",
        run_rows=run_rows(res["runs"]), speedup=speedup_section(res),
        chunk_sizes=chunk_section(res["chunk_sensitivity"]) + tasks_section(res),
        plot=part("scaling", "plot", png=Path(png).name) + "\n\n" if png else "", verdict=res["verdict"])

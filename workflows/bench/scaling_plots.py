"""scaling.png: wall time against chunk size, and the task timeline of the 2-worker run."""
from workflows.bench.scaling_analysis import TARGET_SPEEDUP, median_run
from workflows.bench.scaling_md import fmt


def write_plot(results, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    sens = results["chunk_sensitivity"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    ax = axes[0]
    if sens:
        x = [d["chunk_points_used"] for d in sens]
        ax.plot(x, [d["wall_s"] for d in sens], "o-", label="2 workers: sweep wall")
        ax.plot(x, [d["compute_s"] for d in sens], "s--", label="2 workers: compute phase")
    sc = results["scaling"]
    if sc:
        ax.axhline(sc["wall_1_worker_s"], color="k", lw=1, label="1 worker (default chunks)")
        ax.axhline(sc["wall_1_worker_s"] / TARGET_SPEEDUP, color="r", lw=1, ls=":",
                   label=f"target: 1 worker / {TARGET_SPEEDUP}")
    if sens:
        ax.set_xscale("log")
        ax.set_xticks(x)
        ax.set_xticklabels([str(v) for v in x])
        ax.minorticks_off()
    ax.set_xlabel("points per chunk (2 workers)")
    ax.set_ylabel("seconds")
    ax.set_ylim(bottom=0)
    ax.set_title(f"{results['scene']['name']}: {results['scene']['n_points']} points")
    ax.legend(fontsize=8)
    ax = axes[1]
    two = median_run(results["runs"], 2, None)
    if two:
        r = two[0]
        for w in range(r["workers"]):
            bars = [(t["start"], t["stop"] - t["start"]) for t in r["tasks"].get("timeline", [])
                    if t["worker"] == w]
            ax.broken_barh(bars, (w - 0.35, 0.7), facecolors="tab:blue", edgecolors="white", linewidth=0.5)
        ax.set_yticks(range(r["workers"]))
        ax.set_yticklabels([f"worker {i}" for i in range(r["workers"])])
        ax.set_xlabel("seconds since the first task")
        ax.set_title(f"2 workers, default chunks: {r['n_chunks']} tasks, tail {fmt(r['tasks'].get('tail_s'))} s",
                     fontsize=10)
        ax.set_ylim(-0.5, r["workers"] - 0.5)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

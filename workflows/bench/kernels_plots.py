"""The work-precision plots of the kernel benchmarks (wp_*.png), from the measured rows."""
import numpy as np

from workflows.bench.scene import BOUNDARY, BOUNDARY_BRACKETS, STEP_PLACEMENTS

COLORS = {"stable": "tab:blue", "near_pd": "tab:orange", "near_ns": "tab:green", "chaotic": "tab:red"}


def _floor(x):
    return np.maximum(np.asarray(x, float), 1e-16)


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _tag(row):
    """The setting's value as a point label: rtol or steps per period."""
    return f"{row['value']:.0e}" if row["method"] == "dop853" else f"{int(row['value'])}"


def _finish(plt, fig, ax, path, xlabel, ylabel, title, **legend):
    """Log-log axes, labels, grid and legend; save to path."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    ax.legend(**legend)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_wp(path, rows, refs, err_max_key, err_med_key, time_key, title, xlabel, ylabel, ref_key,
            peer=None, peer_err=None):
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.8, 5.4))
    for name, color in COLORS.items():
        for method, style, marker in (("dop853", "-", "o"), ("rk4", "--", "s")):
            rs = [r for r in rows if r["point"] == name and r["method"] == method]
            if not rs:
                continue
            t = [r[time_key] * 1e3 for r in rs]
            ax.plot(_floor([r[err_max_key] for r in rs]), t, style, color=color, marker=marker, ms=4, lw=1.3,
                    label=f"{name}" if method == "dop853" else None)
            ax.plot(_floor([r[err_med_key] for r in rs]), t, ":", color=color, marker=marker, ms=3,
                    mfc="none", lw=0.8)
            bad = [r for r in rs if r["status"] != 0 or r.get("n_failed", 0)]
            if bad:
                ax.plot(_floor([r[err_max_key] for r in bad]), [r[time_key] * 1e3 for r in bad], "x",
                        color="k", ms=8)
            if name == "stable":
                for r in rs:
                    ax.annotate(_tag(r), (max(r[err_max_key], 1e-16), r[time_key] * 1e3), fontsize=6,
                                xytext=(3, 3), textcoords="offset points", color="0.3")
        e = next(e for e in refs["points"] if e["name"] == name)
        ax.axvline(max(e["error_estimate"][ref_key], 1e-16), color=color, lw=0.6, ls=(0, (1, 3)))
    if peer:
        for method, marker in (("DOP853", "*"), ("LSODA", "^")):
            rs = [r for r in peer if r["method"] == method]
            for r in rs:
                ax.plot(max(r[peer_err], 1e-16), r["t"] * 1e3, marker, color=COLORS[r["point"]], ms=10,
                        mec="k", mew=0.5)
            if rs:
                ax.plot([], [], marker, color="0.7", mec="k", ms=10, label=f"scipy {method} (one run)")
    ax.plot([], [], "-o", color="0.3", ms=4, label="dop853, worst case")
    ax.plot([], [], "--s", color="0.3", ms=4, label="rk4, worst case")
    ax.plot([], [], ":o", color="0.3", ms=3, mfc="none", label="median")
    ax.plot([], [], "x", color="k", label="a Newton solve failed")
    ax.plot([], [], ls=(0, (1, 3)), color="0.3", label="reference error estimate")
    _finish(plt, fig, ax, path, xlabel, ylabel, title, fontsize=7, ncol=2, loc="lower left")


def plot_boundary(path, rows, refs):
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.8, 5.4))
    for method, style, marker, color in (("dop853", "-", "o", "tab:blue"), ("rk4", "--", "s", "tab:purple")):
        rs = [r for r in rows if r["method"] == method]
        t = [r["t"] * 1e3 for r in rs]
        ax.plot(_floor([r["err_max"] for r in rs]), t, style, marker=marker, color=color,
                label=f"{method}, worst of {len(BOUNDARY_BRACKETS)} brackets")
        ax.plot(_floor([r["err"] for r in rs]), t, ":", marker=marker, mfc="none", ms=4, color=color,
                label=f"{method}, timed bracket")
        for r in rs:
            ax.annotate(_tag(r), (max(r["err_max"], 1e-16), r["t"] * 1e3), fontsize=7, xytext=(3, 3),
                        textcoords="offset points", color="0.3")
    ax.axvline(max(refs["boundary"]["error_estimate_relative"], 1e-16), color="0.4", ls=(0, (1, 3)),
               label="reference error estimate")
    b = BOUNDARY["bracket"]
    _finish(plt, fig, ax, path, "relative error of the boundary speed", "wall time per locate_boundary [ms]",
            f"Stability boundary (period doubling near 80.88 Hz, {BOUNDARY['clearance'] * 1e6:.1f} um; "
            f"timed bracket {b[0]:g}-{b[1]:g} Hz)", fontsize=8)


def plot_all(out, data, refs):
    """wp_orbit, wp_multipliers, wp_monodromy and wp_boundary.png in `out`."""
    wp, peer = data["work_precision"], data["peer"]
    plot_wp(out / "wp_orbit.png", wp, refs, "err_orbit_max", "err_orbit_med", "t_orbit",
            "Periodic-orbit solve: state error vs time (8 Newton starts)",
            "orbit error (max-norm of the scaled state: um, um/period)", "wall time per orbit solve [ms]",
            "state", peer=peer, peer_err="err_orbit")
    plot_wp(out / "wp_multipliers.png", wp, refs, "err_mult_max", "err_mult_med", "t_orbit",
            "Periodic-orbit solve: multiplier error vs time (8 Newton starts)",
            "multiplier error (largest distance after matching)", "wall time per orbit solve [ms]",
            "multipliers", peer=peer, peer_err="err_mult")
    plot_wp(out / "wp_monodromy.png", wp, refs, "err_mono_max", "err_mono_med", "t_mono",
            f"One monodromy at the exact state: multiplier error vs time ({len(STEP_PLACEMENTS)} step placements)",
            "multiplier error (largest distance after matching)",
            "wall time per monodromy (one variational period) [ms]", "multipliers")
    plot_boundary(out / "wp_boundary.png", data["boundary"], refs)

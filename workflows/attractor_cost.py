"""What the attractor diagnostics cost on the Fig. 13 scene, what each shortcut saves, and what
it costs in accuracy (`make bench-attractor`).

    python -m workflows.attractor_cost                    # the full Fig. 13 grid (12005 points) and the cascade
    python -m workflows.attractor_cost --speed-step 0.5 --cascade-step 0.5   # quicker (2405 + 89 points)
    python -m workflows.attractor_cost --render-only      # the markdown again from the JSON
    python -m workflows.attractor_cost --compare-only     # the accuracy tables again from the cubes in build/

Runs on a local cluster (one process per worker), in this order:
- Fig. 13 (configs/bai2006_fig13.toml): orbits only; the reference (no early stop of the
  transient, Lyapunov runs to a 2 % standard error or the cap: the diagnostics before these
  shortcuts); the reference again with one more transient period (its noise floor: how often
  two equally long runs from slightly different states disagree); early stop of the transient
  only; that and the scene's lyapunov_rtol; the scene as shipped (those and the converged stop
  of the Lyapunov runs, `analysis.lyapunov_converged_stop`); with
  --lyapunov-everywhere also a Lyapunov run at every point (no 'derive when stable').
- the cascade (configs/bai2006_cascade.toml, swept up and down): reference, its noise floor, as
  shipped, and as shipped with the Fig. 13 scene's lyapunov_rtol.
Writes docs/benchmarks/attractor_cost.{json,md}: wall and CPU time of each run, summed point
time per attractor class, and each fast run's agreement with the reference
(workflows.attractor_accuracy).
"""
import argparse
import json
import re
import resource
import time
from pathlib import Path

from rotorsweep.pipeline import config, cube, sweep, warmup
from workflows import attractor_accuracy as acc
from workflows.bench import render
from workflows.bench.common import DOCS, ROOT, add_render_options, log, loadavg, provenance

FIG13 = ROOT / "configs" / "bai2006_fig13.toml"
CASCADE = ROOT / "configs" / "bai2006_cascade.toml"
WORK = ROOT / "build" / "attractor_cost"           # the runs' cubes (what --compare-only reads)
# the diagnostics without the shortcuts (transient to its full length, Lyapunov to a 2 % standard
# error or the cap)
REFERENCE = {"attractor": True, "stop_when_settled": False, "lyapunov_rtol": 0.02, "lyapunov_converged_stop": False}
# the reference again from slightly different states (every transient one period longer): how
# far two equally long runs disagree where the attractor depends on where a run starts
AGAIN = ("reference, one more transient period", {**REFERENCE, "transient_periods": 201})
FIG13_RUNS = {
    "orbits_only": ("orbits + Floquet only", {"attractor": False}),
    "reference": ("+ attractor, reference (full transients, Lyapunov to 2 % or the cap)", REFERENCE),
    "again": AGAIN,
    "settle": ("+ attractor, transient stopped when settled", {**REFERENCE, "stop_when_settled": True}),
    "settle_rtol": ("+ attractor, settled stop + the scene's lyapunov_rtol",
                    {"attractor": True, "lyapunov_converged_stop": False}),
    "fast": ("+ attractor, as shipped (settled stop + the scene's lyapunov_rtol + converged stop)", {"attractor": True}),
}
EVERYWHERE = ("+ attractor, Lyapunov run everywhere (no derive when stable)",
              {**REFERENCE, "derive_when_stable": False})
# the cascade as shipped, and with the Fig. 13 scene's Lyapunov tolerance (its exponents are drawn)
CASCADE_RUNS = {"reference": ("reference", REFERENCE), "again": AGAIN, "fast": ("as shipped", {}),
                "fig13_rtol": ("as shipped, with the Fig. 13 scene's lyapunov_rtol", {"lyapunov_rtol": None})}


def scene(path, overrides, speed_step=None):
    """The scene at `path` with [analysis] keys replaced by `overrides` (and another speed step)."""
    text = path.read_text()
    if speed_step is not None:
        text = re.sub(r"step = [0-9.]+\}", f"step = {speed_step}}}", text, count=1)
    for key in overrides:
        text = re.sub(rf"(?m)^{key}\s*=.*$", "", text)
    extra = "".join(f"{k} = {json.dumps(v)}\n" for k, v in overrides.items())
    text = text.replace("[analysis]\n", f"[analysis]\n{extra}", 1)
    return config.parse_config(text, path=f"{path.name} {overrides}", allow_large=True)


def _cpu():
    """CPU seconds of this process and its finished children (the cluster's workers)."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def timed_run(cfg, path, workers):
    load, cpu0, t0 = loadavg(), _cpu(), time.perf_counter()
    sweep.run(cfg, path, workers=workers, overwrite=True, progress=False)
    wall, cpu = time.perf_counter() - t0, _cpu() - cpu0
    return {"wall_s": wall, "cpu_s": cpu, "load_start": load}, cube.open_cube(path).load()


def classes(ds, suffix=""):
    """Point masks by what the point turned out to be."""
    att, k, stable = ds["attractor" + suffix].values, ds["period" + suffix].values, ds["stable"].values
    return {
        "stable period-1 orbit": (stable == 1) & (att == 1) & (k == 1),
        "period k > 1": (att == 1) & (k > 1),
        "periodic, k unresolved": (att == 1) & (k == 0),
        "other period-1 (orbit unstable or not found)": (stable != 1) & (att == 1) & (k == 1),
        "quasi-periodic": att == 2,
        "chaotic": att == 3,
        "diverged": att == 4,
        "not settled": att == 5,
    }


def summarize(timing, ds):
    t = ds["compute_time"].values
    out = {**timing, "points": int(t.size), "compute_s": float(t.sum()), "mean_ms_per_point": float(1e3 * t.mean())}
    if "attractor" in ds:
        out["classes"] = {name: {"points": int(m.sum()), "compute_s": float(t[m].sum()),
                                 "mean_ms": float(1e3 * t[m].mean()) if m.any() else None}
                          for name, m in classes(ds).items()}
    return out


def _cube(scene_name, run):
    return WORK / f"{scene_name}_{run}.nc"


def measure(args):
    WORK.mkdir(parents=True, exist_ok=True)
    log(f"compiling (or loading) the kernels: {warmup.compile_model(scene(FIG13, {}).model):.1f} s, not timed")
    runs = dict(FIG13_RUNS, **({"everywhere": EVERYWHERE} if args.lyapunov_everywhere else {}))
    res = {"fig13": {}, "cascade": {}}
    for name, (_, over) in runs.items():
        log(f"Fig. 13: {name}")
        timing, ds = timed_run(scene(FIG13, over, args.speed_step), _cube("fig13", name), args.workers)
        res["fig13"][name] = summarize(timing, ds)
    rtol = scene(FIG13, {}).data["analysis"]["lyapunov_rtol"]
    for name, (_, over) in CASCADE_RUNS.items():
        log(f"cascade: {name}")
        over = {k: rtol if v is None else v for k, v in over.items()}
        timing, ds = timed_run(scene(CASCADE, over, args.cascade_step), _cube("cascade", name), args.workers)
        res["cascade"][name] = summarize(timing, ds)
    res["settings"] = {"speed_step": args.speed_step, "cascade_step": args.cascade_step, "workers": args.workers,
                       "fig13_lyapunov_rtol": rtol,
                       "cascade_lyapunov_rtol": scene(CASCADE, {}).data["analysis"]["lyapunov_rtol"]}
    return res


def accuracy(res):
    """Each run's agreement with the reference, from the cubes the runs left in build/."""
    def load(scene_name, run):
        return cube.open_cube(_cube(scene_name, run)).load()
    ref = load("fig13", "reference")
    res["fig13_accuracy"] = {name: acc.compare(load("fig13", name), ref)
                             for name in res["fig13"] if name not in ("orbits_only", "reference")}
    ref = load("cascade", "reference")
    res["cascade_accuracy"] = {}
    for name in (n for n in res["cascade"] if n != "reference"):
        ds = load("cascade", name)
        for direction, suffix in (("up", ""), ("down", "_down")):
            res["cascade_accuracy"][f"{name}, sweep {direction}"] = acc.compare(ds, ref, suffix)
    return res


def _run_table(runs, labels):
    base = runs.get("orbits_only")
    rows = []
    for name, r in runs.items():
        ratio = f"{r['wall_s'] / base['wall_s']:.1f}x" if base else "-"
        rows.append([labels[name], f"{r['wall_s']:.1f}", f"{r['cpu_s']:.1f}", f"{r['compute_s']:.1f}",
                     f"{r['mean_ms_per_point']:.1f}", ratio, r["load_start"]])
    return render.table(["run", "wall [s]", "CPU [s]", "summed point time [s]", "mean per point [ms]",
                         "wall / orbits only", "load at start"], rows)


def _class_table(runs, names):
    rows = []
    for cls in runs[names[0]]["classes"]:
        cells = [runs[n]["classes"][cls] for n in names]
        if any(c["points"] for c in cells):
            rows.append([cls] + [f"{c['points']} / {c['mean_ms']:.1f} / {c['compute_s']:.1f}" if c["points"] else "0"
                                 for c in cells])
    return render.table(["class"] + [f"{n}: points / ms per point / summed s" for n in names], rows)


def report(res):
    fig, casc = res["fig13"], res["cascade"]
    labels = {name: label for name, (label, _) in {**FIG13_RUNS, "everywhere": EVERYWHERE}.items()}
    attractor_runs = [n for n in fig if n != "orbits_only"]
    accuracy = "\n\n".join(f"**{labels[name]}** against the reference:\n\n{acc.markdown(c)}"
                           for name, c in res["fig13_accuracy"].items())
    cascade_labels = {n: label for n, (label, _) in CASCADE_RUNS.items()}

    def cascade_label(key):
        name, direction = key.split(", ")
        return f"{cascade_labels[name]}, {direction}"
    cascade_accuracy = "\n\n".join(f"**{cascade_label(key)}** against the reference:\n\n{acc.markdown(c)}"
                                     for key, c in res["cascade_accuracy"].items())
    fast, base = fig["fast"], fig["orbits_only"]
    return render.fill(
        "attractor_cost", command=res["provenance"]["command"], date=res["provenance"]["date"],
        points=fig["orbits_only"]["points"], speed_step=res["settings"]["speed_step"],
        workers=res["settings"]["workers"], machine=_machine(res), load=res["provenance"]["load"],
        rtol=res["settings"]["fig13_lyapunov_rtol"], cascade_rtol=res["settings"]["cascade_lyapunov_rtol"],
        runs=_run_table(fig, labels), fast_wall=f"{fast['wall_s']:.1f}", ratio=f"{fast['wall_s'] / base['wall_s']:.1f}",
        fast_cpu=f"{fast['cpu_s']:.1f}", cpu_ratio=f"{fast['cpu_s'] / base['cpu_s']:.1f}",
        ref_cpu=f"{fig['reference']['cpu_s']:.1f}",
        saving=f"{fig['reference']['compute_s'] / fast['compute_s']:.1f}",
        classes=_class_table(fig, attractor_runs), accuracy=accuracy,
        summary=acc.summary(res["fig13_accuracy"], labels.get),
        cascade_summary=acc.summary(res["cascade_accuracy"], cascade_label),
        cascade_runs=_run_table(casc, cascade_labels),
        cascade_classes=_class_table(casc, list(casc)), cascade_accuracy=cascade_accuracy)


def _machine(res):
    m = res["provenance"]["machine"]
    return (f"{m['cpu']}, {m['cores']} cores ({m['usable_cores']} usable), Python {m['python']}, "
            f"numpy {m['numpy']}, scipy {m['scipy']}, numba {m['numba']}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed-step", type=float, default=0.1, help="Fig. 13 speed step [Hz] (0.1: the full grid)")
    ap.add_argument("--cascade-step", type=float, default=0.1, help="cascade speed step [Hz] (0.1: the scene's)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--lyapunov-everywhere", action="store_true",
                    help="also run Fig. 13 with a Lyapunov run at every point (long: ~15 min on the full grid)")
    ap.add_argument("--out", type=Path, default=DOCS)
    add_render_options(ap, "attractor_cost.md", "attractor_cost.json", WORK)
    ap.add_argument("--compare-only", action="store_true",
                    help="run nothing: the accuracy tables again from the JSON's timings and the cubes in build/")
    args = ap.parse_args(argv)
    if args.render_only or args.compare_only:
        res = json.loads(((args.data or args.out) / "attractor_cost.json").read_text())
    else:
        load = loadavg()
        res = measure(args)
        res["provenance"] = provenance(load, "workflows.attractor_cost", argv)
    if not args.render_only:
        res = accuracy(res)
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "attractor_cost.json").write_text(json.dumps(res, indent=2))
    (args.out / "attractor_cost.md").write_text(report(res))
    print(report(res))


if __name__ == "__main__":
    main()

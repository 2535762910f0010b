"""First-result time per model, cold (empty Numba cache) and warm (cache filled by the cold run):
what compiling costs a user before the first answer.

    python -m workflows.bench.compile [--revision REV ...] [--models NAME ...] [--keep]
        # -> docs/benchmarks/compile.{json,md}

Each measurement is a fresh process running the model's first point through the CLI
(`rotorsweep point`, by compile_probe.py, which also records the compile seconds per function),
with its own empty cache directory ($ROTORSWEEP_CACHE) for the cold run
and the same directory again for the warm runs (5, interleaved across revisions and models;
the median is reported). CPU time (user + sys of the child) is recorded
beside wall time: on a shared machine the wall time moves with the load, the compile work does
not. A revision other than the working tree is exported (`git archive`) under build/compile/."""
import argparse
import json
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from workflows.bench import render, trees
from workflows.bench.common import DOCS, ROOT, loadavg, log, provenance

# The first point of each model's scene (linear_oscillator and damped_mathieu have none: tests
# only). A conservative model has no `point` (no forcing period): symmetric4's and asymmetric5's
# first result is their scene's backbones (`rotorsweep backbone`, every mode by manifold and
# continuation, one Dask worker); {out} is a file in the run's cache directory.
POINTS = {
    "jeffcott_clearance": ["point", "--speed", "100", "--clearance", "7.6e-6", "--json"],
    "duffing": ["point", "--config", "configs/duffing_resonance.toml", "--at", "omega=1.0", "--json"],
    "rigid_preloaded": ["point", "--config", "configs/filipkovsky2016_quick.toml", "--at", "speed=250",
                        "--at", "support_frequency=150", "--json"],
    "symmetric4": ["backbone", "configs/filipkovsky2010_symmetric.toml", "--workers", "1", "-q", "--overwrite",
                   "-o", "{out}"],
    "asymmetric5": ["backbone", "configs/filipkovsky2010_axial.toml", "--workers", "1", "-q", "--overwrite",
                    "-o", "{out}"],
}
WORKTREE = "worktree"


def tree_of(revision):
    """The source tree to measure: this working tree, or `revision` exported under build/compile."""
    if revision == WORKTREE:
        return ROOT
    path = ROOT / "build" / "compile" / revision
    if not path.exists():
        path.mkdir(parents=True)
        archive = subprocess.run(["git", "archive", revision], cwd=ROOT, check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(path)], input=archive, check=True)
    return path


def label(revision):
    """The revision as the results name it: the working tree as its commit (+ if it has changes)."""
    if revision != WORKTREE:
        return revision
    git = ["git", "-C", str(ROOT)]
    sha = subprocess.run([*git, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run([*git, "status", "--porcelain", "--untracked-files=no"], capture_output=True, text=True).stdout
    return f"{sha}+" if dirty.strip() else sha


PROBE = Path(__file__).with_name("compile_probe.py")
# functions whose exclusive compile time is at least this are listed by name (the rest summed)
LISTED_S = 0.3


def run_point(tree, cache, args):
    """(wall s, CPU s of the child, {function: exclusive compile CPU s}) of one `rotorsweep` command
    in a fresh process (through compile_probe)."""
    env = {**trees.env(tree), "ROTORSWEEP_CACHE": str(cache), "NUMBA_NUM_THREADS": "1"}
    for name in ("NUMBA_CACHE_DIR", "ROTORSWEEP_NUMBA_CACHE_DIR", "ROTORSWEEP_MODELS"):
        env.pop(name, None)
    args = [a.replace("{out}", str(Path(cache) / "result.nc")) for a in args]
    probe = Path(cache) / "compile_times.json"
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, str(PROBE), str(probe), trees.cli_module(tree), *args], cwd=tree, env=env, check=True,
                   capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return round(wall, 2), round(cpu, 2), json.loads(probe.read_text())


# Warm runs per model and revision: their median is reported. One run is not a measurement of a
# ~1 s target here: back-to-back warm points of one tree varied 0.9-1.4 s on this 2-core VM.
WARM_RUNS = 5


def _record(measured, load):
    """{wall_s, cpu_s (medians), load_before, compile_s} of a model's runs of one kind."""
    walls, cpus = [m[0] for m in measured], [m[1] for m in measured]
    return {"wall_s": statistics.median(walls), "cpu_s": statistics.median(cpus), "load_before": load,
            "compile_s": round(sum(measured[0][2].values()), 2)}


def measure(trees, models):
    """{label: {model: {"cold": ..., "warm": ...}}} for trees {label: source tree}: each pair's
    cold point first (compiling into a cache of its own; with the compile seconds per function),
    then WARM_RUNS rounds of one warm point of every pair, interleaved so that the machine's drift
    (its speed moved by a third within minutes here) falls on every revision alike. A warm record
    holds the median of its runs and every run."""
    caches, results = {}, {}
    try:
        for lab, tree in trees.items():
            for model in models:
                caches[lab, model] = Path(tempfile.mkdtemp(prefix="rotorsweep_bench_compile_"))
                load = loadavg()
                cold = run_point(tree, caches[lab, model], POINTS[model])
                results.setdefault(lab, {})[model] = {"cold": {**_record([cold], load), "by_function": cold[2]}}
                log(f"{lab} {model} cold: {cold[0]:.1f} s wall, {cold[1]:.1f} s CPU, load {load}")
        load = loadavg()
        warm = {key: [] for key in caches}
        for _ in range(WARM_RUNS):
            for lab, model in caches:
                warm[lab, model].append(run_point(trees[lab], caches[lab, model], POINTS[model]))
        for (lab, model), runs in warm.items():
            record = _record(runs, load)
            record.update(runs_wall_s=[r[0] for r in runs], runs_cpu_s=[r[1] for r in runs])
            results[lab][model]["warm"] = record
            log(f"{lab} {model} warm: median {record['wall_s']:.2f} s wall of {record['runs_wall_s']}")
        return results
    finally:
        for cache in caches.values():
            shutil.rmtree(cache, ignore_errors=True)


def _warm_wall(warm):
    """The warm wall time as the table shows it: with the range of the runs when there were several."""
    runs = warm.get("runs_wall_s")
    return warm["wall_s"] if not runs else f"{warm['wall_s']} ({min(runs)}-{max(runs)})"


def breakdown(result):
    """Where each model's cold compile time went, for the revisions measured with compile_probe."""
    rows = []
    for rev, per_model in result["results"].items():
        for model, r in per_model.items():
            by_function = r["cold"].get("by_function")
            if not by_function:
                continue
            top = sorted(((s, f) for f, s in by_function.items() if s >= LISTED_S), reverse=True)
            rest = sum(by_function.values()) - sum(s for s, _ in top)
            listed = ", ".join(f"`{f}` {s:.1f}" for s, f in top)
            rows.append([f"`{rev}`", model, f"{r['cold']['compile_s']:.1f}", f"{listed}, other {rest:.1f}"])
    return render.table(["revision", "model", "compiling [CPU s]", "by function (exclusive CPU s)"], rows)


def markdown(result):
    rows = []
    for rev, per_model in result["results"].items():
        for model, r in per_model.items():
            rows.append([f"`{rev}`", model, r["cold"]["wall_s"], r["cold"]["cpu_s"], r["cold"]["load_before"][0],
                         _warm_wall(r["warm"]), r["warm"]["cpu_s"]])
    table = render.table(["revision", "model", "cold wall [s]", "cold CPU [s]", "load (1 min)",
                          "warm wall [s]", "warm CPU [s]"], rows)
    runs = "\n".join(f"- `{run['command']}` on {run['date']}, load {run['load']}" for run in result["runs"])
    machines = {json.dumps(run["machine"]) for run in result["runs"]}
    return render.fill("compile", table=table, runs=runs, machine="; ".join(sorted(machines)),
                       breakdown=breakdown(result))


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m workflows.bench.compile", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--revision", action="append",
                    help=f"git revision to measure, repeatable (default: the working tree, `{WORKTREE}`)")
    ap.add_argument("--models", nargs="+", choices=list(POINTS), default=list(POINTS))
    ap.add_argument("--keep", action="store_true",
                    help="add to the results already in --out (revisions measured in separate runs)")
    ap.add_argument("--out", type=Path, default=DOCS)
    args = ap.parse_args(argv)
    path = args.out / "compile.json"
    result = json.loads(path.read_text()) if args.keep and path.exists() else {"results": {}, "runs": []}
    load = loadavg()
    result["results"].update(measure({label(rev): tree_of(rev) for rev in args.revision or [WORKTREE]}, args.models))
    result["runs"].append(provenance(load, "workflows.bench.compile", argv))
    args.out.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=1) + "\n")
    (args.out / "compile.md").write_text(markdown(result))
    log(f"wrote {args.out / 'compile.md'}")
    return result


if __name__ == "__main__":
    main()

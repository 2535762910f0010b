"""End-to-end latency of the commands a newcomer types (README "A 5-minute tour", `continue` on
the Duffing resonance and on the Bai fold scene's 7.6 um line), before and after a change, in one
run (issue 35):

    python -m workflows.bench.latency [--base 74f5cb3] [--repeats 5] [--only info,point] [--reports]
        # -> docs/benchmarks/latency.{json,md}

The base revision is checked out into build/latency/<rev> (git worktree) and run with its own tree
first on PYTHONPATH and as working directory; the working tree is "after". Every command runs once per tree unmeasured
(warm Numba cache, warm file cache), then `--repeats` times per tree, alternating, so that load
drifts hit both; wall and CPU (user + system of the command and the processes it waited for) are
recorded and their medians reported with the load average around each. The machine may be shared:
the numbers say what this run measured, the load says how quiet it was. The reports (about 90 s
each, no target) run only with --reports, so that the default run takes a few minutes."""
import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

from workflows.bench import trees
from workflows.bench.common import DOCS, ROOT, loadavg, log, provenance

BUILD = ROOT / "build" / "latency"
DEMO = BUILD / "demo.nc"
BAI_76 = BUILD / "bai2006_fold_7.6um.toml"
# (name, argv after `rotorsweep` or a python -c program, the target of issue 35 in s or None)
REPORTS = ("report", "report --point")
COMMANDS = (
    ("import rotorsweep", ["-c", "import rotorsweep"], 0.5),
    # the parts every command pays: the interpreter, numba (the kernels), xarray (the result files) and
    # scipy.linalg, which numba imports on its first compiled call (BLAS check; the kernels call LAPACK)
    ("python -c pass", ["-c", "pass"], None),
    ("import numba", ["-c", "import numba"], None),
    ("import numba + scipy.linalg", ["-c", "import numba, scipy.linalg.cython_blas"], None),
    ("import xarray", ["-c", "import xarray"], None),
    ("info", ["info", DEMO], 0.6),
    ("query --unstable", ["query", DEMO, "--unstable"], 0.6),
    ("query --attractors", ["query", DEMO, "--attractors"], 0.6),
    ("query --where --var", ["query", DEMO, "--where", "speed=80:120", "--where", "clearance=7.6e-6",
                             "--var", "max_abs_multiplier"], 0.6),
    ("point", ["point", "--speed", "100", "--clearance", "7.6e-6"], 0.6),
    ("point --attractor", ["point", "--speed", "36", "--clearance", "19e-6", "--attractor"], None),
    ("point --config fig13 --at", ["point", "--config", "configs/bai2006_fig13.toml", "--at", "speed=31.2",
                                   "--at", "clearance=15.2e-6"], None),
    ("continue duffing_resonance", ["continue", "configs/duffing_resonance.toml", "-o", BUILD / "{tree}" / "duffing.nc",
                                    "--overwrite"], 1.0),
    ("continue bai2006_fold 7.6 um", ["continue", BAI_76, "-o", BUILD / "{tree}" / "bai76.nc", "--overwrite"], 1.2),
    ("report", ["report", DEMO, "-o", BUILD / "{tree}" / "report", "--overwrite"], None),
    ("report --point", ["report", DEMO, "-o", BUILD / "{tree}" / "report_point", "--overwrite", "--point",
                        "speed=36", "clearance=19e-6"], None),
)


def checkout(rev):
    """A worktree of `rev` under build/latency (reused when present)."""
    path = BUILD / rev
    if not path.exists():
        subprocess.run(["git", "worktree", "add", "--detach", str(path), rev], cwd=ROOT, check=True,
                       capture_output=True)
    return path


def prepare():
    """The demo cube (the tour's `make demo`) and the Bai fold scene restricted to 7.6 um."""
    BUILD.mkdir(parents=True, exist_ok=True)
    text = (ROOT / "configs" / "bai2006_fold.toml").read_text()
    BAI_76.write_text(text.replace("clearance = [7.6e-6, 19.0e-6]", "clearance = [7.6e-6]"))
    if not DEMO.exists():
        log("computing the demo cube once (rotorsweep run configs/demo.toml)")
        run_command(ROOT, ["run", "configs/demo.toml", "-o", DEMO, "--overwrite", "-q"], "after")


def argv_of(args, tree_name):
    return [str(a).replace("{tree}", tree_name) for a in args]


def run_command(tree, args, tree_name):
    """(wall s, CPU s) of one command run in `tree` (its code first on PYTHONPATH)."""
    env = trees.env(tree)
    env.pop("NUMBA_CACHE_DIR", None)            # each tree keys its own cache on its kernel sources
    env.pop("ROTORSWEEP_NUMBA_CACHE_DIR", None)
    # an installed package has its bytecode (pip compiles it; the unmeasured first run writes a
    # tree's): with PYTHONDONTWRITEBYTECODE set, every command compiled all its modules from source
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    argv = argv_of(args, tree_name)
    cmd = [sys.executable, *argv] if argv[0] == "-c" else [sys.executable, "-m", trees.cli_module(tree), *argv]
    (BUILD / tree_name).mkdir(parents=True, exist_ok=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    # in the tree: `python -c` and `-m` put the working directory first on sys.path
    proc = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed in {tree}:\n{proc.stderr[-2000:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def measure(trees, commands, repeats):
    """{command: {tree: {"wall": [...], "cpu": [...], "load1": [...]}}}, tree order alternating."""
    result = {}
    for name, args, _ in commands:
        runs = {t: {"wall": [], "cpu": [], "load1": []} for t in trees}
        for t, path in trees.items():
            run_command(path, args, t)          # warm: Numba cache, file cache, Python bytecode
        for k in range(repeats):
            for t in (list(trees) if k % 2 == 0 else list(trees)[::-1]):
                wall, cpu = run_command(trees[t], args, t)
                runs[t]["wall"].append(round(wall, 3))
                runs[t]["cpu"].append(round(cpu, 3))
                runs[t]["load1"].append(round(os.getloadavg()[0], 2))
        log(f"{name}: " + ", ".join(f"{t} {statistics.median(r['wall']):.2f} s wall "
                                    f"{statistics.median(r['cpu']):.2f} s CPU" for t, r in runs.items()))
        result[name] = runs
    return result


def write(result, out):
    targets = {name: target for name, _, target in COMMANDS}
    rows = []
    for name, runs in result["runs"].items():
        med = {t: {k: statistics.median(v) for k, v in r.items()} for t, r in runs.items()}
        b, a = med["before"], med["after"]
        target = targets.get(name)
        rows.append(f"| `{name}` | {len(runs['after']['wall'])} | {b['wall']:.2f} | {b['cpu']:.2f} | {a['wall']:.2f} | {a['cpu']:.2f} | "
                    f"{b['wall'] / a['wall']:.1f}x | {'' if target is None else f'{target:g}'} | "
                    f"{min(min(r['load1']) for r in runs.values()):.1f}-{max(max(r['load1']) for r in runs.values()):.1f} |")
    text = f"""# Latency of small commands (issue 35)

Each command of the README's 5-minute tour and `continue` on `configs/duffing_resonance.toml` and
on the Bai fold scene's 7.6 um line, end to end (process start to exit), warm Numba cache, median
of the runs per tree (column "runs"), the trees alternating. Before: `{result['base']}`
({result['base_label']}); after: the working tree of `{result['head']}`. CPU: user + system of the
command and the processes it waited for (a local cluster's workers). Load: the 1-minute load
average after each run; the machine is shared, and a loaded machine stretches wall time.

| command | runs | before wall [s] | before CPU [s] | after wall [s] | after CPU [s] | wall speed-up | target [s] | load (1 min) |
| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |
{chr(10).join(rows)}

{floor_text(result["runs"])}

Machine: {result['machine']['cpu']}, {result['machine']['usable_cores']} usable cores; load
{result['load']}; {result['date']}. Reproduce: `make bench-latency` (`{result['command']}`).
"""
    (out / "latency.md").write_text(text)
    (out / "latency.json").write_text(json.dumps(result, indent=1) + "\n")


def floor_text(runs):
    """What every command pays before its own work, from the start-up rows (after, median CPU)."""
    cpu = {name: statistics.median(r["after"]["cpu"]) for name, r in runs.items()}
    parts = ("python -c pass", "import numba", "import numba + scipy.linalg", "import xarray")
    if not all(p in cpu for p in parts):
        return ""
    return (f"Where the time goes (after, median CPU): the interpreter {cpu['python -c pass']:.2f} s; numba "
            f"{cpu['import numba']:.2f} s, which the commands that integrate import (`point`, `continue`; `info` "
            "and `query` read the model specs, which live apart from their njit kernels); scipy.linalg "
            f"{cpu['import numba + scipy.linalg'] - cpu['import numba']:.2f} s more, which numba's BLAS check imported "
            "at the first compiled call before: now only a kernel calling LAPACK imports it, at its first call "
            "(pipeline/__init__.py); xarray (with pandas) "
            f"{cpu['import xarray']:.2f} s, which `info`, `query` and `run` (a sweep cube) import; `continue` and "
            "`backbone` write their results with netCDF4 directly (pipeline/plainnc.py) and import neither. "
            "A command run as the process collects no reference cycles in its first 2 s (start-up makes only "
            "long-lived objects, which each full collection walked: `pipeline.collector_after_startup`), skips the "
            "interpreter's final garbage collection (`gc.freeze`), numba's cffi set-up and, without a "
            ".numba_config.yaml to read, its yaml import. "
            "A continuation's own work: Newton's parameter column a forward difference at the first iterate "
            "(one plain integration instead of two), a peak's slope from the tangent's parameter pass plus one "
            "pass along the state without a parameter term (one right-hand side per stage instead of three), "
            "event searches predicted from the nearest solved point, and in this process only the kernels the "
            "line calls loaded (rotorkernels/continuation/arclength.py, engine.py, pipeline/results.py; the "
            "start's orbit without samples, whose kernel is then not loaded): the "
            "Bai 7.6 um line's branch 0.84 -> 0.65 s in-process. "
            "`import rotorsweep` loads its names on first use and registers the accessor when xarray is imported; "
            "each command's imports are checked in tests/test_latency.py (no plotting, Dask or scipy solvers in "
            "info, query or point; no numba in info or query, on a sweep cube, a continuation or a backbone "
            "result; no numba or xarray in `import rotorsweep` or the argument parsing).")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", default="74f5cb3", help="the revision before (default: before issue 35)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--only", help="comma-separated command names to run (default: all but the reports)")
    ap.add_argument("--reports", action="store_true", help=f"also {' and '.join(REPORTS)} (~90 s each)")
    ap.add_argument("--out", type=Path, default=DOCS)
    ap.add_argument("--merge", action="store_true",
                    help="keep the commands of an earlier latency.json in --out that this run does not measure")
    args = ap.parse_args(argv)
    commands = [c for c in COMMANDS if c[0] in args.only.split(",")] if args.only else \
        [c for c in COMMANDS if args.reports or c[0] not in REPORTS]
    label = subprocess.run(["git", "log", "-1", "--format=%s", args.base], cwd=ROOT, capture_output=True,
                           text=True).stdout.strip()[:70]
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                          text=True).stdout.strip()
    load = loadavg()
    prepare()
    trees = {"before": checkout(args.base), "after": ROOT}
    runs = measure(trees, commands, args.repeats)
    if args.merge and (args.out / "latency.json").exists():
        earlier = json.loads((args.out / "latency.json").read_text())["runs"]
        runs = {**earlier, **runs}
    result = {"base": args.base, "base_label": label, "head": head, "repeats": args.repeats, "runs": runs,
              **provenance(load, "workflows.bench.latency", argv)}
    args.out.mkdir(parents=True, exist_ok=True)
    write(result, args.out)
    log(f"wrote {args.out / 'latency.md'}")


if __name__ == "__main__":
    main()

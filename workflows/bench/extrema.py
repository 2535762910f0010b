"""Per-point cost of a Fig. 13 sweep before and after the exact extrema (issue 32), in one run:

    python -m workflows.bench.extrema [--base aace0b1] [--rounds 7]   # -> docs/benchmarks/extrema.{json,md}

What is timed: `compute.solve_segment` (a sweep task's work) on the Fig. 13 scene, orbits only
(`[analysis] attractor = false`: 40 speeds 30.0-33.9 Hz at 7.6, 15.2 and 19.0 um) and with
attractors (12 speeds 30.0-31.1 Hz at the same clearances), CPU time per point
(`time.process_time`: other processes on a loaded machine count less than in wall time), after a
warm-up call (compilation excluded). The base revision is checked out into build/revisions/<rev>
(git worktree, its own Numba cache) and run in its own process; the after side is this
checkout. Rounds alternate the order of the two, so that load drifts hit both; the medians over
the rounds and the median of the per-round ratios are reported, with the load average of
every round."""
import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from workflows.bench import render
from workflows.bench.common import DOCS, ROOT, loadavg, log, provenance
from workflows.bench import trees
from workflows.bench.revisions import checkout

CHILD = """
import json, os, time
from pathlib import Path
from {pipeline} import compute, config
text = Path('configs/bai2006_fig13.toml').read_text()
CLEARANCES = (7.6e-6, 15.2e-6, 19.0e-6)

def scene_of(data):
    # (what compute.solve_segment takes, the fixed values): the scene object where the tree has
    # one (the pipeline's scene module), else the config dict (trees before it)
    try:
        from {pipeline} import scene
    except ImportError:
        return data, compute.fixed_values(data)
    built = scene.from_data(data)
    return built, dict(built.fixed)

def per_point(attractor, lo, n):
    data = config.parse_config(text).data
    data, fixed = scene_of({**data, 'analysis': {**data['analysis'], 'attractor': attractor}})
    for c in CLEARANCES:     # warm-up: every kernel these segments call compiled or loaded
        compute.solve_segment(data, [{**fixed, 'clearance': c, 'speed': lo + 0.1 * i} for i in range(2)])
    out = {}
    for c in CLEARANCES:
        pts = [{**fixed, 'clearance': c, 'speed': lo + 0.1 * i} for i in range(n)]
        t = time.process_time()
        compute.solve_segment(data, pts)
        out[f'{c * 1e6:.1f}'] = (time.process_time() - t) / n
    return out
print(json.dumps({'orbits': per_point(False, 30.0, 40), 'attractors': per_point(True, 30.0, 12),
                  'load': os.getloadavg()[0]}))
"""


def time_once(tree):
    env = trees.env(tree)                     # the tree's own code under its own names
    env.pop("NUMBA_CACHE_DIR", None)          # each tree keys its own cache on its sources
    env.pop("ROTORSWEEP_NUMBA_CACHE_DIR", None)
    child = CHILD.replace("{pipeline}", trees.pipeline_module(tree))
    out = subprocess.run([sys.executable, "-c", child], cwd=tree, env=env, check=True, capture_output=True,
                         text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(trees, rounds):
    """{side: [one child's result per round]}, the sides' order alternating between rounds."""
    runs = {side: [] for side in trees}
    sides = list(trees)
    for k in range(rounds):
        for side in (sides if k % 2 == 0 else sides[::-1]):
            runs[side].append(time_once(trees[side]))
            log(f"round {k + 1}/{rounds} {side}: {json.dumps(runs[side][-1])}")
    return runs


def _mean(run, mode):
    return float(np.mean(list(run[mode].values())))


def summary(runs, mode):
    """(median before, median after, median of the per-round ratios after / before) of the mean
    per-point CPU time over the clearances."""
    before = np.array([_mean(r, mode) for r in runs["before"]])
    after = np.array([_mean(r, mode) for r in runs["after"]])
    return float(np.median(before)), float(np.median(after)), float(np.median(after / before))


def markdown(result):
    """docs/benchmarks/extrema.md from its JSON."""
    runs = result["runs"]
    rows = []
    for k, (b, a) in enumerate(zip(runs["before"], runs["after"])):
        cells = [f"{_mean(b, m) * 1e3:.3f} / {_mean(a, m) * 1e3:.3f}" for m in ("orbits", "attractors")]
        rows.append([k + 1, *cells, f"{b['load']:.1f} / {a['load']:.1f}"])
    heads = {}
    for mode in ("orbits", "attractors"):
        b, a, ratio = summary(runs, mode)
        heads[mode] = (f"{b * 1e3:.3f} ms before, {a * 1e3:.3f} ms after: ratio of the medians "
                       f"{a / b - 1:+.1%}, median of the per-round ratios {ratio - 1:+.1%}")
    table = render.table(["round", "orbits only [CPU ms/point] before / after",
                          "with attractors [CPU ms/point] before / after", "load (1 min) before / after"], rows)
    return render.fill("extrema", table=table, orbits=heads["orbits"], attractors=heads["attractors"],
                       base=result["base"], head=result.get("head", "this checkout"), machine=json.dumps(result["machine"]), load=result["load"],
                       rounds=result["rounds"], date=result["date"], command=result["command"])


def write(result, out):
    (out / "extrema.md").write_text(markdown(result))
    (out / "extrema.json").write_text(json.dumps(result, indent=1) + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", default="aace0b1", help="the revision before (default: sampled orbit means)")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--out", type=Path, default=DOCS)
    args = ap.parse_args(argv)
    load = loadavg()
    runs = measure({"before": checkout(args.base), "after": ROOT}, args.rounds)
    head = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    result = {"base": args.base, "head": head, "runs": runs, "rounds": args.rounds,
              **provenance(load, "workflows.bench.extrema", argv)}
    args.out.mkdir(parents=True, exist_ok=True)
    write(result, args.out)
    log(f"wrote {args.out / 'extrema.md'}")


if __name__ == "__main__":
    main()

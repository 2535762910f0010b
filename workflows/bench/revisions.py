"""Per-point cost of the sweep's work unit at two git revisions, in one run: did a change of the
kernels or of the pipeline around them move the cost?

    python -m workflows.bench.revisions [--base REV] [--rounds 7]   # -> docs/benchmarks/revisions.{json,md}

Each revision is checked out into build/revisions/<rev> (git worktree) and timed in its own
process (its own Numba cache) on the same segment: `compute.solve_segment` over 32 consecutive
speeds of the Fig. 13 scene at 7.6 um, orbits and Floquet multipliers only (the natural
continuation a sweep runs). Rounds alternate between the revisions so that load drifts hit both;
the best round of each is compared. Compilation is excluded (a warm-up call first)."""
import argparse
import json
import subprocess
import sys
from pathlib import Path

from workflows.bench import render, trees
from workflows.bench.common import DOCS, ROOT, loadavg, log, provenance

CHILD = """
import json, sys, time
from {pipeline} import compute, config
text = open('configs/bai2006_fig13.toml').read().replace('attractor = true', 'attractor = false')
cfg = config.parse_config(text, allow_large=True)
data = cfg.scene if hasattr(cfg, 'scene') else cfg.data   # revisions before the scene object take the dict
points = [dict(speed=60.0 + 0.5 * k, clearance=7.6e-6, contact_angle=None, preload=0.0) for k in range(32)]
compute.solve_segment(data, points)   # compile, or load the Numba cache
best = float('inf')
for _ in range(int(sys.argv[1])):
    t0 = time.perf_counter()
    compute.solve_segment(data, points)
    best = min(best, time.perf_counter() - t0)
print(json.dumps(best / len(points)))
"""


def checkout(rev):
    """A worktree of `rev` under build/revisions (reused when present)."""
    path = ROOT / "build" / "revisions" / rev
    if not path.exists():
        subprocess.run(["git", "worktree", "add", "--detach", str(path), rev], cwd=ROOT, check=True,
                       capture_output=True)
    return path


def time_once(tree, repeats):
    env = trees.env(tree)
    env.pop("NUMBA_CACHE_DIR", None)          # each tree keys its own cache on its sources
    env.pop("ROTORSWEEP_NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", CHILD.replace("{pipeline}", trees.pipeline_module(tree)), str(repeats)], cwd=tree, env=env, check=True,
                         capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1])


def measure(revs, rounds, repeats):
    trees = {rev: checkout(rev) for rev in revs}
    seconds = {rev: [] for rev in revs}
    for k in range(rounds):
        for rev in (revs if k % 2 == 0 else revs[::-1]):
            seconds[rev].append(time_once(trees[rev], repeats))
            log(f"round {k + 1}/{rounds} {rev}: {seconds[rev][-1] * 1e3:.3f} ms per point")
    return seconds


def write(result, out):
    base, head = result["revisions"]
    best = {rev: min(v) for rev, v in result["seconds_per_point"].items()}
    rows = [[f"`{rev}` ({result['labels'][rev]})", f"{best[rev] * 1e3:.3f}",
             f"{min(v) * 1e3:.3f} .. {max(v) * 1e3:.3f}"]
            for rev, v in result["seconds_per_point"].items()]
    ratio = best[head] / best[base]
    spread = max(max(v) / min(v) for v in result["seconds_per_point"].values())
    text = render.fill("revisions", table=render.table(["revision", "best [ms/point]", "all rounds [ms/point]"], rows),
                       ratio=f"{ratio:.3f}", spread=f"{spread:.2f}", **{k: result[k] for k in ("date", "command")},
                       machine=json.dumps(result["machine"]), load=result["load"], rounds=result["rounds"])
    (out / "revisions.md").write_text(text)
    (out / "revisions.json").write_text(json.dumps(result, indent=1) + "\n")


def _label(rev):
    return subprocess.run(["git", "log", "-1", "--format=%s", rev], cwd=ROOT, capture_output=True,
                          text=True).stdout.strip()[:60]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", default="cc006f3", help="the revision to compare with (default: before the model registry)")
    ap.add_argument("--head", default="HEAD", help="the revision measured against it (committed)")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--repeats", type=int, default=3, help="timed calls per round (best taken)")
    ap.add_argument("--out", type=Path, default=DOCS)
    args = ap.parse_args(argv)
    head = subprocess.run(["git", "rev-parse", "--short", args.head], cwd=ROOT, capture_output=True,
                          text=True, check=True).stdout.strip()
    revs = [args.base, head]
    load = loadavg()
    seconds = measure(revs, args.rounds, args.repeats)
    result = {"revisions": revs, "labels": {r: _label(r) for r in revs}, "seconds_per_point": seconds,
              "rounds": args.rounds, **provenance(load, "workflows.bench.revisions", argv)}
    args.out.mkdir(parents=True, exist_ok=True)
    write(result, args.out)
    log(f"wrote {args.out / 'revisions.md'}")


if __name__ == "__main__":
    main()

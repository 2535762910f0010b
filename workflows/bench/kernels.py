"""Kernel benchmarks: reference solutions, work-precision, a scipy peer baseline and a C floor.

    python -m workflows.bench.kernels                # full run (~3-5 min on 2 cores) -> docs/benchmarks/
    python -m workflows.bench.kernels --quick        # reduced run (< 2 min) -> build/bench_quick/
    python -m workflows.bench.kernels --refs         # also recompute the reference solutions
    python -m workflows.bench.kernels --render-only  # README.md and plots again from results.json

Writes results.json (every measured number), README.md (templates/kernels.md filled from it),
PNG work-precision plots and reference_points.json (the reference solutions; recomputed only
when missing or with --refs).

What is measured (all on the Bai 2006 rotor, `jeffcott_clearance`, scaled units: tau = t / T,
lengths in um, so the basic orbit has period 1):

1. Reference solutions at four points (stable, near period doubling, near Neimark-Sacker,
   chaotic attractor around an unstable orbit): `references`.
2. Work-precision of the kernels (DOP853 rtol 1e-5..1e-12, RK4 64..4096 steps per period):
   orbit solve, monodromy and stability-boundary location (`work_precision`).
3. A peer baseline in the same run: scipy `solve_ivp` (DOP853 and LSODA) doing the same shooting
   the way a user would (`peer_baseline`, `peers/jeffcott_scipy.py`).
4. A C floor: the same scaled right-hand side in plain C (gcc -O3 -march=native, no fast-math),
   evaluated over the same states as the Numba right-hand side (`cfloor`, `peers/jeffcott_c.py`).

Timing: `time.perf_counter`, one warm-up call first (Numba compilation and caches excluded),
then the best of N repeats; calls shorter than 2 ms are batched and averaged within a repeat.
"""
import argparse
import datetime
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

from workflows.bench.common import DOCS, ROOT, add_render_options, log, loadavg, machine_info
from workflows.bench.references import REF_NAME

QUICK_OUT = ROOT / "build" / "bench_quick"
RESULTS = "results.json"


def _gcc_version():
    gcc = shutil.which("gcc")
    if not gcc:
        return None
    try:
        return subprocess.run([gcc, "--version"], capture_output=True, text=True, timeout=30).stdout.splitlines()[0]
    except (OSError, subprocess.SubprocessError, IndexError):
        return None


def measure(out, quick, repeats, regenerate_refs, command):
    """Run every measurement; returns the results.json content (references written to `out`)."""
    # imported here: --render-only needs neither the kernels nor Numba
    from workflows.bench import jeffcott as jc
    from workflows.bench.cfloor import c_floor
    from workflows.bench.peer_baseline import finite_difference_check, peer_baseline
    from workflows.bench.references import load_references, recheck
    from workflows.bench.scene import (DOP_RTOLS_FULL, DOP_RTOLS_QUICK, HEADLINE_RTOL, RK4_STEPS_FULL,
                                       RK4_STEPS_QUICK)
    from workflows.bench.work_precision import boundary_work_precision, recommendations, work_precision

    t_start = time.perf_counter()
    machine = dict(machine_info(), gcc=_gcc_version(),
                   date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                   loadavg_start=loadavg())
    log(f"bench kernels ({'quick' if quick else 'full'}) -> {out}; {machine['cpu']}, {machine['cores']} cores, "
        f"load {machine['loadavg_start']}")
    refs = load_references(out, regenerate_refs, machine)
    residuals = recheck(refs)
    settings = ([jc.make_setting("dop853", r) for r in (DOP_RTOLS_QUICK if quick else DOP_RTOLS_FULL)]
                + [jc.make_setting("rk4", s) for s in (RK4_STEPS_QUICK if quick else RK4_STEPS_FULL)])
    log("work-precision ...")
    wp = work_precision(refs, settings, repeats)
    bwp = boundary_work_precision(refs, settings, max(3, repeats // 4))
    log("scipy peer ...")
    peer_repeats = 2 if quick else 5
    peer = peer_baseline(refs, wp, ("DOP853", "LSODA"), (HEADLINE_RTOL,) if quick else (1e-8, HEADLINE_RTOL),
                         peer_repeats)
    fd = None if quick else finite_difference_check(refs["points"][0])
    log("C floor ...")
    run = dict(mode="quick" if quick else "full", command=command, repeats=repeats, peer_repeats=peer_repeats,
               headline_rtol=HEADLINE_RTOL, n_states=20_000, passes=20 if quick else 50,
               early_rtol=jc.EARLY_RTOL, early_switch=jc.EARLY_SWITCH)
    cfl = c_floor(refs, run["n_states"], run["passes"], repeats)
    return dict(machine=machine, loadavg_end=loadavg(), run=run,
                settings=[{k: v for k, v in s.items() if k != "opts"} for s in settings],
                work_precision=wp, boundary=bwp, peer=peer, fd_check=fd, c_floor=cfl,
                recommended=recommendations(wp, bwp, len(refs["points"])), reference_recheck=residuals,
                seconds=time.perf_counter() - t_start)


def render(out, data, refs):
    """README.md and the plots in `out` from results.json and reference_points.json content."""
    from workflows.bench.kernels_md import render_readme
    from workflows.bench.kernels_plots import plot_all

    plot_all(out, data, refs)
    (out / "README.md").write_text(render_readme(data, refs))


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m workflows.bench.kernels", description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="reduced run (< 2 min), written to build/bench_quick/")
    ap.add_argument("--refs", action="store_true", help="recompute the reference solutions")
    ap.add_argument("--out", type=Path, default=None, help="output directory (default docs/benchmarks/, "
                                                            "build/bench_quick/ with --quick)")
    ap.add_argument("--repeats", type=int, default=None, help="best-of-N repeats (default 25, quick 7)")
    add_render_options(ap, "README.md and plots", f"{RESULTS} and {REF_NAME}", QUICK_OUT)
    args = ap.parse_args(argv)
    default_dir = QUICK_OUT if args.quick else DOCS
    out = args.out or default_dir
    out.mkdir(parents=True, exist_ok=True)
    if args.render_only:
        src = args.data or default_dir
        data = json.loads((src / RESULTS).read_text())
        refs = json.loads((src / REF_NAME).read_text())
    else:
        command = " ".join(["python -m workflows.bench.kernels", *(sys.argv[1:] if argv is None else argv)])
        data = measure(out, args.quick, args.repeats or (7 if args.quick else 25), args.refs, command)
        (out / RESULTS).write_text(json.dumps(data, indent=1, default=float))
        refs = json.loads((out / REF_NAME).read_text())
    render(out, data, refs)
    log(f"wrote {out / 'README.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

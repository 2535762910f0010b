"""Per-point cost of every rotor model against scipy and C (issue 17, item 3): the same measurement
as the Jeffcott benchmark (`make bench`) for rigid_preloaded, symmetric4 and asymmetric5.

    python -m workflows.bench.models                 # -> docs/benchmarks/models.{json,md} (~3 min)
    python -m workflows.bench.models --quick         # one rtol, fewer repeats -> build/bench_models_quick/
    python -m workflows.bench.models --render-only   # models.md again from models.json

Per point (`POINTS`):
(a) the point's solve, ours against scipy `solve_ivp` DOP853 at the same rtol / atol on the same
    equations (`peers/rotor_scipy.py`), both from the same start, their errors against a tight
    reference (so that "equal tolerance" is checked, not assumed), and the ratio. Forced model
    (rigid_preloaded): Newton shooting for the periodic orbit with its monodromy, then the
    Floquet multipliers. Conservative models: the autonomous orbit at a given amplitude of a
    backbone (unknown period, phase and amplitude conditions, Gauss-Newton:
    `orbits.AutonomousOrbitProblem.solve`) with its monodromy and multipliers.
(b) the cost of one right-hand side and of one variational derivative: C -O3 (`peers/rotor_rhs.c`),
    Numba in an njit loop, and per evaluation inside `flow`; the C values are checked against the
    kernels' at orbit and random states in the same run (`models_floor`).
"""
import argparse
import json
import sys
import time
from pathlib import Path


from workflows.bench.common import DOCS, ROOT, add_render_options, log, loadavg, provenance

QUICK_OUT = ROOT / "build" / "bench_models_quick"
NAME = "models"
REF_RTOL, REF_CHECK_RTOL = 1e-13, 1e-14
# The shipped scenes' values (configs/filipkovsky2016_fig2a.toml; filipkovsky2010_*.toml): the
# model defaults with these keys.
FIG2A = dict(preload=300.0, preload_law="hertz", eccentricity=10e-6, damping=500.0, nominal_angle=15.0)
PAPERS_2010 = dict(preload=300.0, preload_law="hertz", outer_race_radius=0.02753, speed=100.0)
POINTS = [
    dict(name="rigid_loaded", model="rigid_preloaded", values=dict(FIG2A, speed=340.0), approach=[300.0, 320.0, 340.0],
         rtols=(1e-8, 1e-10), kind="Fig. 2a scene, 15 deg, 340 Hz: every ball loaded along the orbit"),
    dict(name="rigid_unloading", model="rigid_preloaded", values=dict(FIG2A, speed=440.0),
         approach=[300.0, 340.0, 380.0, 400.0, 420.0, 440.0], rtols=(1e-8, 1e-10),
         kind="Fig. 2a scene, 15 deg, 440 Hz: balls unload on every turn (min deformation -1.8 x preload's)"),
    dict(name="symmetric4_conical", model="symmetric4", values=PAPERS_2010, mode=2, amplitude=6e-6,
         rtols=(1e-10, 1e-12), kind="backbone of the first conical mode (simple frequency) at 6 um"),
    dict(name="asymmetric5_transverse", model="asymmetric5", values=PAPERS_2010, mode=1, amplitude=6e-6,
         rtols=(1e-10, 1e-12), kind="backbone of the first transverse mode (axial coupling) at 6 um"),
]


def measure(quick, repeats, passes, command_argv):
    """Every measurement: returns the models.json content."""
    from workflows.bench.models_floor import floor_costs
    from workflows.bench.models_points import prepare, record, solve_rows

    load = loadavg()
    t_start = time.perf_counter()
    log(f"bench models ({'quick' if quick else 'full'}); load {load}")
    points = []
    for point in POINTS:
        ref = prepare(point, REF_RTOL, REF_CHECK_RTOL)
        log(f"  {point['name']}: reference ready (error estimate {ref['error_state']:.1e} / {ref['error_mult']:.1e})")
        rtols = point["rtols"][-1:] if quick else point["rtols"]
        rows = solve_rows(ref, rtols, 2 if quick else repeats)
        floor = floor_costs(point, ref, 2000 if quick else 5000, passes)
        log(f"  {point['name']}: {rows[-1]['ratio']:.0f}x scipy; rhs {floor['numba_rhs_ns'] / floor['c_rhs_ns']:.2f}x C")
        points.append(dict(name=point["name"], model=point["model"], kind=point["kind"],
                           reference=record(ref),
                           rows=rows, floor=floor))
    return dict(mode="quick" if quick else "full", points=points, repeats=repeats, passes=passes,
                ref_rtol=REF_RTOL, ref_check_rtol=REF_CHECK_RTOL,
                seconds=time.perf_counter() - t_start, **provenance(load, "workflows.bench.models", command_argv))


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m workflows.bench.models", description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help=f"one rtol, fewer repeats, to {QUICK_OUT.relative_to(ROOT)}/")
    ap.add_argument("--out", type=Path, default=None, help="output directory (default docs/benchmarks/)")
    ap.add_argument("--repeats", type=int, default=5, help="best-of-N scipy calls (each followed by 10 of ours)")
    ap.add_argument("--passes", type=int, default=50,
                    help="passes of the C and Numba loops over the states, and flow calls (best taken)")
    add_render_options(ap, f"{NAME}.md", f"{NAME}.json", QUICK_OUT)
    args = ap.parse_args(argv)
    from workflows.bench.models_md import markdown

    default_dir = QUICK_OUT if args.quick else DOCS
    out = args.out or default_dir
    out.mkdir(parents=True, exist_ok=True)
    if args.render_only:
        data = json.loads(((args.data or default_dir) / f"{NAME}.json").read_text())
    else:
        data = measure(args.quick, args.repeats, args.passes, sys.argv[1:] if argv is None else argv)
        (out / f"{NAME}.json").write_text(json.dumps(data, indent=1, default=float) + "\n")
    (out / f"{NAME}.md").write_text(markdown(data))
    log(f"wrote {out / (NAME + '.md')}")
    return data


if __name__ == "__main__":
    main()

"""The reductions of the rigid_preloaded model (SPEC 2: "the speed/accuracy trade of each
reduction is reported"): each reduced scene against the fuller model it stands for, at one
point of the Filipkovsky 2016 rotor (15 deg bearing, 300 N, 250 Hz shaft speed, vertical support
vibration).

    python -m workflows.bench.reductions [--repeats 5] [--support-frequency 625]
                                         # -> docs/benchmarks/reductions.{json,md}

Each row: the periodic orbit of both by Newton shooting (warm start from the converged orbit:
the timed call is the Newton check plus the monodromy, what a continuation step costs), best of
`--repeats`; the error of the reduced orbit against the fuller one: the state at t = 0 in SI
(positions and velocities, max-norm relative to the orbit's size) and the y_B half peak-to-peak
(relative). Rows:

- balanced vs unbalanced: eccentricity 0 (the support vibration alone, period 1 / f_omega) vs
  the unbalance term present at zero amplitude, which makes the forcing two-frequency: period
  q / f_Omega for f_omega / f_Omega = p / q. In this model that is also the one- vs
  two-frequency reduction (a balanced rotor under support vibration has one frequency).
- fixed ball angles vs cage rotation: rigid_preloaded has no cage rotation (ball angles are
  fixed, SPEC 2.2): no row to measure, said so.
- cubic power-series law vs exact Hertz sum: measured where the model accepts `[bearing] law`
  (the cubic law of the 2010 papers); skipped, and said so, where it does not.
"""
import argparse
import json
from pathlib import Path

import numpy as np

from rotorsweep.kernels import continuation as kc, integrators as ig, shooting
from rotorsweep.kernels.models import rigid_preloaded as rp
from rotorsweep.kernels.models.spec import Built
from workflows.bench import render
from workflows.bench.common import DOCS, best_time, loadavg, log, provenance

SPEC = rp.SPEC
POINT = {"speed": 250.0, "eccentricity": 0.0, "support_acceleration": 4.0, "nominal_angle": 15.0}
RTOL, ATOL, NEWTON_TOL = 1e-10, 1e-12, 1e-9
SAMPLES = 256          # orbit samples per support period for the half peak-to-peak


def scene_values(**over):
    """The model's defaults at the benchmark point, with `over`."""
    v = {p.name: (p.unset if p.axis else p.default) for p in SPEC.parameters}
    return {**v, **POINT, **over}


def two_frequency_built(v):
    """The fuller model of a balanced point: the unbalance term present at zero amplitude, so
    the forcing period is the common period of f_omega and f_Omega (rigid_preloaded.forcing_of
    with both forcings on)."""
    forcing = rp.forcing_of(v["speed"], v["support_frequency"], True, True, v["max_denominator"])
    state = rp.bearing_state(v)
    support = rp.support_vector(v["support_direction"], v["support_acceleration"])
    p = rp.kernel_params(rp.Rotor.of(v), state, rp.geometry(v["nominal_angle"]).n_balls, forcing, v["speed"],
                         0.0, support)
    return Built(p, forcing.period, {"support_periods": forcing.support_turns}, True)


def orbit(built, opts):
    """(the converged orbit, a warm-started solve of it to time: Newton from the orbit plus the
    monodromy)."""
    sol = kc.solve_orbit(SPEC, built.p, opts, cold_guess=SPEC.cold_guess, tol=NEWTON_TOL)

    def solve():
        return kc.solve_orbit(SPEC, built.p, opts, [sol.state], cold_guess=SPEC.cold_guess, tol=NEWTON_TOL)
    return sol, solve


def _si_state(u, period):
    """(q [m], q' [m/s]) from the scaled state (tau = t / period, lengths in LENGTH_SCALE)."""
    return np.concatenate([u[:5], u[5:] / period]) * rp.LENGTH_SCALE


def half_pp_y_b(state, built, support_periods, opts):
    """Half peak-to-peak of y_B [m] over the orbit (SAMPLES per support period)."""
    n = int(round(SAMPLES * support_periods))
    y = shooting.sample_orbit(SPEC.kernel, state, built.p, 1.0, n, opts)[:, 3] * rp.LENGTH_SCALE
    return 0.5 * (y.max() - y.min())


def compare(reduced, fuller, repeats, opts):
    """Speed and error of one reduction: reduced/fuller are (label, Built, support periods)."""
    row = {}
    states = {}
    for key, (label, built, periods) in (("reduced", reduced), ("fuller", fuller)):
        sol, solve = orbit(built, opts)
        seconds, again = best_time(solve, repeats)
        states[key] = (sol, built, periods)
        row[key] = {"model": label, "status": int(sol.status), "seconds": seconds,
                    "period_s": built.period, "newton_converged": bool(again.status == shooting.CONVERGED)}
    (r_sol, r_built, r_n), (f_sol, f_built, f_n) = states["reduced"], states["fuller"]
    r_state, f_state = _si_state(r_sol.state, r_built.period), _si_state(f_sol.state, f_built.period)
    scale = np.abs(f_state).max()
    r_amp, f_amp = half_pp_y_b(r_sol.state, r_built, r_n, opts), half_pp_y_b(f_sol.state, f_built, f_n, opts)
    row.update(speedup=row["fuller"]["seconds"] / row["reduced"]["seconds"],
               state_error=float(np.abs(r_state - f_state).max() / scale),
               half_pp_y_b_m=f_amp, half_pp_error=float(abs(r_amp - f_amp) / f_amp))
    return row


def balanced_row(support_frequency, repeats, opts):
    v = scene_values(support_frequency=support_frequency)
    fuller = two_frequency_built(v)
    row = compare(("balanced: eccentricity 0, one frequency, period 1 / f_omega", SPEC.build(v), 1.0),
                  ("unbalance term present at zero amplitude, two frequencies, period q / f_Omega", fuller,
                   fuller.derived["support_periods"]), repeats, opts)
    return {"reduction": "balanced vs unbalanced (one vs two frequencies)", **row}


def law_row(support_frequency, repeats, opts):
    """cubic vs exact Hertz, when the model has the `law` key (else a skipped row)."""
    names = [p.name for p in SPEC.parameters]
    if "law" not in names:
        return {"reduction": "cubic power-series law vs exact Hertz sum", "skipped":
                "rigid_preloaded has no [bearing] law key in this build (the cubic law is being added on "
                "another branch); rerun the benchmark once it is merged"}
    par = SPEC.parameter("law")
    exact = par.default
    v = scene_values(support_frequency=support_frequency)
    row = compare(("cubic power-series law", SPEC.build({**v, "law": "cubic"}), 1.0),
                  (f"exact Hertz ball sum (law = {exact!r})", SPEC.build({**v, "law": exact}), 1.0), repeats, opts)
    return {"reduction": "cubic power-series law vs exact Hertz sum", **row}


CAGE_ROW = {"reduction": "fixed ball angles vs cage rotation",
            "skipped": "rigid_preloaded has no cage rotation: its ball angles are fixed (SPEC 2.2), so there is "
                       "no fuller model to compare with"}


def measure(support_frequency, repeats):
    opts = ig.settings(rtol=RTOL, atol=ATOL)
    rows = []
    for name, fn in (("balanced", balanced_row), ("law", law_row)):
        log(f"reductions: {name}")
        rows.append(fn(support_frequency, repeats, opts))
    return rows[:1] + [CAGE_ROW] + rows[1:]


def _cells(row):
    if "skipped" in row:
        return [row["reduction"], "-", "-", "-", "-", "-", f"skipped: {row['skipped']}"]
    r, f = row["reduced"], row["fuller"]
    return [row["reduction"], f"{r['model']}: {r['seconds'] * 1e3:.2f} ms", f"{f['model']}: {f['seconds'] * 1e3:.2f} ms",
            f"{row['speedup']:.2f}x", f"{row['state_error']:.1e}", f"{row['half_pp_error']:.1e}",
            f"y_B half peak-to-peak {row['half_pp_y_b_m'] * 1e6:.4f} um"]


def markdown(result):
    table = render.table(["reduction", "reduced (solve)", "fuller (solve)", "speedup", "rel. state error",
                          "rel. error y_B half p-p", "note"], [_cells(r) for r in result["rows"]])
    return render.fill("reductions", date=result["date"], command=result["command"],
                       machine=json.dumps(result["machine"]), load=result["load"], repeats=result["repeats"],
                       point=json.dumps(result["point"]), table=table)


def write(result, out):
    out.mkdir(parents=True, exist_ok=True)
    (out / "reductions.md").write_text(markdown(result))
    (out / "reductions.json").write_text(json.dumps(result, indent=1) + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=5, help="timed solves per model (best taken)")
    ap.add_argument("--support-frequency", type=float, default=625.0,
                    help="f_omega [Hz]; 625 / 250 = 5 / 2: the fuller model's period is 5 support periods")
    ap.add_argument("--out", type=Path, default=DOCS)
    args = ap.parse_args(argv)
    load = loadavg()
    rows = measure(args.support_frequency, args.repeats)
    result = {"point": {**POINT, "support_frequency": args.support_frequency, "rtol": RTOL, "atol": ATOL,
                        "newton_tol": NEWTON_TOL}, "rows": rows, "repeats": args.repeats,
              **provenance(load, "workflows.bench.reductions", argv)}
    write(result, args.out)
    log(f"wrote {args.out / 'reductions.md'}")
    return result


if __name__ == "__main__":
    main()

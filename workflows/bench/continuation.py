"""Pseudo-arclength continuation against a scipy peer, in one run: the forced Duffing resonance
curve (hardening: zeta 0.05, gamma 1, F 0.1, omega 0.5 to 2, two folds).

    python -m workflows.bench.continuation [--rtols 1e-8 1e-10] [--repeats 5]
                                           # -> docs/benchmarks/continuation.{json,md}

(a) rotorsweep.kernels.continuation.arclength.continue_orbit; (b) `ScipyContinuation`
(workflows/bench/peers/duffing_scipy.py), the same algorithm written as a scipy user would:
solve_ivp DOP853 on the variational equations, the same unknowns, bordered Newton, step rules and
settings, folds by Brent on det(M - I). Both at the same rtol, atol = rtol / 100, Newton tolerance
= rtol. Measured: converged branch points per second (the whole continuation timed, fold location
included), and the error at the located folds against a tight reference (solve_ivp rtol 1e-13 in
physical time + fsolve on [phi(u) - u, det(M - I)]), whose own error is estimated by repeating it
at rtol 3e-14."""
import argparse
import json
import time
from pathlib import Path

import numpy as np

from rotorsweep.kernels import integrators as ig, models
from rotorsweep.kernels.continuation import arclength as al, solve_orbit
from workflows.bench import render
from workflows.bench.common import DOCS, loadavg, log, provenance
from workflows.bench.peers.duffing_scipy import Duffing, ScipyContinuation, fold_reference

DUFFING = Duffing(zeta=0.05, gamma=1.0, force=0.1)
OMEGA = (0.5, 2.0)
SETTINGS = dict(ds=0.02, ds_max=0.1, max_steps=2000)


def _settings(rtol):
    return al.Settings(tol=rtol, **SETTINGS)


def _start(rtol):
    """The family and the orbit at the range's start (not timed: both continuations start there)."""
    spec = models.get("duffing")
    opts = ig.settings("dop853", rtol=rtol, atol=rtol / 100, amplitude_limit=1e3)
    values = {"zeta": DUFFING.zeta, "gamma": DUFFING.gamma, "force": DUFFING.force}
    family = al.Family(spec, lambda omega: spec.build({**values, "omega": omega}).p, opts)
    sol = solve_orbit(spec, family.params(OMEGA[0]), opts, cold_guess=spec.cold_guess, tol=rtol)
    return family, sol.state


def run_ours(rtol, repeats):
    """(best wall seconds, best CPU seconds, branch) of arclength.continue_orbit over OMEGA (one
    warm-up call first)."""
    family, state = _start(rtol)
    wall, cpu, branch = np.inf, np.inf, None
    for k in range(repeats + 1):
        t0, c0 = time.perf_counter(), time.process_time()
        branch = al.continue_orbit(family, OMEGA[0], state, OMEGA, _settings(rtol))
        if k:
            wall, cpu = min(wall, time.perf_counter() - t0), min(cpu, time.process_time() - c0)
    return wall, cpu, branch


def run_peer(rtol):
    """(wall seconds, CPU seconds, points, folds, RHS calls) of the scipy continuation (one run)."""
    _, state = _start(rtol)
    peer = ScipyContinuation(DUFFING, 1.0, rtol, rtol / 100, _settings(rtol))
    t0, c0 = time.perf_counter(), time.process_time()
    points, folds = peer.run(OMEGA[0], state, OMEGA)
    return time.perf_counter() - t0, time.process_time() - c0, points, folds, peer.n_rhs


def references(folds):
    """Tight fold references from near each located fold, and their error estimates (rtol 3e-14)."""
    out = []
    for omega, state in folds:
        ref = fold_reference(DUFFING, omega, state, rtol=1e-13, atol=1e-15)
        check = fold_reference(DUFFING, ref[0], ref[1], rtol=3e-14, atol=3e-16)   # scipy's floor: 2.2e-14
        out.append({"omega": ref[0], "state": ref[1].tolist(), "residual": ref[2],
                    "error_omega": abs(check[0] - ref[0]) / ref[0],
                    "error_state": float(np.abs(check[1] - ref[1]).max())})
    return out


def fold_errors(folds, refs):
    """Relative omega error and max-norm state error of each located fold against its reference."""
    return [{"omega": omega, "error_omega": abs(omega - ref["omega"]) / ref["omega"],
             "error_state": float(np.abs(np.asarray(state) - ref["state"]).max())}
            for (omega, state), ref in zip(sorted(folds, key=lambda f: -f[0]), sorted(refs, key=lambda r: -r["omega"]))]


def measure(rtols, repeats):
    runs = []
    for rtol in rtols:
        log(f"rtol {rtol:g}: arclength.continue_orbit (best of {repeats})")
        seconds, cpu_ours, branch = run_ours(rtol, repeats)
        ours = [(e.point.lam, e.point.state) for e in branch.events if e.kind == al.FOLD]
        log(f"rtol {rtol:g}: scipy continuation")
        wall, cpu, points, peer_folds, peer_rhs = run_peer(rtol)
        peer = [(X[2], X[:2]) for X in peer_folds]
        refs = references(ours)
        runs.append({
            "rtol": rtol,
            "ours": {"points": len(branch.points), "seconds": seconds, "cpu_seconds": cpu_ours,
                     "points_per_s": len(branch.points) / seconds,
                     "n_rhs": branch.n_rhs, "end": al.END_REASONS[branch.end], "folds": fold_errors(ours, refs)},
            "scipy": {"points": len(points), "seconds": wall, "cpu_seconds": cpu, "points_per_s": len(points) / wall,
                      "n_rhs": peer_rhs, "folds": fold_errors(peer, refs)},
            "references": refs,
        })
        runs[-1]["ratio"] = runs[-1]["ours"]["points_per_s"] / runs[-1]["scipy"]["points_per_s"]
        runs[-1]["ratio_cpu"] = cpu / cpu_ours      # equal point counts: the CPU time per point
        log(f"rtol {rtol:g}: {runs[-1]['ours']['points_per_s']:.0f} vs {runs[-1]['scipy']['points_per_s']:.2f} "
            f"points/s, ratio {runs[-1]['ratio']:.0f}")
    return runs


def _fold_cells(folds):
    return " / ".join(f"{f['error_omega']:.1e}" for f in folds), " / ".join(f"{f['error_state']:.1e}" for f in folds)


def markdown(result):
    rows = []
    for run in result["runs"]:
        for name, label in (("ours", "arclength.continue_orbit"), ("scipy", "scipy peer")):
            r = run[name]
            err_omega, err_state = _fold_cells(r["folds"])
            rows.append([f"{run['rtol']:g}", label, r["points"], f"{r['seconds']:.3f} ({r['cpu_seconds']:.3f})",
                         f"{r['points_per_s']:.1f}",
                         r["n_rhs"], " / ".join(f"{f['omega']:.12f}" for f in r["folds"]), err_omega, err_state])
    refs = result["runs"][-1]["references"]
    text = render.fill(
        "continuation", date=result["date"], command=result["command"], machine=json.dumps(result["machine"]),
        load=result["load"], repeats=result["repeats"],
        table=render.table(["rtol", "continuation", "points", "wall [s] (CPU)", "points/s (wall)", "RHS evals",
                            "folds omega", "rel. error omega", "error state"], rows),
        ratios=", ".join(f"**{run['ratio_cpu']:.0f}x** at rtol {run['rtol']:g} by CPU time ({run['ratio']:.0f}x by "
                         "wall time)" for run in result["runs"]),
        references=" and ".join(f"omega = {r['omega']:.13f}, state ({r['state'][0]:.12f}, {r['state'][1]:.12f}) "
                                f"(error estimate {r['error_omega']:.1e} relative, {r['error_state']:.1e} in the state)"
                                for r in refs))
    return text


def write(result, out):
    (out / "continuation.md").write_text(markdown(result))
    (out / "continuation.json").write_text(json.dumps(result, indent=1) + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rtols", type=float, nargs="+", default=[1e-8, 1e-10])
    ap.add_argument("--repeats", type=int, default=5, help="timed runs of ours (best taken); the peer runs once")
    ap.add_argument("--out", type=Path, default=DOCS)
    args = ap.parse_args(argv)
    load = loadavg()
    runs = measure(args.rtols, args.repeats)
    result = {"problem": {**DUFFING._asdict(), "omega": list(OMEGA), "settings": SETTINGS}, "runs": runs,
              "repeats": args.repeats, **provenance(load, "workflows.bench.continuation", argv)}
    args.out.mkdir(parents=True, exist_ok=True)
    write(result, args.out)
    log(f"wrote {args.out / 'continuation.md'}")


if __name__ == "__main__":
    main()

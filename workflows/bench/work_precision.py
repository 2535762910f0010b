"""Work-precision of the kernels: time and error of the orbit solve, of one monodromy and of a
stability-boundary location per integrator setting, and the cheapest setting per error target.

Orbit solve: Newton (staged, as the pipeline solves a start off the orbit; plain Newton from the
same starts for its errors) from the reference state perturbed by +-1 % per component (timed from
the first sign pattern, errors over all eight); monodromy: one variational integration over one
period from the reference state (timed with the integrator's own first step, errors over 16
initial steps); boundary: `boundary.locate_boundary` at the period-doubling crossing near
80.9 Hz, 7.6 um (timed for one bracket, errors over three)."""
import numpy as np

from workflows.bench import jeffcott as jc
from workflows.bench.common import RoundRobin, log
from workflows.bench.references import from_complex_list, match, state_error
from workflows.bench.scene import BOUNDARY_BRACKETS, REC_QUANTITIES, START_PATTERNS, STEP_PLACEMENTS, TARGETS, rec_key


def _orbit_errors(orbits, s_ref, lam_ref):
    """Failures and error statistics of orbit solves (from the starts) against the reference."""
    ok = [o for o in orbits if o.status == jc.CONVERGED]
    e_orb = np.array([state_error(o.state, s_ref) for o in ok]) if ok else np.array([np.inf])
    e_mul = np.array([match(jc.multipliers(o.monodromy), lam_ref) for o in ok]) if ok else np.array([np.inf])
    timed = orbits[0]
    return dict(
        n_failed=len(orbits) - len(ok), n_rhs_orbit=int(timed.n_rhs),
        err_orbit=state_error(timed.state, s_ref),
        err_orbit_med=float(np.median(e_orb)), err_orbit_max=float(e_orb.max()),
        err_mult=match(jc.multipliers(timed.monodromy), lam_ref),
        err_mult_med=float(np.median(e_mul)), err_mult_max=float(e_mul.max()))


def _errors(orbits, monos, s_ref, lam_ref):
    """Errors of the converged orbit solves and of the monodromies against the reference."""
    e_mono = np.array([match(jc.multipliers(m.reshape(jc.N, jc.N)), lam_ref) for m in monos])
    return dict(**_orbit_errors(orbits, s_ref, lam_ref),
                err_mono=float(e_mono[0]), err_mono_med=float(np.median(e_mono)), err_mono_max=float(e_mono.max()))


def work_precision(refs, settings, repeats):
    """Orbit-solve and monodromy timings (interleaved over all points and settings) and errors."""
    timer = RoundRobin()
    rows = []
    for e in refs["points"]:
        p, s_ref = np.array(e["p"]), np.array(e["state"])
        lam_ref = from_complex_list(e["multipliers"])
        guesses = [s_ref * (1.0 + 0.01 * pat) for pat in START_PATTERNS]
        z_ref = jc.initial_state(s_ref, True)
        for st in settings:
            opts, tol = st["opts"], st["tol"]
            key = (e["name"], st["label"])
            orbit = timer.add(key + ("orbit",), lambda p=p, g=guesses[0], o=opts, t=tol: jc.orbit(p, g, o, t))
            _, _, n_rhs_mono = timer.add(key + ("mono",), lambda p=p, z0=z_ref, o=opts: jc.flow(p, z0, o, True))
            orbits = [orbit] + [jc.orbit(p, g, opts, tol) for g in guesses[1:]]
            monos = jc.monodromies(p, s_ref, opts, STEP_PLACEMENTS)
            # the same starts by plain Newton (the peer's algorithm): the staged one's accuracy against it
            plain = ([jc.orbit(p, g, opts, tol, staged=False) for g in guesses] if st["method"] == "dop853"
                     else None)
            rows.append(dict(
                point=e["name"], method=st["method"], value=st["value"], label=st["label"],
                newton_tol=tol, status=int(orbit.status), reason=int(orbit.reason),
                iterations=int(orbit.iterations), n_rhs_mono=int(n_rhs_mono),
                plain=_orbit_errors(plain, s_ref, lam_ref) if plain else None,
                **_errors(orbits, monos, s_ref, lam_ref)))
        log(f"  work-precision {e['name']}: errors done")
    times = timer.run(repeats)
    for r in rows:
        r["t_orbit"] = times[(r["point"], r["label"], "orbit")]
        r["t_mono"] = times[(r["point"], r["label"], "mono")]
    log(f"  work-precision: {repeats} timing rounds done")
    return rows


def boundary_work_precision(refs, settings, repeats):
    """Time of one boundary location per setting and its relative error over the brackets."""
    bnd = refs["boundary"]
    states = [np.array(s) for s in bnd["bracket_states"]]
    timer = RoundRobin(min_batch=0)
    rows = []
    for st in settings:
        found = timer.add(st["label"], lambda st=st: jc.locate(st["opts"], st["tol"], states, 1e-12))
        errs = [abs(found.value - bnd["speed_hz"]) / bnd["speed_hz"]]
        for br in BOUNDARY_BRACKETS[1:]:
            try:
                v = jc.locate(st["opts"], st["tol"], states, 1e-12, br).value
                errs.append(abs(v - bnd["speed_hz"]) / bnd["speed_hz"])
            except jc.BoundaryError:
                errs.append(np.inf)
        rows.append(dict(label=st["label"], method=st["method"], value=st["value"],
                         evaluations=int(found.evaluations), speed_hz=float(found.value),
                         err=errs[0], err_max=float(max(errs)), status=0))
    times = timer.run(repeats)
    for r in rows:
        r["t"] = times[r["label"]]
    log("  boundary work-precision: done")
    return rows


def recommend(rows, err_key, time_key, target, n_points):
    """Cheapest setting (summed time over the points) whose error is <= target at every point and
    whose solves all converged."""
    by_label = {}
    for r in rows:
        by_label.setdefault(r["label"], []).append(r)
    best = None
    for label, rs in by_label.items():
        if len(rs) != n_points or any(r[err_key] > target or r["status"] != 0 or r.get("n_failed", 0)
                                      for r in rs):
            continue
        total = sum(r[time_key] for r in rs)
        if best is None or total < best[1]:
            best = (label, total, max(r[err_key] for r in rs), max(r[time_key] for r in rs))
    if best is None:
        return None
    return dict(label=best[0], mean_time=best[1] / n_points, max_time=best[3], max_err=best[2])


def recommendations(wp, bwp, n_points):
    """{'<quantity> <target>': cheapest setting or None} for every quantity and target."""
    rec = {}
    for key, err_key, time_key in REC_QUANTITIES:
        rows, n = ([dict(r, point="b") for r in bwp], 1) if key == "boundary" else (wp, n_points)
        for target in TARGETS:
            rec[rec_key(key, target)] = recommend(rows, err_key, time_key, target, n)
    return rec

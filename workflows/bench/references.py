"""Reference solutions at the four points and at the stability boundary (reference_points.json).

Newton shooting with DOP853 at rtol 1e-13, checked against DOP853 at rtol 1e-14, fixed-step RK4
at 2^15..2^17 steps per period and an independent numpy right-hand side integrated by scipy; the
largest difference is the stated error of the reference."""
import json
import time

import numpy as np
from scipy.optimize import linear_sum_assignment

from workflows.bench import jeffcott as jc
from workflows.bench.common import DOCS, log
from workflows.bench.peers.jeffcott_scipy import ScipyPeer
from workflows.bench.scene import (
    BAI, BOUNDARY, BOUNDARY_BRACKETS, CHECK_ATOL, CHECK_RK4_STEPS, CHECK_RTOL, POINTS, REF_ATOL,
    REF_CHECK_KEY, REF_NEWTON_TOL, REF_RTOL, REF_STEP_PLACEMENTS, START_PATTERNS, contact_angle)

REF_NAME = "reference_points.json"
N = jc.N


def match(a, b):
    """Largest pairwise distance between two multiplier sets after optimal matching."""
    cost = np.abs(np.subtract.outer(np.asarray(a, complex), np.asarray(b, complex)))
    rows, cols = linear_sum_assignment(cost)
    return float(cost[rows, cols].max())


def state_error(s, ref):
    return float(np.max(np.abs(np.asarray(s) - np.asarray(ref))))


def complex_list(lam):
    return [[float(z.real), float(z.imag)] for z in np.asarray(lam, complex)]


def from_complex_list(items):
    return np.array([complex(re, im) for re, im in items])


def median_multipliers(p, state, opts, placements=REF_STEP_PLACEMENTS):
    """(multipliers of the element-wise median monodromy over step placements, all monodromies)."""
    monos = jc.monodromies(p, state, opts, placements)
    return jc.multipliers(np.median(monos, axis=0).reshape(N, N)), monos


def _check_entry(s, lam, ref_s, ref_lam, **extra):
    return dict(state_diff=state_error(s, ref_s), multiplier_diff=match(lam, ref_lam), **extra)


def _orbit_check(sol, s_ref, lam_ref):
    return _check_entry(sol.state, jc.multipliers(sol.monodromy), s_ref, lam_ref,
                        converged=bool(sol.status == jc.CONVERGED), residual=float(sol.residual))


def reference_checks(p, s_ref, lam_ref):
    """Differences of the other constructions to the reference (from a state perturbed by 1e-6
    relative, so that Newton has to iterate)."""
    near = s_ref * (1.0 + 1e-6 * START_PATTERNS[0])
    check_opts = jc.dop853(CHECK_RTOL, CHECK_ATOL)
    alt = jc.orbit(p, near, check_opts, REF_NEWTON_TOL)
    alt_lam, _ = median_multipliers(p, alt.state, check_opts)
    checks = {REF_CHECK_KEY: _check_entry(alt.state, alt_lam, s_ref, lam_ref,
                                          converged=bool(alt.status == jc.CONVERGED),
                                          residual=float(alt.residual))}
    rk4 = {steps: jc.orbit(p, near, jc.rk4(steps), REF_NEWTON_TOL) for steps in CHECK_RK4_STEPS}
    for steps, sol in rk4.items():
        checks[f"rk4 {steps} steps"] = _orbit_check(sol, s_ref, lam_ref)
    a, b = rk4[CHECK_RK4_STEPS[-2]], rk4[CHECK_RK4_STEPS[-1]]
    checks["rk4 2^16 vs 2^17 steps (its own error)"] = _check_entry(
        a.state, jc.multipliers(a.monodromy), b.state, jc.multipliers(b.monodromy))
    s_sp, mono_sp, _, nfev, conv = ScipyPeer(jc.named_params(p)).shoot(
        near, "DOP853", REF_RTOL, REF_ATOL, REF_NEWTON_TOL, max_iter=4)
    checks["scipy DOP853 rtol=1e-13, independent numpy rhs (one run)"] = _check_entry(
        s_sp, jc.multipliers(mono_sp), s_ref, lam_ref, converged=bool(conv), nfev=int(nfev))
    return checks


def _attractor(p, period):
    lle, err = jc.largest_lyapunov(p, jc.static_guess(p), jc.dop853(1e-10, 1e-12))
    return dict(lle_per_period=lle, lle_stderr=err, lle_per_s=lle / period,
                how="Benettin from the static guess: 300 transient periods, 2000 periods measured, "
                    "one tangent vector renormalised every period, dop853 rtol 1e-10; stderr from 10 blocks")


def compute_reference(point):
    """The reference solution of one point and its checks (a few seconds)."""
    p, period = jc.bai_params(point["speed"], point["clearance"])
    start = jc.approach(point, jc.dop853(1e-12, 1e-14), 1e-11)
    ref_opts = jc.dop853(REF_RTOL, REF_ATOL)
    orbit = jc.orbit(p, start, ref_opts, REF_NEWTON_TOL)
    if orbit.status != jc.CONVERGED:
        raise RuntimeError(f"reference orbit at {point['name']} did not converge: {orbit}")
    s_ref = orbit.state
    lam_ref, monos = median_multipliers(p, s_ref, ref_opts)
    single = np.array([match(jc.multipliers(m.reshape(N, N)), lam_ref) for m in monos])
    max_abs, stable, leading = jc.classify(lam_ref)
    checks = reference_checks(p, s_ref, lam_ref)
    entry = dict(
        name=point["name"], kind=point["kind"], speed_hz=point["speed"],
        clearance_m=point["clearance"], contact_angle_rad=contact_angle(point["clearance"]),
        period_s=float(period), approach_hz=point["approach"], p=[float(x) for x in p],
        state=[float(x) for x in s_ref],
        state_si=[float(x) for x in jc.to_physical(s_ref, period)],
        monodromy=[[float(x) for x in row] for row in np.median(monos, axis=0).reshape(N, N)],
        multipliers=complex_list(lam_ref), max_abs=float(max_abs), stable=bool(stable),
        leading_type=leading, newton_iterations=int(orbit.iterations), residual=float(orbit.residual),
        single_run_scatter=dict(
            median=float(np.median(single)), q90=float(np.quantile(single, 0.9)), max=float(single.max()),
            how=f"multiplier distance of each of the {len(monos)} single DOP853 rtol 1e-13 monodromies "
                f"(initial steps 0 and 1e-6..3e-2) from the reference"),
        checks=checks,
        error_estimate=dict(state=checks[REF_CHECK_KEY]["state_diff"],
                            multipliers=checks[REF_CHECK_KEY]["multiplier_diff"],
                            rule=f"difference to the same construction at {REF_CHECK_KEY}"),
    )
    if point["name"] == "chaotic":
        entry["attractor"] = _attractor(p, period)
    return entry


def compute_boundary_reference(near_pd_state):
    a, b = BOUNDARY["bracket"]
    opts = jc.dop853(REF_RTOL, REF_ATOL)
    solve = jc.boundary_solver(opts, REF_NEWTON_TOL)
    states = [solve(a, near_pd_state).state, solve(b, near_pd_state).state]
    ref = jc.locate(opts, REF_NEWTON_TOL, states, 1e-14)

    def rel_diff(found):
        return abs(found.value - ref.value) / ref.value

    checks = {f"dop853 rtol=1e-13, bracket {br[0]:g}-{br[1]:g} Hz":
              rel_diff(jc.locate(opts, REF_NEWTON_TOL, states, 1e-14, br)) for br in BOUNDARY_BRACKETS[1:]}
    checks[REF_CHECK_KEY] = rel_diff(jc.locate(jc.dop853(CHECK_RTOL, CHECK_ATOL), REF_NEWTON_TOL, states, 1e-14))
    checks["rk4 65536 steps (its own error ~1e-9 in the multipliers)"] = rel_diff(
        jc.locate(jc.rk4(2 ** 16), REF_NEWTON_TOL, states, 1e-14))
    est = max(v for k, v in checks.items() if not k.startswith("rk4"))
    return dict(clearance_m=BOUNDARY["clearance"], bracket_hz=list(BOUNDARY["bracket"]),
                speed_hz=float(ref.value), evaluations=int(ref.evaluations),
                leading_multiplier=complex_list(ref.solution.multipliers[:1])[0],
                bracket_states=[[float(x) for x in s] for s in states],
                checks_relative=checks, error_estimate_relative=est,
                how=f"locate_boundary (Brent on max|lambda| - 1, xtol_rel 1e-14) with solve_orbit at "
                    f"dop853 rtol {REF_RTOL:g}, atol {REF_ATOL:g}, Newton tol {REF_NEWTON_TOL:g}; error "
                    f"estimate = largest difference to other brackets and to rtol 1e-14")


METHOD = dict(
    reference=f"state: rotorsweep.kernels.shooting (Newton, analytic variational monodromy) with "
              f"DOP853 rtol {REF_RTOL:g}, atol {REF_ATOL:g}, Newton tolerance "
              f"{REF_NEWTON_TOL:g} (relative residual), started from a continuation chain "
              f"through 'approach_hz'; monodromy: element-wise median of "
              f"{len(REF_STEP_PLACEMENTS)} variational DOP853 rtol {REF_RTOL:g} integrations "
              f"over one period from that state, each with a different initial step (a single "
              f"run's monodromy error has a heavy tail, see single_run_scatter); multipliers: "
              f"its eigenvalues",
    error_estimate=f"the same construction at DOP853 rtol {CHECK_RTOL:g}, atol {CHECK_ATOL:g} "
                   f"(Newton from the reference state perturbed by 1e-6 relative): state "
                   f"max-norm difference (scaled units) and largest multiplier distance after "
                   f"optimal matching",
    other_checks="fixed-step RK4 at 2^15, 2^16, 2^17 steps per period (a second method; it "
                 "converges slowly across the contact switching, so it confirms the state to "
                 "~1e-11 and the multipliers only to its own error ~1e-9), and an independent "
                 "numpy right-hand side integrated by scipy DOP853 at rtol 1e-13 (one run)")


def build_references(machine):
    log("computing reference solutions ...")
    t0 = time.perf_counter()
    entries = []
    for point in POINTS:
        e = compute_reference(point)
        entries.append(e)
        log(f"  {e['name']}: |lambda|max {e['max_abs']:.6f}, error estimate state "
            f"{e['error_estimate']['state']:.1e}, multipliers {e['error_estimate']['multipliers']:.1e}")
    near_pd = next(e for e in entries if e["name"] == "near_pd")
    bnd = compute_boundary_reference(np.array(near_pd["state"]))
    log(f"  boundary: {bnd['speed_hz']:.12f} Hz (relative error estimate {bnd['error_estimate_relative']:.1e})")
    return dict(
        description="Reference periodic orbits of the Bai 2006 rotor (jeffcott_clearance) for the "
                    "kernel benchmarks. Scaled units: tau = t / T, lengths in um; state = (x, y, "
                    "dx/dtau, dy/dtau); state_si in m and m/s.",
        parameters=dict(BAI, contact_angle="cos a = 1 - c / (r_i + r_o - D_b) (Bai 2006 eq. 6)",
                        phase=0.0, cage_rotation=True),
        method=METHOD, generated=machine["date"], machine=machine,
        seconds=round(time.perf_counter() - t0, 1), points=entries, boundary=bnd)


def load_references(out, regenerate, machine):
    """The references of `out` (else those in docs/benchmarks, copied to `out`), computed when
    missing or when `regenerate`."""
    path = out / REF_NAME
    source = path if path.exists() else DOCS / REF_NAME
    if source.exists() and not regenerate:
        refs = json.loads(source.read_text())
        log(f"reference solutions from {source}")
        if source != path:
            path.write_text(source.read_text())
    else:
        refs = build_references(machine)
        path.write_text(json.dumps(refs, indent=1))
    return refs


def recheck(refs):
    """{point: residual}: the stored states must still be fixed points of the current kernels."""
    opts = jc.dop853(REF_RTOL, REF_ATOL)
    residuals = {}
    for e in refs["points"]:
        residuals[e["name"]] = jc.fixed_point_residual(np.array(e["p"]), np.array(e["state"]), opts)
        if residuals[e["name"]] > 1e-10:
            log(f"WARNING: stored reference {e['name']} is no longer a fixed point of the kernels "
                f"(residual {residuals[e['name']]:.1e}); rerun with --refs")
    return residuals

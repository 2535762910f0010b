"""docs/benchmarks/README.md from results.json and reference_points.json, through
templates/kernels.md and templates/kernels_parts.md."""
import numpy as np

from workflows.bench.render import fill, part, table
from workflows.bench.scene import (BOUNDARY, BOUNDARY_BRACKETS, DEFAULT_LABEL, START_PATTERNS,
                                   STEP_PLACEMENTS, TARGETS, rec_key)

# what each recommendation is for: (description, unit of its time)
REC_LABELS = {
    "orbit": ("orbit state (worst of 8 starts)", "orbit solve"),
    "mult": ("multipliers from the orbit solve (worst of 8 starts)", "orbit solve"),
    "mult_typ": ("multipliers from the orbit solve (median of 8 starts)", "orbit solve"),
    "mono": ("multipliers of one monodromy (worst of 16 step placements)", "monodromy"),
    "mono_typ": ("multipliers of one monodromy (median of 16 placements)", "monodromy"),
    "boundary": ("boundary location, relative (worst of 3 brackets)", "locate_boundary"),
}
HEADLINE_RECS = ("orbit", "mult", "mono", "boundary")
STAGED_RTOLS = (1e-8, 1e-10, 1e-12)     # the staged-vs-plain table's settings

# Issue 17's targets (issue 5's were 200x and 2x): a point >= PEER_TARGET x faster than scipy DOP853 at
# equal tolerance, the right-hand side within RHS_TARGET x a C -O3 loop of the same equations.
PEER_TARGET = 300
RHS_TARGET = 1.5


def _e(x):
    return "0" if x == 0 else (f"{x:.1e}" if np.isfinite(x) else "n/a")


def _ms(t):
    return f"{t * 1e3:.3g}"


def _spread(key, values, fmt):
    """{key: median, key_min: min, key_max: max}, formatted."""
    return {key: fmt(np.median(values)), f"{key}_min": fmt(min(values)), f"{key}_max": fmt(max(values))}


def _x(v):
    return f"{v:.0f}"


def _med(rows, key):
    return np.median([r[key] for r in rows])


def _part(key, **values):
    return part("kernels", key, **values)


def per_rhs_ns(wp):
    """(min, median, max) ns per RHS evaluation inside the DOP853 orbit solves."""
    per = [r["t_orbit"] / r["n_rhs_orbit"] * 1e9 for r in wp if r["method"] == "dop853"]
    return min(per), float(np.median(per)), max(per)


# --- header and headline ------------------------------------------------------------------------

def header_values(data):
    m, run = data["machine"], data["run"]
    lo, med, hi = per_rhs_ns(data["work_precision"])
    return dict(command=run["command"], mode=run["mode"], seconds=f"{data['seconds']:.0f}",
                cpu=m["cpu"], cores=m["cores"], usable_cores=m["usable_cores"],
                loadavg_start=m["loadavg_start"], loadavg_end=data["loadavg_end"], platform=m["platform"],
                python=m["python"], numpy=m["numpy"], scipy=m["scipy"], numba=m["numba"],
                gcc=m["gcc"] or "none", date=m["date"], repeats=run["repeats"], peer_repeats=run["peer_repeats"],
                per_rhs_min=f"{lo:.0f}", per_rhs_max=f"{hi:.0f}", per_rhs_median=f"{med:.0f}",
                per_rhs_noise=f"{(hi / lo - 1) * 100:.0f}")


def _target(met):
    return "met" if met else "NOT met"


def peer_headline_values(peer, hr):
    dop = [r for r in peer if r["method"] == "DOP853" and r["rtol"] == hr and np.isfinite(r["t_ours_same"])]
    same = [r["t"] / r["t_ours_same"] for r in dop]
    cpu = [r["t_cpu"] / r["t_ours_same"] for r in dop]
    interp = [r["t"] / r["t_ours_matched"] for r in peer if r["method"] == "DOP853" and r["rtol"] == hr]
    lsoda = [r["t"] / r["t_ours_matched"] for r in peer if r["method"] == "LSODA" and r["rtol"] == hr]
    plain = [r["t"] / r["t_ours_plain"] for r in dop]
    gain = [r["t_ours_same"] / r["t_ours_plain"] for r in dop]
    return dict(headline_rtol=f"{hr:.0e}", peer_target=_target(min(min(cpu), min(same)) >= PEER_TARGET), peer_target_x=PEER_TARGET,
                **_spread("same", same, _x), **_spread("cpu_ratio", cpu, _x), **_spread("interp", interp, _x),
                **_spread("lsoda", lsoda, _x), **_spread("plain", plain, _x),
                **_spread("staged_gain", gain, lambda v: f"{v:.2f}"))


def cfloor_medians(P):
    """Median ns per evaluation over the points, per c_floor column."""
    keys = ("c_rhs_ns", "numba_rhs_ns", "numba_force_ns", "flow_rk4_ns", "flow_dop853_ns", "c_var_ns",
            "numba_var_ns", "flow_rk4_var_ns", "flow_dop853_var_ns", "python_aug_ns")
    return {k[:-3]: _med(P, k) for k in keys}


def headline_cfloor(cfl):
    if not (cfl["points"] and cfl["compiler"]):
        return ""
    P, c = cfl["points"], cfloor_medians(cfl["points"])

    def ratio(key, base):
        return f"{np.median([r[key] / r[base] for r in P]):.1f}"
    rhs_ratio = np.median([r["numba_rhs_ns"] / r["c_rhs_ns"] for r in P])
    return _part("headline_cfloor", rhs_ratio=f"{rhs_ratio:.1f}", numba_rhs=f"{c['numba_rhs']:.0f}",
                 c_rhs=f"{c['c_rhs']:.1f}", rhs_target=_target(rhs_ratio <= RHS_TARGET), rhs_target_x=RHS_TARGET,
                 flow_rk4_ratio=ratio("flow_rk4_ns", "c_rhs_ns"), flow_dop853_ratio=ratio("flow_dop853_ns", "c_rhs_ns"),
                 flow_var_ratio=ratio("flow_dop853_var_ns", "c_var_ns"), flow_dop853_var=f"{c['flow_dop853_var']:.0f}",
                 c_var=f"{c['c_var']:.0f}", var_ratio=ratio("numba_var_ns", "c_var_ns"),
                 numba_var=f"{c['numba_var']:.0f}") + "\n"


def headline_recommended(rec):
    rows = []
    for key in HEADLINE_RECS:
        desc, unit = REC_LABELS[key]
        r = rec.get(rec_key(key, 1e-8))
        value = (f"{r['label']} (worst measured {_e(r['max_err'])}, {_ms(r['mean_time'])} ms per {unit})"
                 if r else "none of the settings")
        rows.append(f"| recommended: {desc} <= 1e-8 | {value} |")
    return "\n".join(rows)


def headline_values(data):
    d = [r for r in data["work_precision"] if r["label"] == DEFAULT_LABEL]
    return dict(**_spread("t_orbit", [r["t_orbit"] for r in d], _ms),
                **_spread("t_mono", [r["t_mono"] for r in d], _ms),
                newton_iterations=int(_med(d, "iterations")),
                **peer_headline_values(data["peer"], data["run"]["headline_rtol"]),
                headline_cfloor=headline_cfloor(data["c_floor"]),
                headline_recommended=headline_recommended(data["recommended"]))


# --- 1. references ------------------------------------------------------------------------------

def reference_table(refs, residuals):
    rows = []
    for e in refs["points"]:
        lam = complex(*e["multipliers"][0])
        rows.append([e["name"], f"{e['speed_hz']:g}", f"{e['clearance_m'] * 1e6:.1f}", f"{e['period_s'] * 1e3:.4f}",
                     ", ".join(f"{x:.6f}" for x in e["state"]), f"{lam.real:+.6f}{lam.imag:+.6f}j",
                     f"{e['max_abs']:.6f}", e["kind"], _e(e["error_estimate"]["state"]),
                     _e(e["error_estimate"]["multipliers"]), _e(residuals.get(e["name"], np.nan))])
    return table(["point", "speed [Hz]", "c [um]", "T [ms]", "state (x, y, x', y'), scaled", "leading multiplier",
                  "max abs", "what", "ref. error state", "ref. error multipliers", "residual today"], rows)


def checks_table(refs):
    points = refs["points"]
    rows = [[k] + [f"{_e(e['checks'][k]['state_diff'])} / {_e(e['checks'][k]['multiplier_diff'])}" for e in points]
            for k in points[0]["checks"]]
    scatter = [e["single_run_scatter"] for e in points]
    rows.append(["single DOP853 rtol 1e-13 monodromy vs reference (median / 90% / max of 40 step placements)"]
                + [f"{_e(s['median'])} / {_e(s['q90'])} / {_e(s['max'])}" for s in scatter])
    return table(["check"] + [e["name"] for e in points], rows)


def reference_values(refs, residuals):
    meth, b = refs["method"], refs["boundary"]
    chaotic = next(e for e in refs["points"] if "attractor" in e)
    a = chaotic["attractor"]
    return dict(
        ref_method=meth["reference"], ref_error_estimate=meth["error_estimate"],
        ref_other_checks=meth["other_checks"], ref_generated=refs["generated"], ref_seconds=refs["seconds"],
        reference_table=reference_table(refs, residuals), checks_table=checks_table(refs),
        lle=f"{a['lle_per_period']:.3f}", lle_stderr=f"{a['lle_stderr']:.3f}", lle_per_s=f"{a['lle_per_s']:.1f}",
        lle_how=a["how"], chaotic_max_abs=f"{chaotic['max_abs']:.3f}",
        boundary_speed=f"{b['speed_hz']:.10f}", boundary_clearance=f"{b['clearance_m'] * 1e6:.1f}",
        boundary_error=_e(b["error_estimate_relative"]),
        boundary_checks="; ".join(f"{k}: {_e(v)}" for k, v in b["checks_relative"].items()),
        boundary_how=b["how"])


# --- 2. work-precision --------------------------------------------------------------------------

def point_tables(wp, names):
    header = ["setting", "fails", "Newton it.", "RHS evals (orbit)", "orbit [ms]", "monodromy [ms]",
              "err orbit (timed / max)", "err mult (timed / median / max)", "err mono (timed / median / max)"]
    out = []
    for name in names:
        rows = [[r["label"], r["n_failed"], r["iterations"], r["n_rhs_orbit"], _ms(r["t_orbit"]), _ms(r["t_mono"]),
                 f"{_e(r['err_orbit'])} / {_e(r['err_orbit_max'])}",
                 f"{_e(r['err_mult'])} / {_e(r['err_mult_med'])} / {_e(r['err_mult_max'])}",
                 f"{_e(r['err_mono'])} / {_e(r['err_mono_med'])} / {_e(r['err_mono_max'])}"]
                for r in wp if r["point"] == name]
        out.append(f"**{name}**\n\n" + table(header, rows))
    return "\n\n".join(out)


def staged_table(wp, names):
    """Staged against plain Newton from the same 8 starts, DOP853 at the STAGED_RTOLS."""
    rows = []
    for name in names:
        for r in wp:
            q = r["plain"]
            if r["point"] != name or r["method"] != "dop853" or r["value"] not in STAGED_RTOLS:
                continue
            rows.append([name, r["label"], f"{r['n_rhs_orbit']} / {q['n_rhs_orbit']}",
                         f"{_e(r['err_orbit_max'])} / {_e(q['err_orbit_max'])}",
                         f"{_e(r['err_mult_med'])} / {_e(q['err_mult_med'])}",
                         f"{_e(r['err_mult_max'])} / {_e(q['err_mult_max'])}", f"{r['n_failed']} / {q['n_failed']}"])
    return table(["point", "setting", "RHS evals (timed start)", "err orbit (max)", "err mult (median)",
                  "err mult (max)", "fails"], rows)


def recommended_table(rec):
    rows = []
    for key, (desc, unit) in REC_LABELS.items():
        for target in TARGETS:
            r = rec.get(rec_key(key, target))
            rows.append([desc, f"{target:.0e}", r["label"] if r else "none of the settings",
                         _e(r["max_err"]) if r else "", f"{_ms(r['mean_time'])} ms per {unit}" if r else ""])
    return table(["quantity", "target", "cheapest setting", "worst measured error", "time"], rows)


def default_verdict(wp, rec):
    """The config default against the cheapest settings for a 1e-8 multiplier error."""
    d = [r for r in wp if r["label"] == DEFAULT_LABEL]
    d_typ, d_max = max(r["err_mult_med"] for r in d), max(r["err_mult_max"] for r in d)
    d_time = np.mean([r["t_orbit"] for r in d])
    worst8, typ8 = rec.get(rec_key("mult", 1e-8)), rec.get(rec_key("mult_typ", 1e-8))
    if worst8 is None:
        advice = _part("verdict_none")
    elif worst8["label"] == DEFAULT_LABEL:
        advice = _part("verdict_good")
    else:
        loose = [r for r in wp if r["label"] == "dop853 rtol=1e-08"]
        loosen = _part("verdict_loosen", saving=f"{(1 - np.mean([r['t_orbit'] for r in loose]) / d_time) * 100:.0f}",
                       error=_e(max(r["err_mult_max"] for r in loose))) if loose else ""
        typical = _part("verdict_typical", label=typ8["label"], time=_ms(typ8["mean_time"])) + " " if typ8 else ""
        advice = _part("verdict_costlier", label=worst8["label"], time=_ms(worst8["mean_time"]),
                       ratio=f"{worst8['mean_time'] / d_time:.2f}", typical=typical,
                       below=f"{1e-8 / max(d_typ, 1e-16):.0f}",
                       digits=f"{np.log10(max(d_max, 1e-16) / max(d_typ, 1e-16)):.1f}",
                       extra=f"{(worst8['mean_time'] / d_time - 1) * 100:.0f}", loosen=loosen)
    return _part("verdict", time=_ms(d_time), typical=_e(d_typ), worst=_e(d_max),
                 mono=_e(max(r["err_mono_max"] for r in d)), advice=advice)


def boundary_table(bwp):
    return table(["setting", "time [ms]", "orbit solves", "boundary [Hz]", "relative error (timed / worst)"],
                 [[r["label"], _ms(r["t"]), r["evaluations"], f"{r['speed_hz']:.10f}",
                   f"{_e(r['err'])} / {_e(r['err_max'])}"] for r in bwp])


def work_precision_values(data, names):
    wp = data["work_precision"]
    return dict(start_pattern=", ".join(f"{x:+g}" for x in START_PATTERNS[0]), n_starts=len(START_PATTERNS),
                n_placements=len(STEP_PLACEMENTS), point_tables=point_tables(wp, names),
                staged_table=staged_table(wp, names), early_rtol=f"{data['run']['early_rtol']:.0e}",
                early_switch=f"{data['run']['early_switch']:.0e}",
                bracket_lo=f"{BOUNDARY['bracket'][0]:g}", bracket_hi=f"{BOUNDARY['bracket'][1]:g}",
                other_brackets=", ".join(f"{a:g}-{b:g}" for a, b in BOUNDARY_BRACKETS[1:]),
                boundary_table=boundary_table(data["boundary"]),
                recommended_table=recommended_table(data["recommended"]),
                default_verdict=default_verdict(wp, data["recommended"]))


# --- 3. peer, 4. C floor ------------------------------------------------------------------------

def _peer_row(r):
    dop = r["method"] == "DOP853"
    same = np.isfinite(r["t_ours_same"])
    return [r["point"], r["method"], f"{r['rtol']:.0e}", f"{r['t'] * 1e3:.0f} ({r['t_cpu'] * 1e3:.0f})",
            f"{r['iterations']}{'' if r['converged'] else ' (not conv.)'}", r["nfev"],
            f"{_e(r['err_orbit'])} / {_e(r['err_mult'])}", _ms(r["t_ours_same"]) if same else "n/a",
            r["n_rhs_ours_same"] if dop else "",
            f"{_e(r['ours_same_err_orbit'])} / {_e(r['ours_same_err_mult'])}" if dop else "",
            f"{r['t'] / r['t_ours_same']:.0f}x" if same else "n/a",
            _ms(r["t_ours_plain"]) if dop else "n/a", f"{r['t'] / r['t_ours_plain']:.0f}x" if dop else "n/a",
            _ms(r["t_ours_matched"]) + ("" if r["matched_inside"] else " (clamped)"),
            f"{r['t'] / r['t_ours_matched']:.0f}x"]


def peer_values(data):
    fd = data["fd_check"]
    fd_text = _part("finite_differences", point=fd["point"], rtol=f"{fd['rtol']:.0e}", t_fd=f"{fd['t_fd']:.2f}",
                    nfev_fd=fd["nfev_fd"], err_fd=_e(fd["err_mult_fd"]), t_aug=f"{fd['t_aug']:.2f}",
                    nfev_aug=fd["nfev_aug"], err_aug=_e(fd["err_mult_aug"])) + "\n\n" if fd else ""
    header = ["point", "scipy", "rtol", "scipy [ms] (CPU)", "Newton it.", "RHS calls", "err orbit / mult (scipy)",
              "ours, same [ms]", "RHS evals (ours)", "err orbit / mult (ours)", "ratio same", "ours plain [ms]",
              "ratio plain",
              "ours, interp. [ms]", "ratio interp."]
    return dict(finite_differences=fd_text, peer_table=table(header, [_peer_row(r) for r in data["peer"]]))


def _cfloor_row(r):
    checksum = (f"{_e(r['checksum_rel_diff_rhs'])} / {_e(r['checksum_rel_diff_var'])}"
                if "checksum_rel_diff_rhs" in r else "n/a")
    return [r["point"], f"{r['c_rhs_ns']:.1f}"] + [f"{r[k]:.0f}" for k in (
        "numba_rhs_ns", "numba_force_ns", "flow_rk4_ns", "flow_dop853_ns", "c_var_ns", "numba_var_ns",
        "flow_rk4_var_ns", "flow_dop853_var_ns", "python_rhs_ns", "python_aug_ns")] + [checksum]


def cfloor_values(data):
    cfl, run, io = data["c_floor"], data["run"], data["c_floor"]["integrator_only"]
    method = (_part("cfloor_skipped", skipped=cfl["skipped"]) if cfl["skipped"] else
              _part("cfloor_method", compiler=cfl["compiler"], n_states=run["n_states"], passes=run["passes"]))
    cols = ["point", "C rhs", "Numba models.rhs loop", "Numba ring_load (scalars)", "flow rk4 / n_rhs",
            "flow dop853 / n_rhs", "C var.", "Numba derivative var.", "flow rk4 var. / n_rhs",
            "flow dop853 var. / n_rhs", "python rhs", "python aug. rhs", "checksum diff rhs / var"]
    return dict(cfloor_method=method, cfloor_table=table(cols, [_cfloor_row(r) for r in cfl["points"]]),
                io_dop853=f"{io['flow_dop853_ns']:.0f}", io_dop853_var=f"{io['flow_dop853_var_ns']:.0f}",
                io_rk4=f"{io['flow_rk4_ns']:.0f}", io_rk4_var=f"{io['flow_rk4_var_ns']:.0f}",
                io_derivative=f"{io['derivative_var_ns']:.0f}")


# --- interpretation -----------------------------------------------------------------------------

def _references_bullet(refs):
    pts = refs["points"]
    return _part("references", state=_e(max(e["error_estimate"]["state"] for e in pts)),
                 multipliers=_e(max(e["error_estimate"]["multipliers"] for e in pts)),
                 scatter=_e(max(e["single_run_scatter"]["max"] for e in pts)))


def _dop853_bullet(wp):
    dop = [r for r in wp if r["method"] == "dop853" and r["status"] == 0]
    ratio = np.median([r["err_orbit"] / r["value"] for r in dop if r["err_orbit"] > 0])
    tail = np.median([r["err_mono_max"] / max(r["err_mono_med"], 1e-16) for r in dop])
    cost = (np.median([r["t_orbit"] for r in dop if r["value"] == 1e-12])
            / np.median([r["t_orbit"] for r in dop if r["value"] == 1e-8]))
    return _part("dop853", ratio=f"{ratio:.1g}", tail=f"{tail:.0f}", cost=f"{cost:.1f}")


def _rk4_order(rows, key):
    """Observed convergence order of `key` between the fewest and the most steps."""
    rs = sorted((r for r in rows if r[key] > 0), key=lambda r: r["value"])
    if len(rs) < 2:
        return np.nan
    return np.log(rs[0][key] / rs[-1][key]) / np.log(rs[-1]["value"] / rs[0]["value"])


def _rk4_bullet(wp, names):
    rk = [r for r in wp if r["method"] == "rk4"]
    o_s = [_rk4_order([r for r in rk if r["point"] == n], "err_orbit") for n in names]
    o_m = [_rk4_order([r for r in rk if r["point"] == n], "err_mono") for n in names]
    return _part("rk4", orbit_lo=f"{np.nanmin(o_s):.1f}", orbit_hi=f"{np.nanmax(o_s):.1f}",
                 mult_lo=f"{np.nanmin(o_m):.1f}", mult_hi=f"{np.nanmax(o_m):.1f}")


def _newton_bullet(wp):
    fails = [r for r in wp if r["n_failed"]]
    if not fails:
        return _part("newton_converged")
    return _part("newton_failed", failed=sum(r["n_failed"] for r in fails), solves=8 * len(wp),
                 where=", ".join(sorted({r["label"] + " @ " + r["point"] for r in fails})))


def _boundary_bullet(bwp):
    bd = [r for r in bwp if r["method"] == "dop853"]
    tight = min(bd, key=lambda r: r["value"])
    dflt = next(r for r in bd if r["label"] == DEFAULT_LABEL)
    ev = [r["evaluations"] for r in bd]
    return _part("boundary", ev_min=min(ev), ev_max=max(ev), tight_label=tight["label"], tight_time=_ms(tight["t"]),
                 tight_evaluations=tight["evaluations"], tight_error=_e(tight["err_max"]),
                 default_time=_ms(dflt["t"]), default_evaluations=dflt["evaluations"],
                 default_error=_e(dflt["err_max"]))


def _peer_bullet(peer, c, hr, early_rtol):
    pd = [r for r in peer if r["method"] == "DOP853" and r["rtol"] == hr]
    rs = [r["t"] / r["t_ours_same"] for r in pd if np.isfinite(r["t_ours_same"])]
    rp = [r["t"] / r["t_ours_plain"] for r in pd]
    ours_per = np.median([r["t_ours_same"] / max(r["n_rhs_ours_same"], 1) * 1e9 for r in pd])
    target = (_part("peer_met") if min(rs) >= PEER_TARGET else
              _part("peer_not_met", target=PEER_TARGET, needed=f"{ours_per * min(rs) / PEER_TARGET:.0f}"))
    return _part("peer", calls=f"{np.median([r['nfev'] / max(r['n_rhs_ours_plain'], 1) for r in pd]):.2f}",
                 scipy_us=f"{np.median([r['t'] / max(r['nfev'], 1) * 1e9 for r in pd]) / 1e3:.1f}",
                 python_us=f"{c['python_aug'] / 1e3:.0f}",
                 ours_ns=f"{np.median([r['t_ours_plain'] / max(r['n_rhs_ours_plain'], 1) * 1e9 for r in pd]):.0f}",
                 plain=f"{np.median(rp):.0f}", plain_lo=f"{min(rp):.0f}", plain_hi=f"{max(rp):.0f}",
                 staged_calls=f"{np.median([r['n_rhs_ours_same'] / max(r['n_rhs_ours_plain'], 1) for r in pd]):.2f}",
                 early_rtol=f"{early_rtol:.0e}", median=f"{np.median(rs):.0f}",
                 lo=f"{min(rs):.0f}", hi=f"{max(rs):.0f}", target=target, peer_target_x=PEER_TARGET)


def _cfloor_bullets(c, io, per_rhs_median):
    loop, nv = c["numba_rhs"], c["numba_var"]
    floor = _part("cfloor", force=f"{c['numba_force']:.0f}", c=f"{c['c_rhs']:.0f}",
                  force_ratio=f"{c['numba_force'] / c['c_rhs']:.1f}", loop=f"{loop:.0f}",
                  loop_ratio=f"{loop / c['c_rhs']:.1f}", loop_target=_target(loop / c["c_rhs"] <= RHS_TARGET), rhs_target_x=RHS_TARGET,
                  nv=f"{nv:.0f}", cv=f"{c['c_var']:.0f}", var_ratio=f"{nv / c['c_var']:.1f}",
                  frk=f"{c['flow_rk4']:.0f}", fdp=f"{c['flow_dop853']:.0f}", fvr=f"{c['flow_rk4_var']:.0f}",
                  fv=f"{c['flow_dop853_var']:.0f}")
    limits = _part("limits", loop=f"{loop:.0f}", c=f"{c['c_rhs']:.0f}", io_var=f"{io['flow_dop853_var_ns']:.0f}",
                   io_derivative=f"{io['derivative_var_ns']:.0f}",
                   io_own=f"{max(io['flow_dop853_var_ns'] - io['derivative_var_ns'], 0):.0f}",
                   io_own_rk4=f"{max(io['flow_rk4_var_ns'] - io['derivative_var_ns'], 0):.0f}",
                   per_rhs=f"{per_rhs_median:.0f}", nv=f"{nv:.0f}", integrator=f"{max(per_rhs_median - nv, 0):.0f}")
    return [floor, limits]


def interpretation(data, refs):
    wp, cfl = data["work_precision"], data["c_floor"]
    names = [e["name"] for e in refs["points"]]
    c = cfloor_medians(cfl["points"])
    bullets = [_references_bullet(refs), _dop853_bullet(wp), _rk4_bullet(wp, names), _newton_bullet(wp),
               _boundary_bullet(data["boundary"]), "- " + default_verdict(wp, data["recommended"]),
               _peer_bullet(data["peer"], c, data["run"]["headline_rtol"], data["run"]["early_rtol"])]
    if cfl["compiler"]:
        bullets += _cfloor_bullets(c, cfl["integrator_only"], per_rhs_ns(wp)[1])
    return "\n".join(bullets)


def render_readme(data, refs):
    """The text of README.md: `data` as in results.json, `refs` as in reference_points.json."""
    names = [e["name"] for e in refs["points"]]
    return fill("kernels", **header_values(data), **headline_values(data),
                **reference_values(refs, data["reference_recheck"]), **work_precision_values(data, names),
                **peer_values(data), **cfloor_values(data), interpretation=interpretation(data, refs))

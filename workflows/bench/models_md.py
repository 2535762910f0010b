"""models.md from models.json (templates/models.md): tables and the headline."""
import numpy as np

from workflows.bench import render

TARGET = 1.5            # Numba right-hand side / C floor (issue 17, item 3)


def _e(x):
    return f"{x:.1e}"


def _ns(x):
    return "-" if x is None or not np.isfinite(x) else f"{x:.0f}" if x >= 100 else f"{x:.1f}"


def _points(data):
    rows = []
    for pt in data["points"]:
        r = pt["reference"]
        what = (f"orbit over one forcing period (T = {r['period_s'] * 1e3:.4g} ms)" if r["j"] is None else
                f"q_{r['j']} = {r['amplitude']:.3g} um, period {r['period'] * r['period_s'] * 1e3:.5g} ms")
        rows.append([pt["name"], pt["model"], pt["kind"], what, f"{r['max_abs']:.6f}",
                     f"{_e(r['error_state'])} / {_e(r['error_period'])} / {_e(r['error_mult'])}",
                     "yes" if r["converged"] else "NO"])
    return render.table(["point", "model", "what", "solved for", "max abs multiplier",
                         "ref. error state / period / multipliers", "ref. converged"], rows)


def _solves(data):
    rows = []
    for pt in data["points"]:
        for r in pt["rows"]:
            o, s = r["ours"], r["scipy"]
            rows.append([pt["name"], f"{r['rtol']:g}", f"{r['t_scipy'] * 1e3:.0f} ({r['t_scipy_cpu'] * 1e3:.0f})",
                         f"{r['t_ours'] * 1e3:.3g} ({r['t_ours_cpu'] * 1e3:.3g})", f"**{r['ratio']:.0f}x** ({r['ratio_cpu']:.0f}x)",
                         f"{s['iterations']} / {o['iterations']}", f"{s['n_rhs']} / {o['n_rhs']}",
                         f"{_e(s['err_state'])} / {_e(o['err_state'])}", ("-" if pt["reference"]["j"] is None else f"{_e(s['err_period'])} / {_e(o['err_period'])}"),
                         f"{_e(s['err_mult'])} / {_e(o['err_mult'])}",
                         "yes" if s["converged"] and o["converged"] else "NO"])
    return render.table(["point", "rtol", "scipy [ms] (CPU)", "ours [ms] (CPU)", "ratio (CPU)", "iterations scipy / ours",
                         "RHS calls scipy / ours", "err state scipy / ours", "err period scipy / ours",
                         "err multipliers scipy / ours", "both converged"], rows)


def _ratio(f, key):
    """Numba / C of `key` (rhs, rhs_steps: both against the C rhs; var)."""
    return f[f"numba_{key}_ns"] / f[f"c_{key.split('_')[0]}_ns"]


def _floor(data):
    rows = []
    for pt in data["points"]:
        f = pt["floor"]
        rows.append([pt["name"], _ns(f["c_rhs_ns"]), _ns(f["numba_rhs_ns"]), f"**{_ratio(f, 'rhs'):.2f}x**",
                     _ns(f["numba_rhs_steps_ns"]), f"{_ratio(f, 'rhs_steps'):.2f}x",
                     _ns(f["flow_dop853_ns"]), _ns(f["flow_rk4_ns"]), _ns(f["c_var_ns"]), _ns(f["numba_var_ns"]),
                     f"{_ratio(f, 'var'):.2f}x", _ns(f["numba_var_const_ns"]),
                     f"{f['numba_var_const_ns'] / f['c_var_ns']:.2f}x", _ns(f["flow_dop853_var_ns"]), _ns(f["flow_rk4_var_ns"]),
                     _ns(f["python_rhs_ns"]), _ns(f["python_aug_ns"])])
    return render.table(["point", "C rhs", "Numba rhs loop", "Numba / C", "Numba rhs, step-loop style", "Numba / C",
                         "flow dop853 / n_rhs", "flow rk4 / n_rhs",
                         "C var.", "Numba var. loop", "Numba / C var.", "Numba var., constant-size J Phi",
                         "constant-size / C var.", "flow dop853 var. / n_rhs",
                         "flow rk4 var. / n_rhs", "python rhs", "python aug. rhs"], rows)


def _check(data):
    rows = [[pt["name"], pt["floor"]["check"]["n_states"], _e(pt["floor"]["check"]["rhs"]),
             _e(pt["floor"]["check"]["var_f"]), _e(pt["floor"]["check"]["var_tangent"])]
            for pt in data["points"] if "check" in pt["floor"]]
    return render.table(["point", "states", "rhs", "var. derivative: f", "var. derivative: J Phi"], rows)


def _headline(data):
    lines = []
    for pt in data["points"]:
        f, best = pt["floor"], pt["rows"][-1]
        ratio = _ratio(f, "rhs_steps")
        lines.append(f"- **{pt['name']}** ({pt['model']}): scipy DOP853 / ours at rtol {best['rtol']:g} = "
                     f"**{best['ratio']:.0f}x** by wall time, {best['ratio_cpu']:.0f}x by CPU time (errors scipy / ours: state {_e(best['scipy']['err_state'])} / "
                     f"{_e(best['ours']['err_state'])}, multipliers {_e(best['scipy']['err_mult'])} / "
                     f"{_e(best['ours']['err_mult'])}); right-hand side Numba / C = **{ratio:.2f}x** as the step loops "
                     f"call it ({_ratio(f, 'rhs'):.2f}x in a plain njit loop) "
                     f"(target {TARGET}x: {'met' if ratio <= TARGET else 'NOT met'}); variational derivative "
                     f"{_ratio(f, 'var'):.2f}x C.")
    return "\n".join(lines)


def _per_eval(pt):
    """(scipy us per RHS call, ours ns per evaluation) of the tightest row."""
    r = pt["rows"][-1]
    return r["t_scipy"] / r["scipy"]["n_rhs"] * 1e6, r["t_ours"] / r["ours"]["n_rhs"] * 1e9


def _interpretation(data):
    pts = data["points"]
    err_gap = max(max(r["scipy"]["err_state"], r["ours"]["err_state"]) /
                  max(min(r["scipy"]["err_state"], r["ours"]["err_state"]), 1e-16) for pt in pts for r in pt["rows"])
    ratios = [r["ratio"] for pt in pts for r in pt["rows"]]
    per_eval = "; ".join(f"{pt['name']} {a:.1f} us vs {b:.0f} ns" for pt in pts for a, b in [_per_eval(pt)])
    rhs = ", ".join(f"{pt['name']} {_ratio(pt['floor'], 'rhs_steps'):.2f}x ({_ratio(pt['floor'], 'rhs'):.2f}x)"
                    for pt in pts)
    var = ", ".join(f"{pt['name']} {_ratio(pt['floor'], 'var'):.2f}x" for pt in pts)
    const = ", ".join(f"{pt['name']} {pt['floor']['numba_var_const_ns'] / pt['floor']['c_var_ns']:.2f}x C"
                      for pt in pts)
    return "\n".join([
        f"- **Equal tolerance holds**: at every point and rtol both solvers converge in the same number of "
        f"iterations with nearly the same right-hand-side count, and their state errors against the reference "
        f"differ by at most {err_gap:.0f}x (step-placement scatter), so the ratios compare equal accuracy.",
        f"- **Ratios** {min(ratios):.0f}-{max(ratios):.0f}x: a point costs scipy per right-hand-side call, "
        f"against ours per evaluation (tightest rtol): {per_eval}. The peer's numpy augmented system costs "
        f"tens of us per call whatever the size (interpreter overhead), while ours grows with n + n^2 "
        f"(the variational system has {', '.join(sorted({str(pt['floor']['n_var']) for pt in pts if 'n_var' in pt['floor']}))} "
        f"components against Jeffcott's 20): hence lower ratios than the Jeffcott model's.",
        f"- **Right-hand side vs C** (target {TARGET}x), step-loop style (plain njit loop): {rhs}. "
        f"symmetric4 and asymmetric5's `rhs` are `forceinline=True`: Numba compiles each once and marks it "
        f"LLVM `alwaysinline`, and LLVM inlines it into the step loops, which saves a call (23 arguments, "
        f"17 on the stack, and a status check) that matters against symmetric4's ~10 ns of arithmetic; "
        f"`error_model=\"numpy\"` drops a zero-division check and exception branch per evaluation; the "
        f"accelerations are summed in the C floor's order (the same operations: the check below). Before "
        f"(b0944a9, this benchmark, quiet machine): symmetric4 1.66x, asymmetric5 1.14x. Measured one "
        f"revision at a time (2026-11-24, load 2-4, step-loop ns, best of 3 x 50 passes): symmetric4 "
        f"15.6-17.1 -> 12.8-13.8 ns (C 9.1-10.2), asymmetric5 23.9-24.6 -> 20.2-21.9 ns (C 19.0-21.4), "
        f"the state-only `flow` 2-5 ns faster per evaluation (of 25-60 ns). The trade: no compile time "
        f"(symmetric4's first backbone compiles 15.3 s CPU before, 14.8 s after, [compile.md](compile.md)), "
        f"whereas Numba's `inline=\"always\"` on the same two functions (revision 28c7349, the same ns) "
        f"makes it 23.6 s: it types and lowers the body again at every call site. `forceinline` on "
        f"rhs_jac too gave no gain beyond the noise in the variational flows (250-700 ns per evaluation, "
        f"where a call's few ns are about 1 %): not done. A ratio below 1 means that LLVM compiled the "
        f"loop better than gcc did the plain C: the floor is the same equations written plainly in C, not "
        f"a bound.",
        "- **What remains of symmetric4's gap**: gcc vectorizes the four acceleration rows (AVX, after a "
        "runtime check that du overlaps neither u nor p); Numba runs LLVM without its SLP vectorizer "
        "(`NUMBA_SLP_VECTORIZE=0`; set to 1 it measured no change, presumably as the overlap cannot "
        "be excluded at compile time). The C time also depends on where the process's arrays lie: 8.3-10.9 ns "
        "over 50 runs of the same C program (load 1.1-1.4), of which this benchmark "
        "keeps the best of two. The step-loop loop copies each state into a work array (as a stage is "
        "written before each evaluation; about 0.7 ns) while C reads it in place: given the same copy, "
        "C costs 12-14 ns (presumably a store-forwarding stall of its vector loads), so the in-place C loop is the "
        "harder floor and the one kept. The plain loop differs from the step-loop one by the reference "
        "counting of a row view per call, which the step loops are compiled without.",
        f"- **Variational derivative vs C**: {var} (no target; the Jeffcott model's is 1.3x). Why: the kernels' "
        f"tangent product J Phi runs with the state size as a runtime value above 4 states "
        f"(`models.generate.FAST_PATH_MAX_STATE`: constant-size, unrolled copies only up to 4, to bound compile "
        f"time), the C code with the size known at compile time. The same loop with J Phi at a constant size "
        f"(column 'constant-size') costs {const}: a constant-size copy for these models' sizes (8, 10) in the "
        f"generated dispatch would bring the variational derivative, most of an evaluation inside the "
        f"variational `flow`, to about the C floor (at some compile time; not changed here).",
        "- **Conservative multipliers**: the pair at +1 of a conservative orbit (phase and energy direction) "
        "is a Jordan block: its eigenvalues move by about the square root of the monodromy's error, so "
        "multiplier errors of 1e-8..1e-6 at rtol 1e-10..1e-12 are the same for both solvers and say nothing "
        "of the solve's accuracy; the state and period errors do.",
    ])


def markdown(data):
    m = data["machine"]
    return render.fill(
        "models", command=data["command"].strip(), date=data["date"], mode=data["mode"], seconds=f"{data['seconds']:.0f}",
        cpu=m["cpu"], cores=f"{m['cores']} ({m['usable_cores']})", load=data["load"], platform=m["platform"],
        versions=f"{m['python']} / {m['numpy']} / {m['scipy']} / {m['numba']}",
        compiler=data["points"][0]["floor"].get("compiler") or "none (C floor skipped)",
        headline=_headline(data), points=_points(data), ref_rtol=f"{data['ref_rtol']:g}",
        ref_check_rtol=f"{data['ref_check_rtol']:g}", repeats=data["repeats"], solves=_solves(data),
        n_states=data["points"][0]["floor"]["n_states"], passes=data["passes"], floor=_floor(data),
        check=_check(data), interpretation=_interpretation(data))

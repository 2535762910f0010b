"""What `rotorsweep point` prints: a point's row (rotorsweep.pipeline.point, or the attractor
run's) as the JSON result and as text; non-finite numbers are None (JSON null)."""
import numpy as np


def result_of(row, attractor):
    """The point's result dict (`--json`): the orbit, its multipliers and bifurcation; the
    attractor's diagnostics where `attractor`; the torus where the point has one."""
    from rotorsweep.pipeline import schema, torus_points

    lam = [[float(re), float(im)] for re, im in zip(row["multiplier_real"], row["multiplier_imag"])]
    result = {
        "status": schema.ORBIT_STATUS[row["orbit_status"]],
        "reason": schema.ORBIT_REASON[row["orbit_reason"]],
        "newton_iterations": int(row["newton_iterations"]),
        "residual": _num(row["residual"]),
        "multipliers": [[_num(a), _num(b)] for a, b in lam],
        "max_abs_multiplier": _num(row["max_abs_multiplier"]),
        "stable": bool(row["stable"] == 1),
        "bifurcation": schema.BIFURCATION[row["bifurcation"]] if row["bifurcation"] >= 0 else "none",
        "period": float(row["forcing_period"]),
    }
    if "contact_angle_used" in row:
        result["contact_angle"] = float(row["contact_angle_used"])
    if attractor:
        result["attractor"] = _attractor_result(row)
    torus = torus_points.summary(row)
    if torus:
        result["torus"] = torus
    return result


def text(result):
    """The result as the text `point` prints without --json."""
    from rotorsweep.pipeline import torus_points

    parts = [_point_text(result)]
    if "torus" in result:
        parts.append(torus_points.summary_text(result["torus"]))
    if "attractor" in result:
        parts.append(_attractor_text(result["attractor"]))
    return "\n".join(parts)


def _attractor_result(row):
    from rotorsweep.pipeline import schema

    code, k, method = int(row["attractor"]), int(row["period"]), int(row["lle_method"])
    lam = [[_num(re), _num(im)] for re, im in zip(row["attractor_multiplier_real"], row["attractor_multiplier_imag"])]
    mods = np.hypot(row["attractor_multiplier_real"], row["attractor_multiplier_imag"])
    return {
        "class": schema.ATTRACTOR[code] if 0 <= code < len(schema.ATTRACTOR) else None,
        "period": k,
        "lle": _num(row["lle"]),
        "lle_stderr": _num(row["lle_stderr"]),
        "lle_method": schema.LLE_METHOD[method] if 0 <= method < len(schema.LLE_METHOD) else None,
        "lyapunov_exponents": [_num(x) for x in row["lyapunov_exponents"]],
        "multipliers": lam,
        "max_abs_multiplier": _num(np.nanmax(mods)) if np.isfinite(mods).any() else None,
    }


def _attractor_text(a):
    k = a["period"]
    if a["class"] == "periodic":
        period = f"{k} forcing period{'s' if k != 1 else ''}" if k > 0 else "not resolved (up to max_period)"
    else:
        period = "-"
    if a["lle"] is None:
        lle = "-"
    else:
        err = f" +- {a['lle_stderr']:.3g}" if a["lle_stderr"] is not None else ""
        lle = f"{a['lle']:+.6g}{err} 1/s ({a['lle_method']})"
    lines = [
        f"attractor         {a['class']}",
        f"attractor period  {period}",
        f"largest Lyapunov  {lle}",
        "Lyapunov spectrum " + ", ".join("-" if x is None else f"{x:+.5g}" for x in a["lyapunov_exponents"]) + " 1/s",
        "attractor multipliers (orbit over k forcing periods; real, imag, modulus)",
    ]
    if a["max_abs_multiplier"] is None:
        lines.append("  - (no periodic attractor)")
    else:
        for re, im in a["multipliers"]:
            lines.append("  -" if re is None else f"  {re:+.10f} {im:+.10f}  |{np.hypot(re, im):.10f}|")
    return "\n".join(lines)


def _num(x):
    x = float(x)
    return x if np.isfinite(x) else None


def _point_text(r):
    lines = [
        f"status            {r['status']} ({r['reason']})",
        f"newton iterations {r['newton_iterations']}",
        f"residual          {r['residual']:.3e}" if r["residual"] is not None else "residual          -",
        f"forcing period    {r['period']:.6e} s",
    ]
    if "contact_angle" in r:
        lines.append(f"contact angle     {r['contact_angle']:.4f} deg")
    lines.append("multipliers       (real, imag, modulus)")
    for re, im in r["multipliers"]:
        if re is None:
            lines.append("  -")
        else:
            lines.append(f"  {re:+.10f} {im:+.10f}  |{np.hypot(re, im):.10f}|")
    mu = r["max_abs_multiplier"]
    lines.append(f"max |multiplier|  {mu:.10f}" if mu is not None else "max |multiplier|  -")
    verdict = "stable" if r["stable"] else f"unstable ({r['bifurcation']})"
    lines.append(f"periodic orbit    {verdict if r['status'] == 'converged' else 'not found'}")
    return "\n".join(lines)

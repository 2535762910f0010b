"""What a shortcut of the attractor diagnostics costs in accuracy: a fast run against a reference
run of the same scene (same grid, same continuation), point by point.

- class agreement: per reference class, how many points the fast run puts in another class,
  and where (speed, clearance), each marked `near` when it lies next to a change of the
  reference attractor (class or period differs within NEAR_POINTS grid speeds) or within
  NEAR_HZ of a refined stability boundary of the periodic orbit;
- period agreement where both runs found a periodic attractor;
- exponent agreement: both integrated (Benettin), |a - b| <= 3 sqrt(se_a^2 + se_b^2); one
  derived (from the period-k orbit's multipliers, no statistical error) and one integrated,
  within 3 standard errors of the integrated one or 1e-3 relative (the 'derive when stable'
  criterion of attractor_cost); both derived: the moduli of the multipliers, ln|lambda| =
  lle k T, to 1e-5 (the same orbit refined by Newton from two states: the monodromy over k T
  at rtol 1e-10, across the contact kinks of every period, carries an error of 1e-7 to a few
  1e-6).
"""
import numpy as np

from rotorsweep.kernels import attractor as at

NEAR_POINTS = 2          # grid speeds either side
NEAR_HZ = 0.5
LISTED = 12              # disagreements listed per comparison


def _flat(ds, name, suffix=""):
    """A variable on the (speed, clearance) grid as a flat array, speed fastest."""
    return ds[name + suffix].broadcast_like(ds["attractor"]).transpose("clearance", "speed").values.ravel()


def _grid(ds):
    speed, clearance = ds["speed"].values, ds["clearance"].values
    return np.tile(speed, clearance.size), np.repeat(clearance, speed.size), speed.size


def class_names():
    return {code: name.replace("_", " ") for code, name in enumerate(at.ATTRACTOR)}


def _near(ref, suffix):
    """Points next to a change of the reference attractor or a stability boundary."""
    att, k = _flat(ref, "attractor", suffix), _flat(ref, "period", suffix)
    speed, clearance, n = _grid(ref)
    key = att.astype(np.int64) * 10000 + k
    near = np.zeros(key.size, bool)
    for shift in range(1, NEAR_POINTS + 1):
        same_line = (np.arange(key.size) % n) >= shift
        change = np.zeros(key.size, bool)
        change[shift:] = (key[shift:] != key[:-shift]) & same_line[shift:]
        near |= change
        near[:-shift] |= change[shift:]
    if "boundary_speed" in ref:
        for fs, fc in zip(ref["boundary_speed"].values, ref["boundary_clearance"].values):
            near |= (clearance == fc) & (np.abs(speed - fs) <= NEAR_HZ)
    return near


def _exponents_agree(fast, ref, suffix):
    a, b = _flat(fast, "lle", suffix), _flat(ref, "lle", suffix)
    sa, sb = _flat(fast, "lle_stderr", suffix), _flat(ref, "lle_stderr", suffix)
    da, db = _flat(fast, "lle_method", suffix) == 1, _flat(ref, "lle_method", suffix) == 1
    both = np.isfinite(a) & np.isfinite(b)
    diff = np.abs(a - b)
    periods = _flat(ref, "forcing_period") * np.maximum(_flat(ref, "period", suffix), 1)
    ok = np.where(da & db, diff * periods <= 1e-5,
                  np.where(da | db, (diff <= 3 * np.maximum(sa, sb)) | (diff <= 1e-3 * np.abs(b)),
                           diff <= 3 * np.hypot(sa, sb)))
    kinds = {"both derived": da & db, "derived vs integrated": da ^ db, "both integrated": ~da & ~db}
    return {name: {"points": int((m & both).sum()), "agree": int((ok & m & both).sum())} for name, m in kinds.items()}


def compare(fast, ref, suffix=""):
    """Agreement of `fast` with `ref` (cubes of the same scene) for the sweep `suffix`."""
    fa, ra = _flat(fast, "attractor", suffix), _flat(ref, "attractor", suffix)
    fk, rk = _flat(fast, "period", suffix), _flat(ref, "period", suffix)
    speed, clearance, _ = _grid(ref)
    near = _near(ref, suffix)
    names = class_names()
    per_class = {}
    for code in np.unique(ra):
        m = ra == code
        per_class[names[int(code)]] = {"points": int(m.sum()), "disagree": int((m & (fa != ra)).sum()),
                                       "near": int((m & (fa != ra) & near).sum())}
    differ = np.flatnonzero((fa != ra) | ((fa == at.PERIODIC) & (ra == at.PERIODIC) & (fk != rk)))
    where = [{"speed": float(speed[i]), "clearance_um": float(1e6 * clearance[i]),
              "reference": _label(ra[i], rk[i], names), "fast": _label(fa[i], fk[i], names), "near": bool(near[i])}
             for i in differ]
    both_periodic = (fa == at.PERIODIC) & (ra == at.PERIODIC)
    return {"points": int(fa.size), "classes": per_class,
            "periodic_both": int(both_periodic.sum()), "period_agree": int((both_periodic & (fk == rk)).sum()),
            "exponents": _exponents_agree(fast, ref, suffix), "differences": where,
            "differences_near": int(sum(w["near"] for w in where))}


def _label(code, k, names):
    return f"period {k}" if code == at.PERIODIC and k > 0 else names[int(code)]


def markdown(cmp):
    """The tables of one comparison."""
    rows = ["| reference class | points | other class in the fast run | of which near a bifurcation |",
            "| --- | --- | --- | --- |"]
    rows += [f"| {name} | {c['points']} | {c['disagree']} | {c['near']} |" for name, c in cmp["classes"].items()]
    rows += ["", f"Period: {cmp['period_agree']} of {cmp['periodic_both']} points periodic in both runs have "
                 "the same k.", "", "| largest exponent | points | within its error bar |", "| --- | --- | --- |"]
    rows += [f"| {name} | {e['points']} | {e['agree']} |" for name, e in cmp["exponents"].items() if e["points"]]
    diffs = cmp["differences"]
    rows += ["", f"Points whose attractor (class or period) differs: {len(diffs)}, "
                 f"{cmp['differences_near']} of them near a bifurcation"
             + (":" if diffs else ".")]
    if diffs:
        rows += ["", "| speed [Hz] | clearance [um] | reference | fast | near a bifurcation |", "| --- | --- | --- | --- | --- |"]
        rows += [f"| {d['speed']:.1f} | {d['clearance_um']:.1f} | {d['reference']} | {d['fast']} | "
                 f"{'yes' if d['near'] else 'no'} |" for d in diffs[:LISTED]]
        if len(diffs) > LISTED:
            rows.append(f"| ... {len(diffs) - LISTED} more in the JSON | | | | |")
    return "\n".join(rows)


def summary(comparisons, labels):
    """One row per comparison: attractors that differ (near a bifurcation), exponents in their error bar."""
    rows = []
    for key, c in comparisons.items():
        expo = c["exponents"].values()
        n, ok = sum(e["points"] for e in expo), sum(e["agree"] for e in expo)
        rows.append(f"| {labels(key)} | {c['points']} | {len(c['differences'])} ({c['differences_near']}) | "
                    f"{c['period_agree']} / {c['periodic_both']} | {ok} / {n} |")
    return "\n".join(["| run | points | attractor differs (near a bifurcation) | same period k | "
                      "exponent within its error bar |", "| --- | --- | --- | --- | --- |"] + rows)

"""Tori at sweep grid points: where a point's forcing is quasi-periodic (the model's
`torus_forcing`, Built.periodic false: no periodic orbit by design) and the scene asks for the
response ([analysis] floquet), the response is an invariant 2-torus, solved here
(rotorsweep.kernels.torus) instead of being left `not_applicable`.

The circle comes from a settled transient (torus.torus_from_transient: SETTLE_PERIODS iterates of
the stroboscopic map, FIT_PERIODS samples fitted by FIRST_NODES nodes, then Newton on all nodes
with the node count grown until the Fourier tail is below DECAY_TOL, at most MAX_NODES); along a
segment a point first tries the previous quasi-periodic point's circle as its guess (on the fewest
nodes, not below FIRST_NODES, that keep its tail a thousandfold below DECAY_TOL: torus.coarsened;
natural continuation, as the orbits are chained: it keeps following one torus where tori coexist, and
reaches tori a transient leaves; not cheaper: a few variational Newton steps cost about what the
~500 plain stroboscopic steps of the transient do), the transient only where that fails. The
same settings serve the torus lines of `rotorsweep continue` (rotorsweep.pipeline.torus_branches).

Per point (schema.TORUS_VARIABLES): status, normal stability and largest normal Lyapunov
exponent [1/s], rotation number, Fourier modes, error estimate, and the half peak-to-peak of each
observable over the torus, stored as the point's `amplitude_<observable>` so that amplitude maps
are filled: the exact extrema (rotorsweep.kernels.extrema) along the trajectories over one forcing
period from AMPLITUDE_PHASES equal phases of the circle, their max / min over the phases (low by
the phase sampling: torus_amplitude_error estimates it, ~1e-4 relative at 64 phases on Fig. 2b).
Failure is data: a torus that fails has its status and NaN values. Where the Fourier decay fails
(fourier_decay_failed, or non_smooth_circle: the tail falls only algebraically, torus.power_law)
on a model with contacts (ModelSpec.contact_margin), the trajectories from MARGIN_PHASES phases of
the circle tell whether a contact opens along it: then the status is contact_loss (the contact
force, e.g. a Hertz load [delta]_+^{3/2}, is not smooth where a ball lifts off, so neither is the
circle: its spectrum decays by a power of the mode number and no node count within MAX_NODES
resolves it), with the smallest deflection relative to the static one as torus_contact_margin.
"""
import time

import numpy as np

from rotorsweep.pipeline import schema
from rotorsweep.kernels import torus as tr

SETTLE_PERIODS = 400
FIT_PERIODS = 120
FIRST_NODES = 15
MAX_NODES = 63
DECAY_TOL = 1e-9        # the first torus's Fourier tail (node count grown to reach it)
CONTACT_LOSS = "contact_loss"   # the decay failed and a contact opens along the circle
AMPLITUDE_PHASES = 64
MARGIN_PHASES = 32      # phases of the circle, and samples per period along each, for the contact margin


def solve(model, built, opts, tol, guess=None):
    """The torus of a quasi-periodically forced point (a torus.Torus, or None where the
    transient failed): from `guess` (node values, e.g. a neighbour's circle) when given and
    converging there, else from a transient started at the model's cold guess."""
    phase, freq, _ = model.torus_forcing
    p = built.p
    settings = {"tol": tol, "decay_tol": DECAY_TOL, "max_nodes": MAX_NODES}
    if guess is not None:
        circle = tr.solve_torus(model.kernel, tr.coarsened(guess, DECAY_TOL, FIRST_NODES), p, phase, p[freq], opts,
                                **settings)
        if circle.status == tr.CONVERGED:
            return circle
    return tr.torus_from_transient(model.kernel, model.cold_guess(p), p, phase, p[freq], opts, SETTLE_PERIODS,
                                   FIT_PERIODS, FIRST_NODES, **settings)


def amplitudes(model, circle, built, opts):
    """(half peak-to-peak of each observable over the torus (SI), its estimated relative
    shortfall, largest over the observables) (module docstring)."""
    phase, _, _ = model.torus_forcing
    hi, lo = tr.phase_extremes(model, circle, built.p, phase, opts, built.period, AMPLITUDE_PHASES)
    half = 0.5 * (hi.max(axis=0) - lo.min(axis=0))
    short = 0.5 * (tr.phase_sampling_error(hi) + tr.phase_sampling_error(-lo))
    rel = np.where(half > 0, short / np.where(half > 0, half, 1.0), 0.0)
    return half, float(rel.max())


def variables(model, circle, built, opts):
    """Cube variables of one torus point: schema.TORUS_VARIABLES and amplitude_<observable>."""
    status = tr.INTEGRATION_FAILED if circle is None else circle.status
    out = empty_variables()
    if status in (tr.FOURIER_DECAY_FAILED, tr.NON_SMOOTH) and model.contact_margin is not None:
        out["torus_contact_margin"] = contact_margin(model, circle, built.p, opts)
        status = CONTACT_LOSS if out["torus_contact_margin"] < 0 else status
    out["torus_status"] = schema.TORUS_STATUS.index(status)
    if circle is None:
        return out
    out["torus_modes"] = (circle.nodes.shape[0] - 1) // 2
    out["torus_rotation_number"] = circle.rho / (2.0 * np.pi)
    out["torus_error"] = circle.error
    if status != tr.CONVERGED:
        return out
    stab = tr.stability(circle)
    out["torus_stability"] = schema.TORUS_STABILITY.index(stab.status)
    out["torus_exponent"] = stab.exponents[0] / built.period
    out["torus_exponent_error"] = stab.spread / built.period
    half, out["torus_amplitude_error"] = amplitudes(model, circle, built, opts)
    out.update({f"amplitude_{o.name}": half[k] for k, o in enumerate(model.observables)})
    return out


def contact_margin(model, circle, p, opts):
    """The model's contact margin (ModelSpec.contact_margin) over trajectories of one period from
    MARGIN_PHASES phases of the circle, MARGIN_PHASES samples each (nan where it has none)."""
    phase, _, _ = model.torus_forcing
    states = tr.surface_samples(model.kernel, circle, p, phase, opts, MARGIN_PHASES, MARGIN_PHASES)
    margin = model.contact_margin(states.reshape(-1, model.kernel.n_state), p)
    return np.nan if margin is None else margin


def empty_variables():
    """The torus variables of a point without torus (a periodically forced one): no values.
    amplitude_<observable> is not among them: a periodic point has its orbit's."""
    return {name: schema.INT_FILL if np.dtype(dtype).kind in "iu" else np.nan
            for name, (_, dtype, _) in schema.TORUS_VARIABLES.items()}


def segment_rows(model, params, rows, opts, tol):
    """Fill the torus variables of a segment's rows (in place) where any point is quasi-periodically
    forced (every row then holds them, a cube part's variables being the same for all its points);
    each torus starts from the previous one's circle (solve). Returns the seconds per point."""
    seconds = [0.0] * len(rows)
    if not model.torus_forcing or all(par.periodic for par in params):
        return seconds
    guess = None
    for i, (par, row) in enumerate(zip(params, rows)):
        if par.periodic:
            row.update(empty_variables())
            continue
        start = time.perf_counter()
        circle = solve(model, par, opts, tol, guess)
        converged = circle is not None and circle.status == tr.CONVERGED
        guess = circle.nodes if converged else None
        row.update(variables(model, circle, par, opts))
        seconds[i] = time.perf_counter() - start
    return seconds


def summary(row):
    """`rotorsweep point`'s torus of a row (plain values, None where absent), or None where the
    point has no torus (periodic forcing)."""
    if row.get("torus_status", schema.INT_FILL) < 0:
        return None
    stab = int(row["torus_stability"])

    def num(name):
        x = float(row[name])
        return x if np.isfinite(x) else None
    return {"status": schema.TORUS_STATUS[int(row["torus_status"])],
            "stability": schema.TORUS_STABILITY[stab] if stab >= 0 else None,
            "exponent": num("torus_exponent"), "exponent_error": num("torus_exponent_error"),
            "rotation_number": num("torus_rotation_number"), "modes": int(row["torus_modes"]),
            "error": num("torus_error"), "amplitude_error": num("torus_amplitude_error"),
            "contact_margin": num("torus_contact_margin") if "torus_contact_margin" in row else None}


def summary_text(t):
    def g(x, fmt=".3g"):
        return "-" if x is None else format(x, fmt)
    exponent = "-" if t["exponent"] is None else f"{t['exponent']:+.6g} +- {t['exponent_error']:.2g} 1/s"
    return "\n".join([
        f"torus             {t['status']}, {t['stability'] or '-'} (largest normal exponent {exponent})",
        f"torus rotation    {g(t['rotation_number'], '.12g')}, {t['modes']} Fourier modes, error estimate "
        f"{g(t['error'], '.2g')} (scaled state)",
        f"amplitudes        over the torus, relative sampling error {g(t['amplitude_error'], '.2g')}"]
        + ([] if t.get("contact_margin") is None else [contact_text(t)]))


def contact_text(t):
    """The contact margin's line of `point` (a torus whose Fourier decay failed)."""
    margin = t["contact_margin"]
    what = ("a contact opens along the torus: the contact force is not smooth there, the circle's spectrum "
            "decays algebraically" if margin < 0 else "every contact stays closed")
    return f"torus contacts    smallest deflection {margin:+.3g} of the static one: {what}"

"""The events of a torus branch (rotorsweep.pipeline.torus_branches) as the continuation result's event rows:
the flags of rotorsweep.kernels.continuation.tori (TS: the normal stability changes, TF: a fold of
tori), each located between two points (tori.locate_flags; where not located, the row's values
are NaN and its note gives the bracket and why), and each locked ratio omega / Omega = p / q (q <= LOCK_DENOMINATOR)
the branch passes, linked to the periodic-orbit solver.

At a locked ratio the branch's torus is solved exactly there (tori.Locked); its circle then
consists of q-periodic points of the stroboscopic map (one per phase of the support forcing). The
one at phase 0, the phase of the scene's forcing, is the start of Newton shooting over q shaft
turns (rotorsweep.kernels.shooting, the solver of the periodic points): the orbit it converges to is
linked (its state, Floquet multipliers over q turns and amplitudes in the event row) when it lies
within LINK_TOL of the circle; otherwise the row keeps the circle's point, NaN multipliers, and a
note saying why. Each row's `note` says it in words.
"""
import numpy as np

from rotorsweep.kernels import extrema, floquet, shooting
from rotorsweep.kernels.continuation import events as ev

LOCK_DENOMINATOR = 8    # the largest q recognized as a locked ratio on a torus branch
# The shooting's residual (relative to max(1, |u|), scaled state): above the q-turn map's own error
# floor (q <= LOCK_DENOMINATOR shaft turns at the scene's rtol, 1e-10: Newton stalled at 1.5e-11 on
# Fig. 4b's 27/8 and 22/5 orbits with |u| ~ 5 um, which then went unlinked at 1e-11).
SHOOT_TOL = 1e-10
# A linked orbit's distance from the circle, relative to max(1, |u|): the circle is solved to the
# branch's Newton tolerance (1e-9 .. 1e-10) and shooting converges to SHOOT_TOL, so an orbit on the
# torus lies within ~1e-8 of its circle; a different orbit (another solution) lies far off.
LINK_TOL = 1e-6


def event_rows(model, family, built, run, amplitudes_at, each=iter):
    """The record's event_* arrays of a torus Run (amplitudes_at: a point -> (max |o|, half-swing)
    of each observable over its torus; each: the run's events -> them one by one, e.g. with
    progress lines), plus event_note (words per event) and event_periods (forcing
    periods of the event's orbit: a locked p/q row's linked orbit closes after q shaft turns; 1 on a
    flag's row, the branch's). A branch's end (breakdown) is its end reason, not an event
    (tori.follow_tori leaves it out of run.found)."""
    n, n_obs = family.kernel.n_state, len(model.observables)
    rows = [_locked_row(model, family, built, f) if f.event.code == ev.LOCKED else
            _flag_row(family, run, f, amplitudes_at, n_obs) for f in each(run.found)]
    return {
        "event_type": np.array([f.event.code for f in run.found], int),
        "event_parameter": np.array([r[0] for r in rows], float),
        "event_index": np.array([f.index for f in run.found], int),
        "event_state": np.array([r[1] for r in rows], float).reshape(len(rows), n),
        "event_multipliers": np.array([r[2] for r in rows], complex).reshape(len(rows), n),
        "event_amplitude_max": np.array([r[3] for r in rows], float).reshape(len(rows), n_obs),
        "event_amplitude_half_pp": np.array([r[4] for r in rows], float).reshape(len(rows), n_obs),
        "event_note": [r[5] for r in rows],
        "event_periods": np.array([f.event.q if f.event.code == ev.LOCKED else 1 for f in run.found], int),
        "event_parameter_error": np.array([np.nan if f.event.code == ev.LOCKED else f.event.location.lam_error
                                           for f in run.found], float),
    }


def _flag_row(family, run, found, amplitudes_at, n_obs):
    """A TS or TF flag between points index and index + 1, located there by
    tori.locate_flags: the located torus (its lambda, its circle at phase 0, its amplitudes; a
    torus has no Floquet multipliers), or NaN where it was not located, the note then giving the
    bracket and why."""
    a, b = run.points[found.index], run.points[min(found.index + 1, len(run.points) - 1)]
    where = found.event.location
    what = {ev.TORUS_STABILITY: _exponent_change(family, a, b),
            ev.TORUS_FOLD: "the branch turns back"}[found.event.code]
    between = f"between {where.bracket[0]:.10g} and {where.bracket[1]:.10g}"
    nan = np.full(family.kernel.n_state, np.nan + 0j)
    point = found.point
    if point is None:
        return (np.nan, nan.real, nan, np.full(n_obs, np.nan), np.full(n_obs, np.nan),
                f"{what} {between}, not located: {where.reason}")
    hi, half = amplitudes_at(point)
    return (point.lam, family.nodes(point.X)[0], nan, hi, half,
            f"{what}, located to {where.lam_error:.2g} ({between})")


def _exponent_change(family, a, b):
    """A TS flag in words: the largest normal exponent on both sides (per forcing period) with each
    side's normal stability (both can be undecided next to the crossing, where the exponent lies
    within its error of 0, while its sign change is what the flag says)."""
    ea, eb = (p.stability.exponents[0] * family.period for p in (a, b))
    return (f"largest normal exponent {ea:+.3g} -> {eb:+.3g} per forcing period (normal stability "
            f"{a.stability.status} -> {b.stability.status})")


def locked_orbit(model, family, point, q):
    """(shooting.Orbit, the circle's point at phase 0): the orbit of q shaft turns shot from the
    torus's point at phase 0."""
    u0 = family.nodes(point.X)[0]
    p = np.array(family.params(point.lam), float)
    p[family.phase_index] = 0.0
    orbit = shooting.periodic_orbit(model, u0, p, family.opts, periods=q * family.period, tol=SHOOT_TOL,
                                    staged=False)
    return orbit, u0, p


def _locked_row(model, family, built, found):
    event, point = found.event, found.point
    orbit, u0, p = locked_orbit(model, family, point, event.q)
    distance = float(np.abs(orbit.state - u0).max())
    linked = orbit.status == shooting.CONVERGED and distance <= LINK_TOL * max(1.0, np.abs(u0).max())
    head = f"{event.p}/{event.q}: torus {point.stability.status}"
    if not linked:
        why = "did not converge" if orbit.status != shooting.CONVERGED else f"converged {distance:.2g} off the circle"
        nan = np.full(len(model.observables), np.nan)
        return (point.lam, u0, np.full(family.kernel.n_state, np.nan + 0j), nan, nan,
                f"{head}; shooting over {event.q} shaft turns from the circle {why}: no orbit linked")
    mult = floquet.multipliers(orbit.monodromy)
    hi, half = extrema.amplitudes(model, orbit.state, p, event.q * family.period, family.opts, built(point.lam).period)
    note = (f"{head}; periodic orbit of {event.q} shaft turns linked, {distance:.2g} from the circle "
            f"(shooting residual {orbit.residual:.2g} after {orbit.iterations} Newton steps), "
            f"max |multiplier| {np.abs(mult).max():.6g}")
    return point.lam, orbit.state, mult, hi, half, note

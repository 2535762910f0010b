"""One parameter point: the attractor's class, period, exponents and (for a periodic one) the
multipliers of its period-k orbit, from a transient, Poincare samples and, where needed, a
Lyapunov run."""
from collections import namedtuple
from dataclasses import dataclass, fields

import numpy as np

from rotorsweep.kernels import floquet, integrators as ig, shooting
from rotorsweep.kernels.attractor import lyapunov
from rotorsweep.kernels.attractor.period import default_period_rtol, detect_period
from rotorsweep.kernels.attractor.poincare import _poincare
from rotorsweep.kernels.attractor_classes import (  # noqa: F401 (the package's API)
    ATTRACTOR, CHAOTIC, DIVERGED, INTEGRATION_FAILED, NOT_COMPUTED, NOT_SETTLED, PERIODIC, QUASI_PERIODIC)


def failure_class(status):
    """The class of a run that stopped with integrator status `status` (not STATUS_OK)."""
    return INTEGRATION_FAILED if status == ig.STATUS_STEP_UNDERFLOW else DIVERGED

# classify(): an exponent counts as positive (chaos) when lle > SIGMAS * stderr + LLE_FLOOR and
# as negative (a stable orbit) when lle < -(SIGMAS * stderr + LLE_FLOOR); in between it is zero
# within its uncertainty. LLE_FLOOR is per forcing period (per unit tau): a growth by
# exp(0.002) per period cannot be told from zero in the runs used here (a few hundred to a few
# thousand periods), and it keeps a slowly settling orbit or a torus from reading as chaos.
SIGMAS = 3.0
LLE_FLOOR = 2e-3

# exponents, lle, lle_stderr in 1/s; multipliers: of the period-k orbit when the attractor is
# periodic and its orbit was refined by shooting on k T (else NaN); derived: the exponents come
# from those multipliers, not from a Lyapunov run.
Attractor = namedtuple("Attractor", "code period lle lle_stderr samples end_state status periods_used "
                                    "exponents multipliers derived")


def closed_curve(samples, max_gap=np.pi / 3, max_jump=0.25, min_aspect=0.02):
    """Whether the tail of the Poincare samples (second half) lies on one closed curve around
    its centroid, as the section of a 2-torus does (heuristic, documented thresholds).

    The tail is projected on its two principal axes; in polar coordinates about the centroid,
    sorted by angle, the points must (1) surround the centroid, no angular gap over `max_gap`
    (a circle map with irrational rotation fills its curve; settling period-k points leave k
    clusters), (2) trace a continuous radius, no jump between angular neighbours over
    `max_jump` x the mean radius (a chaotic cloud jumps), (3) not be collinear, second principal
    extent >= `min_aspect` x the first (a slowly settling orbit near a period doubling
    alternates along a line). Needs at least 16 tail points."""
    s = np.asarray(samples, float)
    tail = s[len(s) // 2:]
    if len(tail) < 16 or not np.all(np.isfinite(tail)):
        return False
    x = tail - tail.mean(axis=0)
    _, sv, vt = np.linalg.svd(x, full_matrices=False)
    if sv[0] == 0.0 or len(sv) < 2 or sv[1] < min_aspect * sv[0]:
        return False
    xy = x @ vt[:2].T
    ang = np.arctan2(xy[:, 1], xy[:, 0])
    rad = np.hypot(xy[:, 0], xy[:, 1])
    order = np.argsort(ang)
    ang, rad = ang[order], rad[order]
    gaps = np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi]))
    if gaps.max() > max_gap:
        return False
    jumps = np.abs(np.diff(np.concatenate([rad, rad[:1]])))
    return bool(jumps.max() <= max_jump * rad.mean())


def classify(samples, lle, lle_stderr, period_k, status=ig.STATUS_OK, *, sigmas=SIGMAS,
             floor=LLE_FLOOR, check_curve=True, forced_torus=False):
    """(code into ATTRACTOR, k) from the Poincare samples, the largest exponent and its standard
    error, and the detected period.

    - diverged: a failed integration (NaN or amplitude limit), NaN samples, or a NaN exponent;
      integration_failed: the integrator's step size underflowed;
    - periodic, k = period_k, when the samples repeat with period k > 0;
    - chaotic when lle > sigmas * lle_stderr + floor (positive beyond its uncertainty);
    - not_settled (a contracting attractor whose period is not resolved: longer than max_period,
      or not settled to the detection tolerance, typically close to a bifurcation) when
      lle < -(sigmas * lle_stderr + floor);
      Under quasi-periodic forcing (forced_torus) a contracting attractor whose samples lie on
      a closed curve is the forced torus (the forcing's phase is no state, so its exponent
      is not 0): quasi_periodic;
    - zero within the uncertainty: quasi_periodic -- unless check_curve is set and the tail
      samples do not lie on a closed curve (`closed_curve`): then not_settled. This is what
      an orbit next to a bifurcation looks like (a multiplier near -1 or +1: the state settles
      onto, or drifts off, the orbit over thousands of periods, leaving clustered or collinear
      points and |lle| ~ 0), and what the sweeps find within ~0.1 Hz of a period doubling.
    lle, lle_stderr and floor share units: per forcing period (per unit tau) for the default
    floor. `samples` may be None when only the exponent is known (no curve check then)."""
    if status != ig.STATUS_OK:
        return failure_class(status), 0
    if not np.isfinite(lle):
        return DIVERGED, 0
    if samples is not None and not np.all(np.isfinite(samples)):
        return DIVERGED, 0
    if period_k > 0:
        return PERIODIC, int(period_k)
    margin = sigmas * (lle_stderr if np.isfinite(lle_stderr) else np.inf) + floor
    if lle > margin:
        return CHAOTIC, 0
    if lle < -margin:
        on_curve = forced_torus and samples is not None and closed_curve(samples)
        return (QUASI_PERIODIC, 0) if on_curve else (NOT_SETTLED, 0)
    if check_curve and samples is not None and not closed_curve(samples):
        return NOT_SETTLED, 0
    return QUASI_PERIODIC, 0



def _shoot_k(model, state, p, opts, k):
    """Newton on k forcing periods from a state already on (or next to) the orbit."""
    return shooting.shoot(model.kernel, state.copy(), p, float(k), opts, max(1e-9, 10.0 * float(opts[ig.S_RTOL])), 10)


def _minimal_period(model, state, p, opts, k, rel_tol):
    """Smallest divisor d of k for which the converged period-k orbit through `state` returns
    after d periods (within rel_tol x max(1, max|state|)). Samples that settle slowly onto a
    period-d orbit whose multiplier is close to -1 alternate with a decay too slow for the
    detection tolerance and pass for period 2 d; the Newton-converged orbit does not."""
    scale = rel_tol * max(1.0, float(np.abs(state).max()))
    for d in range(1, k):
        if k % d:
            continue
        u, status, _, _ = ig.flow(model.kernel, 0.0, float(d), state.copy(), p, False, opts, 0.0)
        if status == ig.STATUS_OK and np.abs(u - state).max() <= scale:
            return d
    return k


def periodic_orbit_of(model, state, p, opts, k, rel_tol):
    """Refine a period-k attractor through `state` by shooting on k T: (k_min, orbit state,
    multipliers of the k_min-periodic orbit), or None when Newton does not converge. k is
    reduced to the orbit's minimal period (`_minimal_period`)."""
    orbit = _shoot_k(model, state, p, opts, k)
    if orbit[2] != shooting.CONVERGED:
        return None
    d = _minimal_period(model, orbit[0], p, opts, k, rel_tol)
    if d < k:
        again = _shoot_k(model, orbit[0], p, opts, d)
        if again[2] == shooting.CONVERGED:
            orbit, k = again, d
    return k, orbit[0], floquet.multipliers(orbit[1])


def exponents_of_orbit(multipliers, k, period):
    """The Lyapunov spectrum of a periodic orbit: ln|lambda_i| / (k T), largest first."""
    return np.sort(np.log(np.abs(np.asarray(multipliers))))[::-1] / (k * period)


# settle_on_orbit(multipliers=...): an orbit whose multipliers are all within SETTLE_CONTRACTION of 0
# (its deviations shrink by 10 % or more per period: no bifurcation is near, where the basin
# could be small) counts as reached once the state is within SETTLE_NEAR x its size and got
# closer over the last period; a state that close to such an orbit converges onto it (a start
# on another attractor does not come that close), and the last factor 100 of convergence took
# half of the settling periods (Fig. 13: 8-16 -> 1-4 periods per point).
SETTLE_NEAR = 1e-3
SETTLE_CONTRACTION = 0.9


def settle_on_orbit(model, u0, p, opts, orbit_state, max_periods, rel_tol, k=1, multipliers=None):
    """Integrate from u0 k forcing periods at a time until the state is within rel_tol x
    max(1, max|orbit_state|) of the period-k orbit's state -- or, given the orbit's multipliers
    with max|lambda| <= SETTLE_CONTRACTION, within SETTLE_NEAR x that and closer than a period
    before. Returns (state, periods used, reached). A start in the orbit's basin converges like
    max|lambda|^n; one on another attractor does not, and its periods then count as that
    attractor's transient."""
    u = np.asarray(u0, float).copy()
    size = max(1.0, float(np.abs(orbit_state).max()))
    near = multipliers is not None and np.abs(multipliers).max() <= SETTLE_CONTRACTION
    h = 0.0
    steps = int(max_periods) // k
    last = -np.inf           # the near test needs one period of contraction
    for n in range(steps + 1):
        dist = np.abs(u - orbit_state).max()
        if dist <= rel_tol * size or (near and dist <= SETTLE_NEAR * size and dist < last):
            return u, n * k, True
        if n == steps:
            break
        last = dist
        u, status, _, h = ig.flow(model.kernel, 0.0, float(k), u, p, False, opts, h)
        if status != ig.STATUS_OK:
            break
    return u, n * k, False


def settle_on_continued_orbit(model, u0, p, opts, k, max_periods, rel_tol):
    """The 'derive when stable' shortcut for the neighbour's period-k attractor: the period-k
    orbit through u0 (the neighbour's end state, next to its orbit) refined by shooting on k T,
    and, when it is stable, the transient integrated k periods at a time until it reaches that
    orbit (`settle_on_orbit`). Returns (orbit (k, state, multipliers) or None, state reached,
    periods used): None, 0 periods, when the refinement fails or the orbit is unstable; None,
    the periods used, when the state did not reach it (another attractor: those periods are its
    transient)."""
    orbit = periodic_orbit_of(model, np.asarray(u0, float), p, opts, k, rel_tol)
    if orbit is None or np.abs(orbit[2]).max() >= 1.0:
        return None, u0, 0
    u, used, reached = settle_on_orbit(model, u0, p, opts, orbit[1], max_periods, rel_tol, orbit[0], orbit[2])
    return (orbit if reached else None), u, used


def _on_stable_orbit(model, orbit_state, multipliers, period, n_samples, end_state):
    lle_all = exponents_of_orbit(multipliers, 1, period)
    samples = np.tile(orbit_state, (n_samples, 1))
    return Attractor(PERIODIC, 1, float(lle_all[0]), 0.0, samples, end_state, ig.STATUS_OK, 0.0,
                     lle_all, np.asarray(multipliers, complex), True)


# diagnose(): periodic samples whose refined orbit has max|lambda| > 1 + UNSTABLE_MARGIN sit on an
# unstable orbit, not an attractor; up to ESCAPES new transients follow, each from `escape_from`.
UNSTABLE_MARGIN = 1e-6
ESCAPES = 2
ESCAPE_KICK = 1e-3
# Where escape_from looks for the period-2k orbit born at a flip: offsets of the period-k state
# along the flip's eigenvector, relative to the state's size. Just past a flip the new orbit lies
# close (Fig. 13, 93.1 Hz, 3.8 um: 2.8 % of the size at a multiplier of -1.0018); Newton from
# a smaller offset returns to the period-k orbit, which is a period-2k orbit too.
FLIP_OFFSETS = (1e-2, 3e-2, 1e-1)


def escape_from(model, orbit, state, p, opts, rel_tol):
    """Where a transient that repeats on the unstable orbit `orbit` = (k, state, multipliers)
    goes on from. Past a flip (the largest multiplier real, below -1) the orbit is left so slowly
    that a kick of ESCAPE_KICK stays within the period tolerance for thousands of periods (at
    -1.0018: x1.4 in 200 periods); the stable period-2k orbit born there (`flipped_orbit`) is
    then the start. Otherwise (or when there is none) `state` kicked by ESCAPE_KICK x its size."""
    born = flipped_orbit(model, orbit, p, opts, rel_tol)
    if born is not None:
        return born[1]
    return state + ESCAPE_KICK * max(1.0, float(np.abs(state).max()))


def flipped_orbit(model, orbit, p, opts, rel_tol):
    """The stable orbit of minimal period 2k born where the period-k orbit `orbit` lost stability
    by a flip, found by shooting on 2k periods from the period-k state offset along the flip's
    eigenvector (FLIP_OFFSETS, both signs): (2k, state, multipliers), or None (not a flip; no
    offset converges to such an orbit: a subcritical flip, or the orbit lies farther)."""
    k, state, _ = orbit
    shot = _shoot_k(model, state, p, opts, k)     # its monodromy: periodic_orbit_of keeps the multipliers only
    if shot[2] != shooting.CONVERGED:
        return None
    lams, vecs = np.linalg.eig(shot[1])
    i = int(np.argmax(np.abs(lams)))
    if lams[i].imag != 0.0 or lams[i].real >= -1.0:
        return None
    v = vecs[:, i].real / np.abs(vecs[:, i].real).max()
    size = max(1.0, float(np.abs(state).max()))
    for offset in FLIP_OFFSETS:
        for sign in (1.0, -1.0):
            born = periodic_orbit_of(model, state + sign * offset * size * v, p, opts, 2 * k, rel_tol)
            if born is not None and born[0] == 2 * k and np.abs(born[2]).max() < 1.0:
                return born
    return None


# settle_periodic(): the transient runs in blocks of SETTLE_BLOCK periods; once at least
# SETTLE_MIN_WINDOW samples are in, the last (up to 4 x max_period) are tested for a period after
# each block (`detect_period` on their second half: a period-k orbit needs 4 k samples).
SETTLE_BLOCK = 8
SETTLE_MIN_WINDOW = 16


def settle_periodic(model, u0, p, opts, n_transient, max_period, rel_tol):
    """The transient, stopped early when the stroboscopic map has settled on a stable periodic
    orbit: the recent samples repeat with a period k (the `detect_period` test of the full
    samples), the period-k orbit refined from the last one (`periodic_orbit_of`) converges and
    is stable. Returns (orbit (k, state, multipliers) or None, state reached, periods used, status).
    Samples repeating on an unstable orbit (a start next to it: the neighbour's attractor just
    past a bifurcation) are kicked off it, up to ESCAPES times; a refinement that fails, or
    another unstable one, ends the testing: the transient then runs its full length, as without
    this shortcut."""
    u = np.asarray(u0, float)
    window = [u]
    used, testing, kicks = 0, True, 0
    while used < n_transient:
        block = min(SETTLE_BLOCK, n_transient - used)
        samples, status, u = _poincare(model.kernel, u, p, opts, 0, block + 1, 0.0, 0.0)
        used += block
        if status != ig.STATUS_OK:
            return None, u, used, int(status)
        if not testing:
            continue
        window = (window + list(samples[1:]))[-4 * max_period:]
        if len(window) < SETTLE_MIN_WINDOW:
            continue
        k = detect_period(np.array(window), max_period, rel_tol)
        if k == 0:
            continue
        orbit = periodic_orbit_of(model, u, p, opts, k, rel_tol)
        if orbit is not None and np.abs(orbit[2]).max() < 1.0:
            return orbit, u, used, ig.STATUS_OK
        # repeating samples on an unstable orbit: a start too close to it (as in diagnose),
        # kicked off it; a refinement that fails ends the testing
        testing = orbit is not None and kicks < ESCAPES
        if testing:
            kicks += 1
            u = escape_from(model, orbit, u, p, opts, rel_tol)
            window = [u]
    return None, u, used, ig.STATUS_OK


def _orbit_samples(model, orbit_state, p, opts, k, n_samples):
    """n_samples stroboscopic samples on a period-k orbit, the last one `orbit_state` (what the
    sampled trajectory would show once settled onto it, without integrating it)."""
    points, _, _ = _poincare(model.kernel, np.asarray(orbit_state, float), p, opts, 0, k, 0.0, 0.0)
    return points[(np.arange(n_samples) - (n_samples - 1)) % k]


def _on_settled_orbit(model, orbit, p, period, opts, n_samples, reached):
    """The Attractor of a settled stop. Its end state is the state the transient reached, not the
    refined orbit: a neighbour past a bifurcation started exactly on this (then unstable) orbit
    would leave it only after many periods; the full transient's end state has the same
    residual offset."""
    k, state, lams = orbit
    expo = exponents_of_orbit(lams, k, period)
    return Attractor(PERIODIC, k, float(expo[0]), 0.0, _orbit_samples(model, state, p, opts, k, n_samples),
                     np.asarray(reached, float).copy(), ig.STATUS_OK, 0.0, expo, lams, True)


@dataclass(frozen=True)
class Settings:
    """How `diagnose` treats every point. The first eight fields are the scene's [analysis] keys of
    the same names (`from_keys` picks them from that section; the scene's defaults stop settled
    transients and converged Lyapunov runs, these do not); the others are fixed by the pipeline.

    transient_periods: forcing periods integrated before the Poincare samples; poincare_samples:
    how many samples; max_period: the longest period k looked for in them; derive_when_stable: a
    stable periodic attractor's exponents come from its multipliers (False: always a Lyapunov
    run); stop_when_settled: the transient stops once the map has settled on a stable period-k
    orbit. A Lyapunov run (`lyapunov.lyapunov_spectrum`, whose arguments the lyapunov_ fields
    are) measures lyapunov_min_periods (None: min(lyapunov_max_periods, 100)) to
    lyapunov_max_periods periods, and stops once stderr <= lyapunov_rtol |lle| + lyapunov_atol,
    or with lyapunov_converged_stop also once its weighted average has converged (a torus).
    period_rtol: the period test's tolerance (None: `default_period_rtol(opts)`)."""
    transient_periods: int = 200
    poincare_samples: int = 128
    max_period: int = 32
    derive_when_stable: bool = True
    stop_when_settled: bool = False
    lyapunov_max_periods: int = 2000
    lyapunov_rtol: float = 0.02
    lyapunov_converged_stop: bool = False
    lyapunov_min_periods: float | None = None
    lyapunov_atol: float = 1e-4
    lyapunov_align_periods: float = 20.0
    lyapunov_weighted: bool = True
    lyapunov_renorm_periods: float = 1.0
    lyapunov_blocks: int = 10
    period_rtol: float | None = None

    @classmethod
    def from_keys(cls, section):
        """The settings named in `section` (a mapping such as a scene's [analysis] table; keys that
        are no field are ignored), the others at their defaults."""
        return cls(**{f.name: section[f.name] for f in fields(cls) if f.name in section})

    def problems(self, where=""):
        """Messages for settings that cannot work, each naming its field as `where` + name (e.g.
        "analysis."); checked before any work starts."""
        out = [f"{where}{name}: must be an integer >= {lo} (got {getattr(self, name)!r})"
               for name, lo in (("transient_periods", 0), ("max_period", 1), ("poincare_samples", 1))
               if int(getattr(self, name)) < lo]
        if self.poincare_samples < 4 * self.max_period:
            out.append(f"{where}poincare_samples: must be >= 4 x {where}max_period (= {4 * self.max_period}): "
                       "a period is detected on the second half of the samples and must repeat there at least twice")
        for name in ("lyapunov_rtol", "lyapunov_atol", "lyapunov_align_periods", "lyapunov_min_periods"):
            value = getattr(self, name)
            if value is not None and not value >= 0:
                out.append(f"{where}{name}: must be >= 0 (got {value!r})")
        if self.period_rtol is not None and not self.period_rtol > 0:
            out.append(f"{where}period_rtol: must be > 0 (got {self.period_rtol!r})")
        return out + [where + text for text in lyapunov.run_problems(
            self.lyapunov_renorm_periods, self.lyapunov_blocks, self.lyapunov_max_periods)]


def diagnose(model, u0, p, period, opts, settings=Settings(), *, stable_orbit=None, continued_period=0,
             periodic=True):
    """One parameter point from u0 at tau = 0: Poincare samples after a transient, their period,
    the largest exponent, and `classify`; how, `settings` (a Settings) says. Settings that cannot
    work raise ValueError before any work.

    A periodic attractor (period k found) is refined by shooting on k T from the last sample
    (already on the orbit: one or two iterations; `periodic_orbit_of`), and its multipliers are
    returned. When the orbit is stable, the exponents follow from them, ln|lambda_i| / (k T),
    stderr 0 (derived=True) -- unless not derive_when_stable.
    stable_orbit = (state, multipliers) of a stable period-1 orbit found by shooting: the
    transient stops as soon as the state reaches it (`settle_on_orbit`), and the point is that
    orbit (samples = its state) with derived exponents -- the 'derive when stable' shortcut.
    stop_when_settled: the transient stops once the map has settled on a stable period-k orbit
    (`settle_periodic`); the point is that orbit, its samples the orbit's k points repeated,
    derived exponents; with continued_period = k > 0 (the neighbour's attractor was a period-k
    orbit) it first refines that orbit from u0 and settles onto it when it is stable
    (`settle_on_continued_orbit`), as stable_orbit does for period 1. lyapunov_converged_stop: a
    Lyapunov run also stops once its weighted average has converged (`lyapunov.CONVERGED_FRACTION`:
    a torus's run no longer goes to lyapunov_max_periods).
    Samples that repeat on an unstable orbit (a start on or next to it) are retaken after a kick
    off it (ESCAPES). Otherwise (no period, the shooting fails, or not derive_when_stable) a Lyapunov
    run starts where the samples end (no second transient). Returns an Attractor: code, period k, lle and lle_stderr
    in 1/s (NaN when not computed), samples, end_state (the state at the last whole period
    reached: the start of the next speed in a continuation of the attractor), status,
    periods_used (measured Lyapunov periods; 0 when none ran), exponents [1/s], multipliers,
    derived.
    periodic=False: a quasi-periodically forced model (not 1-periodic in tau): time runs on
    through the whole diagnosis, the samples are stroboscopic at tau = 1, 2, ..., and no
    periodic orbit is refined (there is none to shoot for)."""
    problems = settings.problems()
    if problems:
        raise ValueError("attractor settings: " + "; ".join(problems))
    clock = 0.0 if periodic else 1.0
    period_rtol = default_period_rtol(opts) if settings.period_rtol is None else settings.period_rtol
    n_transient, n_samples = int(settings.transient_periods), int(settings.poincare_samples)
    max_period = int(settings.max_period)
    derive = settings.derive_when_stable
    u0 = np.asarray(u0, float)
    if stable_orbit is not None and derive:
        state, lams = stable_orbit
        u0, used, reached = settle_on_orbit(model, u0, p, opts, state, n_transient, period_rtol,
                                            multipliers=lams if settings.stop_when_settled else None)
        if reached:
            return _on_stable_orbit(model, state, lams, period, n_samples, state.copy())
        n_transient -= used
    nan = np.full(model.n_state, np.nan)
    settling = settings.stop_when_settled and periodic and derive
    if settling and continued_period > 0:
        orbit, u0, used = settle_on_continued_orbit(model, u0, p, opts, int(continued_period), n_transient,
                                                    period_rtol)
        if orbit is not None:
            return _on_settled_orbit(model, orbit, p, period, opts, n_samples, u0)
        n_transient -= used
    if settling:
        orbit, u0, used, status = settle_periodic(model, u0, p, opts, n_transient, max_period, period_rtol)
        if status != ig.STATUS_OK:
            return Attractor(failure_class(status), 0, np.nan, np.nan, np.full((n_samples, model.n_state), np.nan),
                             u0, status, 0.0, nan, nan * (1 + 1j), False)
        if orbit is not None:
            return _on_settled_orbit(model, orbit, p, period, opts, n_samples, u0)
        n_transient -= used
    for attempt in range(1 + ESCAPES):
        samples, status, end = _poincare(model.kernel, u0, p, opts, n_transient, n_samples, 0.0, clock)
        if status != ig.STATUS_OK:
            return Attractor(failure_class(status), 0, np.nan, np.nan, samples, end, int(status), 0.0,
                             nan, nan * (1 + 1j), False)
        k = detect_period(samples, max_period, period_rtol)
        orbit = periodic_orbit_of(model, end, p, opts, k, period_rtol) if k > 0 and periodic else None
        # Samples that repeat on an unstable orbit only show a start too close to it (a weakly
        # unstable orbit is left slowly): take a new transient from off it.
        if orbit is None or np.abs(orbit[2]).max() <= 1.0 + UNSTABLE_MARGIN or attempt == ESCAPES:
            break
        u0 = escape_from(model, orbit, end, p, opts, period_rtol)
        n_transient = max(n_transient, 1)
    lams = nan * (1 + 1j)      # no orbit: both parts NaN
    if orbit is not None:
        k, _, lams = orbit
        if np.abs(lams).max() < 1.0 and derive:
            expo = exponents_of_orbit(lams, k, period)
            return Attractor(PERIODIC, k, float(expo[0]), 0.0, samples, end, int(status), 0.0,
                             expo, lams, True)
    s = settings
    expo, stderr, n_done, lstatus, end2, t_end = lyapunov.run_benettin(
        model, end, p, opts, 0, s.lyapunov_renorm_periods, s.lyapunov_max_periods, s.lyapunov_blocks,
        s.lyapunov_rtol, s.lyapunov_min_periods, s.lyapunov_atol, s.lyapunov_align_periods, s.lyapunov_weighted,
        clock * (n_transient + n_samples - 1), clock, s.lyapunov_converged_stop)
    code, k = classify(samples, expo[0], stderr[0], k, lstatus, forced_torus=not periodic)
    if code == NOT_SETTLED and lstatus == ig.STATUS_OK:
        # a contracting attractor whose samples had not settled: by the end of the Lyapunov run
        # they have, so sample again there
        again, status2, end3 = _poincare(model.kernel, end2, p, opts, 0, n_samples, clock * t_end, clock)
        k2 = detect_period(again, max_period, period_rtol) if status2 == ig.STATUS_OK else 0
        orbit = periodic_orbit_of(model, end3, p, opts, k2, period_rtol) if k2 > 0 and periodic else None
        if orbit is not None and np.abs(orbit[2]).max() < 1.0:
            k, _, lams = orbit
            code, samples, end2 = PERIODIC, again, end3
    if code != PERIODIC or k == 0:
        lams = nan * (1 + 1j)      # no orbit: both parts NaN
    return Attractor(code, k, float(expo[0]) / period, float(stderr[0]) / period, samples, end2,
                     int(lstatus), n_done * float(s.lyapunov_renorm_periods), np.asarray(expo) / period, lams,
                     False)

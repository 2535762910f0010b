"""One orbit, one record: which located points of a continuation are the same closed curve, and
where distinct stable orbits coexist (issue 32 item 3).

A period-k orbit started at s is the same closed curve as the one started at phi_j(s) (phi_j: the
flow over j forcing periods, j = 0..k-1): a period-k branch has k phase copies, and switching
at a period doubling met twice on a loop, or at the two period doublings that bound a closed
period-2k loop, follows the same orbits again. In the line's task (where the kernel is),
`mark_copies` records per located point the first record of the same orbit, and
`line_coexistence` counts the distinct stable orbits on each piece of the line's parameter
range (exact orbits compared, not branches); `mark_branch_copies` marks whole branches that are
another's copy (listed once). Everything users read (info, the events table, the
coexistence table, the band map) reads those, through `distinct_events` and `coexistence`.
"""
import itertools
import json

import numpy as np

from rotorsweep.kernels import continuation_codes as codes

# Two located points are the same orbit when, at the same parameter, one's state is within
# SAME_ORBIT_FACTOR x newton_tol x max(1, |s|) of a phase copy of the other's (the Newton's own
# residual scaling). The Newton leaves a residual <= newton_tol x max(1, |s|), i.e. a state error
# of ||(M - I)^-1|| times that (below ~1e2 away from multipliers +1, and located events are
# pinned by the bordered system where M - I is singular), and the event location along the
# branch adds its arclength tolerance (1e-11 in the same normalized units); the factor leaves a
# margin of 10 over both. Distinct orbits at one parameter are O(1) apart in these units (their
# states differ by the amplitude of a period-k component, which vanishes only AT the period
# doubling that creates it, where the two are one orbit).
SAME_ORBIT_FACTOR = 1e3


def phase_copies(family, state, lam, periods):
    """[phi_j(state) for j in 0..periods-1] at lam (phi_0 = state); None if a flow failed."""
    one = family.with_periods(1)
    out = [np.asarray(state, float)]
    for _ in range(int(periods) - 1):
        r, _, status, _ = one.return_map(out[-1], lam, False)
        if status != 0:
            return None
        out.append(out[-1] + r)
    return out


def same_orbit(copies, state, tol):
    """Whether `state` is one of the phase copies of an orbit, within the Newton-derived tolerance."""
    scale = max(1.0, float(np.abs(state).max()))
    return copies is not None and any(np.abs(c - state).max() <= SAME_ORBIT_FACTOR * tol * scale for c in copies)


# A peak's parameter is as exact as the amplitude's slope along the branch over the slope's own
# derivative there: the Bai rotor's period-4 peak at 15.2 um is so flat that its copies (the same
# orbit reached as different branches) lie up to ~2e-5 Hz apart while one orbit's other events
# agree to 1e-9 Hz. Each located peak carries that error (event_parameter_error, estimated by
# arclength.Family.peak_error): two peaks are candidates for one orbit when their parameters agree
# within the sum of their errors and their amplitudes within AMPLITUDE_FACTOR x newton_tol of
# themselves (at a peak the amplitude is stationary: the parameter's error moves it only to second
# order, the orbit's error by about the Newton's residual; the factor as SAME_ORBIT_FACTOR's).
# The orbits then decide, compared at one parameter (`_same_peak`).
AMPLITUDE_FACTOR = SAME_ORBIT_FACTOR


def peak_candidates(r, k, r2, k2, row, tol):
    """Peaks k of record r and k2 of r2 may be one orbit: parameters within the sum of their error
    estimates (never where one has no finite estimate), the peak observable's (`row`) half
    peak-to-peak within AMPLITUDE_FACTOR x tol of itself (the other observables' are not
    stationary there: they move with the parameter's error)."""
    error = sum(x["event_parameter_error"][j] if "event_parameter_error" in x else np.nan
                for x, j in ((r, k), (r2, k2)))
    if not (np.isfinite(error) and abs(r2["event_parameter"][k2] - r["event_parameter"][k]) <= error):
        return False
    a, a2 = (float(x["event_amplitude_half_pp"][j][row]) for x, j in ((r, k), (r2, k2)))
    return abs(a - a2) <= AMPLITUDE_FACTOR * tol * max(abs(a), abs(a2))


def mark_copies(family, records, settings):
    """Set records[b]["event_copy_of"] (per event: the line's flat event index of the first
    record of the same located orbit) in place. Events match when of one kind and period, at the
    same parameter (within the same tolerance in mu = lambda / scale; peaks within their errors,
    `peak_candidates`, then `_same_peak`) and one state is a phase copy of the other."""
    events = [(b, k) for b, r in enumerate(records) for k in range(len(r["event_type"]))]
    first = list(range(len(events)))
    for i, (b, k) in enumerate(events):
        r, copies = records[b], None
        lam, peak = r["event_parameter"][k], r["event_type"][k] == codes.PEAK
        window = SAME_ORBIT_FACTOR * settings.tol * family.scale
        for j in range(i):
            r2, k2 = records[events[j][0]], events[j][1]
            if first[j] != j or r2["periods"] != r["periods"] or r2["event_type"][k2] != r["event_type"][k] or \
                    (not peak and abs(r2["event_parameter"][k2] - lam) > window):
                continue
            if peak:
                found = peak_candidates(r, k, r2, k2, family.peak, settings.tol) and \
                    _same_peak(family, r, k, r2, k2, settings)
            else:
                copies = copies or phase_copies(family, r["event_state"][k], lam, r["periods"])
                found = same_orbit(copies, r2["event_state"][k2], settings.tol)
            if found:
                first[i] = j
                break
    offsets = np.cumsum([0] + [len(r["event_type"]) for r in records])
    for b, r in enumerate(records):
        r["event_copy_of"] = np.array(first[offsets[b]:offsets[b + 1]], int)
    return mark_branch_copies(family, records, settings)


def _same_peak(family, r, k, r2, k2, settings):
    """Peak k of record r is a phase copy of peak k2 of r2, compared at one parameter: r's state
    corrected by Newton to r2's parameter (an orbit a few 1e-4 Hz away: Newton's first guess
    within its convergence), then `same_orbit`."""
    lam2 = float(r2["event_parameter"][k2])
    point = _corrected(family.with_periods(r["periods"]), lam2, r["event_state"][k], settings)
    return point is not None and same_orbit(phase_copies(family, r2["event_state"][k2], lam2, r["periods"]),
                                            point.state, settings.tol)


def _corrected(family, lam, guess, settings):
    """The orbit at lam Newton-corrected from guess (None: no convergence). Its kernels are imported
    here, not above: the readers below (info, query) load no Numba."""
    from rotorsweep.kernels.continuation import arclength as al
    return al.start(family, lam, guess, 1, settings)


def mark_branch_copies(family, records, settings):
    """Set records[b]["copy_of"] in place: the first record that is the same family of closed
    curves (-1: none), e.g. a period-2k loop reached from both its period doublings, or a
    period-k branch followed again from another phase. Branch b copies an earlier distinct
    record a of the same period when, in the middle of b's parameter range (away from the period
    doublings at a loop's ends, where the halves of a loop meet), one of b's orbits is a phase
    copy of one of a's (each record's chords bracketing it corrected by Newton, `_orbits_at`);
    the data of both stay, what users read lists the first."""
    for b, r in enumerate(records):
        r["copy_of"] = -1
        if len(r["parameter"]) < 2:
            continue
        lam = 0.5 * (float(np.min(r["parameter"])) + float(np.max(r["parameter"])))
        own = [point.state for point in _orbits_at(family, r, lam, settings, stable_only=False)]
        for a in range(b):
            ra = records[a]
            if ra["copy_of"] >= 0 or ra["periods"] != r["periods"]:
                continue
            if any(same_orbit(phase_copies(family, point.state, lam, r["periods"]), state, settings.tol)
                   for point in _orbits_at(family, ra, lam, settings, stable_only=False) for state in own):
                r["copy_of"] = a
                break
    return records


def line_coexistence(family, records, settings, lam_range):
    """[(lo, hi, branches)]: the line's parameter range cut at the ends of the branches' stable
    runs; per piece, one branch per DISTINCT stable orbit at its middle. Whole branches cannot be
    compared (the Bai rotor's period-4 branches cross at their period doublings and part there),
    so the orbits are: every stable chord of every branch bracketing the middle, corrected to its
    exact orbit there (Newton at fixed parameter), kept when it stayed near its chord (`_near`)
    and is not a phase copy of one kept before."""
    runs = [(lo, hi) for r in records for lo, hi in record_runs(r)]
    lo_r, hi_r = lam_range
    edges = sorted({lo_r, hi_r, *(x for run in runs for x in run if lo_r <= x <= hi_r)})
    return [(a, z, [b for b, _ in distinct_stable_orbits(family, records, settings, 0.5 * (a + z))])
            for a, z in zip(edges[:-1], edges[1:])]


def distinct_stable_orbits(family, records, settings, lam):
    """[(branch, Point)]: one per distinct stable orbit of the branch records at lam (every stable
    chord bracketing lam corrected to its exact orbit, phase copies of one kept before dropped);
    what line_coexistence counts, and what a sweep's jump records of its two coexisting orbits."""
    kept = []
    for b, r in enumerate(records):
        for point in _orbits_at(family, r, lam, settings):
            if not any(same_orbit(copies, point.state, settings.tol) for _, _, copies in kept):
                kept.append((b, point, phase_copies(family, point.state, lam, r["periods"])))
    return [(b, point) for b, point, _ in kept]


def _orbits_at(family, r, lam, settings, stable_only=True):
    """Points of the (stable) orbits of branch record r at lam (one per (stable) chord bracketing it)."""
    fam = family.with_periods(r["periods"])
    p = r["parameter"]
    stable = np.abs(r["multipliers"]).max(axis=1) < 1.0 if stable_only else np.ones(len(p), bool)
    out = []
    for i in np.flatnonzero(((p[:-1] - lam) * (p[1:] - lam) <= 0) & (stable[:-1] | stable[1:])):
        s0, s1 = r["state"][i], r["state"][i + 1]
        guess = s0 + (lam - p[i]) / (p[i + 1] - p[i]) * (s1 - s0) if p[i + 1] != p[i] else s0
        point = _corrected(fam, lam, guess, settings)
        if point is not None and _near(point.state, guess, s0, s1, settings) and (
                not stable_only or np.abs(point.multipliers).max() < 1.0):
            out.append(point)
    return out


def _near(state, guess, s0, s1, settings):
    """The corrected orbit is the chord's: a branch leaves its chord by at most the chord's length
    x the angle between successive tangents (max_angle; the sagitta of an arc turning by that
    angle is an eighth of it), plus the Newton-derived tolerance."""
    return np.abs(state - guess).max() <= settings.max_angle * np.abs(s1 - s0).max() + \
        SAME_ORBIT_FACTOR * settings.tol * max(1.0, float(np.abs(state).max()))


def record_runs(r):
    """[(lo, hi)] of a branch record's runs of stable orbits, ends at its located events."""
    stable = np.abs(r["multipliers"]).max(axis=1) < 1.0 if len(r["parameter"]) else np.zeros(0, bool)
    return runs_of(r["parameter"], stable, dict(zip(r["event_index"].tolist(), r["event_parameter"].tolist())))


def runs_of(lam, stable, located):
    """[(lo, hi)] runs of stable points along a branch (parameter lam); a run's end at a located
    event (located: {point before it: its parameter}) is the event's parameter, else the last
    stable point's."""
    n, runs, start = len(lam), [], None
    for i in range(n):
        if stable[i] and start is None:
            start = located.get(i - 1, lam[i])
        if start is not None and (i == n - 1 or not stable[i + 1]):
            end = located.get(i, lam[i]) if i < n - 1 else lam[i]
            runs.append((min(start, end), max(start, end)))
            start = None
    return runs


# --- on a result ---------------------------------------------------------------------------------

def event_copy_of(ds):
    n = ds.sizes.get("event", 0)
    return ds["event_copy_of"].values if "event_copy_of" in ds else np.arange(n)


def distinct_events(ds):
    """Indices of the located points listed once (the first record of each)."""
    return np.flatnonzero(event_copy_of(ds) == np.arange(ds.sizes.get("event", 0)))


def stable_runs(ds, b):
    """[(lo, hi)] parameter intervals of branch b's runs of stable orbits (runs_of)."""
    n = int(ds["branch_points"].values[b])
    located = {int(p): float(v) for br, p, v, k in zip(ds["event_branch"].values, ds["event_point"].values,
                                                       ds["event_parameter"].values, ds["event_type"].values)
               if br == b and k not in (codes.PEAK, codes.LOCKED) and np.isfinite(v)}
    # a peak or a locked ratio changes no stability; a torus flag not located has no parameter
    return runs_of(ds["parameter"].values[b, :n], ds["stable"].values[b, :n] == 1, located)


def _line_keys(ds):
    return [c for c in ds.coords if ds[c].dims == ("branch",)]


def coexistence(ds):
    """(line keys, {line values: [(lo, hi, branches)]}): the one answer to how many distinct
    stable orbits coexist where (the band map, `info` and the coexistence table all read it):
    each line's parameter range cut where that changes, `branches` one branch per distinct stable
    orbit (line_coexistence, computed in the line's task). A result written before that was
    recorded counts stable runs instead (a period-2k branch once: a loop holds s and phi_k(s))."""
    keys = _line_keys(ds)
    lines = {}
    if "piece_lo" in ds:
        for lo, hi, b, orbits in zip(ds["piece_lo"].values, ds["piece_hi"].values, ds["piece_line"].values,
                                     ds["piece_branches"].values):
            where = tuple(float(ds[c].values[b]) for c in keys)
            lines.setdefault(where, []).append((float(lo), float(hi), [int(x) for x in str(orbits).split()]))
        return keys, lines
    lo_r, hi_r = json.loads(ds.attrs["range"])
    for b in range(ds.sizes["branch"]):
        lines.setdefault(tuple(float(ds[c].values[b]) for c in keys), []).extend((lo, hi, b) for lo, hi in stable_runs(ds, b))
    out = {}
    for where, runs in lines.items():
        edges = sorted({lo_r, hi_r, *(x for lo, hi, _ in runs for x in (lo, hi) if lo_r <= x <= hi_r)})
        out[where] = [(a, z, _stable_here(ds, runs, 0.5 * (a + z))) for a, z in zip(edges[:-1], edges[1:])]
    return keys, out


def _stable_here(ds, runs, lam):
    periods = ds["branch_periods"].values
    covering = [b for lo, hi, b in runs if lo <= lam <= hi]
    return sorted(b for b in set(covering) for _ in range(covering.count(b) if periods[b] == 1 else 1))


def stability_classes(ds):
    """Per line: [(lo, hi, n)] pieces with n distinct stable orbits (0: none found, 1: stable,
    2+: multistable), from `coexistence`."""
    keys, lines = coexistence(ds)
    return keys, {w: [(lo, hi, len(bs)) for lo, hi, bs in pieces] for w, pieces in lines.items()}


def bistable_intervals(ds):
    """Where two or more distinct stable orbits coexist on one line: [{line values..., lo, hi,
    branches}], `coexistence`'s pieces with two or more, neighbours with the same branches merged."""
    keys, lines = coexistence(ds)
    width = np.ptp(json.loads(ds.attrs["range"]))
    out = []
    for where, pieces in lines.items():
        multi = [(lo, hi, bs) for lo, hi, bs in pieces if len(bs) >= 2 and hi - lo > 1e-9 * width]
        for _, group in itertools.groupby(_touching(multi), key=lambda p: p[3]):
            group = list(group)
            out.append({**dict(zip(keys, where)), "lo": group[0][0], "hi": group[-1][1],
                        "branches": sorted(set(group[0][2]))})
    return out


def _touching(pieces):
    """(lo, hi, branches, run number): consecutive pieces with equal branches share a run number."""
    run, prev = 0, None
    for lo, hi, bs in pieces:
        if prev is not None and (prev[2] != bs or prev[1] != lo):
            run += 1
        prev = (lo, hi, bs)
        yield lo, hi, tuple(bs), run


def branch_copy_of(ds):
    """Per branch: the first branch of the same closed curves (itself: distinct; a result written
    before copies were marked: every branch itself)."""
    n = ds.sizes.get("branch", 0)
    if "branch_copy_of" not in ds:
        return np.arange(n)
    copy = ds["branch_copy_of"].values
    return np.where(copy >= 0, copy, np.arange(n))


def distinct_branches(ds):
    """Indices of the branches listed once (no copy of an earlier one)."""
    return np.flatnonzero(branch_copy_of(ds) == np.arange(ds.sizes.get("branch", 0)))

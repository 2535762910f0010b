"""The torus line of `rotorsweep continue`: where the scene's forcing is quasi-periodic (two
frequencies, the model's `torus_forcing`), the response is an invariant 2-torus, followed along
the parameter by rotorsweep.kernels.continuation.tori instead of a periodic orbit.

The first torus comes from a settled transient: the stroboscopic map (one first-forcing period T,
the second forcing's phase advancing by rho) iterated SETTLE_PERIODS times from the model's cold
guess, then FIT_PERIODS samples fitted by a trigonometric interpolant (torus.fitted_guess) on
FIRST_NODES nodes (within the scene's bounds) and solved (torus.solve_torus, nodes grown until the
Fourier tail is below DECAY_TOL). Along the branch the node count adapts to the circle's spectral
decay (tori.follow_tori) within the bounds of the scene's [continuation] torus_min_modes and
torus_max_modes (K Fourier modes, 2K + 1 nodes; node_bounds): it grows (N -> 2N + 1) where a
point's tail exceeds DECAY_TOL, as the first torus's, and shrinks where a coarser count keeps it a
thousandfold below; at the most nodes the tail may rise to BREAKDOWN_TOL, and the branch ends `torus_breakdown` where it exceeds that, its detail
saying whether a contact opens along the last circle (contact_note: contact_loss, the usual cause).
Each point records its count (torus_modes: K of its 2K + 1 nodes).

Per point: the half-swing (half peak-to-peak) and max |o| of each observable over the torus,
the torus error estimate and Fourier modes, the normal stability and its largest exponent. The amplitudes are the
exact extrema (rotorsweep.kernels.extrema) of the trajectories over one period T from AMPLITUDE_PHASES
equally spaced phases of the circle: exact along each trajectory, sampled in the phase, so the
sup over the phase of each trajectory's extremum is low by at most its curvature in the phase
times (pi / AMPLITUDE_PHASES)^2 / 2 (a parabola's drop at half the phase spacing): ~1.2e-3
relative for a swing varying over the phase by O(1) of itself, less for weak phase dependence
(tests/test_torus_continue.py: 1e-4 against a long DOP853 transient).

A long branch reports its progress every PROGRESS_SECONDS (BranchProgress, through the family's
on_point): the parameter reached, the points solved, the Fourier modes, the locked ratios passed.
The lines are logged (the command's log file) and shown on the stream that `progress_on` names in
this process (`continue` in-process: its stream; a Dask worker's lines stay in that worker).
"""
import contextlib
import time

import numpy as np

from rotorsweep.pipeline import compute, runlog, torus_events, torus_points
from rotorsweep.pipeline.torus_points import AMPLITUDE_PHASES, DECAY_TOL, FIRST_NODES, FIT_PERIODS, SETTLE_PERIODS
from rotorsweep.kernels import torus as tr
from rotorsweep.kernels.continuation import engine, tori

BREAKDOWN_TOL = 1e-7    # a tail above it at the most nodes ends the branch (below it: more nodes above DECAY_TOL)
# The torus branch's parameter counts in its own unit (Hz), not in range widths: the circle's rms
# change is ~0.02 per Hz where the response is flat (Fig. 3a), so there a step of ds_max moves the
# parameter by ~ds_max Hz whatever the range, and near a resonance the circle by ~ds_max (tori.py).
PARAMETER_UNIT = 1.0
POLISH_TOL = 1e-12      # each stored circle's residual, relative to max(1, max |U|) (tori.polish)
TORUS_STATUS = {tr.UNSTABLE: 0, tr.STABLE: 1, tr.UNDECIDED: 2}
PROGRESS_SECONDS = 10.0  # between two progress lines of one branch


class _Shown:
    """Where this process shows the torus progress lines (progress_on; None: only logged)."""
    stream = None


@contextlib.contextmanager
def progress_on(stream):
    """Show the torus branches' progress lines computed in this process on `stream` (None: none)."""
    old, _Shown.stream = _Shown.stream, stream
    try:
        yield
    finally:
        _Shown.stream = old


class BranchProgress:
    """The family's on_point: a line every PROGRESS_SECONDS (module docstring). Points solved
    counts every corrector solution (steps, retried steps, located events, a step past the
    range's edge), the branch's own points are fewer."""

    def __init__(self, pl, family, max_q):
        self.pl, self.family, self.seconds = pl, family, PROGRESS_SECONDS
        self.locks = tori.locked_ratios(family, pl.range, max_q)
        self.solved, self.t0 = 0, time.monotonic()
        self.last = self.t0

    def __call__(self, point):
        self.solved += 1
        now = time.monotonic()
        inside = min(self.pl.range) <= point.lam <= max(self.pl.range)    # a step past the edge is not reached
        if inside and now - self.last >= self.seconds:
            self.last = now
            runlog.phase_printer(_Shown.stream)(self.line(point, now - self.t0))

    def line(self, point, elapsed):
        pl = self.pl
        done = (point.lam - pl.start) / (pl.stop - pl.start)
        passed = [f"{e.p}/{e.q}" for e in self.locks if (e.level - pl.start) * (e.level - point.lam) <= 0]
        modes = (self.family.nodes(point.X).shape[0] - 1) // 2
        return (f"torus branch: {pl.parameter} {point.lam:.6g} ({done:.0%} of {pl.start:g} to {pl.stop:g}) after "
                f"{runlog.fmt_seconds(elapsed)}, {self.solved} points solved, {modes} Fourier modes, locked ratios "
                f"passed: {' '.join(passed) or 'none'}")


def shown(items, what):
    """The items one by one, with a line every PROGRESS_SECONDS while they take long ("torus record:
    polishing 40 of 925 points after 1m10s"): the record after a branch (each point polished, its
    amplitudes over the circle, the locked ratios' periodic orbits) took longer than the branch
    itself on Fig. 3a (3.3 of 5.9 min wall) and was silent."""
    items = list(items)
    say = runlog.phase_printer(_Shown.stream)
    t0 = last = time.monotonic()
    for k, item in enumerate(items):
        now = time.monotonic()
        if now - last >= PROGRESS_SECONDS:
            last = now
            say(f"torus record: {what} {k} of {len(items)} after {runlog.fmt_seconds(now - t0)}")
        yield item


def is_torus_line(scene, parameter, start, where):
    """Whether the line's forcing at the start is quasi-periodic (a torus, not an orbit)."""
    spec = scene.model
    if not spec.torus_forcing:
        return False
    return not _builder(scene, where, parameter)(start).periodic


def _builder(scene, where, parameter):
    """lambda -> Built with the model's torus values (tau: one first-forcing period)."""
    build = compute.builder(scene)
    values = {**scene.fixed, **where, **scene.model.torus_forcing[2]}
    return lambda lam: build({**values, parameter: lam})


def node_bounds(scene):
    """(fewest, most) nodes of the scene's torus branches: [continuation] torus_min_modes and
    torus_max_modes K, 2K + 1 nodes each."""
    sec = scene.continuation
    return 2 * int(sec.torus_min_modes) + 1, 2 * int(sec.torus_max_modes) + 1


def torus_family(scene, pl, where, n_nodes):
    spec = scene.model
    phase, freq, _ = spec.torus_forcing
    built = _builder(scene, where, pl.parameter)
    lo, hi = node_bounds(scene)
    return tori.TorusFamily(spec.kernel, lambda lam: built(lam).p, lambda lam: float(built(lam).p[freq]), phase,
                            scene.integrator, n_nodes, scale=PARAMETER_UNIT,
                            decay_tol=DECAY_TOL, min_nodes=lo, max_nodes=hi, breakdown_tol=BREAKDOWN_TOL), built


def first_torus(scene, pl, where):
    """(the first torus at the start, the family sized to it, built); the torus's status says
    whether it converged."""
    spec = scene.model
    phase, freq, _ = spec.torus_forcing
    lo, hi = node_bounds(scene)
    n_first = min(max(FIRST_NODES, lo), hi)
    family, built = torus_family(scene, pl, where, n_first)
    p = built(pl.start).p
    circle = tr.torus_from_transient(spec.kernel, spec.cold_guess(p), p, phase, p[freq], family.opts, SETTLE_PERIODS,
                                     FIT_PERIODS, n_first, tol=pl.settings.tol, decay_tol=DECAY_TOL, max_nodes=hi)
    if circle is None:
        return None, family, built
    return circle, family._replace(n_nodes=circle.nodes.shape[0]), built


def continue_torus_line(scene, pl, where):
    """The torus branch of one line as a one-record list (branch_record's keys plus torus_*)."""
    spec = scene.model
    circle, family, built = first_torus(scene, pl, where)
    direction = 1 if pl.stop > pl.start else -1
    if circle is None or circle.status != tr.CONVERGED:
        why = "the transient failed" if circle is None else f"the torus solve ended {circle.status}"
        return [torus_record(spec, family, built, engine.Run([], [], engine.START_FAILED,
                                                       f"no torus at {pl.parameter} = {pl.start!r}: {why}"), 0)]
    family = family._replace(on_point=BranchProgress(pl, family, torus_events.LOCK_DENOMINATOR))
    counter = engine.Counter()
    first = tori.start(family, pl.start, circle.nodes, direction, pl.settings, counter)
    if first is None:
        run, errors = engine.Run([], [], engine.START_FAILED, f"the torus start did not converge at {pl.start!r}"), []
    else:
        run, errors = polished(family, tori.follow_tori(family, first, pl.range, pl.settings, counter,
                                                        torus_events.LOCK_DENOMINATOR))
        run = run._replace(detail=run.detail + contact_note(spec, family, run))
    record = torus_record(spec, family, built, run, counter.n, errors)
    record["coexistence"] = stable_pieces(record, pl.range)
    return [record]


def contact_note(spec, family, run):
    """Where the branch ends torus_breakdown on a model with contacts: whether a contact opens along
    its last circle (torus_points.contact_margin), the usual cause (module docstring of
    torus_points); "" otherwise."""
    if run.end != engine.TORUS_BREAKDOWN or spec.contact_margin is None or not run.points:
        return ""
    last = run.points[-1]
    margin = torus_points.contact_margin(spec, family.torus(last), family.params(last.lam), family.opts)
    if not margin < 0:
        return f"; every contact stays closed along the last circle (smallest deflection {margin:+.3g} of the static one)"
    return (f"; contact_loss: a contact opens along the last circle (smallest deflection {margin:+.3g} of the "
            f"static one), the contact force is not smooth there")


def polished(family, run):
    """(run, errors): the run with each point's and located event's circle refined to POLISH_TOL
    at its lambda (tori.polish: what the result stores, its amplitudes and error estimate, is then
    solved far below the continuation's corrector tolerance; docs/guide/continue.md, "error
    estimate"), and each point's error estimate (torus_error) from the polish's last Jacobian."""
    def refine(point):
        return None if point is None else tori.polish(family, point, POLISH_TOL)[0]
    done = [tori.polish(family, p, POLISH_TOL) for p in shown(run.points, "polishing points:")]
    errors = [torus_error(family, p, jac) for p, jac in done]
    return run._replace(points=[p for p, _ in done], found=[f._replace(point=refine(f.point)) for f in run.found]), errors


def stable_pieces(record, lam_range):
    """The line's coexistence pieces (rotorsweep.pipeline.coexistence's (lo, hi, stable branches)): between
    two consecutive points the torus branch (0) is stable where both ends are; outside the
    points nothing is known stable."""
    lam, stable = record["parameter"], record["torus_status"] == TORUS_STATUS[tr.STABLE]
    if len(lam) < 2:
        return [(*lam_range, [])]
    pieces = [(min(a, b), max(a, b), [0] if sa and sb else [])
              for a, b, sa, sb in zip(lam[:-1], lam[1:], stable[:-1], stable[1:])]
    lo, hi = lam.min(), lam.max()
    return ([(lam_range[0], lo, [])] if lo > lam_range[0] else []) + sorted(pieces) + (
        [(hi, lam_range[1], [])] if hi < lam_range[1] else [])


def torus_record(model, family, built, run, n_rhs, errors=()):
    """One torus branch as plain arrays: the orbit record's keys (multipliers NaN, orbit_state
    the circle at phase 0, period T), torus_error (`errors`: polished's, one per point; none
    for a run without points), torus_exponent [1/s], torus_status, torus_modes
    (K of each point's 2K + 1 nodes), torus_nodes (points, N, n: the circle's node values, scaled
    state, at phases 2 pi j / N_k, NaN beyond a point's own N_k), and the branch's events
    (rotorsweep.pipeline.torus_events: flags and locked ratios, with event_note)."""
    n_state = family.kernel.n_state
    pts = run.points
    if len(errors) != len(pts):
        raise ValueError(f"{len(errors)} error estimates for {len(pts)} torus points")
    amp = np.array([torus_amplitudes(model, family, built, p) for p in shown(pts, "amplitudes of points:")]).reshape(
        len(pts), 2, len(model.observables))
    counts = np.array([family.nodes(p.X).shape[0] for p in pts], int)
    periods = np.array([built(p.lam).period for p in pts])
    none = np.zeros(0)
    return {**torus_events.event_rows(model, family, built, run,
                                      lambda p: torus_amplitudes(model, family, built, p),
                                      lambda found: shown(found, "events (locked ratios' orbits):")),
        "parameter": np.array([p.lam for p in pts]), "arclength": arclength(family, pts),
        "state": np.array([family.nodes(p.X)[0] for p in pts]).reshape(len(pts), n_state),
        "multipliers": np.full((len(pts), n_state), np.nan + 0j),
        "amplitude_max": amp[:, 0], "amplitude_half_pp": amp[:, 1], "period": periods,
        "periods": 1, "parent": -1, "end": int(run.end), "detail": run.detail, "n_rhs": int(n_rhs),
        "torus_error": np.array(errors, float),
        "torus_exponent": np.array([p.stability.exponents[0] for p in pts]) / periods if len(pts) else none,
        "torus_status": np.array([TORUS_STATUS[p.stability.status] for p in pts], int),
        "torus_modes": (counts - 1) // 2,
        "torus_nodes": padded_nodes(family, pts, counts.max(initial=1)),
    }


def arclength(family, points):
    """Cumulative chord length along the points (normalized unknowns; where the node count
    changes, the earlier point's circle re-interpolated at the later count)."""
    steps = [np.linalg.norm(tori.resampled(family, b.X, family.nodes(a.X).shape[0]) - a.X)
             for a, b in zip(points[:-1], points[1:])]
    return np.concatenate(([0.0], np.cumsum(steps)))[:len(points)]


def padded_nodes(family, points, n_nodes):
    """(points, n_nodes, n) the points' node values, NaN beyond each point's own count."""
    out = np.full((len(points), n_nodes, family.kernel.n_state), np.nan)
    for k, p in enumerate(points):
        nodes = family.nodes(p.X)
        out[k, :len(nodes)] = nodes
    return out


def torus_error(family, point, jacobian):
    """The point's error estimate (torus.error_estimate) from dR/dX at its circle (tori.polish's;
    inf where that or the estimate's shots failed)."""
    if jacobian is None:
        return np.inf
    lam = family.lam(point.X)
    err, ok, _ = tr.error_estimate(family.kernel, family.nodes(point.X), family.circle_jacobian(point.X, jacobian),
                                   family.params(lam), family.phase_index, family.rotation(lam), family.period,
                                   family.opts, point.tail)
    return err if ok else np.inf


def torus_amplitudes(model, family, built, point):
    """(max |o|, half peak-to-peak of o) over the torus for each observable, SI (module docstring)."""
    lam = family.lam(point.X)
    hi, lo = tr.phase_extremes(model, family.torus(point), family.params(lam), family.phase_index, family.opts,
                               built(lam).period, AMPLITUDE_PHASES)
    hi, lo = hi.max(axis=0), lo.min(axis=0)
    return np.maximum(hi, -lo), 0.5 * (hi - lo)

"""Two-parameter continuation of bifurcation points of forced periodic orbits: a fold (LP), a
period-doubling (PD) or a Neimark-Sacker (NS) point located on a branch by `arclength` is followed
in a second scene parameter nu (a clearance, a preload, a forcing amplitude, ...), which gives the
stability boundary as a curve in the (lambda, nu) plane.

Formulation: the minimally augmented system (Govaerts and Kuznetsov; MatCont and BifurcationKit
use it). Unknowns Y = (s, mu, eta), the orbit's scaled initial state s, mu = lambda / lam_scale,
eta = nu / nu_scale (scales that make both O(1), as `arclength.Family.scale` does for lambda);
for NS also kappa = cos(theta) of the critical pair exp(+-i theta): Y = (s, kappa, mu, eta).
Equations: phi(s, lambda, nu) - s = 0, G = 0 and the arclength condition t . (Y - Y_k) = ds,
with G the k x k block of the bordered system

    [[A, B], [C^T, 0]] [W; G] = [0; I],
    A = M - I (fold), M + I (PD), M^2 - 2 kappa M + I (NS, k = 2; fold and PD: k = 1),

B, C the left and right null vectors of A at the previous curve point. The bordered matrix stays
regular near the curve, and G = 0 exactly where A has a k-dimensional kernel, i.e. a multiplier at
+1, at -1, or the pair exp(+-i theta). For NS two of G's four entries are solved, the pair whose
rows condition the Newton matrix best, chosen again at every curve point (as MatCont does).
Why this system: it has n + 2 (n + 3) unknowns where the standard augmented system
[phi - s, A w, w.w - 1] has 2n + 2 (NS: 3n + 3) and needs the derivatives of A w in all of them;
G is smooth and well scaled near the curve (|G| ~ the smallest singular values of A), unlike
det(A), whose scale drifts with the other multipliers; and G has a cheap gradient:

    G_ij,z = -v_i^T (dA/dz) w_j,   V from the transposed bordered system (V^T A + G C^T = 0, V^T B = I),
    dA/dz = dM/dz (fold, PD),  dM/dz M + M dM/dz - 2 kappa dM/dz (NS),  dA/dkappa = -2 M.

- In s: the row (a^T (dM/ds_l) b)_l equals a^T D_b M, with D_b M the derivative of M along b
  (second derivatives of phi are symmetric), a central difference of two variational integrations
  at s +- h b / |b|: two integrations per direction b (fold, PD: b = w; NS: w_j and M w_j), whatever
  n is (column by column would take 2n, 8 for the Jeffcott model and 20 for a 5-DOF model).
- In lambda and nu: central differences of two variational integrations each, which also give the
  columns dphi/dmu, dphi/deta (the models are not differentiated in their parameters).
So a Newton iterate costs 7 variational integrations (NS: 13). With the step 1e-5 (`fd_step`,
scaled units) the truncation error is O(1e-10) and the integrator's noise ~ rtol / 1e-5; these
columns enter only the Newton matrix and the tangent, never the residuals phi - s and G, so, as in
`arclength`, the converged curve points are exact to the Newton tolerances and the integrator's
accuracy, and an error of the columns only slows Newton down a little.

A curve is a problem of the continuation engine (`BifurcationCurve`, engine's contract), which
owns the steps as for every problem: tangent predictor, the step grows after a fast corrector and
halves after a failed or slow one or a turn of the tangent by more than `max_angle`; B and C are
renewed at every accepted point (carried on the points). A curve ends on the edge of the parameter
box (the edge point is solved exactly), when it closes on its first point, when the step budget
is spent or when the corrector fails at the minimum step, always with a status (engine's
END_REASONS) and never an exception. Curve points at given values of nu (`marks`: the clearances
of a sweep's grid, for a cross-check with its refined boundaries) are `events.Level` events,
solved exactly where the curve crosses them; the codimension-2 points are `events.Flag` events.

Codimension-2 points are flagged between two curve points, not located: on a fold curve, a cusp
(the curve's projection on the (lambda, nu) plane reverses: both parameter components of the
tangent change sign) and a fold-flip (another multiplier crosses -1); on a PD curve, a fold-flip
(another multiplier crosses +1) and a 1:2 resonance (a second multiplier reaches -1); on an NS
curve, the strong resonances 1:1, 1:2, 1:3, 1:4 (kappa crosses 1, -1, -1/2, 0; beyond |kappa| = 1
the curve goes on as a neutral saddle, where the pair is real with product 1).
"""
import itertools
from dataclasses import dataclass, replace
from typing import Callable, NamedTuple

import numpy as np

from rotorsweep.kernels import floquet, integrators as ig
from rotorsweep.kernels.continuation import arclength as al, engine, events as ev
from rotorsweep.kernels.continuation.engine import (  # noqa: F401 (the names this module has always offered)
    END_REASONS, INTEGRATION_FAILED, LEFT_RANGE, NEWTON_FAILED, START_FAILED, STEP_BUDGET)

CLOSED = engine.CLOSED_LOOP     # the curve came back to its first point (an isola)

# The critical multiplier by event kind: A = M - critical I is singular on the curve.
CRITICAL = {al.FOLD: 1.0, al.PERIOD_DOUBLING: -1.0}
KINDS = (al.FOLD, al.PERIOD_DOUBLING, al.NEIMARK_SACKER)
CODIM2_LABELS = ("cusp", "fold_flip", "resonance_1_2", "resonance_1_1", "resonance_1_3", "resonance_1_4")
CUSP, FOLD_FLIP, RESONANCE_1_2, RESONANCE_1_1, RESONANCE_1_3, RESONANCE_1_4 = range(6)
# kappa = cos(theta) of a Neimark-Sacker pair at the strong resonances
STRONG_RESONANCES = ((RESONANCE_1_1, 1.0), (RESONANCE_1_2, -1.0), (RESONANCE_1_3, -0.5), (RESONANCE_1_4, 0.0))


@dataclass(frozen=True)
class Settings(engine.Settings):
    """engine.Settings and the tolerance on the solved entries of G (absolute: with orthonormal
    B, C, |G| is about the distance of the critical multipliers from where they must be)."""
    tol_g: float = 1e-9

    def problems(self):
        out = super().problems()
        if not self.tol_g > 0:
            out.append(f"tol_g = {self.tol_g!r}: must be > 0")
        return out


class Plane(NamedTuple):
    """The forced-orbit problems of `model` over (lambda, nu): params(lambda, nu) -> kernel vector."""
    model: object
    params: Callable
    opts: np.ndarray
    lam_scale: float = 1.0
    nu_scale: float = 1.0
    periods: float = 1.0

    def family(self, nu):
        """The one-parameter family along lambda at fixed nu (for arclength.continue_orbit)."""
        return al.Family(self.model, lambda lam: self.params(lam, nu), self.opts, self.lam_scale, self.periods)

    def split(self, Y):
        """(s, lambda, nu) of the unknowns Y = (s, mu, eta) or (s, kappa, mu, eta)."""
        return Y[:self.model.n_state], Y[-2] * self.lam_scale, Y[-1] * self.nu_scale


class CurvePoint(NamedTuple):
    """A converged point of a bifurcation curve."""
    Y: np.ndarray           # (s, mu, eta); NS: (s, kappa, mu, eta)
    lam: float
    nu: float
    monodromy: np.ndarray
    multipliers: np.ndarray
    critical: complex       # the multiplier nearest to +1 (fold), -1 (PD), exp(i theta) (NS)
    tangent: np.ndarray     # unit, oriented along the direction of travel
    border: tuple           # (B, C, entries): left and right null vectors of A here, G's entries solved
    iterations: int
    residual: float         # max|phi - s| / max(1, max|s|)
    g: float                # max |G_ij| over the entries solved

    @property
    def state(self):
        return self.Y[:self.monodromy.shape[0]]

    @property
    def X(self):
        """The unknowns (the engine's name for Y)."""
        return self.Y


class Codim2(NamedTuple):
    kind: int               # CODIM2_LABELS index
    index: int              # between points[index] and points[index + 1]


class Curve(NamedTuple):
    kind: int               # arclength.FOLD, PERIOD_DOUBLING or NEIMARK_SACKER
    points: list            # CurvePoint, in the order of travel
    marked: list            # CurvePoint where nu equals one of the marks, in the order met
    codim2: list            # Codim2
    end: int                # END_REASONS index
    detail: str
    periods: float
    n_rhs: int


class _IntegrationFailed(Exception):
    """The flow diverged or failed at one of the integrations of a Newton iterate."""


class _Linearization(NamedTuple):
    r: np.ndarray           # phi - s
    monodromy: np.ndarray
    G: np.ndarray           # k x k bordering block (k = 1: fold, PD; 2: NS)
    V: np.ndarray           # n x k left solution of the bordered system
    W: np.ndarray           # n x k right solution (A W = -B G)


def _coefficients(kind, Y, n):
    """(a2, a1, a0) of A = a2 M^2 + a1 M + a0 I."""
    if kind == al.NEIMARK_SACKER:
        return 1.0, -2.0 * Y[n], 1.0
    return 0.0, 1.0, -CRITICAL[kind]


def _matrix(kind, Y, mono):
    a2, a1, a0 = _coefficients(kind, Y, mono.shape[0])
    return a2 * mono @ mono + a1 * mono + a0 * np.eye(mono.shape[0])


def _flow(plane, s, lam, nu, counter):
    r, mono, status, n_rhs = plane.family(nu).return_map(s, lam, True)
    counter.n += n_rhs
    if status != ig.STATUS_OK:
        raise _IntegrationFailed
    return r, mono


def _bordered_solutions(A, border):
    """(W, G, V) of [[A, B], [C^T, 0]] [W; G] = [0; I] and its transpose."""
    B, C, _ = border
    n, k = B.shape
    K = np.zeros((n + k, n + k))
    K[:n, :n], K[:n, n:], K[n:, :n] = A, B, C.T
    E = np.zeros((n + k, k))
    E[n:] = np.eye(k)
    right, left = np.linalg.solve(K, E), np.linalg.solve(K.T, E)
    return right[:n], right[n:], left[:n]


def _linearize(plane, kind, Y, border, counter):
    """phi - s and the bordering block G at Y: the residuals are phi - s and G at border's entries."""
    s, lam, nu = plane.split(Y)
    r, mono = _flow(plane, s, lam, nu, counter)
    W, G, V = _bordered_solutions(_matrix(kind, Y, mono), border)
    return _Linearization(r, mono, G, V, W)


def _residual(lin, border):
    return np.array([lin.G[i, j] for i, j in border[2]])


def _along(plane, Y, b, fd_step, counter):
    """D_b M: the derivative of the monodromy along b in s (central difference)."""
    s, lam, nu = plane.split(Y)
    width = np.linalg.norm(b)
    h = fd_step * max(1.0, np.abs(s).max())
    _, m_plus = _flow(plane, s + h * b / width, lam, nu, counter)
    _, m_minus = _flow(plane, s - h * b / width, lam, nu, counter)
    return (m_plus - m_minus) * width / (2.0 * h)


def _jacobian(plane, kind, Y, lin, fd_step, counter):
    """The rows of phi - s and of every entry G_ij (module docstring): (Jphi, {(i, j): row})."""
    s, lam, nu = plane.split(Y)
    n, M = s.size, lin.monodromy
    a2, a1, _ = _coefficients(kind, Y, n)
    Jphi = np.zeros((n, Y.size))
    Jphi[:, :n] = M - np.eye(n)
    rows = {(i, j): np.zeros(Y.size) for i in range(lin.W.shape[1]) for j in range(lin.W.shape[1])}
    along_w = [_along(plane, Y, w, fd_step, counter) for w in lin.W.T]
    along_mw = [_along(plane, Y, M @ w, fd_step, counter) for w in lin.W.T] if a2 else None
    for (i, j), row in rows.items():
        v, w = lin.V[:, i], lin.W[:, j]
        row[:n] = -a1 * (v @ along_w[j])
        if a2:
            row[:n] -= a2 * (v @ along_mw[j] + (M.T @ v) @ along_w[j])
            row[n] = 2.0 * (v @ M @ w)                  # dA/dkappa = -2 M
    for k in (Y.size - 2, Y.size - 1):
        step = fd_step * max(1.0, abs(Y[k]))
        up, down = Y.copy(), Y.copy()
        up[k] += step
        down[k] -= step
        r_up, m_up = _flow(plane, s, *plane.split(up)[1:], counter)
        r_down, m_down = _flow(plane, s, *plane.split(down)[1:], counter)
        Jphi[:, k] = (r_up - r_down) / (2.0 * step)
        dM = (m_up - m_down) / (2.0 * step)
        dA = a2 * (dM @ M + M @ dM) + a1 * dM
        for (i, j), row in rows.items():
            row[k] = -(lin.V[:, i] @ dA @ lin.W[:, j])
    return Jphi, rows


def _system(Jphi, rows, entries):
    return np.vstack([Jphi] + [rows[e] for e in entries])


def _best_entries(Jphi, rows, t):
    """For NS the two entries of G whose rows make the Newton matrix best conditioned (largest
    |det| with unit rows); for fold and PD the one entry."""
    if len(rows) == 1:
        return tuple(rows)
    unit = {e: r / np.linalg.norm(r) for e, r in rows.items()}
    pairs = list(itertools.combinations(sorted(unit), 2))
    return max(pairs, key=lambda pair: abs(np.linalg.det(np.vstack([_system(Jphi, unit, pair), t]))))


def _orthonormal(X):
    return np.linalg.qr(X)[0]


def _critical(kind, Y, lams):
    """The multiplier nearest to +1 (fold), -1 (PD), or to the root of mu^2 - 2 kappa mu + 1 with
    positive imaginary part (NS)."""
    if kind == al.NEIMARK_SACKER:
        kappa = Y[lams.size]
        target = complex(kappa, np.sqrt(max(0.0, 1.0 - kappa * kappa)))
    else:
        target = CRITICAL[kind]
    return complex(lams[np.argmin(np.abs(lams - target))])


def _border_at(kind, Y, mono):
    """Left and right singular vectors of A's k smallest singular values, all entries of G."""
    U, _, Vt = np.linalg.svd(_matrix(kind, Y, mono))
    k = 2 if kind == al.NEIMARK_SACKER else 1
    return U[:, -k:], Vt[-k:].T, tuple(itertools.product(range(k), repeat=2))


def _initial_unknowns(plane, event, nu0):
    """Y at the event: (s, mu, eta), with kappa = cos(theta) of the critical pair for NS."""
    p = event.point
    Y = [p.state]
    if event.kind == al.NEIMARK_SACKER:
        # the multiplier nearest the unit circle among those with a positive imaginary part
        pair = p.multipliers[np.argmin(np.abs(np.abs(p.multipliers) - 1.0) + (p.multipliers.imag <= 0))]
        Y.append([pair.real / abs(pair)])
    return np.concatenate(Y + [[p.lam / plane.lam_scale, nu0 / plane.nu_scale]])


class _Solution(NamedTuple):
    Y: np.ndarray
    lin: _Linearization
    iterations: int
    residual: float

    @property
    def X(self):
        return self.Y


class _Seed(NamedTuple):
    """A stand-in for the point a corrector starts from: its tangent and border."""
    tangent: np.ndarray
    border: tuple


class BifurcationCurve(NamedTuple):
    """The curve of fold, PD or NS points (`kind`) of plane's orbits over (lambda, nu): an engine
    problem (engine's contract), unknowns Y (module docstring), Newton corrector on the minimally
    augmented system bordered with the border carried by the point it starts from."""
    plane: Plane
    kind: int

    @property
    def parameters(self):
        return (("lambda", -2, self.plane.lam_scale), ("nu", -1, self.plane.nu_scale))

    def correct(self, Y0, c, target, at, settings, counter):
        """Newton on [phi - s = 0, G at the border's entries = 0, c . Y = target] from Y0:
        (solution, None) or (None, failure), failure NEWTON_FAILED or INTEGRATION_FAILED."""
        plane, kind, border = self.plane, self.kind, at.border
        Y = Y0.copy()
        try:
            for it in range(settings.max_newton + 1):
                lin = _linearize(plane, kind, Y, border, counter)
                g = _residual(lin, border)
                res = np.abs(lin.r).max() / max(1.0, np.abs(plane.split(Y)[0]).max())
                if res <= settings.tol and np.abs(g).max() <= settings.tol_g:
                    return _Solution(Y, lin, it, res), None
                if it == settings.max_newton:
                    break
                Jphi, rows = _jacobian(plane, kind, Y, lin, settings.fd_step, counter)
                K = np.vstack([_system(Jphi, rows, border[2]), c])
                Y = Y + np.linalg.solve(K, -np.concatenate([lin.r, g, [c @ Y - target]]))
        except _IntegrationFailed:
            return None, INTEGRATION_FAILED
        except np.linalg.LinAlgError:
            pass
        return None, NEWTON_FAILED

    def point(self, sol, at, settings, counter):
        """A converged solution made a CurvePoint (tangent and renewed border there); None if that
        failed."""
        plane, kind, Y, lin = self.plane, self.kind, sol.Y, sol.lin
        try:
            Jphi, rows = _jacobian(plane, kind, Y, lin, settings.fd_step, counter)
            t = engine.tangent(np.vstack([_system(Jphi, rows, at.border[2]), at.tangent]))
        except (_IntegrationFailed, np.linalg.LinAlgError):
            return None
        _, lam, nu = plane.split(Y)
        lams = floquet.multipliers(lin.monodromy)
        renewed = (_orthonormal(lin.V), _orthonormal(lin.W), _best_entries(Jphi, rows, t))
        return CurvePoint(Y, lam, nu, lin.monodromy, lams, _critical(kind, Y, lams), t, renewed, sol.iterations,
                          sol.residual, float(np.abs(_residual(lin, at.border)).max()))

    def where(self, point):
        return f"lambda = {point.lam!r}, nu = {point.nu!r}"

    def solves_edge(self, k, edge):
        return True


def start(plane, event, nu0, direction=1, settings=Settings(), counter=None):
    """The first curve point: the event's point (a fold, period doubling or Neimark-Sacker point
    located by arclength on the branch at nu = nu0) corrected on the augmented system at fixed
    nu0, its tangent pointing to increasing nu for direction +1. Returns (CurvePoint or None,
    detail)."""
    counter = counter or engine.Counter()
    p = event.point
    curve = BifurcationCurve(plane, event.kind)
    Y0 = _initial_unknowns(plane, event, nu0)
    fixed = np.zeros(Y0.size)
    fixed[-1] = 1.0
    patient = replace(settings, max_newton=max(settings.max_newton, engine.START_NEWTON))
    border = _border_at(event.kind, Y0, p.monodromy)
    try:
        lin = _linearize(plane, event.kind, Y0, border, counter)
        border = border[:2] + (_best_entries(*_jacobian(plane, event.kind, Y0, lin, settings.fd_step, counter),
                                             fixed),)
    except (_IntegrationFailed, np.linalg.LinAlgError):
        return None, f"no linearization at the event (lambda = {p.lam!r}, nu = {nu0!r})"
    seed = _Seed(direction * fixed, border)
    sol, failure = curve.correct(Y0, fixed, Y0[-1], seed, patient, counter)
    if failure is not None:
        return None, f"{END_REASONS[failure]} correcting the event at lambda = {p.lam!r}, nu = {nu0!r}"
    first = curve.point(sol, seed, settings, counter)
    return first, ("" if first is not None else f"no tangent at lambda = {p.lam!r}, nu = {nu0!r}")


def _codim2_events(kind):
    """The codimension-2 flags of a curve of `kind` (module docstring), in the order listed."""
    if kind == al.NEIMARK_SACKER:
        return [ev.KappaCrosses(code, kappa, CODIM2_LABELS[code]) for code, kappa in STRONG_RESONANCES]
    flags = [ev.Cusp(CUSP, CODIM2_LABELS[CUSP])] if kind == al.FOLD else []
    flags.append(ev.OtherMultiplierCrosses(FOLD_FLIP, -CRITICAL[kind], CODIM2_LABELS[FOLD_FLIP]))
    if kind == al.PERIOD_DOUBLING:
        flags.append(ev.OtherMultiplierCrosses(RESONANCE_1_2, -1.0, CODIM2_LABELS[RESONANCE_1_2]))
    return flags


def _codim2_between(kind, a, b):
    """Codimension-2 kinds flagged between a and b (module docstring)."""
    return [flag.code for flag in _codim2_events(kind) if flag.detect(None, a, b)]


def follow_curve(plane, kind, first, box, settings=Settings(), marks=(), counter=None):
    """Pseudo-arclength continuation of the bifurcation curve of `kind` from the CurvePoint
    `first` until it leaves box = ((lambda_lo, lambda_hi), (nu_lo, nu_hi)), closes, the step budget
    is spent, or the corrector fails at the minimum step (engine.follow). Curve points at the nu
    values `marks` are solved where the curve crosses them."""
    counter = counter or engine.Counter()
    levels = [ev.Level(m, k=1) for m in marks]
    run = engine.follow(BifurcationCurve(plane, kind), first, box, settings, levels + _codim2_events(kind), counter)
    marked = [first for m in marks if ev.same_value(m, first.nu)]
    marked += [f.point for f in run.found if f.event.locates]
    codim2 = [Codim2(f.event.code, f.index) for f in run.found if not f.event.locates]
    return Curve(kind, run.points, marked, codim2, run.end, run.detail, plane.periods, counter.n)


def continue_bifurcation(plane, event, nu0, box, settings=Settings(), direction=1, marks=()):
    """Follow the fold, period doubling or Neimark-Sacker `event` (located by arclength on a branch of
    plane.family(nu0)) in (lambda, nu) from nu0, towards increasing nu for direction +1.

    Raises ValueError for arguments that cannot work (settings, event kind, a start outside the
    box) before any integration; every numerical failure is the returned Curve's status."""
    problems = settings.problems()
    (lo, hi), (nu_lo, nu_hi) = box
    if not (lo <= event.point.lam <= hi and nu_lo <= nu0 <= nu_hi):
        problems.append(f"the event (lambda = {event.point.lam!r}, nu = {nu0!r}) lies outside the box {box!r}")
    if event.kind not in KINDS:
        problems.append(f"event kind {al.EVENT_TYPES[event.kind]!r}: only fold, period_doubling and "
                        "neimark_sacker curves are continued")
    if problems:
        raise ValueError("; ".join(problems))
    counter = engine.Counter()
    first, detail = start(plane, event, nu0, direction, settings, counter)
    if first is None:
        return Curve(event.kind, [], [], [], START_FAILED, detail, plane.periods, counter.n)
    return follow_curve(plane, event.kind, first, box, settings, marks, counter)


def summary(curve):
    """Short text: points, marked points, codimension-2 flags, how it ended."""
    lines = [f"{al.EVENT_LABELS[curve.kind]} curve: {len(curve.points)} points, ended: "
             f"{END_REASONS[curve.end]} ({curve.detail})"]
    lines += [f"  nu = {p.nu!r}: lambda = {p.lam!r}, critical multiplier {p.critical:.9f}" for p in curve.marked]
    lines += [f"  {CODIM2_LABELS[c.kind]} between lambda = {curve.points[c.index].lam!r} and "
              f"{curve.points[c.index + 1].lam!r}" for c in curve.codim2]
    return "\n".join(lines)

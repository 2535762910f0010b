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

Steps as in `arclength`: tangent predictor, the step grows after a fast corrector and halves after
a failed or slow one or a turn of the tangent by more than `max_angle`; B and C are renewed at
every accepted point. A curve ends on the edge of the parameter box (the edge point is solved
exactly), when it closes on its first point, when the step budget is spent or when the corrector
fails at the minimum step, always with a status (END_REASONS) and never an exception. Curve points
at given values of nu (`marks`: the clearances of a sweep's grid, for a cross-check with its
refined boundaries) are solved exactly where the curve crosses them.

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

from rotorkernels import floquet, integrators as ig
from rotorkernels.continuation import arclength as al

# How a curve ended. The first five codes mean what they mean in arclength.END_REASONS.
END_REASONS = al.END_REASONS[:5] + ("closed",)   # closed: came back to its first point (an isola)
LEFT_RANGE, STEP_BUDGET, NEWTON_FAILED, INTEGRATION_FAILED, START_FAILED, CLOSED = range(6)

# The critical multiplier by event kind: A = M - critical I is singular on the curve.
CRITICAL = {al.FOLD: 1.0, al.PERIOD_DOUBLING: -1.0}
KINDS = (al.FOLD, al.PERIOD_DOUBLING, al.NEIMARK_SACKER)
CODIM2_LABELS = ("cusp", "fold_flip", "resonance_1_2", "resonance_1_1", "resonance_1_3", "resonance_1_4")
CUSP, FOLD_FLIP, RESONANCE_1_2, RESONANCE_1_1, RESONANCE_1_3, RESONANCE_1_4 = range(6)
# kappa = cos(theta) of a Neimark-Sacker pair at the strong resonances
STRONG_RESONANCES = ((RESONANCE_1_1, 1.0), (RESONANCE_1_2, -1.0), (RESONANCE_1_3, -0.5), (RESONANCE_1_4, 0.0))


@dataclass(frozen=True)
class Settings(al.Settings):
    """arclength.Settings and the tolerance on the solved entries of G (absolute: with orthonormal
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


def _unit_null(J, t_prev):
    """Unit null vector of J (one row fewer than columns) oriented like t_prev."""
    rhs = np.zeros(J.shape[1])
    rhs[-1] = 1.0
    t = np.linalg.solve(np.vstack([J, t_prev]), rhs)
    return t / np.linalg.norm(t)


def correct(plane, kind, Y0, border, c, target, settings, counter):
    """Newton on [phi - s = 0, G at border's entries = 0, c . Y = target] from Y0.

    Returns (Y, linearization, iterations, residual, None) or (None, None, iterations, residual,
    failure) with failure NEWTON_FAILED or INTEGRATION_FAILED."""
    Y, res = Y0.copy(), np.inf
    try:
        for it in range(settings.max_newton + 1):
            lin = _linearize(plane, kind, Y, border, counter)
            g = _residual(lin, border)
            res = np.abs(lin.r).max() / max(1.0, np.abs(plane.split(Y)[0]).max())
            if res <= settings.tol and np.abs(g).max() <= settings.tol_g:
                return Y, lin, it, res, None
            if it == settings.max_newton:
                break
            Jphi, rows = _jacobian(plane, kind, Y, lin, settings.fd_step, counter)
            K = np.vstack([_system(Jphi, rows, border[2]), c])
            Y = Y + np.linalg.solve(K, -np.concatenate([lin.r, g, [c @ Y - target]]))
    except _IntegrationFailed:
        return None, None, it, res, INTEGRATION_FAILED
    except np.linalg.LinAlgError:
        pass
    return None, None, it, res, NEWTON_FAILED


def _best_entries(Jphi, rows, t):
    """For NS the two entries of G whose rows make the Newton matrix best conditioned (largest
    |det| with unit rows); for fold and PD the one entry."""
    if len(rows) == 1:
        return tuple(rows)
    unit = {e: r / np.linalg.norm(r) for e, r in rows.items()}
    pairs = list(itertools.combinations(sorted(unit), 2))
    return max(pairs, key=lambda pair: abs(np.linalg.det(np.vstack([_system(Jphi, unit, pair), t]))))


def _point(plane, kind, Y, lin, border, t_prev, iterations, residual, settings, counter):
    """A converged Y made a CurvePoint (tangent and renewed border there); None if that failed."""
    try:
        Jphi, rows = _jacobian(plane, kind, Y, lin, settings.fd_step, counter)
        t = _unit_null(_system(Jphi, rows, border[2]), t_prev)
    except (_IntegrationFailed, np.linalg.LinAlgError):
        return None
    _, lam, nu = plane.split(Y)
    lams = floquet.multipliers(lin.monodromy)
    renewed = (_orthonormal(lin.V), _orthonormal(lin.W), _best_entries(Jphi, rows, t))
    return CurvePoint(Y, lam, nu, lin.monodromy, lams, _critical(kind, Y, lams), t, renewed, iterations, residual,
                      float(np.abs(_residual(lin, border)).max()))


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


def start(plane, event, nu0, direction=1, settings=Settings(), counter=None):
    """The first curve point: the event's point (a fold, period doubling or Neimark-Sacker point
    located by arclength on the branch at nu = nu0) corrected on the augmented system at fixed
    nu0, its tangent pointing to increasing nu for direction +1. Returns (CurvePoint or None,
    detail)."""
    counter = counter or al.Counter()
    p = event.point
    Y0 = _initial_unknowns(plane, event, nu0)
    fixed = np.zeros(Y0.size)
    fixed[-1] = 1.0
    patient = replace(settings, max_newton=max(settings.max_newton, al.START_NEWTON))
    border = _border_at(event.kind, Y0, p.monodromy)
    try:
        lin = _linearize(plane, event.kind, Y0, border, counter)
        border = border[:2] + (_best_entries(*_jacobian(plane, event.kind, Y0, lin, settings.fd_step, counter),
                                             fixed),)
    except (_IntegrationFailed, np.linalg.LinAlgError):
        return None, f"no linearization at the event (lambda = {p.lam!r}, nu = {nu0!r})"
    Y, lin, it, res, failure = correct(plane, event.kind, Y0, border, fixed, Y0[-1], patient, counter)
    if failure is not None:
        return None, f"{END_REASONS[failure]} correcting the event at lambda = {p.lam!r}, nu = {nu0!r}"
    first = _point(plane, event.kind, Y, lin, border, direction * fixed, it, res, settings, counter)
    return first, ("" if first is not None else f"no tangent at lambda = {p.lam!r}, nu = {nu0!r}")


def _step(plane, kind, a, ds, settings, counter):
    """One predictor-corrector step of length ds from a: (CurvePoint, None) or (None, failure)."""
    X0 = a.Y + ds * a.tangent
    Y, lin, it, res, failure = correct(plane, kind, X0, a.border, a.tangent, a.tangent @ a.Y + ds, settings, counter)
    if failure is not None:
        return None, failure
    b = _point(plane, kind, Y, lin, a.border, a.tangent, it, res, settings, counter)
    return (b, None) if b is not None else (None, INTEGRATION_FAILED)


def _solve_on_segment(plane, kind, a, b, index, value, settings, counter):
    """The curve point between a and b where Y[index] = value (an edge or a mark), or None."""
    frac = (value - a.Y[index]) / (b.Y[index] - a.Y[index])
    c = np.zeros(a.Y.size)
    c[index] = 1.0
    Y, lin, it, res, failure = correct(plane, kind, a.Y + frac * (b.Y - a.Y), a.border, c, value, settings, counter)
    return None if failure is not None else _point(plane, kind, Y, lin, a.border, a.tangent, it, res, settings,
                                                   counter)


def _exit(plane, a, b, box):
    """(Y index, scaled edge value, text) of the first box edge crossed going from a (inside) to b
    (outside)."""
    crossings = []
    for k, ((lo, hi), name, scale) in enumerate(zip(box, ("lambda", "nu"), (plane.lam_scale, plane.nu_scale))):
        va, vb = (a.lam, b.lam) if k == 0 else (a.nu, b.nu)
        for edge in [e for e, beyond in ((lo, vb < lo), (hi, vb > hi)) if beyond]:
            crossings.append(((edge - va) / (vb - va), a.Y.size - 2 + k, edge / scale, f"{name} reached {edge!r}"))
    return min(crossings)[1:]


def _inside(point, box):
    (lo, hi), (nlo, nhi) = box
    return lo <= point.lam <= hi and nlo <= point.nu <= nhi


def _passed_marks(a, b, marks):
    """The marks crossed going from a to b, in the order met."""
    passed = [m for m in marks if not _same(m, a.nu) and ((a.nu - m) * (b.nu - m) < 0 or _same(m, b.nu))]
    return sorted(passed, key=lambda m: abs(m - a.nu))


def _same(m, nu):
    """nu is the mark m up to round-off (a point solved at eta = m / nu_scale)."""
    return abs(nu - m) <= 1e-12 * abs(m)


def _codim2_between(kind, a, b):
    """Codimension-2 kinds flagged between a and b (module docstring)."""
    if kind == al.NEIMARK_SACKER:
        n = a.monodromy.shape[0]
        return [k for k, kappa in STRONG_RESONANCES if (a.Y[n] - kappa) * (b.Y[n] - kappa) <= 0]
    found = []
    if kind == al.FOLD and a.tangent[-2:] @ b.tangent[-2:] < 0:
        found.append(CUSP)
    if _sign_change(_others(a), _others(b), -CRITICAL[kind]):
        found.append(FOLD_FLIP)
    if kind == al.PERIOD_DOUBLING and _sign_change(_others(a), _others(b), -1.0):
        found.append(RESONANCE_1_2)
    return found


def _others(point):
    """The multipliers without the critical one."""
    lams = point.multipliers
    return np.delete(lams, np.argmin(np.abs(lams - point.critical)))


def _sign_change(la, lb, value):
    """prod(lambda_i - value) changes sign (a real multiplier crossed value)."""
    def sign(lams):
        return np.prod((lams - value) / np.abs(lams - value)).real >= 0
    return sign(la) != sign(lb)


def _closes(first, a, b):
    """The step a -> b passes the first point again, heading the same way: a closed curve. (The
    first point projects inside the chord a -> b and lies near it: the chord's sagitta on a curve
    turning by at most max_angle is below a tenth of its length.)"""
    chord = b.Y - a.Y
    along = (first.Y - a.Y) @ chord / (chord @ chord)
    off = np.linalg.norm(first.Y - a.Y - along * chord)
    return 0.0 < along <= 1.0 and off < 0.1 * np.linalg.norm(chord) and chord @ first.tangent > 0


def follow_curve(plane, kind, first, box, settings=Settings(), marks=(), counter=None):
    """Pseudo-arclength continuation of the bifurcation curve of `kind` from the CurvePoint
    `first` until it leaves box = ((lambda_lo, lambda_hi), (nu_lo, nu_hi)), closes, the step budget
    is spent, or the corrector fails at the minimum step. Curve points at the nu values `marks`
    are solved where the curve crosses them."""
    counter = counter or al.Counter()
    points, codim2 = [first], []
    marked = [first for m in marks if _same(m, first.nu)]
    ds = settings.ds
    end, detail = STEP_BUDGET, f"{settings.max_steps} steps"
    while len(points) <= settings.max_steps:
        a = points[-1]
        b, failure = _step(plane, kind, a, ds, settings, counter)
        if b is not None and al.rejected(a, b, settings):
            b, failure = None, NEWTON_FAILED
        if b is None:
            if ds <= settings.ds_min * 1.000001:
                end = failure
                detail = (f"{END_REASONS[failure]} at the minimum step {settings.ds_min} after "
                          f"lambda = {a.lam!r}, nu = {a.nu!r}")
                break
            ds = max(settings.ds_min, ds / 2.0)
            continue
        if not _inside(b, box):
            index, value, detail = _exit(plane, a, b, box)
            edge = _solve_on_segment(plane, kind, a, b, index, value, settings, counter)
            if edge is not None:
                _record(plane, kind, a, edge, points, marked, codim2, marks, settings, counter)
            end = LEFT_RANGE
            break
        if len(points) > 2 and _closes(first, a, b):
            marked.extend(p for p in _marks_between(plane, kind, a, first, marks, settings, counter) if p is not first)
            end, detail = CLOSED, f"back at the first point after {len(points)} steps"
            break
        _record(plane, kind, a, b, points, marked, codim2, marks, settings, counter)
        if b.iterations <= settings.fast_newton:
            ds = min(settings.ds_max, ds * settings.grow)
    return Curve(kind, points, marked, codim2, end, detail, plane.periods, counter.n)


def _marks_between(plane, kind, a, b, marks, settings, counter):
    """The curve points at the marks crossed going from a to b, in the order met."""
    found = []
    for m in _passed_marks(a, b, marks):
        at = b if _same(m, b.nu) else _solve_on_segment(plane, kind, a, b, len(a.Y) - 1, m / plane.nu_scale,
                                                         settings, counter)
        if at is not None:
            found.append(at)
    return found


def _record(plane, kind, a, b, points, marked, codim2, marks, settings, counter):
    """Append b, the marked points between a and b and the codimension-2 flags."""
    marked.extend(_marks_between(plane, kind, a, b, marks, settings, counter))
    codim2.extend(Codim2(k, len(points) - 1) for k in _codim2_between(kind, a, b))
    points.append(b)


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
    counter = al.Counter()
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

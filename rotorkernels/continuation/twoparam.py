"""Two-parameter continuation of bifurcation points of forced periodic orbits: a fold (LP) or a
period-doubling (PD) point located on a branch by `arclength` is followed in a second scene
parameter nu (a clearance, a preload, a forcing amplitude, ...), which gives the stability
boundary as a curve in the (lambda, nu) plane.

Formulation: the minimally augmented system (Govaerts and Kuznetsov; MatCont and BifurcationKit
use it). Unknowns Y = (s, mu, eta), the orbit's scaled initial state s, mu = lambda / lam_scale,
eta = nu / nu_scale (scales that make both O(1), as `arclength.Family.scale` does for lambda).
Equations: phi(s, lambda, nu) - s = 0, g(s, lambda, nu) = 0 and the arclength condition
t . (Y - Y_k) = ds. g is the bordering scalar of

    [[A, b], [c^T, 0]] [w; g] = [0; 1],     A = M - I (fold) or M + I (period doubling),

with b, c the left and right critical null vectors of A at the previous curve point: the bordered
matrix stays regular near the curve, and g = 0 exactly where A is singular, i.e. where one
multiplier is +1 (fold) or -1 (period doubling). Why this system: it has n + 2 unknowns (the
standard augmented system [phi - s, A w, w.w - 1] has 2n + 2 and needs the derivatives of A w in
all of them), g is smooth and well scaled near the curve (|g| ~ the smallest singular value of A),
unlike det(A), whose scale drifts with the other multipliers, and g has a cheap gradient:

    g_z = -v^T (dM/dz) w,   v from the transposed bordered system (v^T A + g c^T = 0, v^T b = 1).

- In s: the row (v^T (dM/ds_j) w)_j equals v^T D_w M, with D_w M the derivative of M along w
  (second derivatives of phi are symmetric), a central difference of two variational integrations
  at s +- h w / |w|: two integrations for the whole row whatever n is (column by column would take
  2n, 8 for the Jeffcott model and 20 for a 5-DOF model).
- In lambda and nu: central differences of two variational integrations each, which also give the
  columns dphi/dmu, dphi/deta (the models are not differentiated in their parameters).
So a Newton iterate costs seven variational integrations. With the step 1e-5 (`fd_step`, scaled
units) the truncation error is O(1e-10) and the integrator's noise ~ rtol / 1e-5; these columns
enter only the Newton matrix and the tangent, never the residuals phi - s and g, so, as in
`arclength`, the converged curve points are exact to the Newton tolerances and the integrator's
accuracy, and an error of the columns only slows Newton down a little.

Steps as in `arclength`: tangent predictor, the step grows after a fast corrector and halves after
a failed or slow one or a turn of the tangent by more than `max_angle`; b and c are renewed at
every accepted point. A curve ends on the edge of the parameter box (the edge point is solved
exactly), when it closes on its first point, when the step budget is spent or when the corrector
fails at the minimum step, always with a status (END_REASONS) and never an exception. Curve points
at given values of nu (`marks`: the clearances of a sweep's grid, for a cross-check with its
refined boundaries) are solved exactly where the curve crosses them.

Codimension-2 points are flagged between two curve points, not located: on a fold curve, a cusp
(the curve's projection on the (lambda, nu) plane reverses: both parameter components of the
tangent change sign) and a fold-flip (another multiplier crosses -1); on a period-doubling curve,
a fold-flip (another multiplier crosses +1) and a 1:2 resonance (a second multiplier reaches -1).
Neimark-Sacker curves are not implemented.
"""
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
CODIM2_LABELS = ("cusp", "fold_flip", "resonance_1_2")
CUSP, FOLD_FLIP, RESONANCE_1_2 = range(3)


@dataclass(frozen=True)
class Settings(al.Settings):
    """arclength.Settings and the tolerance on the bordering scalar g (an absolute value: |g| is
    about the distance of the critical multiplier from +-1 with unit b, c)."""
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
        """(s, lambda, nu) of the unknowns Y = (s, mu, eta)."""
        return Y[:-2], Y[-2] * self.lam_scale, Y[-1] * self.nu_scale


class CurvePoint(NamedTuple):
    """A converged point of a bifurcation curve."""
    Y: np.ndarray           # (s, mu, eta)
    lam: float
    nu: float
    monodromy: np.ndarray
    multipliers: np.ndarray
    critical: complex       # the multiplier nearest to +1 (fold) or -1 (period doubling)
    tangent: np.ndarray     # unit, oriented along the direction of travel
    border: tuple           # (b, c): unit left and right null vectors of A here
    iterations: int
    residual: float         # max|phi - s| / max(1, max|s|)
    g: float

    @property
    def state(self):
        return self.Y[:-2]


class Codim2(NamedTuple):
    kind: int               # CODIM2_LABELS index
    index: int              # between points[index] and points[index + 1]


class Curve(NamedTuple):
    kind: int               # arclength.FOLD or arclength.PERIOD_DOUBLING
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
    g: float
    v: np.ndarray           # left solution of the bordered system
    w: np.ndarray           # right solution (A w = -g b)


def _flow(plane, s, lam, nu, counter):
    r, mono, status, n_rhs = plane.family(nu).return_map(s, lam, True)
    counter.n += n_rhs
    if status != ig.STATUS_OK:
        raise _IntegrationFailed
    return r, mono


def _bordered_solutions(A, border):
    """(w, g, v) of [[A, b], [c^T, 0]] [w; g] = [0; 1] and its transpose."""
    b, c = border
    n = b.size
    K = np.zeros((n + 1, n + 1))
    K[:n, :n], K[:n, n], K[n, :n] = A, b, c
    e = np.zeros(n + 1)
    e[n] = 1.0
    right, left = np.linalg.solve(K, e), np.linalg.solve(K.T, e)
    return right[:n], float(right[n]), left[:n]


def _linearize(plane, kind, Y, border, counter):
    """Residuals at Y (phi - s, g) and what their Jacobian needs."""
    s, lam, nu = plane.split(Y)
    r, mono = _flow(plane, s, lam, nu, counter)
    A = mono - CRITICAL[kind] * np.eye(s.size)
    w, g, v = _bordered_solutions(A, border)
    return _Linearization(r, mono, g, v, w)


def _jacobian(plane, Y, lin, fd_step, counter):
    """[[M - I, dphi/dmu, dphi/deta], [g_s, g_mu, g_eta]] at Y (module docstring)."""
    s, lam, nu = plane.split(Y)
    n = s.size
    width = np.linalg.norm(lin.w)
    h = fd_step * max(1.0, np.abs(s).max())
    _, m_plus = _flow(plane, s + h * lin.w / width, lam, nu, counter)
    _, m_minus = _flow(plane, s - h * lin.w / width, lam, nu, counter)
    J = np.empty((n + 1, n + 2))
    J[:n, :n] = lin.monodromy - np.eye(n)
    J[n, :n] = -(lin.v @ (m_plus - m_minus)) * width / (2.0 * h)
    for k in (n, n + 1):
        step = fd_step * max(1.0, abs(Y[k]))
        up, down = Y.copy(), Y.copy()
        up[k] += step
        down[k] -= step
        r_up, m_up = _flow(plane, s, *plane.split(up)[1:], counter)
        r_down, m_down = _flow(plane, s, *plane.split(down)[1:], counter)
        J[:n, k] = (r_up - r_down) / (2.0 * step)
        J[n, k] = -(lin.v @ (m_up - m_down) @ lin.w) / (2.0 * step)
    return J


def _unit_null(J, t_prev):
    """Unit null vector of J (n + 1 rows, n + 2 columns) oriented like t_prev."""
    rhs = np.zeros(J.shape[1])
    rhs[-1] = 1.0
    t = np.linalg.solve(np.vstack([J, t_prev]), rhs)
    return t / np.linalg.norm(t)


def correct(plane, kind, Y0, border, c, target, settings, counter):
    """Newton on [phi - s = 0, g = 0, c . Y = target] from Y0.

    Returns (Y, linearization, iterations, residual, None) or (None, None, iterations, residual,
    failure) with failure NEWTON_FAILED or INTEGRATION_FAILED."""
    Y, res = Y0.copy(), np.inf
    try:
        for it in range(settings.max_newton + 1):
            lin = _linearize(plane, kind, Y, border, counter)
            res = np.abs(lin.r).max() / max(1.0, np.abs(Y[:-2]).max())
            if res <= settings.tol and abs(lin.g) <= settings.tol_g:
                return Y, lin, it, res, None
            if it == settings.max_newton:
                break
            J = _jacobian(plane, Y, lin, settings.fd_step, counter)
            Y = Y + np.linalg.solve(np.vstack([J, c]), -np.append(lin.r, [lin.g, c @ Y - target]))
    except _IntegrationFailed:
        return None, None, it, res, INTEGRATION_FAILED
    except np.linalg.LinAlgError:
        pass
    return None, None, it, res, NEWTON_FAILED


def _point(plane, kind, Y, lin, t_prev, iterations, residual, settings, counter):
    """A converged Y made a CurvePoint (tangent and renewed border there); None if that failed."""
    try:
        J = _jacobian(plane, Y, lin, settings.fd_step, counter)
        t = _unit_null(J, t_prev)
    except (_IntegrationFailed, np.linalg.LinAlgError):
        return None
    _, lam, nu = plane.split(Y)
    lams = floquet.multipliers(lin.monodromy)
    critical = lams[np.argmin(np.abs(lams - CRITICAL[kind]))]
    border = (lin.v / np.linalg.norm(lin.v), lin.w / np.linalg.norm(lin.w))
    return CurvePoint(Y, lam, nu, lin.monodromy, lams, complex(critical), t, border, iterations, residual, lin.g)


def _border_at(monodromy, kind):
    """Unit left and right singular vectors of A's smallest singular value."""
    A = monodromy - CRITICAL[kind] * np.eye(monodromy.shape[0])
    U, _, Vt = np.linalg.svd(A)
    return U[:, -1], Vt[-1]


def start(plane, event, nu0, direction=1, settings=Settings(), counter=None):
    """The first curve point: the event's point (a fold or period doubling located by arclength on
    the branch at nu = nu0) corrected on the augmented system at fixed nu0, its tangent pointing
    to increasing nu for direction +1. Returns (CurvePoint or None, detail)."""
    counter = counter or al._Counter()
    p = event.point
    Y0 = np.append(p.state, [p.lam / plane.lam_scale, nu0 / plane.nu_scale])
    fixed = np.zeros(Y0.size)
    fixed[-1] = 1.0
    patient = replace(settings, max_newton=max(settings.max_newton, al.START_NEWTON))
    Y, lin, it, res, failure = correct(plane, event.kind, Y0, _border_at(p.monodromy, event.kind), fixed, Y0[-1],
                                       patient, counter)
    if failure is not None:
        return None, f"{END_REASONS[failure]} correcting the event at lambda = {p.lam!r}, nu = {nu0!r}"
    first = _point(plane, event.kind, Y, lin, direction * fixed, it, res, settings, counter)
    return first, ("" if first is not None else f"no tangent at lambda = {p.lam!r}, nu = {nu0!r}")


def _step(plane, kind, a, ds, settings, counter):
    """One predictor-corrector step of length ds from a: (CurvePoint, None) or (None, failure)."""
    X0 = a.Y + ds * a.tangent
    Y, lin, it, res, failure = correct(plane, kind, X0, a.border, a.tangent, a.tangent @ a.Y + ds, settings, counter)
    if failure is not None:
        return None, failure
    b = _point(plane, kind, Y, lin, a.tangent, it, res, settings, counter)
    return (b, None) if b is not None else (None, INTEGRATION_FAILED)


def _solve_on_segment(plane, kind, a, b, index, value, settings, counter):
    """The curve point between a and b where Y[index] = value (an edge or a mark), or None."""
    frac = (value - a.Y[index]) / (b.Y[index] - a.Y[index])
    c = np.zeros(a.Y.size)
    c[index] = 1.0
    Y, lin, it, res, failure = correct(plane, kind, a.Y + frac * (b.Y - a.Y), a.border, c, value, settings, counter)
    return None if failure is not None else _point(plane, kind, Y, lin, a.tangent, it, res, settings, counter)


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
    found = []
    if kind == al.FOLD and a.tangent[-2:] @ b.tangent[-2:] < 0:
        found.append(CUSP)
    other = -CRITICAL[kind]
    if _sign_change(_others(a), _others(b), other):
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
    counter = counter or al._Counter()
    points, codim2 = [first], []
    marked = [first for m in marks if _same(m, first.nu)]
    ds = settings.ds
    end, detail = STEP_BUDGET, f"{settings.max_steps} steps"
    while len(points) <= settings.max_steps:
        a = points[-1]
        b, failure = _step(plane, kind, a, ds, settings, counter)
        if b is not None and (b.iterations > settings.max_newton - 2
                              or al._angle(a.tangent, b.tangent) > settings.max_angle):
            b, failure = None, NEWTON_FAILED     # arclength.follow_branch's rule: stay on the curve
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
    """Follow the fold or period doubling `event` (located by arclength on a branch of
    plane.family(nu0)) in (lambda, nu) from nu0, towards increasing nu for direction +1.

    Raises ValueError for arguments that cannot work (settings, event kind, a start outside the
    box) before any integration; every numerical failure is the returned Curve's status."""
    problems = settings.problems()
    (lo, hi), (nu_lo, nu_hi) = box
    if not (lo <= event.point.lam <= hi and nu_lo <= nu0 <= nu_hi):
        problems.append(f"the event (lambda = {event.point.lam!r}, nu = {nu0!r}) lies outside the box {box!r}")
    if event.kind not in CRITICAL:
        problems.append(f"event kind {al.EVENT_TYPES[event.kind]!r}: only fold and period_doubling curves "
                        "are continued")
    if problems:
        raise ValueError("; ".join(problems))
    counter = al._Counter()
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

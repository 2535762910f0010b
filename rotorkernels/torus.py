"""Invariant 2-tori of a model under two-frequency forcing (quasi-periodic shooting).

The first forcing has period T (the stroboscopic period, scaled time), the second one's phase theta
at the start of a period is a kernel parameter (p[phase_index]) and advances by rho = 2 pi omega /
Omega over T. A torus is an invariant circle u(theta) of the stroboscopic map P_theta (the flow over
T started at phase theta):

    P_theta(u(theta)) = u(theta + rho).

Fourier collocation (Schilder, Osinga & Vogt 2005, with the forcing phase as the torus coordinate,
so there is neither a phase condition nor an unknown rotation): u is the trigonometric interpolant
of its values U_j at N = 2K + 1 nodes theta_j = 2 pi j / N; each node is shot over T from phase
theta_j, and Newton solves all nodes at once on

    R(U) = [P_theta_j(U_j)]_j - (S kron I_n) U = 0,    dR/dU = blockdiag(M_j) - S kron I_n,

M_j the nodes' monodromies and S the interpolation matrix that evaluates the interpolant at the
shifted nodes theta_j + rho. N grows until the interpolant's highest modes fall below the decay
tolerance, else the torus ends `fourier_decay_failed` (a torus losing smoothness before it breaks
down), or `non_smooth_circle` where the tail falls only by a power of N as N doubles (a spectrum
|c_m| ~ m^-s: the circle is finitely smooth, e.g. where a contact force that is not smooth in the
state acts along it; `power_law`), the count it would take then projected beyond max_nodes. Each
torus carries an error estimate: the invariance defect between the nodes (at the midpoints, where
collocation does not force it to zero) times the norm of the inverse Jacobian (the defect's
amplification into a distance from the invariant circle), and not below the Fourier tail.

Stability (`stability`): the normal Lyapunov exponents of the linearized map over the rotation,
v -> M(theta) v, theta -> theta + rho (the linearized invariance equation), by QR iteration with
M(theta) the interpolant of the nodes' monodromies; `undecided` where the largest exponent is not
told apart from 0 by its own convergence error. Kernels only: arrays in, arrays out, no I/O.
"""
from typing import NamedTuple

import numpy as np
from numba import njit

from rotorsweep.kernels import extrema, integrators as ig, shooting

CONVERGED, NOT_CONVERGED, FOURIER_DECAY_FAILED, INTEGRATION_FAILED, NON_SMOOTH = (
    "converged", "not_converged", "fourier_decay_failed", "integration_failed", "non_smooth_circle")
STABLE, UNSTABLE, UNDECIDED = "stable", "unstable", "undecided"

_MAX_HALVINGS = 8
_FINE = 100.0      # tolerance ratio of the error estimate's reference flow
# A doubling of N that cuts the tail by less than this power of 2 beyond the best earlier one does
# not accelerate: geometric decay (an analytic circle) doubles the exponent at each doubling.
_ACCELERATION = 1.5
_ROUNDOFF = 1e-12  # a tail this small has reached the coefficients' rounding: no decay law read from it
_ROUNDING = 1e-15  # a relative mode amplitude this small is the DFT's rounding (a few ulps of N values)
COARSEN = 1e-3     # fewer nodes only where their tail stays below this times the decay tolerance (hysteresis)


class Torus(NamedTuple):
    nodes: np.ndarray        # U (N, n): the circle's values at theta_j = 2 pi j / N
    rho: float               # rotation of the forcing phase per period T [rad]
    period: float            # the stroboscopic period T (scaled time)
    status: str              # CONVERGED, NOT_CONVERGED, FOURIER_DECAY_FAILED, INTEGRATION_FAILED, NON_SMOOTH
    iterations: int          # Newton iterations, all resolutions together
    residual: float          # max |R| at the nodes
    tail: float              # the node values' Fourier tail (fourier_tail)
    error: float             # the error estimate (see the module docstring)
    monodromies: np.ndarray  # (N, n, n) at the nodes
    n_rhs: int

    @property
    def thetas(self):
        return node_phases(self.nodes.shape[0])

    def at(self, theta):
        """u(theta) on the circle (any array of phases): the trigonometric interpolant."""
        return interpolation_matrix(self.nodes.shape[0], np.atleast_1d(theta)) @ self.nodes


class Stability(NamedTuple):
    exponents: np.ndarray    # normal Lyapunov exponents per unit scaled time, descending
    spread: float            # their convergence error (two halves of the iteration)
    status: str              # STABLE, UNSTABLE, UNDECIDED
    reason: str              # why undecided ("" otherwise)


def node_phases(n_nodes):
    return 2.0 * np.pi * np.arange(n_nodes) / n_nodes


def interpolation_matrix(n_nodes, thetas):
    """E (len(thetas), N): E @ U is the trigonometric interpolant of the node values U at
    `thetas` (N odd: the Dirichlet kernel sum_{|m| <= K} exp(i m (theta - theta_k)) / N)."""
    k = (n_nodes - 1) // 2
    d = np.asarray(thetas, float)[:, None] - node_phases(n_nodes)[None, :]
    m = np.arange(1, k + 1)
    return (1.0 + 2.0 * np.cos(d[..., None] * m).sum(axis=-1)) / n_nodes


def mode_amplitudes(values):
    """|c_m| (m = 0..K) of the node values (N, ...): the largest over the components of each mode's
    DFT coefficient / N, relative to the largest of the values (floor 1)."""
    n_nodes = values.shape[0]
    coef = np.abs(np.fft.rfft(values.reshape(n_nodes, -1), axis=0)) / n_nodes
    return coef.max(axis=1) / max(1.0, np.abs(values).max())


def fourier_tail(values):
    """How far N nodes resolve the node values (N, ...), relative (mode_amplitudes): the larger of
    the top quarter's largest mode and the modes K + 1 .. 2K + 1 that the next count would add,
    extrapolated from the top quarter's largest mode by the geometric decay rate fitted to the
    upper half of the modes (`decay_rate`; anchored there, not at the fitted line, so a
    band-limited circle, whose top modes are at the rounding level, keeps a rounding-level tail).

    The nodes cannot hold the modes beyond K: those alias, mode K + j onto mode K + 1 - j, down
    to mode 1 for mode 2K, so their energy spreads over all modes and the top quarter alone shows
    only the first few. Where the spectrum decays slowly (c_m ~ r^m, r near 1, or algebraically)
    their sum is 1 / (1 - r) times the top's largest mode; the estimate counts it. A circle whose
    node values mimic a resolved one (a mode near a multiple of N with nothing between) is beyond
    any check on the node values: only the invariance defect between the nodes
    (error_estimate) sees it."""
    amps = mode_amplitudes(values)
    k = amps.size - 1
    top = max(1, (k + 1) // 4)
    highest = float(amps[k + 1 - top:].max())
    rate = decay_rate(amps)
    beyond = 0.0 if rate is None else highest * float((rate ** np.arange(1, k + 2)).sum())
    return max(highest, beyond)


def decay_rate(amps):
    """r (<= 1) of the least-squares line log e_m = log c + m log r through the upper half of
    the modes (K // 2 .. K, m >= 1), e_m = max_{m' >= m} |c_m'| the decaying envelope (so modes
    that vanish by a symmetry do not pass for decay; r <= 1), modes at the rounding level left
    out; None where fewer than two modes remain (the circle is resolved to its rounding)."""
    k = amps.size - 1
    envelope = np.maximum.accumulate(amps[::-1])[::-1]
    m = np.arange(max(1, k // 2), k + 1)
    m = m[envelope[m] > _ROUNDING]
    if m.size < 2:
        return None
    slope, _ = np.polyfit(m, np.log(envelope[m]), 1)
    return float(np.exp(min(slope, 0.0)))


def node_maps(kernel, nodes, thetas, p, phase_index, period, opts, variational):
    """(ends (N, n), monodromies (N, n, n) or None, ok, n_rhs): the stroboscopic map of each node,
    shot over `period` from its forcing phase."""
    n = kernel.n_state
    ends = np.empty_like(nodes)
    monos = np.empty((len(thetas), n, n)) if variational else None
    pj = np.array(p, float)
    n_rhs = 0
    for j, theta in enumerate(thetas):
        pj[phase_index] = theta
        z, status, nr, _ = ig.flow(kernel, 0.0, period, ig.initial_state(nodes[j], n, variational),
                                   pj, variational, opts, 0.0)
        n_rhs += nr
        if status != ig.STATUS_OK:
            return ends, monos, False, n_rhs
        ends[j] = z[:n]
        if variational:
            monos[j] = z[n:].reshape(n, n)
    return ends, monos, True, n_rhs


def collocation(kernel, nodes, p, phase_index, rho, period, opts, variational=True):
    """(residual R (N, n), Jacobian dR/dU or None, monodromies or None, ok, n_rhs) of the
    collocation equations (the Jacobian only with the variational equations)."""
    n_nodes, n = nodes.shape
    thetas = node_phases(n_nodes)
    shift = interpolation_matrix(n_nodes, thetas + rho)
    ends, monos, ok, n_rhs = node_maps(kernel, nodes, thetas, p, phase_index, period, opts, variational)
    if not ok:
        return None, None, None, False, n_rhs
    if not variational:
        return ends - shift @ nodes, None, None, True, n_rhs
    return ends - shift @ nodes, collocation_jacobian(monos, shift), monos, True, n_rhs


def collocation_jacobian(monos, shift):
    """dR/dU = blockdiag(M_j) - S kron I_n of the nodes' monodromies (N, n, n) and the shift
    operator S (N, N) (interpolation_matrix at the nodes' phases + rho)."""
    n_nodes, n = monos.shape[0], monos.shape[1]
    jac = -np.kron(shift, np.eye(n))
    for j in range(n_nodes):
        jac[j * n:(j + 1) * n, j * n:(j + 1) * n] += monos[j]
    return jac


def _newton(kernel, nodes, p, phase_index, rho, period, opts, tol, max_iter):
    """Newton with backtracking on all nodes at once at one resolution:
    (nodes, jacobian, monodromies, status, iterations, residual, n_rhs)."""
    scale = max(1.0, np.abs(nodes).max())
    r, jac, monos, ok, n_rhs = collocation(kernel, nodes, p, phase_index, rho, period, opts)
    if not ok:
        return nodes, None, None, INTEGRATION_FAILED, 0, np.inf, n_rhs
    res = np.abs(r).max()
    for it in range(max_iter + 1):
        if res <= tol * scale:
            return nodes, jac, monos, CONVERGED, it, res, n_rhs
        if it == max_iter:
            break
        try:
            step = np.linalg.solve(jac, -r.ravel()).reshape(nodes.shape)
        except np.linalg.LinAlgError:
            break
        lam = 1.0
        for _ in range(_MAX_HALVINGS):
            trial = nodes + lam * step
            rt, jt, mt, ok, nr = collocation(kernel, trial, p, phase_index, rho, period, opts)
            n_rhs += nr
            if ok and np.abs(rt).max() < (1.0 - 1e-4 * lam) * res:
                nodes, r, jac, monos, res = trial, rt, jt, mt, np.abs(rt).max()
                break
            lam *= 0.5
        else:
            break
    return nodes, jac, monos, NOT_CONVERGED, it, res, n_rhs


def resample(nodes, n_nodes):
    """The circle's node values at another (odd) number of nodes, by its interpolant."""
    return interpolation_matrix(nodes.shape[0], node_phases(n_nodes)) @ nodes


def coarser(n_nodes):
    """The next count down the ladder N -> 2N + 1 (odd)."""
    m = (n_nodes - 1) // 2
    return m if m % 2 else m + 1


def coarser_tail(nodes):
    """The tail the circle would have at the next count down (coarser): the resampled circle's
    fourier_tail, and not below the sum of the modes it drops (known here, only estimated there)."""
    small = coarser(nodes.shape[0])
    amps = mode_amplitudes(nodes)
    return max(fourier_tail(resample(nodes, small)), float(amps[(small - 1) // 2 + 1:].sum()))


def coarsened(nodes, decay_tol, min_nodes):
    """The circle at the fewest nodes down the ladder (not below min_nodes) whose tail
    (coarser_tail) stays below COARSEN times decay_tol (nodes resampled; as given where none
    does): a guess that does not carry more nodes than its circle needs."""
    while coarser(nodes.shape[0]) >= min_nodes and coarser_tail(nodes) <= COARSEN * decay_tol:
        nodes = resample(nodes, coarser(nodes.shape[0]))
    return nodes


def error_estimate(kernel, nodes, jac, p, phase_index, rho, period, opts, tail):
    """(estimate, ok, n_rhs): the invariance defect at the midpoints between nodes times
    ||dR/dU^{-1}||_inf, not below the Fourier tail (scaled like the nodes); inf where dR/dU is
    singular (the circle is not isolated). The midpoints are shot at a hundredth of the
    tolerances, so that the defect holds the solver's own integration error too (against the
    flow, not only against its own map). The norm is exact, from the inverse (LAPACK's getri,
    scipy.linalg, imported here: a command that solves no torus does not load it; 3/4 of numpy's
    solve against I, ~17 ms at 63 nodes of 10 states, a third of a variational collocation):
    LAPACK's condition estimate (gecon, a lower bound) fell short of it by 1.5x on the preloaded
    rotor's tori at 31 and 63 nodes."""
    import scipy.linalg
    n_nodes = nodes.shape[0]
    mid = node_phases(n_nodes) + np.pi / n_nodes
    start = interpolation_matrix(n_nodes, mid) @ nodes
    fine = opts._replace(rtol=opts[ig.S_RTOL] / _FINE, atol=opts[ig.S_ATOL] / _FINE)
    ends, _, ok, n_rhs = node_maps(kernel, start, mid, p, phase_index, period, fine, False)
    if not ok:
        return np.inf, False, n_rhs
    defect = np.abs(ends - interpolation_matrix(n_nodes, mid + rho) @ nodes).max()
    try:
        amplification = np.abs(scipy.linalg.inv(jac)).sum(axis=1).max()
    except np.linalg.LinAlgError:
        return np.inf, True, n_rhs
    return max(defect * amplification, tail * max(1.0, np.abs(nodes).max())), True, n_rhs


def power_law(tails):
    """The exponent s of an algebraic decay of the tails at node counts N, 2N + 1, 4N + 3, ...:
    tail ~ N^-s, s = log2 of the tail's drop per doubling, the largest seen; None while fewer than
    two doublings are known, the tail is at the rounding level, or the last doubling dropped it
    faster than _ACCELERATION times any earlier one (geometric decay: log tail ~ -r N, the drop per
    doubling doubles)."""
    if len(tails) < 3 or tails[-1] < _ROUNDOFF:
        return None
    drops = -np.diff(np.log2(tails))
    if drops[-1] > _ACCELERATION * max(drops[:-1].max(), 0.0):
        return None
    return float(max(drops.max(), 1e-3))


def _too_rough(tails, n_nodes, decay_tol, max_nodes):
    """Whether the tails decay algebraically (power_law) so slowly that reaching decay_tol would
    take more than max_nodes nodes (N (tail / decay_tol)^(1/s), at the largest drop seen)."""
    s = power_law(tails)
    return s is not None and n_nodes * (tails[-1] / decay_tol) ** (1.0 / s) > max_nodes


def solve_torus(kernel, guess, p, phase_index, rho, opts, period=1.0, tol=1e-10, decay_tol=1e-11,
                max_nodes=257, max_iter=20):
    """The invariant circle near `guess` ((N, n) node values, N odd; a periodic state repeated
    over the nodes is a fine guess for weak second forcing) with the rotation rho [rad per period].

    N starts at guess's node count and grows (N -> 2N + 1) while the Fourier tail exceeds
    decay_tol; beyond max_nodes the torus is FOURIER_DECAY_FAILED, or NON_SMOOTH where the tail
    falls algebraically (power_law; then as soon as the count it would take exceeds max_nodes).
    tol: Newton's max |R| relative to max(1, max |U|). Returns a `Torus` (failure is its status,
    never an exception)."""
    nodes = np.array(guess, float)
    if nodes.ndim != 2 or nodes.shape[0] % 2 == 0 or nodes.shape[1] != kernel.n_state:
        raise ValueError(f"guess must be (N odd, {kernel.n_state}), got {nodes.shape}")
    total_it, n_rhs, tails = 0, 0, []
    while True:
        nodes, jac, monos, status, it, res, nr = _newton(kernel, nodes, p, phase_index, rho, period, opts,
                                                         tol, max_iter)
        total_it += it
        n_rhs += nr
        tail = fourier_tail(nodes) if status != INTEGRATION_FAILED else np.inf
        tails.append(tail)
        if status != CONVERGED or tail <= decay_tol:
            break
        if _too_rough(tails, nodes.shape[0], decay_tol, max_nodes):
            status = NON_SMOOTH
            break
        if 2 * nodes.shape[0] + 1 > max_nodes:
            status = FOURIER_DECAY_FAILED
            break
        nodes = resample(nodes, 2 * nodes.shape[0] + 1)
    error = np.inf
    if status in (CONVERGED, FOURIER_DECAY_FAILED, NON_SMOOTH):
        error, ok, nr = error_estimate(kernel, nodes, jac, p, phase_index, rho, period, opts, tail)
        n_rhs += nr
        status = status if ok else INTEGRATION_FAILED
    if monos is None:
        monos = np.full((nodes.shape[0], kernel.n_state, kernel.n_state), np.nan)
    return Torus(nodes, float(rho), float(period), status, total_it, float(res), tail, float(error), monos, n_rhs)


def fitted_guess(samples, phases, n_nodes):
    """Node values (n_nodes, n) of the least-squares trigonometric fit (n_nodes modes) of
    stroboscopic samples (m >= n_nodes, n) at their forcing phases: a guess from a transient that
    has settled near an attracting torus."""
    basis = interpolation_matrix(n_nodes, np.asarray(phases, float))
    return np.linalg.lstsq(basis, np.asarray(samples, float), rcond=None)[0]


def settled_samples(kernel, state, p, phase_index, rho, opts, n_settle, n_fit):
    """(samples (n_fit, n), their phases, ok) of the stroboscopic map (period 1) iterated n_fit
    times after n_settle iterates from `state` at phase 0."""
    samples, phases, theta = [], [], 0.0
    for k in range(n_settle + n_fit):
        if k >= n_settle:
            samples.append(state.copy())
            phases.append(theta)
        ends, _, ok, _ = node_maps(kernel, state[None, :], [theta], p, phase_index, 1.0, opts, False)
        if not ok:
            return None, None, False
        state, theta = ends[0], (theta + rho) % (2.0 * np.pi)
    return np.array(samples), np.array(phases), True


def torus_from_transient(kernel, state, p, phase_index, rho, opts, n_settle, n_fit, n_nodes, **solve):
    """The torus an attracting transient from `state` settles on: its stroboscopic samples
    (settled_samples) fitted by n_nodes nodes (fitted_guess), then solve_torus(**solve). None
    where the transient could not be integrated."""
    samples, phases, ok = settled_samples(kernel, np.asarray(state, float), p, phase_index, rho, opts,
                                          n_settle, n_fit)
    if not ok:
        return None
    return solve_torus(kernel, fitted_guess(samples, phases, n_nodes), p, phase_index, rho, opts, **solve)


def periodic_guess(state, n_nodes):
    """Node values (n_nodes, n) of a constant circle through one periodic state."""
    return np.tile(np.asarray(state, float), (n_nodes, 1))


def stability(torus, n_steps=4000, theta0=0.0, margin=1e-6):
    """Normal Lyapunov exponents of the torus (per unit scaled time) by QR iteration of the
    linearized map along the rotation, the monodromy interpolated between the nodes.

    Undecided when the torus did not converge, the monodromies are not resolved by the nodes, or
    the largest exponent lies within its convergence error (the two halves' difference, at least
    `margin`) of 0."""
    if torus.status != CONVERGED:
        return Stability(np.full(torus.nodes.shape[1], np.nan), np.inf, UNDECIDED, f"torus {torus.status}")
    n_nodes, n = torus.nodes.shape
    flat = torus.monodromies.reshape(n_nodes, n * n)
    thetas = theta0 + torus.rho * np.arange(n_steps)
    logs = qr_logs((dirichlet_matrix(n_nodes, thetas) @ flat).reshape(n_steps, n, n))
    half = n_steps // 2
    first = np.sort(logs[:half].mean(axis=0))[::-1] / torus.period
    second = np.sort(logs[half:].mean(axis=0))[::-1] / torus.period
    exponents = np.sort(logs.mean(axis=0))[::-1] / torus.period
    spread = max(float(np.abs(first - second).max()), margin)
    if fourier_tail(torus.monodromies) > 1e-6:
        return Stability(exponents, spread, UNDECIDED, "monodromies not resolved by the nodes")
    if abs(exponents[0]) <= spread:
        return Stability(exponents, spread, UNDECIDED, "largest exponent within its error of 0")
    return Stability(exponents, spread, STABLE if exponents[0] < 0 else UNSTABLE, "")


def dirichlet_matrix(n_nodes, thetas):
    """interpolation_matrix(n_nodes, thetas) in closed form, sin(N d / 2) / (N sin(d / 2)) with
    d = theta - theta_k reduced to [-pi, pi) (1 at d = 0): O(N) per phase instead of O(N^2), for
    the stability's thousands of phases. The reduction keeps it accurate where d nears a multiple
    of 2 pi (both sines small); its absolute error, that of d (eps |theta|), is the sum's too."""
    d = (np.asarray(thetas, float)[:, None] - node_phases(n_nodes)[None, :] + np.pi) % (2.0 * np.pi) - np.pi
    s = np.sin(0.5 * d)
    small = s == 0.0
    return np.where(small, 1.0, np.sin(0.5 * n_nodes * d) / (n_nodes * np.where(small, 1.0, s)))


@njit(cache=True, nogil=True)
def qr_logs(monos):
    """logs (n_steps, n): log |R_kk| of the QR iteration Q_{k+1} R_k = M_k Q_k from Q_0 = I
    (Householder reflections, as LAPACK's geqrf; compiled: numpy's qr costs ~20 us a call in
    Python overhead, the step itself ~1 us at n = 10)."""
    n_steps, n = monos.shape[0], monos.shape[1]
    logs = np.empty((n_steps, n))
    q = np.eye(n)
    a = np.empty((n, n))
    v = np.empty((n, n))
    for k in range(n_steps):
        for i in range(n):
            for j in range(n):
                acc = 0.0
                for m in range(n):
                    acc += monos[k, i, m] * q[m, j]
                a[i, j] = acc
        for j in range(n):
            norm = 0.0
            for i in range(j, n):
                norm += a[i, j] * a[i, j]
            norm = np.sqrt(norm)
            logs[k, j] = np.log(norm)
            alpha = -norm if a[j, j] >= 0.0 else norm
            vnorm = 0.0
            for i in range(j, n):
                v[j, i] = a[i, j] - (alpha if i == j else 0.0)
                vnorm += v[j, i] * v[j, i]
            vnorm = np.sqrt(vnorm)
            for i in range(j, n):
                v[j, i] = v[j, i] / vnorm if vnorm > 0.0 else 0.0
            _reflect(a, v, j)
        for i in range(n):
            for j in range(n):
                q[i, j] = 1.0 if i == j else 0.0
        for j in range(n - 1, -1, -1):
            _reflect(q, v, j)
    return logs


@njit(cache=True, nogil=True, inline="always")
def _reflect(a, v, j):
    """a[j:, j:] <- (I - 2 v_j v_j^T) a[j:, j:] (v_j: row j of v, nonzero from index j; columns
    before j are zero below row j in both uses: the reduced matrix, and Q built backwards)."""
    n = a.shape[0]
    for c in range(j, n):
        dot = 0.0
        for i in range(j, n):
            dot += v[j, i] * a[i, c]
        for i in range(j, n):
            a[i, c] -= 2.0 * v[j, i] * dot


def surface_samples(kernel, circle, p, phase_index, opts, n_phases=64, n_per_period=64):
    """States on the torus (n_phases, n_per_period, n): the trajectories over one period T from
    n_phases points of the circle, each from its forcing phase (what an amplitude, a time history
    or a picture of the torus reads). An amplitude from them is the torus's to the sampling
    grid: the sup of a smooth function on a grid of spacing h lies within O(h^2) of the true sup."""
    phases = 2.0 * np.pi * np.arange(n_phases) / n_phases
    starts = circle.at(phases)
    pj = np.array(p, float)
    out = np.empty((n_phases, n_per_period, kernel.n_state))
    for j, theta in enumerate(phases):
        pj[phase_index] = theta
        out[j] = shooting.sample_orbit(kernel, starts[j], pj, circle.period, n_per_period, opts)
    return out


def phase_extremes(model, circle, p, phase_index, opts, period, n_phases):
    """(hi, lo) (n_phases, n_observables) SI: the exact extrema (rotorsweep.kernels.extrema) of each
    observable along the trajectory over one period T from each of n_phases equally spaced phases
    of the circle (period: T in seconds, for the observables' units). Their max / min over the
    phases is the torus's to the phase sampling (see phase_sampling_error)."""
    phases = node_phases(n_phases)
    starts = circle.at(phases)
    pj = np.array(p, float)
    hi = np.empty((n_phases, len(model.observables)))
    lo = np.empty_like(hi)
    for j, theta in enumerate(phases):
        pj[phase_index] = theta
        hi[j], lo[j] = extrema.extremes(model, starts[j], pj, circle.period, opts, period)
    return hi, lo


def phase_sampling_error(values):
    """Estimated shortfall of max over the phase samples (n_phases, ...) below the sup over the
    circle: the rise of the parabola through the largest sample and its two (cyclic) neighbours
    to its vertex, (d1 - d2)^2 / (8 (d1 + d2)) with d1, d2 >= 0 the drops to the neighbours (an
    error O(h^2) in the phase spacing h, bounded by (d1 + d2) / 8 at a kink)."""
    k = np.argmax(values, axis=0)
    cols = np.arange(values.shape[1])
    n = values.shape[0]
    top = values[k, cols]
    d1, d2 = top - values[(k - 1) % n, cols], top - values[(k + 1) % n, cols]
    total = d1 + d2
    return np.where(total > 0, (d1 - d2) ** 2 / (8.0 * np.where(total > 0, total, 1.0)), 0.0)

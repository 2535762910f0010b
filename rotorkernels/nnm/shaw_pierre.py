r"""Shaw-Pierre invariant manifold to cubic order of one mode of a conservative gyroscopic system
(Filipkovsky 2010, eqs. 20-27 of the symmetric-rotor paper, 5-9 of the axial one).

Formulation: the papers' one, in physical coordinates of the first-order system. The state
x = (q, v), v = q', obeys x' = f(x) = A x + F(q) with F = (0, -M^{-1}(f2(q) + f3(q))). One
coordinate J is the master: p = q_J (displacement, m) and its velocity r = v_J (the papers' q;
named r here to keep q for the coordinates). Every state component is a cubic polynomial in (p, r)
with the papers' nine monomials, in their order:

    x_s = X_s(p, r) = sum_m gamma[s, m] mono_m(p, r),
    mono = (p, r, p^2, p r, r^2, p^3, p^2 r, p r^2, r^3),

with X_J = p and X_{n+J} = r (rows J and n+J fixed). On the manifold the master obeys p' = r,
r' = W(p, r) := f_{n+J}(X(p, r)), and invariance of the surface is the PDE

    dX/dp r + dX/dr W(p, r) = f(X(p, r)),                                          (*)

matched power by power in (p, r) up to degree 3 (the papers' "equating coefficients of p^mu q^nu").

- Degree 1: gamma_1 spans the real plane of the complex eigenvector phi = zeta + i delta of the
  +i omega eigenvalue, gamma_1 = [zeta delta] [[zeta_J, delta_J], [zeta_{n+J}, delta_{n+J}]]^{-1}:
  the papers' eq. 22 (Avramov-Pierre-Shiryaeva 2006 for gyroscopic systems). This is why a
  gyroscopic mode, whose shape is complex (not a real normal mode: the coordinates are not in
  phase), still fits the graph form: each slave depends on both p and r at first order. It needs
  phi_J != 0: the master must move in the mode (ValueError otherwise).
- Degree k = 2, 3: with the lower degrees known, (*) is linear in the degree-k coefficients C_k
  (2n x (k+1)): C_k L_k - P A C_k = -R_k, where L_k is the derivative along the linear master flow
  (p' = r, r' = -omega^2 p) on degree-k monomials, P = I - gamma_1[:, r] e_{n+J}^T removes the part
  of the state's derivative carried by the master's own equation (W contains C_k through
  f_{n+J}), and R_k is the degree-k residual of (*) with C_k = 0 (quadratic terms of f2 at k = 2;
  f3 and the f2 cross terms of degrees 1 x 2, and dX_2/dr W_2, at k = 3). Solved with numpy in
  the system's natural units: the similarity transform that scales the unknown gamma[s, (a, b)]
  by 1 / sqrt(M_ss) (times omega for a velocity row) and by omega^-b (r ~ omega p), equations
  divided by omega. The scaled operator keeps the eigenvalues (over omega) and has O(1) entries,
  so its singular values measure the distance to resonance. (Max-based row/column equilibration,
  used before, made the regular degree-3 operator of every gyroscopic whirl mode of the
  rotationally symmetric models look singular, condition ~1e17; its truncated least-squares
  solution was a wrong manifold with an O(1) error in kappa, and the two planes of a degenerate
  pair were judged differently.)
- Internal resonance: the operator's eigenvalues are i omega (a - b) - lambda_s (a + b = k,
  lambda_s the other modes' eigenvalues: those of the slaves' linear dynamics P A on the slave
  rows), singular when a slave frequency omega_s = j omega, j in {k, k-2, ...}: 2:1 at degree 2,
  3:1 and 1:1 at degree 3. The graph form itself adds no singularity: a circular whirl of a
  rotationally symmetric rotor (y_J = -x_J' / Omega(A): the slave depends on the amplitude-
  dependent frequency through the cubic terms p^2 r, r^3) is the unique solution when no slave is
  resonant. A singular system whose right-hand side lies in the operator's range (the other
  planar mode of a degenerate pair when the isotropic forces keep the motion planar) is solved by
  least squares, minimum norm in the scaled units (the partner plane's rows stay zero: the planar
  manifold), and noted in Manifold.notes; one that is not raises ValueError naming the ratio.
  Consistency is judged against the larger of the right-hand side and the size of the terms it is
  made of (a right-hand side that cancels to rounding, as for a slave the forces leave linear, is
  no reference).

The reduced oscillator is the master's own equation on the manifold, p'' = W(p, p'), written as

    p'' + sum_m B_m mono_m(p, p') = 0,   B = -W  (B_p = omega^2, B_r = 0 up to rounding),

the papers' eq. 26 (symmetric paper, which keeps only the cubic terms) / the axial paper's B_1..B_9.
Its backbone is in rotorsweep.kernels.nnm.curves.

Choices where the papers are silent: the default master is the coordinate with the largest
displacement in the mode (the papers leave J free); the constant term is zero (expansion about
the static equilibrium, as eq. 14 of the symmetric paper without its static preload term).
"""
from typing import NamedTuple

import numpy as np

from rotorsweep.kernels.nnm import linear
from rotorsweep.kernels.nnm import system as ps

# Exponents (of p, of r) of the monomials; index 0 is the constant, 1..9 the papers' gamma columns.
EXPONENTS = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3))
MONOMIALS = ("p", "r", "p^2", "p r", "r^2", "p^3", "p^2 r", "p r^2", "r^3")
DEGREE = np.array([a + b for a, b in EXPONENTS])
_INDEX = {e: i for i, e in enumerate(EXPONENTS)}
_P, _R = _INDEX[(1, 0)], _INDEX[(0, 1)]

# Equilibrated singular values below this (relative to the largest) make the system singular.
SINGULAR_RTOL = 1e-9
# A singular system is consistent when its least-squares residual is this small relative to |rhs|.
CONSISTENT_RTOL = 1e-8
# A master moving less than this (relative to the mode's largest displacement) cannot carry it.
MASTER_PARTICIPATION = 1e-6
# Slave/master frequency ratios within this of a resonant integer are noted as small divisors.
NEAR_RESONANCE = 1e-2


def _product_table():
    """T[i, j, k] = 1 where mono_i mono_j = mono_k (products beyond degree 3 dropped)."""
    table = np.zeros((10, 10, 10))
    for i, (a, b) in enumerate(EXPONENTS):
        for j, (c, d) in enumerate(EXPONENTS):
            if (a + c, b + d) in _INDEX:
                table[i, j, _INDEX[(a + c, b + d)]] = 1.0
    return table


def _derivative(axis):
    """D[i, k]: d mono_i / d(p or r) = D[i, k] mono_k."""
    d = np.zeros((10, 10))
    for i, e in enumerate(EXPONENTS):
        lower = (e[0] - (axis == 0), e[1] - (axis == 1))
        if e[axis] > 0:
            d[i, _INDEX[lower]] = e[axis]
    return d


PRODUCT = _product_table()
D_P, D_R = _derivative(0), _derivative(1)


def mul(x, y):
    """Product of polynomials (coefficient arrays over EXPONENTS, last axis), truncated at degree 3."""
    return np.einsum("...i,...j,ijk->...k", x, y, PRODUCT)


def field(system, state):
    """f(X) for a state whose components are polynomials in (p, r) (shape (2n, 10))."""
    n = len(system.coordinates)
    q, v = state[:n], state[n:]
    qq = np.einsum("ja,kb,abc->jkc", q, q, PRODUCT)
    qqq = np.einsum("jkc,ld,cde->jkle", qq, q, PRODUCT)
    force = system.G @ v + system.K @ q + np.einsum("ijk,jkc->ic", system.Q2, qq) \
        + np.einsum("ijkl,jkle->ie", system.Q3, qqq)
    return np.concatenate([v, -np.linalg.solve(system.M, force)])


def invariance_residual(system, state, master):
    """dX/dp r + dX/dr W - f(X), W = f_{n+J}(X): zero up to degree 3 on the cubic manifold."""
    n = len(system.coordinates)
    f = field(system, state)
    r = np.eye(10)[_R]
    return mul(state @ D_P, r) + mul(state @ D_R, f[n + master]) - f


class Manifold(NamedTuple):
    mode: linear.LinearMode
    master: int              # J: index of the master coordinate
    names: tuple             # state components: the coordinates, then their velocities (name + "'")
    coefficients: np.ndarray  # gamma (2n x 9), columns MONOMIALS; state = gamma @ mono(p, r)
    reduced: dict            # B_m of p'' + sum_m B_m mono_m(p, p') = 0, keys MONOMIALS (SI)
    notes: tuple             # resonances met and how they were resolved

    @property
    def omega(self):
        """Linear natural frequency [rad/s]."""
        return self.mode.omega

    def slaves(self, p, r):
        """The physical state (q, q') on the manifold at master displacement p [m] and velocity
        r [m/s] (arrays broadcast; the state is the last axis)."""
        p, r = np.broadcast_arrays(np.asarray(p, float), np.asarray(r, float))
        mono = np.stack([p ** a * r ** b for a, b in EXPONENTS[1:]], axis=-1)
        return mono @ self.coefficients.T

    def table(self):
        """The reduced oscillator's coefficients as text, one per line."""
        name = self.names[self.master]
        lines = [f"{name}'' + sum B_m m({name}, {name}') = 0 (r = {name}'), mode {self.mode.label} "
                 f"{self.mode.whirl} at {self.mode.frequency:.6g} Hz"]
        lines += [f"  B[{m:>6}] = {value: .6e}" for m, value in self.reduced.items()]
        return "\n".join(lines)


def _linear_part(vector, master, n):
    """gamma_1 (2n x 2) from the complex eigenvector: the papers' eq. 22. Its 2x2 block has
    determinant omega |phi_J|^2 (phi normalized to a largest displacement of 1)."""
    if abs(vector[master]) <= MASTER_PARTICIPATION:
        raise ValueError(f"the master coordinate (index {master}) does not move in this mode "
                         f"(|phi_J| = {abs(vector[master]):.1e} of the largest): choose another master")
    basis = np.stack([vector.real, vector.imag], axis=1)
    return basis @ np.linalg.inv(basis[[master, n + master]])


def _scales(system, omega, degree, cols, free):
    """The natural size of each degree-`degree` unknown gamma[s, (a, b)] (a + b = degree), up to
    a factor common to all: the coordinate's size relative to the master's ~ 1 / sqrt(M_ss), times
    omega for a velocity row, over omega^b (r ~ omega p)."""
    size = 1.0 / np.sqrt(np.diag(system.M))
    rows = np.concatenate([size, omega * size])
    powers = np.array([omega ** -float(EXPONENTS[c][1]) for c in cols])
    return np.outer(rows, powers).ravel()[free]


def _solve_scaled(op, rhs, scale, omega, size):
    """Least-squares solution of op x = rhs in the natural units (the similarity transform
    x = scale y, equations divided by scale and omega: the scaled operator has the eigenvalues of op
    over omega, i omega (a - b) - lambda_s, and entries O(1)); (x, singular, consistent).
    Consistent: the residual is rounding relative to the larger of |rhs| and `size` (the scaled
    size of the terms rhs is made of: a rhs that cancels to rounding, as a slave that the forces
    leave linear, is not a reference)."""
    scaled = op * scale[None, :] / (scale[:, None] * omega)
    b = rhs / (scale * omega)
    y, *_ = np.linalg.lstsq(scaled, b, rcond=SINGULAR_RTOL)
    sv = np.linalg.svd(scaled, compute_uv=False)
    singular = sv[-1] < SINGULAR_RTOL * sv[0]
    reference = max(np.linalg.norm(b), size, 1e-300)
    consistent = np.linalg.norm(scaled @ y - b) <= CONSISTENT_RTOL * reference
    return y * scale, singular, consistent


def _resonance(slave_omegas, omega, degree):
    """(ratio j, slave frequency) of the slave nearest a degree-`degree` resonance omega_s = j omega."""
    ratios = np.arange(degree, -1, -2)
    gaps = np.abs(slave_omegas[:, None] / omega - ratios[None, :])
    s, j = np.unravel_index(np.argmin(gaps), gaps.shape)
    return int(ratios[j]), float(slave_omegas[s])


def _solve_degree(system, state, master, omega, degree, slave_omegas, notes):
    """Fill the degree-`degree` columns of state (2n x 10) from (*) (module docstring)."""
    n = len(system.coordinates)
    cols = np.flatnonzero(DEGREE == degree)
    lie = D_P @ PRODUCT[:, _R, :] - omega ** 2 * D_R @ PRODUCT[:, _P, :]
    lk = lie[np.ix_(cols, cols)]
    projector = np.eye(2 * n) - np.outer(state[:, _R], np.eye(2 * n)[n + master])
    pa = projector @ ps.state_matrix(system)
    op = np.kron(np.eye(2 * n), lk.T) - np.kron(pa, np.eye(len(cols)))
    free = np.array([s not in (master, n + master) for s in range(2 * n) for _ in cols])
    if not free.any():
        return      # one degree of freedom: no slaves
    rhs = -invariance_residual(system, state, master)[:, cols].ravel()
    every = np.ones(2 * n * len(cols), bool)
    scale, all_scales = _scales(system, omega, degree, cols, free), _scales(system, omega, degree, cols, every)
    size = np.linalg.norm(field(system, state)[:, cols].ravel() / (all_scales * omega))
    x, singular, consistent = _solve_scaled(op[np.ix_(free, free)], rhs[free], scale, omega, size)
    if singular:
        ratio, slave = _resonance(slave_omegas, omega, degree)
        what = (f"{ratio}:1 internal resonance (a slave mode at {slave / (2 * np.pi):.6g} Hz, "
                f"{slave / omega:.6f} x the master's {omega / (2 * np.pi):.6g} Hz) at degree {degree}")
        if not consistent:
            raise ValueError(f"{what} makes the cubic manifold singular")
        notes.append(f"{what}: singular but consistent, least-squares (minimum-norm) coefficients")
    coefficients = np.zeros(2 * n * len(cols))
    coefficients[free] = x
    state[:, cols] = coefficients.reshape(2 * n, len(cols))


def _near_resonances(slave_omegas, omega):
    notes = []
    for slave in slave_omegas:
        for ratio in (1, 2, 3):
            gap = abs(slave / omega - ratio)
            if 0 < gap <= NEAR_RESONANCE * ratio:
                notes.append(f"near {ratio}:1 resonance: slave mode at {slave / (2 * np.pi):.6g} Hz "
                             f"({slave / omega:.6f} x master): small divisor")
    return notes


def manifold(system, mode_index, master=None, kinds=None):
    """The cubic Shaw-Pierre manifold of linear mode `mode_index` (of linear_modes(system, kinds),
    by increasing frequency), master coordinate `master` (index; default: the largest
    displacement in the mode)."""
    modes = linear.linear_modes(system, kinds)
    if not 0 <= mode_index < len(modes):
        raise ValueError(f"mode index {mode_index} out of range: the system has {len(modes)} modes")
    mode = modes[mode_index]
    n = len(system.coordinates)
    master = int(np.argmax(np.abs(mode.shape))) if master is None else master
    if not 0 <= master < n:
        raise ValueError(f"master index {master} out of range for {n} coordinates")
    omega = mode.omega
    slave_omegas = np.array([m.omega for k, m in enumerate(modes) if k != mode_index])
    state = np.zeros((2 * n, 10))
    state[:, [_P, _R]] = _linear_part(mode.vector, master, n)
    notes = _near_resonances(slave_omegas, omega)
    for degree in (2, 3):
        _solve_degree(system, state, master, omega, degree, slave_omegas, notes)
    w = field(system, state)[n + master]
    reduced = {m: float(-w[i + 1]) for i, m in enumerate(MONOMIALS)}
    names = tuple(system.coordinates) + tuple(c + "'" for c in system.coordinates)
    return Manifold(mode, master, names, state[:, 1:].copy(), reduced, tuple(notes))

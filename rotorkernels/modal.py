"""Linear modes of M q'' + D q' + K q = 0 (D: damping plus gyroscopic) and their labels: the one
linear-modes implementation of rotorsweep (`rotorsweep modes` and omega_l, the nonlinear normal
modes, the backbones' starting modes and the series rotors' time scale all call it). Pure numpy:
the models may use it (it is not in rotorsweep.kernels.PYTHON_ONLY).

The first-order form x' = A x (x = (q, q')) has eigenvalues in conjugate pairs s = -zeta w_n +- i w_d
(w_d = w_n sqrt(1 - zeta^2), w_n = |s|); each oscillating mode is reported once (w_d > 0), by
increasing w_d (`eigenpairs`; `modes_of` labels them); a conservative gyroscopic system has
s = +-i omega (`rotorsweep.kernels.nnm.linear_modes`).

Labels come from a per-coordinate description the model provides, `kinds`: one (axis, station)
tag per coordinate, axis "x" or "y" (transverse displacement) or "z" (axial), station any name of
the journal or section the coordinate belongs to (e.g. ("x", "A"), ("y", "A"), ("x", "B"),
("y", "B"), ("z", None)). Without kinds they are read from the coordinate names "x1", "y1", "z"
(axis = first letter, station = the rest); other names give the label "unknown".

- axial: the axial coordinates carry most of the mode's kinetic energy Re(conj(phi) M phi);
- otherwise, with two or more stations, cylindrical when the first two stations move in phase
  (Re(conj(x_a) x_b + conj(y_a) y_b) > 0), conical in anti-phase; with one station, transverse.
- whirl: the shaft turns from +x to +y; a station's orbit
  x = Re(X e^{i w t}), y = Re(Y e^{i w t}) has the mean angular momentum x y' - y x' = -w Im(conj(X) Y),
  summed over stations: positive is forward, negative backward, zero (within WHIRL_TOL) "none";
  "none" also without gyroscopic coupling (G = 0: a shaft at rest, where degenerate pairs may mix
  either way).

Degenerate pairs (two modes at one frequency within DEGENERATE_RTOL: an isotropic rotor's
cylindrical modes, untouched by the gyroscopic moment) have no defined eigenvectors; as in the
2010 papers ("oscillations in two planes") they are returned as the two planar modes, the x-plane
one (least y motion) first, whirl "none".
"""
from typing import NamedTuple

import numpy as np

# Two frequencies closer than this (relative) form a degenerate pair.
DEGENERATE_RTOL = 1e-8
# No whirl when |angular momentum| is below this, relative to the shape's squared size times w.
WHIRL_TOL = 1e-6


class LinearMode(NamedTuple):
    omega: float             # damped natural frequency w_d = Im s [rad/s]
    frequency: float         # damped natural frequency [Hz]
    whirl: str               # forward / backward / none
    label: str               # axial / cylindrical / conical / transverse / unknown
    vector: np.ndarray       # complex eigenvector of A for s, (q, q'), largest |q_n| = 1
    damping_ratio: float = 0.0   # zeta = -Re s / |s|

    @property
    def shape(self):
        """Complex displacement shape (q part of the eigenvector)."""
        return self.vector[:len(self.vector) // 2]

    @property
    def undamped_frequency(self):
        """w_n / 2 pi = |s| / 2 pi [Hz] (equal to `frequency` without damping)."""
        return self.frequency / np.sqrt(1.0 - self.damping_ratio ** 2)


def kinds_from_names(coordinates):
    """(axis, station) per coordinate from names like "x1", "yB", "z"; None if a name does not
    start with x, y or z."""
    if not all(name[:1] in ("x", "y", "z") for name in coordinates):
        return None
    return tuple((name[0], name[1:] or None) for name in coordinates)


def _stations(kinds):
    """{station: (x index, y index)} for the stations having both transverse coordinates, in order."""
    found = {}
    for i, (axis, station) in enumerate(kinds):
        if axis in ("x", "y"):
            found.setdefault(station, {})[axis] = i
    return {s: (c["x"], c["y"]) for s, c in found.items() if len(c) == 2}


def whirl(shape, omega, kinds):
    """forward / backward / none from the mean angular momentum of the stations' orbits."""
    stations = _stations(kinds) if kinds else {}
    momentum = sum(-omega * np.imag(np.conj(shape[ix]) * shape[iy]) for ix, iy in stations.values())
    if not stations or abs(momentum) <= WHIRL_TOL * omega * float(np.sum(np.abs(shape) ** 2)):
        return "none"
    return "forward" if momentum > 0 else "backward"


def label(shape, mass, kinds):
    """axial / cylindrical / conical / transverse / unknown (module docstring)."""
    if not kinds:
        return "unknown"
    energy = np.real(np.conj(shape) * (mass @ shape))
    axial = [i for i, (axis, _) in enumerate(kinds) if axis == "z"]
    if energy[axial].sum() > 0.5 * energy.sum():
        return "axial"
    stations = list(_stations(kinds).values())
    if len(stations) < 2:
        return "transverse"
    (xa, ya), (xb, yb) = stations[:2]
    in_phase = np.real(np.conj(shape[xa]) * shape[xb] + np.conj(shape[ya]) * shape[yb])
    return "cylindrical" if in_phase > 0 else "conical"


def _planar_pair(vectors, kinds):
    """The x-plane and y-plane modes spanning a degenerate pair's eigenspace (columns of vectors)."""
    basis, _ = np.linalg.qr(vectors)
    n = len(vectors) // 2
    out = []
    for other in ("y", "x"):
        rows = [i for i, (axis, _) in enumerate(kinds) if axis == other]
        rows = rows + [n + i for i in rows]
        _, _, vh = np.linalg.svd(basis[rows])
        out.append(basis @ np.conj(vh[-1]))   # the combination with the least `other` motion
    return out


def _normalized(vector):
    n = len(vector) // 2
    return vector / vector[np.argmax(np.abs(vector[:n]))]


def first_order(mass, damping, stiffness):
    """A of x' = A x, x = (q, q'), for M q'' + D q' + K q = 0."""
    n = len(mass)
    m_inv = np.linalg.inv(mass)
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -m_inv @ stiffness
    a[n:, n:] = -m_inv @ damping
    return a


def eigenpairs(a):
    """(eigenvalues s with Im s > 0, ascending in Im s; their eigenvectors as columns) of the
    real matrix `a`: each oscillating pair once, the non-oscillating (real) eigenvalues left out."""
    eigvals, eigvecs = np.linalg.eig(a)
    upper = np.flatnonzero(eigvals.imag > 0)
    upper = upper[np.argsort(eigvals.imag[upper])]
    return eigvals[upper], eigvecs[:, upper]


def modes_of(mass, damping, gyroscopic, stiffness, kinds):
    """The oscillating modes of M q'' + (C + G) q' + K q = 0 (C = `damping`, G = `gyroscopic`,
    already times the shaft speed), by increasing damped frequency (list of LinearMode); kinds as
    in the module docstring (None: labels "unknown", whirl "none")."""
    if kinds is not None and len(kinds) != len(mass):
        raise ValueError(f"{len(kinds)} kinds for {len(mass)} coordinates")
    rotating = bool(np.any(gyroscopic))
    eigvals, eigvecs = eigenpairs(first_order(mass, damping + gyroscopic, stiffness))
    omegas = eigvals.imag
    vectors = [eigvecs[:, k] for k in range(len(eigvals))]
    k = 0
    while k < len(omegas) - 1:
        if omegas[k + 1] - omegas[k] <= DEGENERATE_RTOL * omegas[k] and kinds is not None:
            vectors[k], vectors[k + 1] = _planar_pair(np.stack(vectors[k:k + 2], axis=1), kinds)
            k += 1
        k += 1
    modes = []
    for s, vector in zip(eigvals, vectors):
        vector = _normalized(vector)
        shape = vector[:len(vector) // 2]
        turn = whirl(shape, s.imag, kinds) if rotating else "none"
        modes.append(LinearMode(float(s.imag), float(s.imag / (2 * np.pi)), turn, label(shape, mass, kinds), vector,
                                float(-s.real / abs(s))))
    return modes

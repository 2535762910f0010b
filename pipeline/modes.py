"""Linear analysis of a `rigid_preloaded` scene (`rotorsweep modes`): static equilibrium under
preload (and weight), the linearized natural frequencies and mode shapes with gyroscopic
forward/backward whirl, mode labels, and a Campbell table over shaft speed.

Linearization about the static equilibrium q_s: M q'' + (C + Omega G) q' + K_s q = 0 with
K_s = dP/dq(q_s), the analytic stiffness of the ball sums (the kernel's). Eigenvalues of the
first-order form come in pairs s = -zeta w +- i w_d; each mode is reported once (w_d > 0).

Whirl: the shaft turns from +x to +y (the unbalance force is m0 a Omega^2 (cos, sin)(Omega t)),
so a journal orbit x = Re(X e^{i w t}), y = Re(Y e^{i w t}) whirls forward when
Im(conj(X) Y) < 0 (X = 1, Y = -i: x = cos, y = sin) and backward when > 0; at zero speed the pairs are degenerate and the
direction is not defined ("none"). Labels: axial (z carries most of the mode's kinetic
energy), cylindrical (both journals move in phase), conical (in opposite phase).
"""
import csv
from typing import NamedTuple

import numpy as np

from pipeline import compute
from rotorkernels.models import rigid_preloaded as rp

# The static equilibrium is converged when |P(q) - f_g| <= EQUILIBRIUM_RTOL x the preload.
EQUILIBRIUM_RTOL = 1e-13
# A pair of eigenvalues is degenerate (no whirl direction) when Im(conj(X) Y) is this small
# relative to |X|^2 + |Y|^2.
WHIRL_TOL = 1e-6


class Equilibrium(NamedTuple):
    position: np.ndarray     # q_s [m]
    residual: float          # |P(q_s) - f_g| / P0
    stiffness: np.ndarray    # dP/dq at q_s [N/m]
    iterations: int


class Mode(NamedTuple):
    frequency: float         # damped natural frequency [Hz]
    damping_ratio: float
    whirl: str               # forward / backward / none
    label: str               # axial / cylindrical / conical
    shape: np.ndarray        # complex (x1, y1, x2, y2, z), largest component 1


def scene_values(data, point):
    """The model's values at a point {axis: value} of the scene (its fixed values filled in)."""
    spec = compute.model_of(data)
    if spec.name != rp.SPEC.name:
        raise ValueError(f"modes: model {spec.name!r} has no linear analysis (only {rp.SPEC.name})")
    return {**compute.scene_values(data, spec), **compute.fixed_values(data), **point}


def static_equilibrium(values, max_iter=50):
    """Newton on P(q) = f_g from the centred rotor (where P = 0 by the preload's symmetry)."""
    state = rp.bearing_state(values)
    n_balls = rp.n_balls_of(values)
    load = rp.weight(rp.Rotor.of(values))
    q = np.zeros(rp.N_POS)
    scale = float(values["preload"])
    for it in range(max_iter + 1):
        force, stiffness = rp.bearing_load(q, state, n_balls, values["law"], arrangement=rp.arrangement_of(values))
        residual = np.abs(force - load).max() / scale
        if residual <= EQUILIBRIUM_RTOL or it == max_iter:
            break
        q -= np.linalg.solve(stiffness, force - load)
    return Equilibrium(q, residual, stiffness, it)


def state_matrix(rotor, stiffness, speed_hz):
    """A of x' = A x, x = (q, q'), SI."""
    m_inv = np.linalg.inv(rp.mass_matrix(rotor))
    damp = rotor.damping * np.eye(rp.N_POS) + 2.0 * np.pi * speed_hz * rp.gyroscopic_matrix(rotor)
    n = rp.N_POS
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -m_inv @ stiffness
    a[n:, n:] = -m_inv @ damp
    return a


def _whirl(shape, speed_hz):
    """forward / backward / none from the journals' orbit sense (module docstring); none at
    zero speed, where a degenerate pair's eigenvectors may mix either way."""
    sense = sum(np.imag(np.conj(shape[i]) * shape[i + 1]) for i in (0, 2))
    size = float(np.sum(np.abs(shape) ** 2))
    if speed_hz == 0 or abs(sense) <= WHIRL_TOL * size:
        return "none"
    return "forward" if sense < 0 else "backward"


def _label(shape, mass):
    energy = np.real(np.conj(shape) * (mass @ shape))
    if energy[4] > 0.5 * energy.sum():
        return "axial"
    in_phase = np.real(np.conj(shape[0]) * shape[2] + np.conj(shape[1]) * shape[3])
    return "cylindrical" if in_phase > 0 else "conical"


def modes(values, speed_hz, equilibrium=None):
    """The modes at one shaft speed [Hz], by increasing frequency."""
    eq = static_equilibrium(values) if equilibrium is None else equilibrium
    rotor = rp.Rotor.of(values)
    eigvals, eigvecs = np.linalg.eig(state_matrix(rotor, eq.stiffness, speed_hz))
    mass = rp.mass_matrix(rotor)
    out = []
    for k in np.flatnonzero(eigvals.imag > 0):
        s = eigvals[k]
        shape = eigvecs[:rp.N_POS, k]
        shape = shape / shape[np.argmax(np.abs(shape))]
        out.append(Mode(s.imag / (2.0 * np.pi), -s.real / abs(s), _whirl(shape, speed_hz), _label(shape, mass), shape))
    return sorted(out, key=lambda m: m.frequency)


def campbell(values, speeds_hz):
    """Rows (speed [Hz], mode index, frequency [Hz], damping ratio, whirl, label) over the speeds."""
    eq = static_equilibrium(values)
    return [(float(f), k, m.frequency, m.damping_ratio, m.whirl, m.label)
            for f in speeds_hz for k, m in enumerate(modes(values, f, eq))]


# Filipkovsky 2016's frequency unit omega_l: the lowest natural frequency of the linearized
# system with the bearing of the 15 deg row of the paper's table.
OMEGA_L_ANGLE = 15.0


def omega_l(data):
    """omega_l [Hz] of a scene: the lowest damped natural frequency at the scene's first grid
    point, its bearing replaced by the paper's 15 deg row (loaded angle from the preload solve,
    no imposed angle or R2), at that point's shaft speed. With the paper's rotor it is the axial
    mode, which the shaft speed does not move."""
    first = {name: float(values[0]) for name, values in data["sweep"].items()}
    values = {**scene_values(data, first), "nominal_angle": OMEGA_L_ANGLE, "contact_angle": None,
              "outer_race_radius": None}
    return modes(values, values["speed"])[0].frequency


CAMPBELL_COLUMNS = ("speed_hz", "mode", "frequency_hz", "damping_ratio", "whirl", "label")


def write_campbell(rows, path):
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(CAMPBELL_COLUMNS)
        writer.writerows(rows)


def summary(values, speed_hz):
    """Text: the static state and the modes at one speed (what `rotorsweep modes` prints)."""
    eq = static_equilibrium(values)
    state = rp.bearing_state(values)
    lines = [f"static equilibrium: q = {np.array2string(eq.position, precision=4)} m, "
             f"residual {eq.residual:.1e} x P0 ({eq.iterations} Newton iterations)",
             f"contact angle {np.degrees(state.contact_angle):.4f} deg, axial approach z0 = "
             f"{state.axial_approach:.4e} m, K = {state.contact_constant:.4e} N/m^1.5, "
             f"k_r = {state.radial_stiffness:.4e} N/m, k_a = {state.axial_stiffness:.4e} N/m per bearing",
             f"modes at {speed_hz:g} Hz:",
             f"{'#':>2} {'frequency [Hz]':>15} {'zeta':>8} {'whirl':>9} {'label':>12}"]
    for k, m in enumerate(modes(values, speed_hz, eq)):
        lines.append(f"{k:>2} {m.frequency:>15.4f} {m.damping_ratio:>8.4f} {m.whirl:>9} {m.label:>12}")
    return "\n".join(lines)


def command(cfg, at, campbell_speeds=None, output=None):
    """`rotorsweep modes`: the summary at the scene's first grid point (axis values from `at`
    {axis: value} where given) and, with `output`, the Campbell table over `campbell_speeds`
    [Hz] (default: the scene's speed axis) as CSV. Returns the text to print."""
    first = {name: float(values[0]) for name, values in cfg.axes.items()}
    values = scene_values(cfg.data, {**first, **at})
    text = summary(values, values["speed"])
    if output is not None:
        speeds = cfg.axes["speed"] if campbell_speeds is None else campbell_speeds
        write_campbell(campbell(values, speeds), output)
        text += f"\nCampbell table ({len(speeds)} speeds): {output}"
    return text

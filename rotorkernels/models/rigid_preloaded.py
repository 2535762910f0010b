"""Model `rigid_preloaded` (Filipkovsky 2016, SPEC 2.2): a rigid shaft with one disk on two
axially preloaded angular-contact ball bearings, 5 DOF, forced by disk unbalance at the shaft
frequency Omega and by vibration of both supports at a second frequency omega.

Coordinates q = (x1, y1, x2, y2, z): journal displacements of bearing A (xi = 0) and B (xi = l)
relative to their outer rings, and the axial displacement z. Equations (Lagrange's, from the
kinetic energy T of SPEC 2.2 with Rayleigh damping C (x1'^2 + ... + z'^2) / 2):

    M q'' + (C + Omega G) q' + P(q) = m0 a Omega^2 u_D(t) - M A_s sin(omega t) - f_g

M and G are `mass_matrix` and `gyroscopic_matrix`; u_D = ((1 - s) cos, (1 - s) sin, s cos,
s sin, 0)(Omega t) with s = xi_D / l; A_s the support acceleration amplitude along one axis, the
same at both supports; f_g the weight (gravity in -y, 0 by default as in the paper).

Bearing forces (paper eq. 1), fixed ball angles b_k = 2 pi k / N:

    P_v = K sum_k [delta_k]_+^{3/2} (cos a cos b_k, cos a sin b_k, +-sin a)
    delta_k = x_v cos a cos b_k + y_v cos a sin b_k + (z0 +- z) sin a

Back-to-back convention (the default arrangement): the upper sign for bearing A, the lower for B. The paper writes
z1 = z2 = z; in a preloaded pair one bearing is compressed by an axial shift while the other
is relieved, so +z loads A and unloads B, and P(q) = dPi/dq with the generalized axial force
P_zA - P_zB (zero at q = 0: the preload balances). A ball with delta_k <= 0 carries nothing.

Bearing table, preload law (`bearing.preload_law`: "hertz", the consistent Hertz model, or
"as_printed", the papers' eqs. 6-10 exactly as printed), contact angles, given vs derived values:
`preloaded_pair`. The force law above takes K, alpha and z0 from there; the ball's bracket at rest
(z0 sin a) is the Hertz approach w for "hertz" and eq. 7's z0 sin a for "as_printed", whose static
axial force per bearing is then 1.5 P0 (the rotor stays centred: the two bearings' thrusts oppose).
`bearing.arrangement` face_to_face flips the sign of z in both bearings (+z compresses B).

Forcing: unbalance (eccentricity a > 0) at Omega, support vibration (acceleration > 0) at omega.
With both on, the forcing is periodic only when omega / Omega = p / q (coprime, q at most
`forcing.max_denominator`, see `frequency_ratio`); the common period T = q / f_Omega = p / f_omega
is then the shooting period. Otherwise the point is quasi-periodically forced (Built.periodic
false): no periodic orbit is sought, and the attractor's Poincare samples are taken once per
shaft revolution.

Scaling: tau = t / T (T the common period, or the one active forcing's period), positions in
units of L = 1 um; u = (q / L, dq/dtau / L).
"""
from fractions import Fraction
from typing import NamedTuple

import numpy as np

from rotorsweep.kernels import modal
from rotorsweep.kernels.cubic_law import cubic_coefficients
from rotorsweep.kernels.models.spec import (Built, Equilibrium, LinearSystem, ModelSpec, Observable, Parameter,
                                               kernel_module)
from rotorsweep.kernels.models.preloaded_pair import (  # noqa: F401 (the pair's API, read as rp.*)
    ARRANGEMENTS, BEARING_DERIVED, BEARING_KEYS, DEFAULT_NOMINAL_ANGLE, NOMINAL_ANGLES,
    arrangement_of, bearing_derived, bearing_problems, bearing_state, free_angle_before_version_2, geometry,
    n_balls_of, preload_of, table_geometry, with_row)

LENGTH_SCALE = 1e-6
N_POS = 5
# Kernel parameter vector: 5x5 blocks row-major, then 5-vectors, then scalars.
P_GAIN = 0          # T^2 K sqrt(L) M^-1: ball sums (scaled) -> scaled acceleration
P_DAMP = 25         # T M^-1 (C + Omega G)
P_CONST = 50        # T^2 / L M^-1 (-f_g)
P_UCOS = 55         # T^2 / L M^-1 m0 a Omega^2 u_D, cosine part
P_USIN = 60         # sine part
P_SUP = 65          # -T^2 / L A_s
P_WU, P_WS, P_OFFSET, P_COS_A, P_SIN_A, P_NBALLS, P_COS_D, P_SIN_D = range(70, 78)
P_LAW, P_CR, P_CA, P_Z0, P_TAN2 = range(78, 83)   # law 1: cubic series, its scaled coefficients
P_ARR = 83          # +1 back to back (+z compresses A), -1 face to face (+z compresses B)
P_PHASE = 84        # the support vibration's phase at tau = 0 [rad] (0; the torus solver's node phase)
N_PARAMS = 85
LAWS = {"ball_sum": 0.0, "cubic": 1.0}

# Rational detection: a ratio within RATIO_RTOL of p / q with q <= DETECTION_DENOMINATOR is
# that fraction (typed frequencies are decimals; the golden mean's best such fraction is off by
# 6e-9); p / q with q above the scene's max_denominator has a common period too long to shoot.
RATIO_RTOL = 1e-9
DETECTION_DENOMINATOR = 10_000
RATIONAL, LONG_PERIOD, IRRATIONAL = "rational", "long_period", "irrational"


# --- rotor matrices (SI) -----------------------------------------------------------------------

class Rotor(NamedTuple):
    length: float               # l [m]
    disk_position: float        # xi_D [m] from bearing A
    shaft_mass: float           # m_B [kg]
    shaft_diametral: float      # I_C1 [kg m^2]
    shaft_polar: float          # I_C0
    disk_mass: float            # m_0
    disk_diametral: float       # I_1
    disk_polar: float           # I_0
    damping: float              # C [N s/m] on every coordinate
    gravity: float              # g [m/s^2], acting in -y

    @classmethod
    def of(cls, v):
        return cls(*(float(v[name]) for name in cls._fields))


def _pair(a, b, c):
    """The 5x5 matrix with the 2x2 block [[a, b], [b, c]] on (x1, x2) and on (y1, y2)."""
    m = np.zeros((N_POS, N_POS))
    for i, j in ((0, 2), (1, 3)):
        m[i, i], m[i, j], m[j, i], m[j, j] = a, b, b, c
    return m


def mass_matrix(r):
    """M from T: diametral inertia (I_C1 + I_1) of the tilt (q2 - q1) / l, shaft mass at
    mid-span, disk mass at xi_D; axial mass m_B + m_0."""
    s = r.disk_position / r.length
    i_d = (r.shaft_diametral + r.disk_diametral) / r.length ** 2
    m = _pair(i_d + r.shaft_mass / 4 + r.disk_mass * (1 - s) ** 2,
              -i_d + r.shaft_mass / 4 + r.disk_mass * s * (1 - s),
              i_d + r.shaft_mass / 4 + r.disk_mass * s ** 2)
    m[4, 4] = r.shaft_mass + r.disk_mass
    return m


def gyroscopic_matrix(r):
    """G per unit shaft speed [rad/s] from T's term I_p Omega (y1' - y2')(x2 - x1) / l^2:
    skew-symmetric, g = (I_C0 + I_0) / l^2 (the gyroscopic force is Omega G q')."""
    g = (r.shaft_polar + r.disk_polar) / r.length ** 2
    m = np.zeros((N_POS, N_POS))
    for (i, j), sign in (((0, 1), 1), ((0, 3), -1), ((2, 1), -1), ((2, 3), 1)):
        m[i, j] = sign * g
        m[j, i] = -sign * g
    return m


def unbalance_shape(r):
    """u_D: the generalized unbalance force is m0 a Omega^2 (u_D cos Omega t, rotated by 90 deg
    in (x, y) for the sine part); returns (cosine part, sine part)."""
    s = r.disk_position / r.length
    return np.array([1 - s, 0, s, 0, 0.0]), np.array([0, 1 - s, 0, s, 0.0])


def weight(r):
    """Generalized gravity force (in -y) on (x1, y1, x2, y2, z) [N]."""
    s = r.disk_position / r.length
    w = r.gravity
    return np.array([0.0, -w * (r.shaft_mass / 2 + r.disk_mass * (1 - s)), 0.0,
                     -w * (r.shaft_mass / 2 + r.disk_mass * s), 0.0])


SUPPORT_AXES = {"x": (0, 2), "y": (1, 3), "z": (4,)}


def support_vector(direction, acceleration):
    """A_s [m/s^2]: both supports vibrate along one axis (a rigid-body motion of the frame)."""
    a = np.zeros(N_POS)
    a[list(SUPPORT_AXES[direction])] = acceleration
    return a


# --- bearings ----------------------------------------------------------------------------------

def bearing_load(q, state, n_balls, law="ball_sum", length_scale=LENGTH_SCALE, arrangement="back_to_back"):
    """Generalized bearing force P(q) [N] and its stiffness dP/dq [N/m] at positions q [m]:
    the kernel's bearing loads (`rigid_preloaded_kernels.load`) in SI, for static and linear analysis."""
    from rotorsweep.kernels.models import rigid_preloaded_kernels as kernels   # Numba: only when called

    el = length_scale
    x = np.asarray(q, float) / el
    p = np.zeros(N_PARAMS)       # gain -I, no damping: the lower-left block of the Jacobian is dP/dq
    p[P_GAIN:P_GAIN + 25] = -np.eye(N_POS).ravel()
    _bearing_params(p, state, n_balls, law, el, arrangement)
    s = p[P_ARR]
    a = kernels.load(x[0], x[1], s * x[4], p)
    b = kernels.load(x[2], x[3], -s * x[4], p)
    force = np.array([a[0], a[1], b[0], b[1], s * (a[2] - b[2])])
    jac = np.zeros((2 * N_POS, 2 * N_POS))
    kernels.jacobian(jac, p, a, b)
    k = state.contact_constant
    return k * el ** 1.5 * force, k * el ** 0.5 * jac[N_POS:, :N_POS]


def _bearing_params(p, state, n_balls, law, el, arrangement="back_to_back"):
    """The force-law entries of the kernel vector, in units where a bearing force is K L^1.5
    times the kernel's load (the ball sum of delta^1.5 in units of L; the cubic series with
    c_r, c_a scaled by 1 / (K sqrt(L)), which is `cubic_coefficients` at K = 1, z0 / L)."""
    alpha = state.contact_angle
    p[P_OFFSET] = state.axial_approach * np.sin(alpha) / el
    p[P_COS_A], p[P_SIN_A] = np.cos(alpha), np.sin(alpha)
    p[P_NBALLS] = n_balls
    p[P_COS_D], p[P_SIN_D] = np.cos(2.0 * np.pi / n_balls), np.sin(2.0 * np.pi / n_balls)
    p[P_LAW] = LAWS[law]
    p[P_CR], p[P_CA], p[P_Z0], p[P_TAN2] = cubic_coefficients(1.0, state.axial_approach / el, alpha, n_balls)
    p[P_ARR] = ARRANGEMENTS[arrangement]


# --- forcing frequencies -----------------------------------------------------------------------

class Ratio(NamedTuple):
    kind: str       # RATIONAL, LONG_PERIOD, IRRATIONAL
    p: int
    q: int


def frequency_ratio(ratio, max_denominator):
    """omega / Omega as p / q: RATIONAL when q <= max_denominator, LONG_PERIOD when a fraction
    with a larger denominator (up to DETECTION_DENOMINATOR) matches, else IRRATIONAL (p = q = 0)."""
    frac = Fraction(ratio).limit_denominator(DETECTION_DENOMINATOR)
    if abs(float(frac) - ratio) > RATIO_RTOL * ratio:
        return Ratio(IRRATIONAL, 0, 0)
    return Ratio(RATIONAL if frac.denominator <= max_denominator else LONG_PERIOD,
                 frac.numerator, frac.denominator)


class Forcing(NamedTuple):
    period: float           # T [s], the unit of tau
    shaft_turns: float      # Omega T / 2 pi: shaft revolutions per tau
    support_turns: float    # omega T / 2 pi
    periodic: bool
    ratio: Ratio


def forcing_of(speed, support_frequency, unbalance_on, support_on, max_denominator):
    """The time unit and frequencies of a point (speed, support_frequency in Hz)."""
    if not (unbalance_on and support_on):
        if support_on:
            return Forcing(1.0 / support_frequency, speed / support_frequency, 1.0, True, Ratio(RATIONAL, 1, 1))
        return Forcing(1.0 / speed, 1.0, support_frequency / speed, True, Ratio(RATIONAL, 1, 1))
    ratio = frequency_ratio(support_frequency / speed, max_denominator)
    if ratio.kind == RATIONAL:
        return Forcing(ratio.q / speed, float(ratio.q), float(ratio.p), True, ratio)
    return Forcing(1.0 / speed, 1.0, support_frequency / speed, False, ratio)


def contact_margin(states, p):
    """The smallest ball deflection delta_k of both bearings over scaled states (m, n), relative to
    the static one (P_OFFSET): < 0 where a ball loses contact, its load [delta]_+^{3/2} then not
    smooth in the state (ModelSpec.contact_margin). The cubic series law has no contacts: None."""
    if p[P_LAW] > 0.0:
        return None
    angles = 2.0 * np.pi * np.arange(int(p[P_NBALLS])) / p[P_NBALLS]
    states = np.atleast_2d(states)
    axial = (p[P_ARR] * states[:, 4] * p[P_SIN_A])[:, None]

    def radial(x, y):
        return (x[:, None] * np.cos(angles) + y[:, None] * np.sin(angles)) * p[P_COS_A]
    delta = np.concatenate([radial(states[:, 0], states[:, 1]) + axial, radial(states[:, 2], states[:, 3]) - axial])
    return float((delta.min() + p[P_OFFSET]) / p[P_OFFSET])


# --- build -------------------------------------------------------------------------------------

def kernel_params(rotor, state, n_balls, forcing, speed, eccentricity, support, law="ball_sum",
                  length_scale=LENGTH_SCALE, arrangement="back_to_back"):
    """The kernel parameter vector from SI inputs (state: bearing.PreloadState, support: A_s)."""
    t, el = forcing.period, length_scale
    m_inv = np.linalg.inv(mass_matrix(rotor))
    omega = 2.0 * np.pi * speed
    damp = rotor.damping * np.eye(N_POS) + omega * gyroscopic_matrix(rotor)
    cos_part, sin_part = unbalance_shape(rotor)
    unbalance = t * t / el * rotor.disk_mass * eccentricity * omega ** 2
    p = np.empty(N_PARAMS)
    p[P_GAIN:P_GAIN + 25] = (t * t * state.contact_constant * np.sqrt(el) * m_inv).ravel()
    p[P_DAMP:P_DAMP + 25] = (t * m_inv @ damp).ravel()
    p[P_CONST:P_CONST + 5] = t * t / el * m_inv @ weight(rotor)
    p[P_UCOS:P_UCOS + 5] = unbalance * m_inv @ cos_part
    p[P_USIN:P_USIN + 5] = unbalance * m_inv @ sin_part
    p[P_SUP:P_SUP + 5] = -t * t / el * support
    p[P_WU] = 2.0 * np.pi * forcing.shaft_turns
    p[P_WS] = 2.0 * np.pi * forcing.support_turns
    p[P_PHASE] = 0.0
    _bearing_params(p, state, n_balls, law, el, arrangement)
    return p


def build(v):
    """Kernel inputs at one point from the scene's values (SI; angles in degrees)."""
    state = bearing_state(v)
    rotor = Rotor.of(v)
    forcing = forcing_of(v["speed"], v["support_frequency"], v["eccentricity"] > 0,
                         v["support_acceleration"] > 0, v["max_denominator"])
    support = support_vector(v["support_direction"], v["support_acceleration"])
    p = kernel_params(rotor, state, n_balls_of(v), forcing, v["speed"], v["eccentricity"], support, v["law"],
                      arrangement=arrangement_of(v))
    derived = {
        **bearing_derived(v, state),
        "periodic_forcing": float(forcing.periodic),
        "frequency_ratio_p": float(forcing.ratio.p),
        "frequency_ratio_q": float(forcing.ratio.q),
    }
    return Built(p, forcing.period, derived, forcing.periodic)


# --- config checks -----------------------------------------------------------------------------

def _grid(data, axes, section, name):
    """The values a key takes over the scene: swept, given, or its unset value."""
    if name in axes:
        return [float(x) for x in axes[name]]
    given = data[section].get(name) if section else None
    return [SPEC.parameter(name).unset if given is None else given]


def _ratio_problems(data, axes):
    """Frequency ratios whose common period exceeds forcing.max_denominator, when orbits are
    requested (shooting over such a period would cost that many shaft revolutions per step)."""
    f = data["forcing"]
    if not data["analysis"]["floquet"]:
        return []
    if "speed" not in axes or max(_grid(data, axes, "forcing", "eccentricity")) <= 0 or \
            max(_grid(data, axes, "forcing", "support_acceleration")) <= 0:
        return []
    bad = []
    for speed in _grid(data, axes, None, "speed"):
        for freq in _grid(data, axes, "forcing", "support_frequency"):
            r = frequency_ratio(freq / speed, f["max_denominator"]) if freq > 0 else None
            if r is not None and r.kind == LONG_PERIOD:
                bad.append((freq, speed, r))
    if not bad:
        return []
    freq, speed, r = bad[0]
    where = "sweep.support_frequency" if "support_frequency" in axes else "forcing.support_frequency"
    return [f"{where}: support_frequency / speed = {freq:g} / {speed:g} Hz = {r.p}/{r.q} has a common "
            f"period of {r.q} shaft revolutions, above forcing.max_denominator = {f['max_denominator']} "
            f"({len(bad)} grid point(s)); raise forcing.max_denominator, choose frequencies with a "
            "smaller common period, or set analysis.floquet = false"]


def check(data, axes):
    """Config rules across keys: the bearing table and geometry, a support frequency for a
    support vibration, and shootable frequency ratios."""
    errors = bearing_problems(data, axes) + rotor_problems(data)
    freqs = _grid(data, axes, "forcing", "support_frequency")
    if max(_grid(data, axes, "forcing", "support_acceleration")) > 0 and min(freqs) <= 0:
        errors.append("forcing.support_frequency: must be > 0 when forcing.support_acceleration > 0")
    return errors + _ratio_problems(data, axes)


def static_guess(p):
    """The unforced rotor centred in its bearings (the preload balances at q = 0)."""
    return np.zeros(2 * N_POS)


# --- linear analysis (the spec's capabilities: `rotorsweep modes`, omega_l) -------------------------

# The static equilibrium is converged when |P(q) - f_g| <= EQUILIBRIUM_RTOL x the preload.
EQUILIBRIUM_RTOL = 1e-13
COORDINATES = ("x1", "y1", "x2", "y2", "z")
# Filipkovsky 2016's frequency unit omega_l: the lowest natural frequency of the linearized
# system with the bearing of the 15 deg row of the paper's table.
OMEGA_L_ANGLE = 15.0


def static_equilibrium(v, max_iter=50):
    """Newton on P(q) = f_g from the centred rotor (where P = 0 by the preload's symmetry)."""
    state = bearing_state(v)
    n_balls = n_balls_of(v)
    load = weight(Rotor.of(v))
    q = np.zeros(N_POS)
    for it in range(max_iter + 1):
        force, stiffness = bearing_load(q, state, n_balls, v["law"], arrangement=arrangement_of(v))
        residual = np.abs(force - load).max() / float(v["preload"])
        if residual <= EQUILIBRIUM_RTOL or it == max_iter:
            break
        q -= np.linalg.solve(stiffness, force - load)
    note = (f"contact angle {np.degrees(state.contact_angle):.4f} deg, axial approach z0 = "
            f"{state.axial_approach:.4e} m, K = {state.contact_constant:.4e} N/m^1.5, "
            f"k_r = {state.radial_stiffness:.4e} N/m, k_a = {state.axial_stiffness:.4e} N/m per bearing")
    return Equilibrium(q, residual, it, note)


def linearization(v, equilibrium):
    """M q'' + (C + Omega G) q' + K_s q = 0 with K_s = dP/dq(q_s), the kernel's analytic stiffness."""
    rotor = Rotor.of(v)
    _, stiffness = bearing_load(equilibrium.position, bearing_state(v), n_balls_of(v), v["law"],
                                arrangement=arrangement_of(v))
    return LinearSystem(mass_matrix(rotor), rotor.damping * np.eye(N_POS),
                        2.0 * np.pi * v["speed"] * gyroscopic_matrix(rotor), stiffness, COORDINATES)


def disk_position(v):
    """(xi_D, l) [m]: the disc from bearing A and the bearing span (paper values: the spec's rotor keys)."""
    return float(v["disk_position"]), float(v["length"])


def omega_l(v):
    """omega_l [Hz]: the lowest damped natural frequency at `v` with its bearing replaced by the
    paper's 15 deg row as printed (`with_row`: its geometry, and the loaded angle, K and z0 derived
    again from it). With the paper's rotor it is the axial mode, which the shaft speed does not move."""
    v = with_row(v, OMEGA_L_ANGLE)
    system = linearization(v, static_equilibrium(v))
    return modal.modes_of(system.M, system.C, system.G, system.K, modal.kinds_from_names(COORDINATES))[0].frequency


# Physical limits of the rotor's geometry (ModelSpec parameter limits and check(), so a config
# names the key). The shaft between the bearings is modelled rigid: a 25 mm steel shaft of 10 m
# bends at ~0.5 Hz, so a longer one is a slip of units (mm given as m), not a rotor.
MAX_SHAFT_LENGTH = 10.0
# An imposed contact angle [deg] of the angular-contact pair (catalogues: 10 to 45 deg): below
# 1 deg the preload P0 = Z Q sin(alpha) needs ball loads Q above 57 P0 / Z (1e-9 deg: 6e10 P0 / Z);
# above 60 deg the pair is a thrust bearing, not the radial support the rotor models assume.
CONTACT_ANGLE_LIMITS = (1.0, 60.0)


def shaft_length(default, help="shaft length l between the bearings"):
    """The `rotor.length` key of the rotor models, bounded by MAX_SHAFT_LENGTH."""
    return Parameter(default=default, name="length", section="rotor", lo=0, lo_open=True, hi=MAX_SHAFT_LENGTH,
                     unit="m", help=f"{help} (at most {MAX_SHAFT_LENGTH:g} m: the shaft is modelled rigid)")


def rotor_problems(data):
    """The disk sits on the shaft between the bearings: 0 <= rotor.disk_position <= rotor.length."""
    rotor = data["rotor"]
    position, length = rotor.get("disk_position"), rotor.get("length")
    if isinstance(position, (int, float)) and isinstance(length, (int, float)) and position > length:
        return [f"rotor.disk_position: {position:g} m is beyond the shaft: the disk sits between the bearings, "
                f"at most rotor.length = {length:g} m from bearing A"]
    return []


def _contact_angle():
    lo, hi = CONTACT_ANGLE_LIMITS
    return Parameter(name="contact_angle", section="bearing", unit="degree", long_name="imposed contact angle",
                     axis=True, lo=lo, hi=hi,
                     help=f"contact angle [deg] imposed in the force law; unset: the loaded angle from the preload "
                          f"solve ({lo:g} to {hi:g} deg: below, the preload P0 = Z Q sin(alpha) needs unbounded ball "
                          "loads Q; above, the pair is a thrust bearing)")


def _rotor(name, default, unit, help):
    return Parameter(default=default, name=name, section="rotor", lo=0, lo_open=True, unit=unit, help=help)


SPEC = ModelSpec(
    name="rigid_preloaded",
    id=4,
    version="2",    # 2: the table rows' free angle from their groove geometry under both preload laws
    older_defaults=(("2", "bearing", "free_angle", free_angle_before_version_2),),
    module=kernel_module(__name__),
    n_position=N_POS,
    description="Filipkovsky 2016: 5-DOF rigid rotor on two preloaded angular-contact ball bearings",
    parameters=(
        Parameter(name="speed", unit="Hz", long_name="shaft speed", axis=True, lo=0, hi=1e5,
                  lo_open=True, help="shaft speed f_Omega [Hz] (paper: 250 Hz)"),
        Parameter(name="support_frequency", section="forcing", unit="Hz", long_name="support vibration frequency",
                  axis=True, lo=0, hi=1e5, unset=0.0,
                  help="support vibration frequency f_omega [Hz] (needed when support_acceleration > 0)"),
        Parameter(name="nominal_angle", section="bearing", unit="degree", long_name="nominal contact angle",
                  axis=True, lo=0, hi=90, lo_open=True, hi_open=True, unset=DEFAULT_NOMINAL_ANGLE,
                  help="row of the bearing table (a label): 12, 15, 26, 36 or 40 deg in the 2016 table; "
                       "the 2010 table has one unlabelled row (leave unset)"),
        _contact_angle(),
        Parameter(name="preload", section="bearing", unit="N", long_name="axial preload", axis=True,
                  lo=0, hi=1e5, lo_open=True, unset=300.0,
                  help="axial preload P0 [N] (not in the 2016 paper; default 300 N as in the 2010 papers)"),
        Parameter(name="eccentricity", section="forcing", unit="m", long_name="disk unbalance eccentricity",
                  axis=True, lo=0, hi=1e-3, unset=10e-6,
                  help="disk eccentricity a [m] (not in the paper; default 10 um; 0: balanced rotor)"),
        Parameter(name="support_acceleration", section="forcing", unit="m s-2",
                  long_name="support vibration acceleration amplitude", axis=True, lo=0, hi=1e4, unset=0.0,
                  help="acceleration amplitude A of both supports [m/s^2] (not in the paper; default 0: off)"),
        Parameter("choice", "y", name="support_direction", section="forcing", choices=tuple(SUPPORT_AXES),
                  help="axis the supports vibrate along"),
        Parameter("int", 64, name="max_denominator", section="forcing", lo=1, hi=DETECTION_DENOMINATOR,
                  help="largest q of omega / Omega = p / q shot as periodic (common period q shaft revolutions)"),
        *BEARING_KEYS,
        Parameter("choice", "ball_sum", name="law", section="bearing", choices=tuple(LAWS),
                  help="bearing force law: ball_sum (exact Hertz sum over the balls) or cubic (the 2010 "
                       "papers' power series, small amplitudes: parts from the sum by 1 % at 0.38 z0)"),
        # Filipkovsky 2016, "Результаты численных исследований": l = 0,5 м; xi_D = 0,125 м;
        # m_B = 1,963 кг; I_C1 = 0,04098 кг м2; I_C0 = 0,00015 кг м2; m_0 = 10 кг; I_1 = 0,1 кг м2;
        # I_0 = 0,2 кг м2 (and f_Omega = 250 Гц for Figs. 2b-6, the speed's help).
        shaft_length(0.5),
        Parameter(default=0.125, name="disk_position", section="rotor", lo=0, unit="m",
                  help="disk position xi_D from bearing A"),
        _rotor("shaft_mass", 1.963, "kg", "shaft mass m_B"),
        _rotor("shaft_diametral", 0.04098, "kg m2", "shaft diametral inertia I_C1"),
        _rotor("shaft_polar", 0.00015, "kg m2", "shaft polar inertia I_C0"),
        _rotor("disk_mass", 10.0, "kg", "disk mass m_0"),
        _rotor("disk_diametral", 0.1, "kg m2", "disk diametral inertia I_1"),
        _rotor("disk_polar", 0.2, "kg m2", "disk polar inertia I_0"),
        Parameter(default=500.0, name="damping", section="rotor", lo=0, unit="N s m-1",
                  help="viscous damping C on every coordinate (not in the paper; default 500 N s/m, "
                       "about 1 % of critical in the radial modes at 15 deg, 300 N)"),
        Parameter(default=0.0, name="gravity", section="rotor", lo=0, unit="m s-2",
                  help="gravity in -y (0 as in the paper: the preload dominates the weight)"),
    ),
    continuation=("speed", "support_frequency"),
    build=build,
    cold_guess=static_guess,
    length_scale=LENGTH_SCALE,
    observables=tuple(
        Observable(name, tuple(float(i == k) for i in range(N_POS)), "m", long_name)
        for k, (name, long_name) in enumerate((
            ("x_A", "journal A horizontal displacement"), ("y_A", "journal A vertical displacement"),
            ("x_B", "journal B horizontal displacement"), ("y_B", "journal B vertical displacement"),
            ("z", "axial displacement")))),
    derived={
        **BEARING_DERIVED,
        "periodic_forcing": ("1", "1: periodic forcing (orbit and Floquet); 0: quasi-periodic"),
        "frequency_ratio_p": ("1", "p of support_frequency / speed = p / q (0: incommensurate)"),
        "frequency_ratio_q": ("1", "q: shaft revolutions per common forcing period"),
    },
    check=check,
    equilibrium=static_equilibrium, linearization=linearization, speed="speed", omega_l=omega_l,
    disk_position=disk_position,
    support_frequency="support_frequency",
    torus_forcing=(P_PHASE, P_WS, {"max_denominator": 0}),   # 0: no ratio shot as periodic, tau one shaft turn
    contact_margin=contact_margin,
    derived_axes={"contact_angle": "derived from the preload solve per point, see contact_angle_used"},
)

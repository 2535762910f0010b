"""Model `jeffcott_clearance`: the 2-DOF rigid rotor of Bai 2006 on one ball bearing with radial
clearance (or axial preload), cage rotation, damping and a constant radial load.

Scaling, for conditioning and so that one orbit serves as the Newton start of its neighbour
along the speed axis: time tau = t / T (T the ball-passage period, so the basic periodic orbit
has period 1 whatever the speed), displacements in units of L = 1 um.
The state is u = (x/L, y/L, dx/dtau / L, dy/dtau / L).

The right-hand side, its analytic Jacobian and both from one ball sum (`rhs`, `jac`,
`rhs_jac`, in `jeffcott_clearance_kernels`) are inlined (`inline="always"`) into the group's
bodies in the generated `models.dispatch`, which LLVM inlines into the integrators
(`rotorsweep.kernels.PICKED_BODY`): a compiled call with array arguments costs more than the
9-ball force sum it would wrap.
"""
from functools import lru_cache

import numpy as np

from rotorsweep.kernels import bearing
from rotorsweep.kernels.models.spec import Built, ModelSpec, Observable, Parameter, kernel_module

LENGTH_SCALE = 1e-6  # m: bearing clearances and vibration amplitudes are micrometres

# Parameter vector (indices).
P_DAMP, P_GAIN, P_OFFSET, P_LOAD, P_COS_A, P_SIN_A, P_NBALLS, P_PHI0, P_CAGE, P_COS_D, P_SIN_D = range(11)
N_PARAMS = 11


def cage_speed_ratio(ball_diameter, pitch_diameter, contact_angle):
    """omega_cage / omega_shaft for an outer ring at rest: (1 - (D_b / D_m) cos a) / 2."""
    return 0.5 * (1.0 - ball_diameter / pitch_diameter * np.cos(contact_angle))


def forcing_period(speed_hz, n_balls, ball_diameter, pitch_diameter, contact_angle):
    """Ball-passage period T = 2 pi / (N omega_cage) [s]."""
    omega_cage = 2.0 * np.pi * speed_hz * cage_speed_ratio(ball_diameter, pitch_diameter, contact_angle)
    return 2.0 * np.pi / (n_balls * omega_cage)


def jeffcott_params(*, speed, stiffness, clearance, contact_angle, axial_approach, mass, damping,
                    radial_load, n_balls, ball_diameter, pitch_diameter, cage_rotation=True,
                    phase=0.0, length_scale=LENGTH_SCALE):
    """Parameter vector of `jeffcott_clearance` and the forcing period T [s], from SI inputs.

    speed [Hz], stiffness K [N/m^1.5], clearance c [m], contact_angle [rad], axial_approach s0
    [m] (0 without preload), mass [kg], damping [N s/m], radial_load W [N] acting in -y."""
    period = forcing_period(speed, n_balls, ball_diameter, pitch_diameter, contact_angle)
    L = length_scale
    p = np.empty(N_PARAMS)
    p[P_DAMP] = damping * period / mass
    p[P_GAIN] = period ** 2 * stiffness * np.sqrt(L) / mass
    p[P_OFFSET] = (axial_approach * np.sin(contact_angle) - clearance) / L
    p[P_LOAD] = period ** 2 * radial_load / (mass * L)
    p[P_COS_A] = np.cos(contact_angle)
    p[P_SIN_A] = np.sin(contact_angle)
    p[P_NBALLS] = n_balls
    p[P_PHI0] = phase
    p[P_CAGE] = 1.0 if cage_rotation else 0.0
    p[P_COS_D] = np.cos(2.0 * np.pi / n_balls)
    p[P_SIN_D] = np.sin(2.0 * np.pi / n_balls)
    return p, period


def to_physical(u, period):
    """Scaled state(s) (..., 4) -> (x, y, x', y') in m and m/s."""
    return SPEC.to_physical(u, period)


def static_guess(p):
    """A state near static equilibrium: the lowest ball carries the radial load.

    Used to start the transient of a cold solve; Newton takes over from where it settles."""
    g = p[P_GAIN]
    depth = (p[P_LOAD] / g) ** (2.0 / 3.0) if g > 0 else 0.0
    y = -(depth - p[P_OFFSET]) / p[P_COS_A]
    return np.array([0.0, y, 0.0, 0.0])


@lru_cache(maxsize=8)
def _geometry(preset, nominal_angle, free_angle):
    return bearing.preset(preset, nominal_angle, free_angle=free_angle)


def _free_angle(geom, clearance, contact_angle_deg):
    """The unloaded contact angle: the user's, else from the clearance (Bai eq. 6), else the
    preset's (bearing.free_angle: its groove geometry or its row's label)."""
    if contact_angle_deg is not None and np.isfinite(contact_angle_deg):
        return np.radians(contact_angle_deg)
    if clearance > 0:
        return bearing.free_contact_angle(geom, clearance)
    return geom.nominal_contact_angle


def _stiffness(option, geom, alpha):
    if option == "hertz":
        return bearing.hertz_constant(geom, alpha)
    if option == "bai2006":
        return bearing.BAI2006_CONTACT_CONSTANT
    return float(option)


def build(v):
    """Kernel parameters at one point from the scene's values (SI; contact_angle in degrees,
    None/NaN when not given: then from the clearance)."""
    geom = _geometry(v["preset"], v.get("nominal_angle"), v["free_angle"])
    clearance = v.get("clearance") or 0.0
    preload = v.get("preload") or 0.0
    alpha0 = _free_angle(geom, clearance, v.get("contact_angle"))
    stiffness = _stiffness(v["stiffness"], geom, alpha0)
    alpha, approach = alpha0, 0.0
    if preload > 0:
        if v["preload_constant"] == "filipkovsky":   # the papers' law as printed (no clearance)
            state = bearing.as_printed_state(geom, preload, free_angle=alpha0)
        else:
            state = bearing.preload_state(geom, preload, clearance=clearance, free_angle=alpha0,
                                          stiffness=stiffness)
        alpha, approach, stiffness = state.contact_angle, state.axial_approach, state.contact_constant
    load = v["mass"] * v["gravity"] if v["radial_load"] == "gravity" else v["radial_load"]
    p, period = jeffcott_params(
        speed=v["speed"], stiffness=stiffness, clearance=clearance, contact_angle=alpha,
        axial_approach=approach, mass=v["mass"], damping=v["damping"], radial_load=load,
        n_balls=geom.n_balls, ball_diameter=geom.ball_diameter, pitch_diameter=geom.pitch_diameter,
        cage_rotation=v["cage_rotation"])
    return Built(p, period, {"contact_angle_used": np.degrees(alpha)})


DEFAULT_NOMINAL_ANGLE = 26    # angular_contact_medium when bearing.nominal_angle is not given


def check(data, axes):
    """Config checks that involve several keys of this model."""
    b = data["bearing"]
    errors = []
    if b["nominal_angle"] is not None and b["preset"] != "angular_contact_medium":
        errors.append(f"bearing.nominal_angle: only for preset \"angular_contact_medium\" (preset is {b['preset']!r})")
    else:       # a consistent preset: its geometry bounds the clearance
        for where, values in (("sweep.clearance", axes.get("clearance", ())), ("bearing.clearance", [b["clearance"] or 0.0])):
            problem = _clearance_problem(max(values, default=0.0), b)
            if problem:
                errors.append(f"{where}: {problem}")
    if b["preload_constant"] == "filipkovsky" and max(axes.get("preload", [b["preload"] or 0.0])) <= 0:
        errors.append("bearing.preload_constant: \"filipkovsky\" needs a preload > 0")
    if b["preload_constant"] == "filipkovsky" and max(axes.get("clearance", [b["clearance"] or 0.0])) > 0:
        errors.append("bearing.preload_constant: \"filipkovsky\" (the papers' law as printed) has no clearance")
    return errors


def _clearance_problem(clearance, b):
    """Error text when a clearance exceeds what the preset's geometry allows, else None: the
    groove-centre distance A = r_i + r_o - D_b, where Bai's eq. 6 free contact angle reaches
    90 deg (209: 0.5 mm). Rounded to 6 digits, as A carries the float noise of its sum."""
    limit = _geometry(b["preset"], b["nominal_angle"], b["free_angle"]).groove_center_distance
    if clearance <= limit:
        return None
    return (f"must be <= {limit:.6g} m for bearing.preset \"{b['preset']}\" "
            f"(r_i + r_o - D_b, where the free contact angle reaches 90 deg; got {clearance:g})")


def fill_defaults(data):
    """The nominal angle exists only for the angular preset."""
    b = data["bearing"]
    if b["preset"] == "angular_contact_medium" and b["nominal_angle"] is None:
        b["nominal_angle"] = DEFAULT_NOMINAL_ANGLE


SPEC = ModelSpec(
    name="jeffcott_clearance",
    id=0,
    module=kernel_module(__name__),
    version="2",    # 2: angular_contact_medium's free angle from its groove geometry (bearing.free_angle)
    older_defaults=(("2", "bearing", "free_angle", "nominal"),),
    n_position=2,
    description="Bai 2006: 2-DOF rigid rotor on one ball bearing with clearance or preload",
    parameters=(
        Parameter(name="speed", unit="Hz", long_name="shaft speed", axis=True, lo=0, hi=1e5,
                  lo_open=True, help="shaft speed [Hz]"),
        Parameter(name="clearance", section="bearing", unit="m", long_name="radial internal clearance",
                  axis=True, lo=0, unset=0.0, help="radial clearance [m] (bounded by the preset's geometry)"),
        Parameter(name="contact_angle", section="bearing", unit="degree", long_name="bearing contact angle",
                  axis=True, lo=0, hi=90, lo_open=True, hi_open=True, help="contact angle [deg]"),
        Parameter(name="preload", section="bearing", unit="N", long_name="axial preload", axis=True,
                  lo=0, hi=1e6, hi_open=True, unset=0.0, help="axial preload [N]"),
        Parameter("choice", "209", name="preset", section="bearing", choices=("209", "angular_contact_medium"),
                  help="bearing geometry"),
        Parameter("choice", None, name="nominal_angle", section="bearing", choices=(12, 15, 26, 36, 40),
                  unit="degree", help="nominal contact angle of angular_contact_medium"),
        Parameter("choice", "geometry", name="free_angle", section="bearing", choices=bearing.FREE_ANGLE_SOURCES,
                  help="free contact angle of angular_contact_medium without clearance: geometry (from the "
                       "printed R1, R2, R_K, d; 23.86 deg for the 26 deg row) or nominal (the row's label)"),
        Parameter("float_or", "hertz", name="stiffness", section="bearing", choices=("hertz", "bai2006"),
                  lo=0, lo_open=True, unit="N m-1.5", help="ball contact constant K"),
        Parameter("choice", "consistent", name="preload_constant", section="bearing",
                  choices=("consistent", "filipkovsky")),
        Parameter("bool", True, name="cage_rotation", section="bearing"),
        Parameter(default=2.0, name="mass", section="rotor", lo=0, lo_open=True, unit="kg"),
        Parameter(default=300.0, name="damping", section="rotor", lo=0, unit="N s m-1"),
        Parameter("float_or", "gravity", name="radial_load", section="rotor", choices=("gravity",), unit="N"),
        Parameter(default=9.8, name="gravity", section="rotor", lo=0, unit="m s-2"),
    ),
    continuation=("speed",),
    build=build,
    cold_guess=static_guess,
    length_scale=LENGTH_SCALE,
    observables=(
        Observable("x", (1.0, 0.0), "m", "horizontal journal displacement"),
        Observable("y", (0.0, 1.0), "m", "vertical journal displacement"),
    ),
    derived={"contact_angle_used": ("degree", "contact angle used in the force law")},
    check=check,
    fill_defaults=fill_defaults,
    speed="speed",
    no_linearization="its bearing stiffness varies with the rolling balls' positions (the ball passage is its "
                     "forcing), so it has no static equilibrium to linearize about; its orbits' Floquet "
                     "multipliers (`rotorsweep point`) give its linear stability",
    derived_axes={"contact_angle": "derived from clearance per point, see contact_angle_used"},
    references=("Bai C., Xu Q., Zhang X.: Nonlinear stability of balanced rotor due to the effect of "
                "ball bearing internal clearance, Applied Mathematics and Mechanics 27(2), 159-169 "
                "(2006) (clearance law, 209 bearing); Filipkovsky S. V.: nonlinear normal modes of "
                "rotor vibrations on rolling bearings (2010) and stability and bifurcations of "
                "vibrations of a rotor on ball bearings with axial preload (2016) (preloaded law, "
                "angular-contact geometry)"),
)

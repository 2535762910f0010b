"""The result-cube schema: one table that the sweep, the cube writer, query and report share.

Dimensions of a cube are the swept axes, always in AXES order (a swept axis with one value is
still a dimension); parameters that are not swept are stored as scalar coordinates. Per-point
variables carry the point dimensions plus, for some, `multiplier` or `sample`.
"""

SCHEMA_VERSION = 1

# name -> (units, long_name). Shaft speed in Hz, clearance in m, contact angle in degrees (the
# only angle a user types), preload in N.
AXES = {
    "speed": ("Hz", "shaft speed"),
    "clearance": ("m", "radial internal clearance"),
    "contact_angle": ("degree", "bearing contact angle"),
    "preload": ("N", "axial preload"),
}

ORBIT_STATUS = ("converged", "not_converged", "diverged", "not_applicable")
ORBIT_REASON = (
    "ok",
    "max_iterations",        # Newton used all its iterations without reaching the tolerance
    "line_search_failed",    # no damped step reduced the residual
    "nan_or_overflow",       # the integration produced NaN/inf
    "amplitude_limit",       # the state left the physical amplitude limit (divergence)
    "step_size_underflow",   # the adaptive integrator could not keep its tolerance
    "singular_jacobian",     # the shooting Jacobian M - I could not be solved
    "quasi_periodic_forcing",  # incommensurate forcing: no periodic orbit to shoot for
    "not_requested",         # the scene did not ask for the periodic orbit
)
BIFURCATION = ("none", "fold", "period_doubling", "neimark_sacker")
ATTRACTOR = ("not_computed", "periodic", "quasi_periodic", "chaotic", "diverged")
STABLE = ("unstable", "stable")

# Fill values for points where a quantity does not apply.
INT_FILL = -1
FLOAT_FILL = float("nan")


def _flag(meanings):
    return {"flag_values": list(range(len(meanings))), "flag_meanings": " ".join(meanings)}


# name -> (extra dims after the point dims, dtype, attrs). Floats use NaN where not applicable,
# integers use INT_FILL (declared as _FillValue by the writer).
VARIABLES = {
    "orbit_status": ((), "int8", {"long_name": "periodic orbit (shooting) status", **_flag(ORBIT_STATUS)}),
    "orbit_reason": ((), "int8", {"long_name": "reason behind orbit_status", **_flag(ORBIT_REASON)}),
    "newton_iterations": ((), "int16", {"long_name": "Newton iterations of the shooting solve", "units": "1"}),
    "residual": ((), "float64", {"long_name": "final shooting residual, scaled state (lengths in units of length_scale)", "units": "1"}),
    "multiplier_real": (("multiplier",), "float64", {"long_name": "Floquet multiplier, real part", "units": "1"}),
    "multiplier_imag": (("multiplier",), "float64", {"long_name": "Floquet multiplier, imaginary part", "units": "1"}),
    "max_abs_multiplier": ((), "float64", {"long_name": "largest Floquet multiplier modulus", "units": "1"}),
    "stable": ((), "int8", {"long_name": "periodic orbit is stable (max |multiplier| < 1)", **_flag(STABLE)}),
    "bifurcation": ((), "int8", {"long_name": "how the leading multiplier left the unit circle", **_flag(BIFURCATION)}),
    "forcing_period": ((), "float64", {"long_name": "ball-passage (forcing) period T", "units": "s"}),
    "contact_angle_used": ((), "float64", {"long_name": "contact angle used in the force law", "units": "degree"}),
    "x_mean": ((), "float64", {"long_name": "mean horizontal journal displacement over the orbit", "units": "m"}),
    "y_mean": ((), "float64", {"long_name": "mean vertical journal displacement over the orbit", "units": "m"}),
    "amplitude_x": ((), "float64", {"long_name": "half peak-to-peak horizontal displacement over the orbit", "units": "m"}),
    "amplitude_y": ((), "float64", {"long_name": "half peak-to-peak vertical displacement over the orbit", "units": "m"}),
    "orbit_state": (("state",), "float64", {
        "long_name": "periodic orbit state at t = 0 in the kernel's scaled units", "units": "1",
        "comment": "lengths in units of 1e-6 m, time in units of forcing_period; for "
                   "jeffcott_clearance: x, y, dx/dtau, dy/dtau (tau = t / forcing_period)"}),
    "compute_time": ((), "float64", {"long_name": "wall time spent on this point", "units": "s"}),
}

# Attractor diagnostics ([analysis] attractor = true): what the rotor actually settles on, found by
# integrating from the previous speed's end state (continuation of the attractor along speed).
LLE_METHOD = ("integrated", "derived")
_MODULUS = "Floquet multiplier of the attractor's period-k orbit (shooting over k forcing periods)"
ATTRACTOR_VARIABLES = {
    "attractor": ((), "int8", {"long_name": "attractor class after the transient", **_flag(ATTRACTOR)}),
    "period": ((), "int16", {"long_name": "attractor period in forcing periods (0: none up to max_period)", "units": "1"}),
    "lle": ((), "float64", {"long_name": "largest Lyapunov exponent", "units": "s-1"}),
    "lle_stderr": ((), "float64", {"long_name": "standard error of the largest Lyapunov exponent (block averages; 0 when derived)", "units": "s-1"}),
    "lle_method": ((), "int8", {"long_name": "how lle was obtained: integrated (Benettin/QR) or derived as ln|multiplier| / (k T)", **_flag(LLE_METHOD)}),
    "lyapunov_exponents": (("exponent",), "float64", {"long_name": "Lyapunov spectrum, largest first", "units": "s-1"}),
    "poincare_x": (("sample",), "float64", {"long_name": "horizontal journal displacement once per forcing period (Poincare section)", "units": "m"}),
    "poincare_y": (("sample",), "float64", {"long_name": "vertical journal displacement once per forcing period (Poincare section)", "units": "m"}),
    "attractor_multiplier_real": (("multiplier",), "float64", {"long_name": f"{_MODULUS}, real part", "units": "1"}),
    "attractor_multiplier_imag": (("multiplier",), "float64", {"long_name": f"{_MODULUS}, imaginary part", "units": "1"}),
    "attractor_state": (("state",), "float64", {
        "long_name": "state on the attractor at the end of the run (a whole forcing period), in the kernel's scaled units",
        "units": "1", "comment": "the start of the next speed in the continuation; see orbit_state for the units"}),
    "lyapunov_periods": ((), "float64", {"long_name": "forcing periods integrated for the Lyapunov estimate (0 when derived)", "units": "1"}),
}
# sweep_direction = "both": the same diagnostics sweeping speed downwards, as <name>_down, plus
# where the two directions end on different attractors (coexisting attractors, hysteresis).
DOWN_SUFFIX = "_down"
ATTRACTOR_VARIABLES.update({
    name + DOWN_SUFFIX: (extra, dtype, {**attrs, "long_name": attrs["long_name"] + ", sweeping speed down"})
    for name, (extra, dtype, attrs) in list(ATTRACTOR_VARIABLES.items())})
ATTRACTOR_VARIABLES["hysteresis"] = ((), "int8", {
    "long_name": "up and down sweeps end on different attractors (class, period or orbit differ; 0 where a period is unresolved)", **_flag(("no", "yes"))})
VARIABLES.update(ATTRACTOR_VARIABLES)

# The boundary table: one entry per stability change between neighbouring speeds of a line,
# refined far below the grid step (dimension `boundary`; the other axes' values are stored as
# boundary_<axis>).
BOUNDARY_STATUS = ("refined", "not_refined")
BOUNDARY_DIRECTION = ("loses_stability", "regains_stability")  # with increasing speed
BOUNDARY_VARIABLES = {
    "boundary_speed": ("float64", {"long_name": "refined speed where max |multiplier| = 1", "units": "Hz"}),
    "boundary_type": ("int8", {"long_name": "how the leading multiplier crosses the unit circle", **_flag(BIFURCATION)}),
    "boundary_direction": ("int8", {"long_name": "stability change with increasing speed", **_flag(BOUNDARY_DIRECTION)}),
    "boundary_status": ("int8", {"long_name": "whether the crossing could be refined", **_flag(BOUNDARY_STATUS)}),
    "boundary_grid_low": ("float64", {"long_name": "grid speed below the crossing", "units": "Hz"}),
    "boundary_grid_high": ("float64", {"long_name": "grid speed above the crossing", "units": "Hz"}),
}

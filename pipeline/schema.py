"""The result-cube schema: one table that the sweep, the cube writer, query and report share.

Dimensions of a cube are the swept axes of its model, in the order the model declares them (a
swept axis with one value is still a dimension); axis parameters that are not swept are stored
as scalar coordinates. Per-point variables carry the point dimensions plus, for some,
`multiplier`, `state`, `exponent` or `sample`. Generic variables are listed here; a model adds its
observables (orbit mean and half peak-to-peak, Poincare samples) and derived values
(`variables_of`). The cube names its model (`model`), the model's version and the axis the
orbits were continued along (`continued_axis`).
"""
import numpy as np

from rotorsweep.kernels import attractor_classes, models

SCHEMA_VERSION = 1
DEFAULT_MODEL = "jeffcott_clearance"   # cubes written before models were named in attributes


def model_of(ds):
    """The ModelSpec of a cube (or of a dict of cube attributes)."""
    attrs = getattr(ds, "attrs", ds)
    return models.get(attrs.get("model", DEFAULT_MODEL))


def axes_of(spec):
    """Swept-axis name -> (units, long_name), in the model's order."""
    return {p.name: (p.unit, p.long_name) for p in spec.parameters if p.axis}


def point_axes(ds):
    """The swept axes of a cube, in order: the dimensions of its per-point variables."""
    if "orbit_status" in ds:
        return list(ds["orbit_status"].dims)
    return [a for a in axes_of(model_of(ds)) if a in ds.dims]


def continued_axis(ds):
    """The axis orbits (and attractors) were continued along."""
    return ds.attrs.get("continued_axis") or point_axes(ds)[0]

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
    "unknown_model",         # the kernels were given a model id no model is registered under
)
BIFURCATION = ("none", "fold", "period_doubling", "neimark_sacker")
ATTRACTOR = attractor_classes.ATTRACTOR
STABLE = ("unstable", "stable")

# Fill values for points where a quantity does not apply.
INT_FILL = -1
FLOAT_FILL = float("nan")
# Integers carry no _FillValue attribute: with one, a plain xarray.open_dataset decodes them to
# floats with NaN. INT_FILL is said in their comment instead.
INT_FILL_COMMENT = f"{INT_FILL}: no value (no periodic orbit, or the point was not computed)"


def flag_attrs(meanings):
    """CF flag attributes; flag_values of the flag variables' type (int8), as CF requires."""
    return {"flag_values": np.arange(len(meanings), dtype=np.int8), "flag_meanings": " ".join(meanings)}


# name -> (extra dims after the point dims, dtype, attrs). Floats use NaN where not applicable,
# integers use INT_FILL (see INT_FILL_COMMENT).
VARIABLES = {
    "orbit_status": ((), "int8", {"long_name": "periodic orbit (shooting) status", **flag_attrs(ORBIT_STATUS)}),
    "orbit_reason": ((), "int8", {"long_name": "reason behind orbit_status", **flag_attrs(ORBIT_REASON)}),
    "newton_iterations": ((), "int16", {"long_name": "Newton iterations of the shooting solve", "units": "1"}),
    "residual": ((), "float64", {"long_name": "final shooting residual, scaled state (lengths in units of length_scale)", "units": "1"}),
    "multiplier_real": (("multiplier",), "float64", {"long_name": "Floquet multiplier, real part", "units": "1"}),
    "multiplier_imag": (("multiplier",), "float64", {"long_name": "Floquet multiplier, imaginary part", "units": "1"}),
    "max_abs_multiplier": ((), "float64", {"long_name": "largest Floquet multiplier modulus", "units": "1"}),
    "stable": ((), "int8", {"long_name": "periodic orbit is stable (max |multiplier| < 1)", **flag_attrs(STABLE)}),
    "bifurcation": ((), "int8", {"long_name": "how the leading multiplier left the unit circle", **flag_attrs(BIFURCATION)}),
    "forcing_period": ((), "float64", {"long_name": "forcing period T (time unit of the scaled state)", "units": "s"}),
    "orbit_state": (("state",), "float64", {
        "long_name": "periodic orbit state at t = 0 in the kernel's scaled units", "units": "1",
        "comment": "lengths in units of the model's length scale, time in units of forcing_period "
                   "(tau = t / forcing_period); jeffcott_clearance: x, y, dx/dtau, dy/dtau in um"}),
    "compute_time": ((), "float64", {"long_name": "wall time spent on this point", "units": "s"}),
}

# Attractor diagnostics ([analysis] attractor = true): what the rotor actually settles on, found by
# integrating from the previous speed's end state (continuation of the attractor along speed).
LLE_METHOD = ("integrated", "derived")
_MODULUS = "Floquet multiplier of the attractor's period-k orbit (shooting over k forcing periods)"
ATTRACTOR_VARIABLES = {
    "attractor": ((), "int8", {"long_name": "attractor class after the transient", **flag_attrs(ATTRACTOR)}),
    "period": ((), "int16", {"long_name": "attractor period in forcing periods (0: none up to max_period)", "units": "1"}),
    "lle": ((), "float64", {"long_name": "largest Lyapunov exponent", "units": "s-1"}),
    "lle_stderr": ((), "float64", {"long_name": "standard error of the largest Lyapunov exponent (block averages; 0 when derived)", "units": "s-1"}),
    "lle_method": ((), "int8", {"long_name": "how lle was obtained: integrated (Benettin/QR) or derived as ln|multiplier| / (k T)", **flag_attrs(LLE_METHOD)}),
    "lyapunov_exponents": (("exponent",), "float64", {"long_name": "Lyapunov spectrum, largest first", "units": "s-1"}),
    "attractor_multiplier_real": (("multiplier",), "float64", {"long_name": f"{_MODULUS}, real part", "units": "1"}),
    "attractor_multiplier_imag": (("multiplier",), "float64", {"long_name": f"{_MODULUS}, imaginary part", "units": "1"}),
    "attractor_state": (("state",), "float64", {
        "long_name": "state on the attractor at the end of the run (a whole forcing period), in the kernel's scaled units",
        "units": "1", "comment": "the start of the next speed in the continuation; see orbit_state for the units"}),
    "lyapunov_periods": ((), "float64", {"long_name": "forcing periods integrated for the Lyapunov estimate (0 when derived)", "units": "1"}),
}
# Tori at quasi-periodically forced grid points (models with torus_forcing; rotorsweep.pipeline.torus_points):
# the invariant circle of the stroboscopic map, its normal stability and its Fourier resolution.
TORUS_STATUS = ("converged", "not_converged", "fourier_decay_failed", "integration_failed", "non_smooth_circle",
                "contact_loss")
TORUS_STABILITY = ("unstable", "stable", "undecided")
TORUS_VARIABLES = {
    "torus_status": ((), "int8", {"long_name": "invariant torus (quasi-periodic shooting) status", **flag_attrs(TORUS_STATUS),
                                  "comment": "integration_failed includes a transient (the torus's first guess) that could not be integrated; "
                                             "non_smooth_circle: the Fourier tail falls only algebraically as the nodes double "
                                             "(a finitely smooth circle); contact_loss: the decay failed and a contact opens along "
                                             "the circle (torus_contact_margin < 0), the contact force not smooth there"}),
    "torus_stability": ((), "int8", {"long_name": "normal stability of the torus (sign of its largest normal Lyapunov exponent)",
                                     **flag_attrs(TORUS_STABILITY)}),
    "torus_exponent": ((), "float64", {"long_name": "largest normal Lyapunov exponent of the torus", "units": "s-1"}),
    "torus_exponent_error": ((), "float64", {"long_name": "convergence error of torus_exponent (its two halves' difference)", "units": "s-1"}),
    "torus_rotation_number": ((), "float64", {"long_name": "rotation number of the torus: second forcing's phase advance per forcing_period / 2 pi", "units": "1"}),
    "torus_modes": ((), "int16", {"long_name": "Fourier modes K of the invariant circle (2 K + 1 collocation nodes)", "units": "1"}),
    "torus_error": ((), "float64", {"long_name": "error estimate of the invariant circle, scaled state (lengths in units of length_scale)", "units": "1"}),
    "torus_contact_margin": ((), "float64", {
        "long_name": "smallest contact deflection over the torus relative to the static one (< 0: a contact opens)",
        "units": "1", "comment": "sampled along trajectories from the circle (an upper bound of the true minimum); only where "
                                 "the Fourier decay failed, for models with contacts (ModelSpec.contact_margin)"}),
    "torus_amplitude_error": ((), "float64", {
        "long_name": "estimated relative shortfall of the half peak-to-peak amplitudes over the torus (largest over the observables)",
        "units": "1", "comment": "the amplitudes are exact extrema along trajectories from equally spaced phases of the circle; "
                                 "the phase sampling's shortfall is estimated by the parabola through the extreme samples"}),
}

# sweep_direction = "both": the same diagnostics sweeping the continued axis downwards, as
# <name>_down, plus where the two directions end on different attractors (hysteresis).
DOWN_SUFFIX = "_down"


def observable_variables(spec):
    """Per-orbit and per-sample variables of the model's observables (SI units)."""
    out = {}
    where = " (over the torus where torus_status is set)" if spec.torus_forcing else ""
    for o in spec.observables:
        out[f"{o.name}_mean"] = ((), "float64", {"long_name": f"mean {o.long_name} over the orbit", "units": o.unit})
        out[f"amplitude_{o.name}"] = ((), "float64", {"long_name": f"half peak-to-peak {o.long_name} over the orbit{where}",
                                                      "units": o.unit})
    out.update({name: ((), "float64", {"long_name": long_name, "units": unit})
                for name, (unit, long_name) in spec.derived.items()})
    return out


# Poincare samples are most of a cube's bytes (86 % of Fig. 13's at float64) and serve drawing and
# period reading only; float32 keeps 24 bits of mantissa.
POINCARE_DTYPE = "float32"
POINCARE_COMMENT = ("stored as float32: relative rounding error at most 2**-24 (6e-8), e.g. 1.2e-12 m "
                    "at 20 um; the attractor's period and class were found from the float64 samples")


def poincare_variables(spec):
    return {f"poincare_{o.name}": (("sample",), POINCARE_DTYPE, {
        "long_name": f"{o.long_name} once per forcing period (Poincare section)", "units": o.unit,
        "comment": POINCARE_COMMENT})
        for o in spec.observables}


def _with_down(table):
    out = dict(table)
    out.update({name + DOWN_SUFFIX: (extra, dtype, {**attrs, "long_name": attrs["long_name"] + ", sweeping down"})
                for name, (extra, dtype, attrs) in table.items()})
    out["hysteresis"] = ((), "int8", {
        "long_name": "up and down sweeps end on different attractors (class, period or orbit differ; 0 where a period is unresolved)", **flag_attrs(("no", "yes"))})
    return out


def _fill_comments(table):
    """Integer variables with INT_FILL_COMMENT (after their own comment)."""
    out = {}
    for name, (extra, dtype, attrs) in table.items():
        if np.dtype(dtype).kind in "iu":
            comment = "; ".join(c for c in (attrs.get("comment"), INT_FILL_COMMENT) if c)
            attrs = {**attrs, "comment": comment}
        out[name] = (extra, dtype, attrs)
    return out


def variables_of(spec):
    """Every variable a cube of this model may hold: name -> (extra dims, dtype, attrs)."""
    return _fill_comments({**VARIABLES, **observable_variables(spec), **(TORUS_VARIABLES if spec.torus_forcing else {}),
                           **_with_down({**ATTRACTOR_VARIABLES, **poincare_variables(spec)})})

# The boundary table: one entry per stability change between neighbouring values of the
# continued axis on a line, refined far below the grid step (dimension `boundary`; the other
# axes' values are stored as boundary_<axis>).
BOUNDARY_STATUS = ("refined", "not_refined")
# with increasing axis value; a jump's fold pair: where a second stable orbit appears (the lower
# fold) and where one ends (the upper), the bistable interval between them
BOUNDARY_DIRECTION = ("loses_stability", "regains_stability", "enters_bistable", "leaves_bistable")


def boundary_variables(axis, units, long_name):
    """The boundary table's variables for continued axis `axis`."""
    return {
        f"boundary_{axis}": ("float64", {"long_name": f"refined {long_name} where max |multiplier| = 1", "units": units}),
        "boundary_type": ("int8", {"long_name": "how the leading multiplier crosses the unit circle", **flag_attrs(BIFURCATION)}),
        "boundary_direction": ("int8", {"long_name": f"stability change with increasing {long_name}", **flag_attrs(BOUNDARY_DIRECTION)}),
        "boundary_status": ("int8", {"long_name": "whether the crossing could be refined", **flag_attrs(BOUNDARY_STATUS)}),
        "boundary_grid_low": ("float64", {"long_name": f"grid {long_name} below the crossing", "units": units}),
        "boundary_grid_high": ("float64", {"long_name": f"grid {long_name} above the crossing", "units": units}),
    }

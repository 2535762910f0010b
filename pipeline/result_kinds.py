"""Result kinds: every kind of file the commands write, in one registry with its schema.

    sweep          `rotorsweep run`       the result cube (its schema: rotorsweep.pipeline.schema)
    continuation   `rotorsweep continue`  pseudo-arclength branches, located events, boundary curves
    backbone       `rotorsweep backbone`  nonlinear normal modes: manifold and continuation backbones

A file names its kind in the `result_kind` attribute; a sweep cube has none (it has
`rotorsweep_schema_version` instead, as it had before there were other kinds). `open_result`
opens a file once and returns it with its kind; `info`, `query`, `report` and the xarray accessor
ask the kind what to do, never the file again (the accessor's figures per kind:
rotorsweep.pipeline.explore.FIGURES).

Adding a kind (the contract of ResultKind): a schema table here (variable -> (dims, attrs)), one
ResultKind in KINDS naming the command that writes it and its describe / query / report
functions, and the writer building its data variables with `variables(...)`. The functions are
small adapters here that import their module when called: `info` on a cube never imports the
backbone code or scipy.
"""
from dataclasses import dataclass
from typing import Callable

import numpy as np

from rotorsweep.pipeline import cube, schema

SWEEP, CONTINUATION, BACKBONE = "sweep", "continuation", "backbone"
LINE = "..."        # in a schema's dims: the result's swept axes (a backbone result's lines)


@dataclass(frozen=True)
class ResultKind:
    """One kind of result file. name: its `result_kind` attribute; command: the `rotorsweep`
    command that writes it (its `history` names it); what: the kind in words ("a sweep cube");
    title: the start of its files' `title` attribute;
    variables: its schema, {name: (dims, attrs)} (None: the cube schema, rotorsweep.pipeline.schema);
    check(path, ds): CubeError unless ds is a readable file of this kind (None: every schema
    variable not in `optional`, every coordinate in `coords` and attribute in `attrs` present,
    see missing()); describe(ds) -> text
    (`info`); query(ds, fmt, **options) -> text (`query`, options in query_options);
    report(ds, out_dir, points, forced, say) -> {"html": path, "png": [paths]} (`report`,
    options in report_options). The accessor's figures of each kind: rotorsweep.pipeline.explore.FIGURES."""
    name: str
    command: str
    what: str
    title: str
    variables: dict | None
    check: Callable | None
    describe: Callable
    query: Callable
    report: Callable
    query_options: tuple = ()
    report_options: tuple = ()
    optional: tuple = ()        # schema variables a complete file may lack
    coords: tuple = ()          # coordinates every file has
    attrs: tuple = ()           # global attributes every file has

    def label(self):
        return f"{self.what} (rotorsweep {self.command})"

    def missing(self, ds):
        """What a file of this kind must hold and ds lacks, in words ([]: complete)."""
        return ([f"variable {name}" for name in self.variables if name not in self.optional and name not in ds.data_vars]
                + [f"coordinate {name}" for name in self.coords if name not in ds.coords]
                + [f"attribute {name}" for name in self.attrs if name not in ds.attrs])

    def check_file(self, path, ds):
        """CubeError unless ds is a complete file of this kind, naming what is missing."""
        if self.check is not None:
            return self.check(path, ds)
        missing = self.missing(ds)
        if missing:
            raise cube.CubeError(f"{path} is an incomplete {self.name} result: {', '.join(missing)} missing "
                                 f"(rerun rotorsweep {self.command})")


# --- the schemas ---------------------------------------------------------------------------------
# Attributes known only when a result is written are added by its writer: the continued
# parameter's and the observables' units, the flag tables of the kernels' codes (end reasons,
# event types), the amplitude at which a backbone's two methods part.

_BP = ("branch", "point")
_CURVE = ("curve", "curve_point")
_ORBIT_STATE = schema.VARIABLES["orbit_state"][2]

CONTINUATION_VARIABLES = {
    "parameter": (_BP, {}),
    "arclength": (_BP, {"units": "1", "long_name": "arclength along the branch (normalized state and parameter)"}),
    "orbit_state": (_BP + ("state",), _ORBIT_STATE),
    "amplitude_max": (_BP + ("observable",), {"long_name": "max |observable| over the orbit"}),
    "amplitude_half_pp": (_BP + ("observable",), {"long_name": "half peak-to-peak of the observable over the orbit"}),
    "orbit_period": (_BP, {"units": "s", "long_name": "period of the orbit (k forcing periods)"}),
    "multiplier_real": (_BP + ("multiplier",), {"units": "1", "long_name": "Floquet multiplier, real part"}),
    "multiplier_imag": (_BP + ("multiplier",), {"units": "1", "long_name": "Floquet multiplier, imaginary part"}),
    "max_abs_multiplier": (_BP, {"units": "1", "long_name": "largest Floquet multiplier modulus"}),
    "stable": (_BP, {"long_name": "orbit is stable (max |multiplier| < 1)",
                     "flag_values": np.array([-1, 0, 1], "int8"), "flag_meanings": "no_point unstable stable"}),
    "branch_points": (("branch",), {"units": "1", "long_name": "points on the branch"}),
    "branch_periods": (("branch",), {"units": "1", "long_name": "forcing periods per orbit (k of period-k)"}),
    "branch_parent": (("branch",), {"units": "1", "long_name": "branch index of the branch this one was switched from (-1: none)"}),
    "branch_end": (("branch",), {"long_name": "how the branch ended"}),
    "branch_detail": (("branch",), {"long_name": "how the branch ended, in words"}),
    "event_type": (("event",), {"long_name": "located bifurcation point"}),
    "event_branch": (("event",), {"units": "1", "long_name": "branch index of the event"}),
    "event_copy_of": (("event",), {"units": "1", "long_name": "event holding the first record of this located orbit (itself: distinct)"}),
    "branch_copy_of": (("branch",), {"units": "1", "long_name": "first branch of the same closed orbits (phase copy, loop met twice; -1: distinct)"}),
    "event_point": (("event",), {"units": "1", "long_name": "branch point just before the event"}),
    "event_parameter": (("event",), {"comment": "located on the branch to the arclength tolerance"}),
    "event_parameter_error": (("event",), {"long_name": "error estimate of the event's parameter (peaks: the "
                                          "slope's error over its derivative, plus the location's tolerance; torus "
                                          "TS / TF: the exponent's or the corrector's error; NaN: not estimated)"}),
    "event_multiplier_real": (("event", "multiplier"), {"units": "1", "long_name": "Floquet multiplier at the event, real part"}),
    "event_multiplier_imag": (("event", "multiplier"), {"units": "1", "long_name": "Floquet multiplier at the event, imaginary part"}),
    "event_state": (("event", "state"), _ORBIT_STATE),
    "event_amplitude_max": (("event", "observable"), {"long_name": "max |observable| over the orbit at the event"}),
    "event_amplitude_half_pp": (("event", "observable"), {"long_name": "half peak-to-peak of the observable over the orbit at the event"}),
    # how many distinct stable orbits coexist where (rotorsweep.pipeline.coexistence.line_coexistence)
    "piece_lo": (("piece",), {"long_name": "start of a piece of a line's parameter range"}),
    "piece_hi": (("piece",), {"long_name": "end of a piece of a line's parameter range"}),
    "piece_line": (("piece",), {"units": "1", "long_name": "first branch index of the piece's line"}),
    "piece_branches": (("piece",), {"long_name": "one branch per distinct stable orbit at the piece's middle (space-separated)",
                                   "comment": "phase copies phi_j(s) of one orbit counted once"}),
    # where the forcing is quasi-periodic: torus branches (rotorsweep.pipeline.torus_branches); an orbit
    # branch's points hold NaN / -1 here
    "branch_kind": (("branch",), {"long_name": "what the branch follows",
                                  "flag_values": np.array([0, 1], "int8"), "flag_meanings": "periodic_orbit torus"}),
    "torus_status": (_BP, {"long_name": "normal stability of the invariant torus",
                           "flag_values": np.array([-1, 0, 1, 2], "int8"),
                           "flag_meanings": "no_torus unstable stable undecided"}),
    "torus_error": (_BP, {"units": "1", "long_name": "error estimate of the invariant circle (scaled state units)",
                          "comment": "distance bound of the computed circle from the invariant one: the invariance "
                                     "defect between nodes times ||dR/dU^-1||, not below the Fourier tail"}),
    "torus_exponent": (_BP, {"units": "s-1", "long_name": "largest normal Lyapunov exponent of the torus",
                             "comment": "< 0: attracting (stable)"}),
    "torus_modes": (_BP, {"units": "1", "long_name": "Fourier modes K of the invariant circle (2 K + 1 collocation nodes)",
                          "comment": "adapted along the branch to the circle's spectral decay; -1: no torus"}),
    "torus_nodes": (_BP + ("torus_node", "state"), {**_ORBIT_STATE, "long_name": "the torus's invariant circle at its nodes",
                                                   "comment": "values at the support forcing's phases 2 pi j / N (N: the "
                                                              "point's non-NaN nodes, 2 torus_modes + 1); the trigonometric interpolant of "
                                                              "them is the circle (rotorsweep.kernels.torus.Torus.at)"}),
    "event_periods": (("event",), {"units": "1", "long_name": "forcing periods per orbit at the event (k of period-k; "
                                                               "a torus branch's locked p/q row: q)"}),
    "event_note": (("event",), {"long_name": "the event in words (torus branches: flags, locked ratios p/q and "
                                             "their linked periodic orbits)"}),
    # with report.frequency_unit = "omega_l"
    "parameter_over_omega_l": (_BP, {"units": "1"}),
    "event_parameter_over_omega_l": (("event",), {"units": "1"}),
    # with continuation.curves_in: the boundary curves
    "curve_parameter": (_CURVE, {}),
    "curve_second": (_CURVE, {}),
    "curve_critical_real": (_CURVE, {"units": "1", "long_name": "critical Floquet multiplier, real part"}),
    "curve_critical_imag": (_CURVE, {"units": "1", "long_name": "critical Floquet multiplier, imaginary part"}),
    "curve_type": (("curve",), {"long_name": "bifurcation continued"}),
    "curve_points": (("curve",), {"units": "1", "long_name": "points on the curve"}),
    "curve_end": (("curve",), {"long_name": "how the curve ended"}),
    "curve_detail": (("curve",), {"long_name": "how the curve ended, in words"}),
}

# variables only some continuation results have: with report.frequency_unit = "omega_l", with
# continuation.curves_in
# (piece_*: written since the coexistence counts distinct orbits; a file without them is read by
# counting stable runs, rotorsweep.pipeline.coexistence.coexistence)
CONTINUATION_OPTIONAL = ("branch_kind", "torus_status", "torus_error", "torus_exponent", "torus_modes", "torus_nodes",
                         "event_note", "event_periods", "parameter_over_omega_l",
                         "event_parameter_over_omega_l", "curve_parameter", "curve_second", "curve_critical_real",
                         "curve_critical_imag", "curve_type", "curve_points", "curve_end", "curve_detail",
                         "piece_lo", "piece_hi", "piece_line", "piece_branches", "event_copy_of",
                         "branch_copy_of", "event_parameter_error")

# CF has one unit per variable; the manifold's coefficients have one per element, stated as a rule.
MIXED_UNITS = ("no units attribute: the units differ from element to element (SI); P is the unit of "
               "the mode's master coordinate, state_units[master]; ")
_MODE = (LINE, "mode")
_HZ = {"units": "Hz"}

BACKBONE_VARIABLES = {
    "frequency_manifold": (_MODE + ("amplitude",), {**_HZ, "long_name": "backbone frequency from the cubic invariant manifold"}),
    "frequency_continuation": (_MODE + ("amplitude",), {**_HZ, "long_name": "backbone frequency from continuation of the full model's orbits"}),
    "relative_difference": (_MODE + ("amplitude",), {"units": "1", "long_name": "(continuation - manifold) / continuation frequency"}),
    "linear_frequency": (_MODE, {**_HZ, "long_name": "linear natural frequency"}),
    "kappa": (_MODE, {"units": "rad s-1 m-2", "long_name": "manifold backbone omega = omega_0 + kappa A^2"}),
    "growth_rate": (_MODE, {"units": "s-1 m-2", "long_name": "reduced oscillator's amplitude growth sigma (0 for a conservative system)"}),
    "parting_amplitude": (_MODE, {"units": "m"}),
    "invariance_distance": (_MODE, {"units": "m", "long_name": "largest distance from the manifold over 10 periods of the full orbit started on it at amplitude_max"}),
    "master": (_MODE, {"units": "1", "long_name": "index of the master coordinate (see the coordinate coordinate)"}),
    "mode_label": (_MODE, {"long_name": "mode shape: axial, cylindrical, conical, transverse"}),
    "mode_whirl": (_MODE, {"long_name": "whirl: forward, backward, none"}),
    "reduced_coefficient": (_MODE + ("monomial",), {"long_name": "B_m of the reduced oscillator p'' + sum_m B_m m(p, p') = 0",
                                                   "comment": MIXED_UNITS + "B_m of the monomial p^a r^b is in P^(1-a-b) s^(b-2)"}),
    "manifold_coefficient": (_MODE + ("state", "monomial"), {"long_name": "gamma of the manifold: state = gamma @ monomials(p, p')",
                                                            "comment": MIXED_UNITS + "gamma of state component i and the monomial p^a r^b is "
                                                                       "in state_units[i] P^-(a+b) s^b"}),
    "manifold_notes": (_MODE, {"long_name": "internal resonances met and how they were resolved"}),
    "continuation_end": (_MODE, {"long_name": "how the continuation backbone ended"}),
    "continuation_detail": (_MODE, {"long_name": "how the continuation backbone ended, in words"}),
    "continuation_rhs": (_MODE, {"units": "1", "long_name": "right-hand side evaluations of the continuation"}),
    "point_amplitude": (_MODE + ("point",), {"units": "m", "long_name": "continued orbit: first harmonic amplitude of the master"}),
    "point_amplitude_turning": (_MODE + ("point",), {"units": "m", "long_name": "continued orbit: master displacement at its turning point"}),
    "point_frequency": (_MODE + ("point",), {**_HZ, "long_name": "continued orbit: frequency"}),
    "point_energy_drift": (_MODE + ("point",), {"units": "1", "long_name": "continued orbit: (max - min) / mean of T + V along it"}),
    "point_unit_circle_error": (_MODE + ("point",), {"units": "1", "long_name": "continued orbit: largest | |multiplier| - 1 | away from +1"}),
    "axial_approach": ((LINE,), {"units": "m", "long_name": "preload's axial approach z0"}),
    # the report's manifold surface (absent where surface_mode has no manifold on any line);
    # the slave coordinate's variables take its units
    "surface_value": ((LINE, "surface_p", "surface_r"), {"long_name": "a slave coordinate on the invariant manifold of surface_mode over (p, r)"}),
    "surface_p_values": ((LINE, "surface_p"), {"units": "m", "long_name": "master displacement p"}),
    "surface_r_values": ((LINE, "surface_r"), {"units": "m s-1", "long_name": "master velocity r"}),
    "orbit_p": ((LINE, "orbit_sample"), {"units": "m", "long_name": "full orbit from the manifold: master displacement"}),
    "orbit_r": ((LINE, "orbit_sample"), {"units": "m s-1", "long_name": "full orbit from the manifold: master velocity"}),
    "orbit_slave": ((LINE, "orbit_sample"), {"long_name": "full orbit from the manifold: the slave coordinate"}),
    "orbit_on_surface": ((LINE, "orbit_sample"), {"long_name": "the manifold's value of the slave at the orbit's (p, r)"}),
    "orbit_time": ((LINE, "orbit_sample"), {"units": "s", "long_name": "time along the full orbit"}),
    "surface_info": ((), {"long_name": "surface figure: mode, master, slave, orbit amplitude [m]"}),
}

# the report's manifold surface: absent where surface_mode has no manifold on any line
BACKBONE_OPTIONAL = ("surface_value", "surface_p_values", "surface_r_values", "orbit_p", "orbit_r", "orbit_slave",
                     "orbit_on_surface", "orbit_time", "surface_info")


def variables(kind, values, attrs=None, lines=()):
    """The data variables of a `kind` result for xarray.Dataset, in its schema's order: values
    {name: array} of the schema's variables, attrs {name: attributes known only now} added to the
    schema's, lines: the swept axes LINE stands for."""
    table = KINDS[kind].variables
    unknown = sorted(set(values) - set(table))
    if unknown:
        raise KeyError(f"{kind} result: {', '.join(unknown)} not in its schema (rotorsweep.pipeline.result_kinds)")
    attrs = attrs or {}
    return {name: (_dims(dims, lines), values[name], {**a, **attrs.get(name, {})})
            for name, (dims, a) in table.items() if name in values}


def _dims(dims, lines):
    return tuple(d for part in dims for d in (lines if part == LINE else (part,)))


# --- opening -------------------------------------------------------------------------------------

def kind_of(ds, where="the dataset"):
    """The ResultKind of an opened result (a sweep cube: no result_kind attribute)."""
    name = ds.attrs.get("result_kind", SWEEP)
    if name not in KINDS:
        raise cube.CubeError(f"{where} is a result of kind {name!r}, which this rotorsweep does not know "
                             f"(known: {', '.join(KINDS)})")
    return KINDS[name]


def open_result(path):
    """(dataset in memory, its ResultKind): the file opened once, checked as its kind asks;
    CubeError for anything that is not a rotorsweep result."""
    ds = cube.read_netcdf(path)
    kind = kind_of(ds, path)
    kind.check_file(path, ds)
    return ds, kind


def open_kind(path, name):
    """A result that must be of kind `name`; CubeError naming the kind it is otherwise."""
    ds, kind = open_result(path)
    if kind.name != name:
        raise cube.CubeError(f"{path} is {kind.label()}, not {KINDS[name].label()}")
    return ds


def refuse_options(kind, given, role):
    """ValueError naming an option given ({option: value}, set where true) that does not apply
    to `kind`, and the kinds it applies to; role: where kinds list theirs (query_options,
    report_options)."""
    for option, value in given.items():
        if value and option not in getattr(kind, role):
            applies = [k.label() for k in KINDS.values() if option in getattr(k, role)]
            raise ValueError(f"--{option.replace('_', '-')} applies to {' or '.join(applies)}, "
                             f"not to {kind.label()}")


# --- what each kind does (imported when called) --------------------------------------------------

def _describe_cube(ds):
    return cube.describe(ds)


def _describe_continuation(ds):
    from rotorsweep.pipeline import continuation_result
    return continuation_result.describe(ds)


def _describe_backbone(ds):
    from rotorsweep.pipeline import backbone_reader
    return backbone_reader.describe(ds)


def _query_cube(ds, fmt, where=None, var=None, unstable=False, attractors=None, bistable=False):
    from rotorsweep.pipeline import query
    ds = query.select(ds, query.parse_where(where or []))
    if bistable:
        return query.intervals_table(query.bistable_intervals(ds), fmt=fmt, kind="bistable")
    if unstable:
        return query.intervals_table(query.unstable_intervals(ds), fmt=fmt)
    if attractors:
        return query.intervals_table(query.attractor_intervals(ds, attractors), fmt=fmt)
    return query.to_table(ds, var or None, fmt=fmt)


def _query_continuation(ds, fmt, unstable=False):
    from rotorsweep.pipeline import continuation_result, query
    if unstable:
        return query.intervals_table(query.branch_unstable_stretches(ds), fmt=fmt)
    return query.render(continuation_result.events_table(ds), fmt)


def _query_backbone(ds, fmt):
    from rotorsweep.pipeline import backbone_reader, query
    return query.render(backbone_reader.table(ds), fmt)


def _report_cube(ds, out_dir, points=None, forced=None, say=None):
    from rotorsweep.pipeline import report
    return report.make_report(ds, out_dir, points=points, say=say)


def _report_continuation(ds, out_dir, points=None, forced=None, say=None):
    from rotorsweep.pipeline.report import branch_result
    return branch_result.make_report(ds, out_dir)


def _report_backbone(ds, out_dir, points=None, forced=None, say=None):
    from rotorsweep.pipeline.report import backbone_result
    return backbone_result.make_report(ds, out_dir, forced=forced)


KINDS = {kind.name: kind for kind in (
    ResultKind(SWEEP, "run", "a sweep cube", "rotorsweep result cube", None, cube.check_cube, _describe_cube, _query_cube, _report_cube,
               query_options=("where", "var", "unstable", "attractors", "bistable"), report_options=("point",)),
    ResultKind(CONTINUATION, "continue", "a continuation result", "rotorsweep continuation", CONTINUATION_VARIABLES, None,
               _describe_continuation, _query_continuation, _report_continuation, query_options=("unstable",),
               optional=CONTINUATION_OPTIONAL, coords=("observable",), attrs=("parameter", "range")),
    ResultKind(BACKBONE, "backbone", "a backbone result", "rotorsweep backbones", BACKBONE_VARIABLES, None,
               _describe_backbone, _query_backbone, _report_backbone, report_options=("over",),
               optional=BACKBONE_OPTIONAL, coords=("mode", "amplitude_grid", "monomial", "state", "state_units")),
)}

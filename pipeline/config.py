"""Scene configs: TOML, validated completely before any work starts.

Every problem becomes one line of a ConfigError naming the file, the key as a dotted path, what
was wrong and what is allowed; all problems of a file are reported together. Configs are data
only (tomllib; no eval, no includes)."""
import difflib
import hashlib
import json
import math
import re
from dataclasses import dataclass, field, replace
from functools import cached_property
from importlib import resources
from pathlib import Path

import numpy as np

from rotorsweep.pipeline import gridsize, units
from rotorsweep.kernels import attractor, models
from rotorsweep.kernels.models.spec import Parameter as Key

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

# Models a scene can run: those with an axis to continue along (the validation models have none).
MODELS = tuple(name for name, spec in models.REGISTRY.items() if spec.continuation)


class ConfigError(Exception):
    """A config that cannot be run; the message lists every problem, one per line.

    grid_points is set when the grid size (above numerics.max_points) is the only problem, so a
    front end may ask the user to confirm instead."""

    def __init__(self, message, grid_points=None):
        super().__init__(message)
        self.grid_points = grid_points


# --- declarative schema ------------------------------------------------------------------------
# Generic sections here; a model's own sections (e.g. [bearing], [rotor]) and its sweep axes come
# from its ModelSpec parameters (`model_schema`). Key is the kernels' Parameter type.

def _num(lo=-math.inf, hi=math.inf, lo_open=False, hi_open=False, default=None, kind="float", **kw):
    return Key(kind, default, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open, **kw)


# Frequency units of the reports: Hz, or over omega_l (rotorsweep.pipeline.modes.omega_l, the models whose
# spec has one)
FREQUENCY_UNITS = ("Hz", "omega_l")

# A torus branch's Fourier modes K (2K + 1 nodes): the counts its adaptive node count takes (it
# doubles, N -> 2N + 1, i.e. K -> 2K + 1, from the first torus's 15 nodes, and halves back), 7..127 nodes
TORUS_MODES = (3, 7, 15, 31, 63)

SCHEMA = {
    "scene": {
        "name": Key("str", required=True, pattern=r"[A-Za-z0-9_.-]+", help="name of the scene; default output out/<name>.nc"),
        "model": Key("choice", required=True, choices=MODELS, help="the model (its sections and axes below)"),
        "description": Key("str", default="", help="one line, stored in the cube"),
    },
    "analysis": {
        "floquet": Key("bool", default=True, help="periodic orbit by shooting, Floquet multipliers"),
        "attractor": Key("bool", default=False, help="Poincare section, period, attractor class, Lyapunov exponents"),
        "derive_when_stable": Key("bool", default=True, help="where the transient reaches a stable period-k orbit, "
                                  "take the exponents from its multipliers, ln|lambda| / (k T), not a Lyapunov run"),
        "sweep_direction": Key("choice", default="up", choices=("up", "down", "both"),
                               help="continue the attractor with increasing speed, down, or both (adds *_down "
                                    "variables and hysteresis)"),
        "transient_periods": _num(0, kind="int", default=200, help="forcing periods before the Poincare samples "
                                                                   "(from the previous speed's end state)"),
        "poincare_samples": _num(8, 4096, kind="int", default=128, help="stroboscopic samples per point (>= 4 x max_period)"),
        "max_period": _num(1, 1024, kind="int", default=32, help="longest period k detected"),
        "lyapunov_max_periods": _num(20, 1e6, kind="int", default=2000,
                                     help="cap of a Lyapunov run (it stops earlier, after at least 300 periods, at "
                                          "lyapunov_rtol)"),
        "lyapunov_rtol": _num(0, 1, lo_open=True, hi_open=True, default=0.02,
                              help="a Lyapunov run stops once the largest exponent's standard error is below this fraction of it"),
        "stop_when_settled": Key("bool", default=True,
                                 help="end the transient once the samples repeat on a stable period-k orbit (tested every "
                                      "8 periods), or once the state reaches the previous speed's period-k attractor "
                                      "continued by shooting (a strongly stable orbit, max |lambda| <= 0.9, within 1e-3 "
                                      "of its size); false: always transient_periods"),
        "lyapunov_converged_stop": Key("bool", default=True,
                                       help="a Lyapunov run also stops once its weighted average has converged to 0 (the "
                                            "averages over N/2, 3N/4 and N periods within 1e-4 per period of 0, agreeing to "
                                            "10 % of the standard error: a torus)"),
    },
    "continuation": {   # `rotorsweep continue`: pseudo-arclength branches, one per line of the other axes
        "parameter": Key("str", default="", help="the scene parameter continued (default: the model's continuation axis)"),
        "start": _num(default=None, help="parameter value the branch starts at (default: the sweep's first value of it)"),
        "stop": _num(default=None, help="the other end of the range (default: the sweep's last value of it)"),
        "ds": _num(0, lo_open=True, default=0.02, help="first arclength step, in units of the range width "
                                                        "(torus branches: in the parameter's own unit, e.g. Hz)"),
        "ds_min": _num(0, lo_open=True, default=1e-6, help="smallest step before the branch gives up"),
        "ds_max": _num(0, lo_open=True, default=0.25, help="largest step"),
        "max_steps": _num(1, kind="int", default=2000, help="points per branch at most"),
        "max_angle": _num(0, 1.5, lo_open=True, default=0.25, help="largest angle between tangents of successive points [rad]"),
        "periods": _num(1, 64, kind="int", default=1, help="forcing periods of the orbit continued (period-k orbits)"),
        "period_doubling_switches": _num(0, 6, kind="int", default=2,
                                         help="branch switching depth at period doublings (2: 1 -> 2 -> 4)"),
        "curves_in": Key("str", default="", help="a second swept axis: continue every fold, period doubling and "
                                                  "Neimark-Sacker point of the period-1 branches in it (boundary curves)"),
        "torus_min_modes": Key("choice", default=3, choices=TORUS_MODES,
                               help="a torus branch's fewest Fourier modes K (2K + 1 nodes): its circle's node count "
                                    "shrinks to no fewer where a coarser count resolves it (K -> (K - 1) / 2)"),
        "torus_max_modes": Key("choice", default=31, choices=TORUS_MODES,
                               help="a torus branch's most Fourier modes K (2K + 1 nodes; K -> 2K + 1 where the "
                                    "spectrum widens): where its circle needs more, the branch ends torus_breakdown"),
    },
    "backbone": {   # `rotorsweep backbone`: nonlinear normal modes of a conservative model
        "modes": Key("str", default="all", help="mode numbers (1 = the lowest linear frequency), e.g. \"1, 3\"; or all"),
        "amplitude_max": _num(0, lo_open=True, default=None, unit="m",
                              help="largest master amplitude [m] (first harmonic; default: a quarter of the "
                                   "preload's axial approach z0; must stay below z0)"),
        "amplitude_min": _num(0, lo_open=True, default=None, unit="m", help="smallest master amplitude [m] (default: amplitude_max / 100)"),
        "amplitude_points": _num(3, 2000, kind="int", default=41, help="amplitudes of the grid (log-spaced)"),
        "continuation": Key("bool", default=True, help="also the reference backbone by continuation of the full model's orbits"),
        "ds": _num(0, lo_open=True, default=0.2, help="first arclength step (units of the largest amplitude)"),
        "ds_max": _num(0, lo_open=True, default=2.0, help="largest arclength step"),
        "max_steps": _num(1, kind="int", default=400, help="continuation points per backbone at most"),
        "surface_mode": _num(1, kind="int", default=1, help="mode whose invariant manifold the report draws"),
    },
    "report": {   # how the reports draw the scene's results
        "observable": Key("str", default="", help="observable of the branch diagrams (its orbit's half peak-to-peak "
                                                   "amplitude; default: the model's first observable)"),
        "frequency_unit": Key("choice", default="Hz", choices=FREQUENCY_UNITS,
                              help="Hz, or omega_l: frequencies over the lowest linear natural frequency at a 15 deg "
                                   "contact angle (Filipkovsky 2016's nondimensional frequency; rigid_preloaded)"),
        "torus_detail": _num(default=None, help="the continued parameter's value of the torus the continuation "
                                                "report draws in detail (the nearest point; default: the torus of "
                                                "the largest half-swing)"),
    },
    "numerics": {
        "integrator": Key("choice", default="dop853", choices=("dop853", "rk4"), help="DOP853, or RK4 (rk4_steps per period)"),
        "rtol": _num(0, 1e-2, lo_open=True, default=1e-10, help="DOP853 relative tolerance"),
        "atol": _num(0, 1, lo_open=True, hi_open=True, default=1e-12, help="DOP853 absolute tolerance (scaled state, e.g. um)"),
        "rk4_steps": _num(16, kind="int", default=512, help="RK4 steps per period"),
        "newton_tol": _num(0, lo_open=True, default=1e-9, help="shooting residual (relative) at which Newton stops"),
        "max_newton_iter": _num(1, 1000, kind="int", default=30, help="Newton iteration cap"),
        "transient_periods": _num(0, kind="int", default=30, help="forcing periods integrated before a cold Newton start"),
        "segment_length": _num(1, kind="int", default=32, help="speeds per continuation segment (fixed by the config: "
                                                                "results never depend on scheduling)"),
        "amplitude_limit": _num(0, lo_open=True, default=1e-3, unit="m",
                                help="displacement beyond which a state counts as diverged"),
        "max_points": _num(1, kind="int", default=200_000, help="larger grids need --yes"),
    },
    # where a command runs, not what it computes: left out of the scene's hash (RUN_SECTION)
    "run": {
        "in_process_below": _num(0, default=None, unit="s",
                                 help="estimated CPU seconds of work below which run, continue and backbone compute in "
                                      "this process, without a cluster (0: always a cluster; default: "
                                      "$ROTORSWEEP_IN_PROCESS_BELOW_S, else 3 s); results are the same bit for bit"),
    },
}
RUN_SECTION = "run"
REQUIRED_SECTIONS = ("scene", "sweep")

# the embedded default scene: configs/demo.toml, shipped as package data (rotorsweep.scenes)
DEFAULT_CONFIG_TOML = (resources.files("rotorsweep.scenes") / "demo.toml").read_text(encoding="utf-8")


# --- value checks --------------------------------------------------------------------------------

def _type_name(v):
    return {bool: "boolean", int: "integer", float: "number", str: "string", list: "list",
            dict: "table"}.get(type(v), type(v).__name__)


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def range_text(k):
    """'> 0 and <= 90' of a key or a model parameter (anything with lo, hi, lo_open, hi_open);
    '' when unbounded."""
    lo = "" if k.lo == -math.inf else f"{'>' if k.lo_open else '>='} {k.lo:g}"
    hi = "" if k.hi == math.inf else f"{'<' if k.hi_open else '<='} {k.hi:g}"
    return " and ".join(x for x in (lo, hi) if x)


NUMERIC_KINDS = ("float", "int", "float_or")      # whose limits a key's help explains


def key_help(k):
    """' (what the key is)' where the key says, else nothing (never an empty '()')."""
    return f" ({k.help})" if k.help else ""


def check_number(v, k):
    """Error text for a number outside the key's (or model parameter's) range, or None."""
    if not math.isfinite(v):
        return f"must be a finite number (got {v})"
    bad_lo = v < k.lo or (k.lo_open and v == k.lo)
    bad_hi = v > k.hi or (k.hi_open and v == k.hi)
    return f"must be {range_text(k)} (got {v:g})" if bad_lo or bad_hi else None


def _check_value(v, k):
    """(normalized value, error text or None) for a scalar key."""
    v, problem = units.key_value(v, k)
    if problem:
        return v, problem
    if k.kind == "str":
        if not isinstance(v, str):
            return v, f"must be a string (got {_type_name(v)})"
        if k.pattern and not re.fullmatch(k.pattern, v):
            return v, f"must match {k.pattern} (got {v!r})"
        return v, None
    if k.kind == "bool":
        return v, None if isinstance(v, bool) else f"must be true or false (got {_type_name(v)})"
    if k.kind == "choice":
        if v not in k.choices or isinstance(v, bool):
            allowed = ", ".join(json.dumps(c) for c in k.choices)
            return v, f"unknown value {json.dumps(v) if isinstance(v, (str, int, float)) else _type_name(v)}; allowed: {allowed}"
        return v, None
    if k.kind == "float_or" and isinstance(v, str):
        return v, None    # one of the choices (units.key_value converted or refused any other string)
    if k.kind == "int":
        if not isinstance(v, int) or isinstance(v, bool):
            return v, f"must be an integer (got {_type_name(v)} {v!r})"
        return v, check_number(v, k)
    if not _is_number(v):
        extra = f" or {', '.join(json.dumps(c) for c in k.choices)}" if k.kind == "float_or" else ""
        return v, f"must be a number{extra} (got {_type_name(v)})"
    return float(v), check_number(float(v), k)


def _axis_values(v, rng, errors, where):
    """Grid values of a sweep axis (rng: its Key), appending problems to errors."""
    if isinstance(v, list):
        if not v:
            errors.append(f"{where}: must not be empty")
            return None
        bad = [x for x in v if not _is_number(x)]
        if bad:
            errors.append(f"{where}: must be a list of numbers (got {_type_name(bad[0])} {bad[0]!r})")
            return None
        values = np.array(v, float)
    elif isinstance(v, dict):
        values = _range_values(v, errors, where)
        if values is None:
            return None
    else:
        errors.append(f"{where}: must be a list of numbers or a table {{start, stop, step}} or "
                      f"{{start, stop, num}} (got {_type_name(v)})")
        return None
    for x in values:
        problem = check_number(float(x), rng)
        if problem:
            errors.append(f"{where}: every value {problem}{key_help(rng)}")
            return None
    if np.any(np.diff(values) <= 0):
        errors.append(f"{where}: values must be strictly increasing, without duplicates")
        return None
    return values


def _step_count(start, stop, step):
    return int(math.floor((stop - start) / step + 1e-9)) + 1


def _axis_count(v):
    """Number of values an axis definition gives, without building it (None: malformed, which
    _axis_values reports)."""
    if isinstance(v, list):
        return len(v)
    if not isinstance(v, dict) or not all(_is_number(v.get(k)) and math.isfinite(v[k]) for k in ("start", "stop")):
        return None
    num = v.get("num")
    if isinstance(num, int) and not isinstance(num, bool) and num >= 1 and "step" not in v:
        return num
    step = v.get("step")
    if _is_number(step) and math.isfinite(step) and step > 0 and "num" not in v and v["stop"] >= v["start"]:
        return _step_count(float(v["start"]), float(v["stop"]), float(step))
    return None


def _range_values(v, errors, where):
    keys = set(v)
    unknown = keys - {"start", "stop", "step", "num"}
    if unknown:
        errors.append(f"{where}: unknown key(s) {sorted(unknown)}; allowed: start, stop, and one of step/num")
        return None
    if not {"start", "stop"} <= keys or len(keys & {"step", "num"}) != 1:
        errors.append(f"{where}: needs start, stop and exactly one of step or num")
        return None
    for key in keys:
        val = v[key]
        ok = (isinstance(val, int) and not isinstance(val, bool)) if key == "num" else _is_number(val)
        if not ok or (key != "num" and not math.isfinite(val)):
            errors.append(f"{where}.{key}: must be a finite {'integer' if key == 'num' else 'number'} (got {val!r})")
            return None
    start, stop = float(v["start"]), float(v["stop"])
    if start > stop:
        errors.append(f"{where}: start must be <= stop (got start={start:g}, stop={stop:g})")
        return None
    if "num" in v:
        if v["num"] < 1:
            errors.append(f"{where}.num: must be >= 1 (got {v['num']})")
            return None
        return np.array([start]) if v["num"] == 1 else np.linspace(start, stop, v["num"])
    step = float(v["step"])
    if step <= 0:
        errors.append(f"{where}.step: must be > 0 (got {step:g})")
        return None
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    values = start + step * np.arange(n)
    return np.array([float(f"{x:.12g}") for x in values])   # no float drift: 10 + 0.1 k exactly


# --- the whole file ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Config:
    path: object
    source: str
    data: dict
    axes: dict = field(repr=False)

    @property
    def model(self):
        return models.get(self.data["scene"]["model"])

    @property
    def continued_axis(self):
        return continued_axis(self.model, self.axes)

    @property
    def n_points(self):
        return int(np.prod([len(v) for v in self.axes.values()]))

    @cached_property
    def scene(self):
        """The typed scene (rotorsweep.pipeline.scene.Scene) the commands and their tasks work from, built once."""
        from rotorsweep.pipeline import scene
        return scene.build(self)

    def hash(self):
        """Identifies the scene (data, not formatting): changes with any value but those of
        RUN_SECTION (where it runs), not with comments."""
        scene = {k: v for k, v in self.data.items() if k != RUN_SECTION}
        text = json.dumps(scene, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


# Continuation settings (rotorsweep.kernels.continuation Settings fields) that a scene gives under
# another key than [section].<field>; the others are fixed, not in the config.
SETTINGS_KEYS = {"tol": "numerics.newton_tol"}


def settings_problems(problems, section, keys):
    """The problems of a continuation Settings (its `problems()`, which name its fields) as config
    messages naming the scene's keys: a field the [section] has (`keys`) is `section.field`,
    `tol` is numerics.newton_tol, any other field is a fixed setting (named as such)."""
    out = []
    for text in problems:
        named = [f for f in re.findall(r"[a-z_]+", text.split(":")[0]) if f in keys or f in SETTINGS_KEYS]
        where = ", ".join(SETTINGS_KEYS.get(f, f"{section}.{f}") for f in dict.fromkeys(named))
        head = re.match(r"([a-z_]+) = ([^:]+): (.*)", text)
        if head and len(named) == 1:
            text = f"{head[3]} (got {head[2]})"
        out.append(f"{where or section}: {text}" + ("" if named else " (a fixed setting of the section)"))
    return out


def continued_axis(spec, axes):
    """The axis orbits are continued along: the model's first continuation parameter that the
    scene sweeps over several values, else its first."""
    along = spec.continuation
    return next((a for a in along if len(axes.get(a, ())) > 1), along[0])


def _unknown(key, known, where):
    close = difflib.get_close_matches(key, known, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else f"; allowed: {', '.join(known)}"
    return f"{where}: unknown key{hint}"


def _validate_section(name, table, spec, errors):
    out = {}
    if not isinstance(table, dict):
        errors.append(f"{name}: must be a table (got {_type_name(table)})")
        return out
    for key in table:
        if key not in spec:
            errors.append(_unknown(key, list(spec), f"{name}.{key}"))
    for key, k in spec.items():
        where = f"{name}.{key}"
        if key not in table:
            if k.required:
                errors.append(f"{where}: required")
            out[key] = k.default
            continue
        value, problem = _check_value(table[key], k)
        if problem:
            errors.append(f"{where}: {problem}{key_help(k) if k.kind in NUMERIC_KINDS else ''}")
        out[key] = value
    return out


def model_schema(spec):
    """The model's config sections ({section: {key: Key}}) and its sweep axes ({axis: Key})."""
    sections = {}
    for par in spec.parameters:
        if par.section is not None:
            sections.setdefault(par.section, {})[par.name] = par
    return sections, {par.name: par for par in spec.parameters if par.axis}


def _cross_checks(spec, data, axes, errors):
    along = spec.continuation[0]
    if along not in axes and f"sweep.{along}" not in " ".join(errors):
        errors.append(f"sweep.{along}: required ({along} is the continuation axis of model {spec.name})")
    for par in spec.parameters:
        if par.axis and par.section and par.name in axes and data[par.section].get(par.name) is not None:
            errors.append(f"{par.section}.{par.name}: is also swept in sweep.{par.name}; give it in one place only")
    errors.extend(spec.check(data, axes) if spec.check else [])
    ana = data["analysis"]
    if not (ana["floquet"] or ana["attractor"]):
        errors.append("analysis: floquet and attractor are both false; nothing to compute")
    errors.extend(attractor.Settings.from_keys(ana).problems("analysis."))
    errors.extend(_report_checks(spec, data["report"]))
    errors.extend(_torus_mode_checks(data["continuation"]))
    num = data["numerics"]
    if num["integrator"] == "dop853" and num["newton_tol"] < num["rtol"]:
        errors.append(f"numerics.newton_tol: must be >= numerics.rtol ({num['rtol']:g}); Newton cannot "
                      "converge below the integration accuracy")


def _torus_mode_checks(sec):
    """The torus branches' node-count bounds: the fewest modes no more than the most."""
    lo, hi = sec["torus_min_modes"], sec["torus_max_modes"]
    if lo > hi:
        return [f"continuation.torus_min_modes: must be <= continuation.torus_max_modes ({hi}), got {lo}"]
    return []


def _report_checks(spec, rep):
    errors = []
    names = [o.name for o in spec.observables]
    if rep["observable"] and rep["observable"] not in names:
        errors.append(f"report.observable: {rep['observable']!r} is not an observable of model {spec.name} "
                      f"(allowed: {', '.join(names)})")
    if rep["frequency_unit"] == "omega_l" and spec.omega_l is None:
        with_one = [name for name, other in models.REGISTRY.items() if other.omega_l is not None]
        errors.append(f"report.frequency_unit: omega_l needs a model that defines it "
                      f"({', '.join(with_one)}); model {spec.name} has none: use Hz")
    return errors


def _continuation_keys(raw, spec):
    """The [continuation] keys, start and stop in the unit of the parameter continued."""
    table = raw.get("continuation")
    name = (table.get("parameter") if isinstance(table, dict) else None) or spec.continuation[0]
    par = next((p for p in spec.parameters if p.name == name), None)
    keys = SCHEMA["continuation"]
    if par is None:    # an unknown parameter: the continuation checks name it
        return keys
    return {**keys, **{k: replace(keys[k], unit=par.unit) for k in ("start", "stop")}}


def _scene_model(raw):
    """The ModelSpec the scene names, or None (its problem is reported by the scene section)."""
    scene = raw.get("scene")
    name = scene.get("model") if isinstance(scene, dict) else None
    return models.REGISTRY[name] if name in MODELS else None


def _sweep_axes(table, axis_keys, errors):
    """{axis: grid values} of the [sweep] table, in the model's axis order."""
    if not isinstance(table, dict):
        errors.append(f"sweep: must be a table (got {_type_name(table)})")
        return {}
    for key in table:
        if key not in axis_keys:
            errors.append(_unknown(key, list(axis_keys), f"sweep.{key}"))
    axes = {}
    for name, key in axis_keys.items():
        if table.get(name) is not None:
            values = _axis_values(table[name], key, errors, f"sweep.{name}")
            if values is not None:
                axes[name] = values
    return axes


def _check_grid_size(sweep, axis_names, data, allow_large, errors, label):
    """Raise for a too-large grid from the axis definitions alone, before any array is built
    (a typo like num = 1e9 must not allocate). grid_points lets a front end ask to confirm when
    max_points is the only problem."""
    n = math.prod(c for c in (_axis_count(sweep.get(name)) for name in axis_names) if c is not None)
    limit = data["numerics"]["max_points"]
    limit = limit if isinstance(limit, int) else SCHEMA["numerics"]["max_points"].default
    problem = gridsize.grid_size_problem(n, data, limit, allow_large)
    if problem:
        message, may_confirm = problem
        raise ConfigError("\n".join(f"{label}: {e}" for e in errors + [message]),
                          grid_points=n if may_confirm and not errors else None)


def parse_config(text, path=None, allow_large=False, whole_grid=True):
    """Validate a TOML scene; returns a Config or raises ConfigError listing every problem.
    whole_grid: the command computes every grid point (`run`), so the grid's size is checked;
    `point`, `continue`, `backbone` and `modes` do not, and a large grid is no reason to refuse them.
    Numbers are SI; a string with a unit is converted to the key's unit (rotorsweep.pipeline.units).

    >>> cfg = parse_config('''
    ... [scene]
    ... name = "rpm"
    ... model = "jeffcott_clearance"
    ... [sweep]
    ... speed = {start = "600 rpm", stop = "3000 rpm", num = 5}
    ... clearance = [7.6e-6, "19 um"]
    ... ''')
    >>> cfg.axes["speed"].tolist(), cfg.axes["clearance"].tolist(), cfg.n_points
    ([10.0, 20.0, 30.0, 40.0, 50.0], [7.6e-06, 1.9e-05], 10)
    """
    label = str(path) if path is not None else "<config>"
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{label}: not valid TOML: {exc}") from None
    errors = []
    spec = _scene_model(raw)
    sections, axis_keys = model_schema(spec) if spec else ({}, {})
    tables = {**SCHEMA, "continuation": _continuation_keys(raw, spec), **sections} if spec else SCHEMA
    known = list(tables) + ["sweep"]
    for section in raw:
        if section not in known and spec is not None:
            errors.append(_unknown(section, known, section))
    for section in REQUIRED_SECTIONS:
        if section not in raw:
            errors.append(f"{section}: required section missing")
    data = {name: _validate_section(name, raw.get(name, {}), table, errors) for name, table in tables.items()}
    sweep = raw.get("sweep", {})
    if isinstance(sweep, dict):
        sweep = units.sweep_table(sweep, axis_keys, errors)
    if isinstance(sweep, dict) and whole_grid:
        _check_grid_size(sweep, axis_keys, data, allow_large, errors, label)
    axes = _sweep_axes(sweep, axis_keys, errors) if spec else {}
    data["sweep"] = {name: [float(x) for x in values] for name, values in axes.items()}
    if not errors:
        _cross_checks(spec, data, axes, errors)
    if errors:
        raise ConfigError("\n".join(f"{label}: {e}" for e in errors))
    if spec.fill_defaults:
        spec.fill_defaults(data)
    return Config(None if path is None else str(path), text, data, axes)


# A scene is a few kB; a larger file is not one (a device such as /dev/zero would be read until
# memory runs out).
MAX_CONFIG_BYTES = 1 << 20


def load_config(path, allow_large=False, whole_grid=True):
    """parse_config of a TOML file (at most MAX_CONFIG_BYTES, UTF-8); ConfigError names the file.

    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp(), "demo.toml"); _ = path.write_text(DEFAULT_CONFIG_TOML)
    >>> load_config(path).n_points
    202
    """
    return parse_config(_config_text(path), path=path, allow_large=allow_large, whole_grid=whole_grid)


def _config_text(path):
    """The text of a config file: a regular file of at most MAX_CONFIG_BYTES, UTF-8."""
    p = Path(path)
    try:
        if not p.exists():
            raise ConfigError(f"{path}: no such config file")
        if not p.is_file():
            raise ConfigError(f"{path}: not a regular file (a config is a TOML text file)")
        with open(p, "rb") as fh:
            data = fh.read(MAX_CONFIG_BYTES + 1)
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read ({exc.strerror or exc.__class__.__name__})") from None
    if len(data) > MAX_CONFIG_BYTES:
        raise ConfigError(f"{path}: larger than {MAX_CONFIG_BYTES} bytes; not a scene config")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: cannot read as a TOML text file ({exc.__class__.__name__})") from None

"""Unit strings where people type them: config values and CLI flags ("7.6 um", "600 rpm", "1.2 kN").

A plain number is SI (the key's own unit, as before); a string is read by pint and converted to
the key's unit (`Parameter.unit`, UDUNITS spelling as in the cubes: "m", "Hz", "N m-1.5",
"degree"). Cubes stay SI. pint is imported only when a unit string is met, so plain configs and
`import rotorsweep` do not pay for it.

Cycles and radians: pint counts a radian as dimensionless, so it would read 1 rpm as 2 pi / 60 Hz
and 1 Hz as 1 rad/s. Here Hz counts cycles (a shaft speed of 1 Hz is one turn per second) and an
angular unit (rad/s, rpm) converts with one cycle = 2 pi rad: 600 rpm = 10 Hz, 1 Hz = 2 pi rad/s.
"""
import functools
import json
import math
import re
import sys

# UDUNITS' implicit power ("m-1.5", "s-2") in pint's spelling ("m**-1.5")
_POWER = re.compile(r"([A-Za-z]+)(-?\d+(?:\.\d+)?)")


class UnitError(ValueError):
    """A value that is not a quantity of the expected unit; the message says what was expected."""


@functools.lru_cache(maxsize=1)
def registry():
    """The pint registry (built once, on the first unit string): pint's defaults plus RPM, the
    spelling ROSS users type."""
    ureg = _pint_without_dask().UnitRegistry()
    ureg.define("@alias revolutions_per_minute = RPM")
    return ureg


def _pint_without_dask():
    """pint, imported without Dask. pint.compat imports dask.base whenever Dask is installed (it asks
    importlib.util.find_spec) for its dask-array facet, which rotorsweep never uses: without it a
    unit string costs 0.31 s of CPU instead of 0.49 s over a bare `import numpy` (median of 7
    processes; `python -X importtime` shows dask under pint.compat). A None in sys.modules makes
    find_spec say "not installed"; it stands only while pint is imported, and only when Dask is not
    loaded yet (if it is, pint takes it for free). pint's dask facet stays off in this process."""
    if "dask" in sys.modules or "pint" in sys.modules:
        import pint
        return pint
    sys.modules["dask"] = None
    try:
        import pint
    finally:
        del sys.modules["dask"]
    return pint


def pint_unit(unit):
    """pint's spelling of a UDUNITS unit string: "N m-1.5" -> "N * m**-1.5", "1" -> ""."""
    if unit in ("", "1"):
        return ""
    return " * ".join(_POWER.sub(r"\1**\2", part) for part in unit.split())


def _radian_power(ureg, units):
    return dict(ureg.get_base_units(units)[1]._units).get("radian", 0)


def to_unit(text, unit):
    """The value of `text` (a number with a unit, e.g. "7.6 um") in `unit` (UDUNITS spelling), a
    float; a bare number in the string is taken as already in `unit`. Raises UnitError.

    >>> to_unit("7.6 um", "m")
    7.6e-06
    >>> to_unit("600 rpm", "Hz")
    10.0
    """
    ureg = registry()
    try:
        q = ureg.Quantity(text.strip())
    except Exception as exc:   # pint raises several types for text it cannot read
        raise UnitError(f"cannot read {text!r} as a quantity ({exc}); expected a quantity of "
                        f"{_expected(unit)}, e.g. \"{_example(unit)}\"") from None
    if not isinstance(q, ureg.Quantity):   # "3.0" parses to a plain float
        return float(q)
    if not dict(q.unit_items()):   # "15" or "1.5e-6" as a string: a plain number
        return float(q.magnitude)
    target = ureg.Unit(pint_unit(unit))
    if q.dimensionality != target.dimensionality:
        raise UnitError(f"{text!r} is not a quantity of {_expected(unit)}")
    cycles = _radian_power(ureg, target) - _radian_power(ureg, q.units)
    if cycles and q.dimensionality != ureg.Unit("Hz").dimensionality:
        raise UnitError(f"{text!r} is not a quantity of {_expected(unit)}")
    value = float(q.to(target).magnitude) * (2 * math.pi) ** cycles
    return float(f"{value:.15g}")   # no float noise from the conversion: "7.6 um" is 7.6e-06


def _example(unit):
    return "0.5" if unit in ("", "1") else f"1.5 {unit}"


def _expected(unit):
    return "no unit (a plain number)" if unit in ("", "1") else f"unit {unit}"


# --- config values and flags ---------------------------------------------------------------

def key_value(v, k):
    """(value, error text or None) of a config value for key k (a Parameter): a unit string of a
    number key ("7.6 um") in the key's unit; any other value as it is.

    >>> from rotorsweep.kernels.models.spec import Parameter
    >>> key_value("7.6 um", Parameter(unit="m"))
    (7.6e-06, None)
    >>> key_value("7.6 Hz", Parameter(unit="m"))
    ('7.6 Hz', "'7.6 Hz' is not a quantity of unit m")
    """
    if not isinstance(v, str) or k.kind not in ("float", "float_or") or v in k.choices:
        return v, None
    try:
        return to_unit(v, k.unit), None
    except UnitError as exc:
        if k.kind == "float_or":
            allowed = ", ".join(json.dumps(c) for c in k.choices)
            return v, f"unknown value {json.dumps(v)}; allowed: {allowed} or a number (SI, or with a unit: {exc})"
        return v, str(exc)


def axis_definition(v, key, errors, where):
    """The axis definition with its unit strings in the key's unit (a list's values, a range's
    start, stop and step); None after a bad one (its problem appended to errors)."""
    if isinstance(v, list):
        items = dict(enumerate(v))
    elif isinstance(v, dict):
        items = {name: x for name, x in v.items() if name != "num"}
    else:
        return v
    out = dict(items)
    for name, x in items.items():
        out[name], problem = key_value(x, key)
        if problem:
            errors.append(f"{where}{f'[{name}]' if isinstance(v, list) else f'.{name}'}: {problem}")
            return None
    return list(out.values()) if isinstance(v, list) else {**v, **out}


def sweep_table(table, axis_keys, errors):
    """The [sweep] table with unit strings converted (an axis with a bad one left out)."""
    out = {}
    for name, v in table.items():
        v = axis_definition(v, axis_keys[name], errors, f"sweep.{name}") if name in axis_keys else v
        if v is not None:
            out[name] = v
    return out


def flag_values(flags, spec, unit_of=None):
    """{axis: value} from CLI flags {axis: (flag, text)} (None where not given): a plain number is
    SI, a unit string ("7.6 um", "600 rpm") is converted to the unit of the model's parameter of
    that name (or unit_of[name]). Raises UnitError naming the flag and the unit expected.

    >>> from rotorsweep.kernels import models
    >>> flag_values({"speed": ("--speed", "600 rpm"), "clearance": ("--clearance", None)},
    ...             models.get("jeffcott_clearance"))
    {'speed': 10.0, 'clearance': None}
    """
    unit_of = {**{p.name: p.unit for p in spec.parameters}, **(unit_of or {})}
    values, errors = {}, []
    for name, (flag, text) in flags.items():
        if text is None:
            values[name] = None
            continue
        try:
            values[name] = float(text)
        except ValueError:
            try:
                values[name] = to_unit(text, unit_of.get(name, "1"))
            except UnitError as exc:
                errors.append(f"{flag}: {exc}")
    if errors:
        raise UnitError("\n".join(errors))
    return values

"""Where the swept axes go in a figure (axes and line plans, capped at MAX_PANELS panels) and how
axis values are written (display units, labels, titles)."""
import itertools

import numpy as np

from rotorsweep.pipeline import cube, schema
from rotorsweep.pipeline.report.cubeinfo import continued_axis, other_axes

MAX_PANELS = 12        # facet panels per figure; the rest are listed as omitted

# Display conventions on top of the coordinates' CF attributes: units shown scaled (cube units ->
# factor, display unit), and short axis names for titles (the long_names, e.g. "radial internal
# clearance", are too long for panel titles and legends). Other axes show their long_name.
_UNIT_DISPLAY = {"m": (1e6, "µm"), "degree": (1.0, "deg")}
_SHORT_NAMES = {"speed": "shaft speed", "clearance": "radial clearance",
                "contact_angle": "contact angle", "preload": "preload"}

# display names of the instability types of query.unstable_intervals
TYPE_NAMES = {"fold": "fold", "period_doubling": "period doubling",
              "neimark_sacker": "Neimark-Sacker", "no_orbit": "no periodic orbit",
              "none": "unclassified", "quasi_periodic_unstable": "quasi-periodic unstable",
              "torus_failed": "torus failed"}


def unit_display(units):
    """(factor from cube units, display unit), e.g. "m" -> (1e6, "µm")."""
    return _UNIT_DISPLAY.get(units, (1.0, units))


def axis_display(ds, axis):
    """(factor from cube units, display unit, short label) of an axis, from the CF attributes
    (units, long_name) of its coordinate, the model's axis table where the cube has none."""
    units, long_name = schema.axes_of(schema.model_of(ds)).get(axis, ("1", axis))
    attrs = ds[axis].attrs if axis in ds.coords else {}
    factor, unit = unit_display(attrs.get("units", units))
    return factor, unit, _SHORT_NAMES.get(axis, attrs.get("long_name", long_name))


def fmt(ds, axis, value):
    """A value of an axis in display units, e.g. '7.6 µm'."""
    factor, unit, _ = axis_display(ds, axis)
    if value is None or not np.isfinite(value):
        how = cube.derived_parameters(ds).get(axis, "")
        return "from " + how[len("derived from "):].split(" per point")[0] if how.startswith("derived from ") else "n/a"
    return f"{float(value) * factor:.4g} {unit}"


def axis_label(ds, axis):
    _, unit, label = axis_display(ds, axis)
    return f"{label} [{unit}]"


def where_label(ds, where, short=False, sep=", "):
    """'radial clearance 7.6 µm, contact angle 15 deg' for {axis: value}; short: shorter names."""
    names = {"clearance": "clearance", "contact_angle": "angle"} if short else {}
    return sep.join(f"{names.get(a, axis_display(ds, a)[2])} {fmt(ds, a, v)}" for a, v in where.items())


def fixed_note(ds, plan):
    return where_label(ds, plan["fixed"], sep="; ")


def _omitted_note(plan):
    n = len(plan["omitted"])
    if not n:
        return ""
    total = n + len(plan["shown"])
    return f"showing {len(plan['shown'])} of {total} panels ({n} omitted, listed in the HTML report)"


def figure_title(ds, head, plan):
    """`head`, the fixed axes in brackets, and a second line on omitted panels."""
    fixed = fixed_note(ds, plan)
    title = head + (f" ({fixed})" if fixed else "")
    note = _omitted_note(plan)
    return title + (f"\n{note}" if note else "")


def axes_plan(ds):
    """How the swept axes map onto a figure: x (the continued axis), y (first other swept axis
    or None), facet axes, fixed axes {name: value}, the facet combinations shown and those
    omitted."""
    x = continued_axis(ds)
    swept = [a for a in other_axes(ds) if ds.sizes[a] > 1]
    derived = cube.derived_parameters(ds)     # NaN: fmt writes where it comes from
    fixed = {a: np.nan if a in derived else float(np.ravel(ds[a].values)[0])
             for a in schema.axes_of(schema.model_of(ds))
             if a != x and a not in swept and (a in ds.coords or a in derived)}
    facets = swept[1:]
    combos = [dict(zip(facets, vals)) for vals in itertools.product(*(ds[a].values for a in facets))]
    shown, omitted = _cap(combos)
    return {"x": x, "y": swept[0] if swept else None, "facets": facets, "fixed": fixed,
            "shown": shown, "omitted": omitted}


def line_plan(ds):
    """Like axes_plan, for figures with one panel per line (every combination of the swept axes
    other than the continued one, e.g. one per clearance): {"x", "axes", "fixed", "shown",
    "omitted"}."""
    plan = axes_plan(ds)
    axes = [a for a in (plan["y"], *plan["facets"]) if a]
    combos = [{a: float(v) for a, v in zip(axes, vals)}
              for vals in itertools.product(*(ds[a].values for a in axes))]
    shown, omitted = _cap(combos)
    return {"x": plan["x"], "axes": axes, "fixed": plan["fixed"], "shown": shown, "omitted": omitted}


def _cap(combos):
    """(shown, omitted): at most MAX_PANELS combinations, evenly spread over the list."""
    if len(combos) <= MAX_PANELS:
        return combos, []
    keep = sorted(set(np.linspace(0, len(combos) - 1, MAX_PANELS).round().astype(int)))
    return [combos[i] for i in keep], [c for i, c in enumerate(combos) if i not in set(keep)]

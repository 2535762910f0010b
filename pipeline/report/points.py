"""`rotorsweep report --point`: parse and resolve grid points, recompute them from the cube's
scene, and the table shown with each point's figure."""
import re

import numpy as np

from rotorsweep.pipeline import query, schema
from rotorsweep.pipeline.report.cubeinfo import sweep_labels
from rotorsweep.pipeline.report.plan import TYPE_NAMES, axis_display, where_label

POINT_PERIODS = 256        # forcing periods of the trajectory drawn at a --point
POINT_STEPS = 64           # samples per forcing period (the Poincare section is every 64th)

_POINT_CUBE_VARS = ("orbit_status", "stable", "bifurcation", "max_abs_multiplier", "multiplier_real",
                    "multiplier_imag", "forcing_period", "attractor", "period", "lle", "lle_stderr",
                    "lle_method", "attractor_multiplier_real", "attractor_multiplier_imag", "attractor_state")


def orbit_pair(names, main=""):
    """The two observables a point's orbit is drawn in: the scene's [report] observable `main`
    with its x partner (y_B -> (x_B, y_B)) where the model has one, else the first two."""
    partner = "x" + main[1:] if main.startswith("y") else ""
    return (partner, main) if partner in names else tuple(names[:2])


def parse_point(items):
    """`AXIS=VALUE` strings (several per string allowed, separated by spaces or commas) ->
    {axis: float}, e.g. ["speed=36", "clearance=19e-6"] -> {"speed": 36.0, "clearance": 1.9e-05}."""
    items = [items] if isinstance(items, str) else list(items)
    point = {}
    for item in items:
        for token in (t for t in re.split(r"[\s,]+", str(item).strip()) if t):
            axis, sep, value = (part.strip() for part in token.partition("="))
            if not sep or not axis or not value:
                raise query.QueryError(f"bad point item {token!r}: expected AXIS=VALUE, e.g. speed=36")
            if axis in point:
                raise query.QueryError(f"{axis} is given twice in one point")
            try:
                point[axis] = float(value)
            except ValueError:
                raise query.QueryError(f"bad number {value!r} in point item {token!r}") from None
    return point


def _span(ds, axis):
    """The grid of an axis in cube units, for error messages."""
    grid = ds[axis].values.astype(float)
    unit = ds[axis].attrs.get("units", "")
    if grid.size == 1:
        return f"{grid[0]:g} {unit}"
    return f"{grid.min():g} .. {grid.max():g} {unit} ({grid.size} values)"


def _nearest(ds, axis, value):
    """(grid value, index) nearest to value; an error naming the range when outside the grid."""
    grid = ds[axis].values.astype(float)
    tol = 1e-9 * max(abs(grid.min()), abs(grid.max()), 1e-300)
    if not np.isfinite(value) or value < grid.min() - tol or value > grid.max() + tol:
        raise query.QueryError(f"point {axis}={value:g} is outside the cube's grid: {axis} spans "
                               f"{_span(ds, axis)}")
    i = int(np.argmin(np.abs(grid - value)))
    return float(grid[i]), i


def resolve_point(ds, spec):
    """The grid point nearest to `spec` ({axis: value}, SI units and degrees, or AXIS=VALUE
    strings): {"values": {axis: grid value}, "index": {axis: index}, "asked": spec}. Every swept
    axis with more than one value must be given; a value outside the grid is an error naming
    the valid range."""
    asked = spec if isinstance(spec, dict) else parse_point(spec)
    swept = schema.point_axes(ds)
    known = schema.axes_of(schema.model_of(ds))
    for axis in asked:
        if axis not in known:
            raise query.QueryError(f"unknown axis {axis!r} in point; the axes are {', '.join(known)}")
        if axis not in swept:
            raise query.QueryError(f"point: {axis} is not swept in this cube; its axes are "
                                   f"{', '.join(f'{a} ({_span(ds, a)})' for a in swept)}")
    values, index = {}, {}
    for axis in swept:
        if axis in asked:
            values[axis], index[axis] = _nearest(ds, axis, float(asked[axis]))
        elif ds.sizes[axis] == 1:
            values[axis], index[axis] = float(ds[axis].values[0]), 0
        else:
            raise query.QueryError(f"point: give {axis}=VALUE too; the cube sweeps {axis} over "
                                   f"{_span(ds, axis)}")
    return {"values": values, "index": index, "asked": dict(asked)}


def scene_of(ds):
    """The scene (rotorsweep.pipeline.scene.Scene) of a result's config_toml, which --point and the figures
    that integrate orbits again need."""
    from rotorsweep.pipeline import config as config_mod, scene as scene_mod

    text = ds.attrs.get("config_toml")
    if not text:
        raise query.QueryError("point: this cube stores no scene (config_toml attribute); "
                               "a point cannot be recomputed")
    try:
        return scene_mod.of_result(text, ds.attrs.get("model_version"))
    except config_mod.ConfigError as exc:
        raise query.QueryError(f"point: the cube's scene (config_toml) is not a valid config, "
                               f"so the point cannot be recomputed: {exc}") from None


def point_filename(ds, resolved):
    """point_<speed>Hz_<clearance>um[_<angle>deg][_<preload>N].png (the swept axes, display
    units in ASCII)."""
    parts = []
    for axis, value in resolved["values"].items():
        factor, unit, _ = axis_display(ds, axis)
        parts.append(f"{value * factor:.6g}{unit.replace('µ', 'u')}")
    return "point_" + "_".join(parts).replace("+", "") + ".png"


def compute_point(ds, scene, resolved):
    """Recompute one grid point for the report (rotorsweep.pipeline.compute.point_detail): a trajectory on
    the attractor the sweep found there (started from the cube's attractor_state; a second one
    from attractor_state_down where the down sweep ended elsewhere), plus the cube's values."""
    from rotorsweep.pipeline import compute

    fixed = scene.fixed
    values = resolved["values"]
    point = {**fixed, **values}
    sub = ds.isel(resolved["index"])
    pair = orbit_pair([o.name for o in scene.model.observables], scene.report.observable)
    names = [n + sfx for n in (*_POINT_CUBE_VARS, *(f"poincare_{o}" for o in pair)) for sfx in ("", schema.DOWN_SUFFIX)
             if n + sfx in sub.variables] + (["hysteresis"] if "hysteresis" in sub.variables else [])
    cube_values = {n: np.asarray(sub[n].values) for n in names}
    labels = sweep_labels(ds)
    sweeps = [("", labels[0])]
    if "attractor_state" + schema.DOWN_SUFFIX in cube_values and int(cube_values.get("hysteresis", 0)) == 1:
        sweeps.append((schema.DOWN_SUFFIX, labels[1]))
    runs = []
    for suffix, label in sweeps:
        state = cube_values.get("attractor_state" + suffix)
        start = state if state is not None and np.all(np.isfinite(state)) else None
        detail = compute.point_detail(scene, point, start_state=start, periods=POINT_PERIODS,
                                      steps_per_period=POINT_STEPS)
        runs.append({"suffix": suffix, "label": label, "detail": detail, "from_cube": start is not None})
    return {"resolved": resolved, "point": point, "cube": cube_values, "runs": runs,
            "labels": labels, "where": where_label(ds, values), "pair": pair}


def point_title(pt):
    return "Point " + pt["where"]


def _mult_text(re_, im):
    re_, im = np.asarray(re_, float), np.asarray(im, float)
    if not np.isfinite(re_).any():
        return "-"
    out, skip = [], False
    pairs = [(a, b) for a, b in zip(re_, im) if np.isfinite(a)]
    for j, (a, b) in enumerate(pairs):
        if skip:
            skip = False
            continue
        if abs(b) < 1e-12:
            out.append(f"{a:.4g}")
        elif j + 1 < len(pairs) and np.isclose(pairs[j + 1][0], a) and np.isclose(pairs[j + 1][1], -b):
            out.append(f"{a:.4g}±{abs(b):.4g}i")
            skip = True
        else:
            out.append(f"{a:.4g}{b:+.4g}i")
    return ", ".join(out) + f"  (max |λ| {np.nanmax(np.hypot(re_, im)):.4g})"


def _attractor_rows(values, head, suffix=""):
    """The table rows of the attractor of a cube row or point_detail row."""
    code = int(values["attractor" + suffix])
    name = schema.ATTRACTOR[code].replace("_", "-") if 0 <= code < len(schema.ATTRACTOR) else "-"
    k = int(values["period" + suffix])
    period = f"{k} forcing period{'s' if k != 1 else ''}" if k > 0 else "none found (up to max_period)"
    lle, err = float(values["lle" + suffix]), float(values["lle_stderr" + suffix])
    m = int(values["lle_method" + suffix])
    method = schema.LLE_METHOD[m] if 0 <= m < len(schema.LLE_METHOD) else "-"
    lle_text = f"{lle:+.4g} ± {err:.2g} 1/s ({method})" if np.isfinite(lle) else "-"
    mult = _mult_text(values["attractor_multiplier_real" + suffix], values["attractor_multiplier_imag" + suffix])
    return [(head, name), ("  period", period), ("  largest Lyapunov exp.", lle_text),
            ("  multipliers (kT orbit)", mult)]


def _orbit_verdict(src):
    status = int(src["orbit_status"])
    if status == 0:
        if int(src["stable"]) == 1:
            return "stable"
        return f"unstable ({TYPE_NAMES.get(schema.BIFURCATION[int(src['bifurcation'])], '-')})"
    if status == schema.ORBIT_STATUS.index("not_applicable"):
        return "not computed ([analysis] floquet = false)"
    return f"not found ({schema.ORBIT_STATUS[status]})" if 0 <= status < 4 else "-"


def point_rows(pt):
    """The table of a --point: [(quantity, value)]."""
    cube, values = pt["cube"], pt["resolved"]["values"]
    row = pt["runs"][0]["detail"]["row"]
    asked = pt["resolved"]["asked"]
    where = pt["where"]
    moved = [a for a, v in asked.items() if not np.isclose(v, values[a], rtol=1e-9, atol=0)]
    if moved:
        where += " (nearest grid point to " + ", ".join(f"{a}={asked[a]:g}" for a in moved) + ")"
    period_T = float(row["forcing_period"])
    src = cube if "multiplier_real" in cube else row
    rows = [("grid point", where),
            ("forcing period T", f"{period_T * 1e3:.4g} ms: ball passage {1 / period_T:.5g} Hz, "
                                 f"shaft {values['speed']:.5g} Hz"),
            ("periodic orbit (period T)", _orbit_verdict(src)),
            ("  multipliers", _mult_text(src["multiplier_real"], src["multiplier_imag"]))]
    if "attractor" in cube:
        sweeps = [("", pt["labels"][0])]
        if "attractor" + schema.DOWN_SUFFIX in cube:
            sweeps.append((schema.DOWN_SUFFIX, pt["labels"][1]))
        for suffix, label in sweeps:
            rows += _attractor_rows(cube, f"attractor ({label}, cube)", suffix)
        if "hysteresis" in cube:
            rows.append(("hysteresis", "yes: the sweeps end on different attractors"
                         if int(cube["hysteresis"]) == 1 else "no"))
    else:
        rows += _attractor_rows(row, "attractor (computed now)")
    start = "the cube's attractor_state" if pt["runs"][0]["from_cube"] else "the periodic orbit (diagnosed now)"
    rows.append(("trajectory", f"{POINT_PERIODS} forcing periods from {start}"))
    return rows

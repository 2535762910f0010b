"""Linear analysis of a scene (`rotorsweep modes`), for every model whose spec has a linearization
(`ModelSpec.linear_system`): its static equilibrium, the linearized modes at one point, and a
Campbell table over shaft speed for the models that name one (`ModelSpec.speed`).

Linearization about the static equilibrium q_s: M q'' + (C + G) q' + K q = 0 (the model's own,
e.g. rigid_preloaded's analytic stiffness of the ball sums). The modes, their damped and undamped
natural frequencies, damping ratios, whirl directions and labels are rotorkernels.modal's
(`modes_of`, whose docstring gives the conventions): eigenvalues s = -zeta w_n +- i w_d, each mode
once (w_d > 0), by increasing damped frequency; the logarithmic decrement is 2 pi zeta / sqrt(1 - zeta^2).

Critical speeds: the shaft speeds where a mode's damped frequency equals an excitation line's
frequency, the 1x line f = speed (unbalance) and, where the scene has one, the horizontal line
f = support frequency (`ModelSpec.support_frequency`). The k-th damped frequency in increasing
order is a continuous function of speed (order statistics of continuous curves), so each
crossing is bracketed on a speed grid and located by a scalar root solve (brentq) of
f_k(speed) - line(speed), to CRITICAL_XTOL relative to the top speed.
"""
import csv
import json
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq

from pipeline import compute
from pipeline.config import ConfigError
from rotorkernels import modal


# |zeta| below this is the eigen-solver's rounding of an undamped mode (|Re s| ~ eps |s|): printed as 0.
ZETA_ROUNDING = 1e-12


def scene_values(data, point):
    """The model's values at a point {axis: value} of the scene (its fixed values filled in)."""
    spec = compute.model_of(data)
    return {**compute.scene_values(data, spec), **compute.fixed_values(data), **point}


def require_linearization(spec):
    """ConfigError saying why, for a model without a linearization (one line, exit status 2)."""
    if not spec.has_linearization:
        raise ConfigError(spec.linearization_problem())


def modes(spec, values, equilibrium=None):
    """The modes at `values` (list of rotorkernels.modal.LinearMode), by increasing damped
    frequency; `equilibrium`: the static state if already known (it does not depend on speed)."""
    _, system = spec.linear_system(values, equilibrium)
    return modal.modes_of(system.M, system.C, system.G, system.K, modal.kinds_from_names(system.coordinates))


def campbell(spec, values, speeds_hz):
    """Rows (speed [Hz], mode index, damped frequency [Hz], damping ratio, whirl, label) over the
    speeds (the model's `speed` parameter)."""
    eq, _ = spec.linear_system(values)
    return [(float(f), k, m.frequency, m.damping_ratio, m.whirl, m.label)
            for f in speeds_hz for k, m in enumerate(modes(spec, {**values, spec.speed: float(f)}, eq))]


# speeds of the grid that brackets the crossings; two crossings of one mode with one line closer
# than top / CRITICAL_GRID may be missed (then neither is reported, the sign not changing)
CRITICAL_GRID = 200
CRITICAL_XTOL = 1e-12
# default search range of critical speeds: to this multiple of the highest damped frequency at rest
CRITICAL_RANGE = 2.0


class Line(NamedTuple):
    """An excitation line of a Campbell diagram: f = slope * speed + offset [Hz]."""
    name: str
    slope: float
    offset: float

    def at(self, speed):
        return self.slope * speed + self.offset


class CriticalSpeed(NamedTuple):
    speed_hz: float       # shaft speed of the crossing
    frequency_hz: float   # the mode's damped frequency there (= the line's)
    line: str             # the excitation line's name
    mode: int             # index of the mode by increasing damped frequency
    whirl: str
    label: str
    damping_ratio: float


def excitation_lines(spec, values):
    """The 1x line and, where the model names a support frequency and it is > 0, its line."""
    lines = [Line("1x", 1.0, 0.0)]
    support = float(values.get(spec.support_frequency, 0.0) or 0.0) if spec.support_frequency else 0.0
    if support > 0:
        lines.append(Line(f"support {support:g} Hz", 0.0, support))
    return lines


def critical_speeds(modes_at, speeds_hz, lines):
    """CriticalSpeed of every crossing of a damped frequency with a line over the speed grid
    `speeds_hz` (ascending, > 0), by speed; modes_at(speed) -> list of LinearMode. A bracket
    where the number of oscillating modes changes (a mode turning overdamped) is skipped."""
    speeds = np.asarray(speeds_hz, float)
    table = [[m.frequency for m in modes_at(s)] for s in speeds]
    found = []
    for line in lines:
        for i in range(len(speeds) - 1):
            lo, hi = table[i], table[i + 1]
            if len(lo) != len(hi):
                continue
            for k in range(len(lo)):
                g_lo, g_hi = lo[k] - line.at(speeds[i]), hi[k] - line.at(speeds[i + 1])
                if g_lo * g_hi > 0 or g_hi == 0:
                    continue
                root = brentq(lambda s: modes_at(s)[k].frequency - line.at(s), speeds[i], speeds[i + 1],
                              xtol=CRITICAL_XTOL * speeds[-1], rtol=4 * np.finfo(float).eps)
                m = modes_at(root)[k]
                found.append(CriticalSpeed(float(root), m.frequency, line.name, k, m.whirl, m.label, m.damping_ratio))
    return sorted(found, key=lambda c: (c.speed_hz, c.frequency_hz))


def critical_speed_range(spec, values, equilibrium=None):
    """Default speeds [Hz] to search critical speeds over: above 0 to CRITICAL_RANGE x the
    highest damped frequency at rest (and at least to the highest support line)."""
    at_rest = modes(spec, {**values, spec.speed: 0.0}, equilibrium)
    top = CRITICAL_RANGE * max([m.frequency for m in at_rest] + [ln.offset for ln in excitation_lines(spec, values)])
    return np.linspace(0.0, top, CRITICAL_GRID + 1)[1:]


def scene_critical_speeds(spec, values, speeds_hz=None):
    """critical_speeds of a model with a shaft speed at `values` over `speeds_hz` [Hz]
    (default critical_speed_range)."""
    eq, _ = spec.linear_system(values)
    speeds = critical_speed_range(spec, values, eq) if speeds_hz is None else speeds_hz
    return critical_speeds(lambda s: modes(spec, {**values, spec.speed: float(s)}, eq), speeds,
                           excitation_lines(spec, values))


def station_shapes(mode, coordinates):
    """{station: (X, Y)}: the complex transverse amplitudes of each station of a mode (a journal
    or bearing centre: the coordinates "x1", "y1" make station "1"); its orbit over one period is
    x = Re(X e^{i theta}), y = Re(Y e^{i theta}), theta in [0, 2 pi)."""
    kinds = modal.kinds_from_names(coordinates) or ()
    found = {}
    for value, (axis, station) in zip(mode.shape, kinds):
        if axis in ("x", "y"):
            found.setdefault(station, {})[axis] = complex(value)
    return {station: (c["x"], c["y"]) for station, c in found.items() if len(c) == 2}


def omega_l(data):
    """omega_l [Hz] of a scene: the model's own (`ModelSpec.omega_l`) at the scene's first grid point."""
    spec = compute.model_of(data)
    first = {name: float(values[0]) for name, values in data["sweep"].items()}
    return spec.omega_l(scene_values(data, first))


CAMPBELL_COLUMNS = ("speed_hz", "mode", "frequency_hz", "damping_ratio", "whirl", "label")


def write_campbell(rows, path):
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(CAMPBELL_COLUMNS)
        writer.writerows(rows)


def log_decrement(zeta):
    return 2.0 * np.pi * zeta / np.sqrt(1.0 - zeta ** 2)


def records(spec, values):
    """The static state and the modes at one point as plain data (what `modes --json` prints)."""
    eq, system = spec.linear_system(values)
    found = modes(spec, values, eq)
    return {
        "model": spec.name,
        "speed_hz": float(values[spec.speed]) if spec.speed else None,
        "equilibrium": {"coordinates": list(system.coordinates), "position": eq.position.tolist(),
                        "residual": float(eq.residual), "iterations": int(eq.iterations), "note": eq.note},
        "modes": [{"damped_frequency_hz": m.frequency, "undamped_frequency_hz": float(m.undamped_frequency),
                   "damping_ratio": m.damping_ratio, "log_decrement": float(log_decrement(m.damping_ratio)),
                   "whirl": m.whirl, "label": m.label,
                   "shape_real": m.shape.real.tolist(), "shape_imag": m.shape.imag.tolist()} for m in found],
        **(critical_records(spec, values, eq) if spec.speed else {}),
    }


def critical_records(spec, values, equilibrium):
    """{"critical_speeds": [...], "critical_speed_search_hz": [lo, hi]} (records' part)."""
    speeds = critical_speed_range(spec, values, equilibrium)
    found = scene_critical_speeds(spec, values, speeds)
    return {"critical_speed_search_hz": [float(speeds[0]), float(speeds[-1])],
            "critical_speeds": [c._asdict() for c in found]}


def summary(spec, values):
    """Text: the static state and the modes at one point (what `rotorsweep modes` prints)."""
    rec = records(spec, values)
    eq = rec["equilibrium"]
    where = f" at {rec['speed_hz']:g} Hz shaft speed" if spec.speed else ""
    lines = [f"static equilibrium: q = {np.array2string(np.array(eq['position']), precision=4)} "
             f"({', '.join(eq['coordinates'])}, SI), relative residual {eq['residual']:.1e} "
             f"({eq['iterations']} Newton iterations)"]
    lines += [eq["note"]] if eq["note"] else []
    lines += [f"modes{where}: damped frequency f_d = Im(s) / 2 pi, undamped f_n = |s| / 2 pi, "
              "damping ratio zeta = -Re(s) / |s|",
              f"{'#':>2} {'f_d [Hz]':>14} {'f_n [Hz]':>14} {'zeta':>8} {'whirl':>9} {'label':>12}"]
    for k, m in enumerate(rec["modes"]):
        zeta = m["damping_ratio"] if abs(m["damping_ratio"]) > ZETA_ROUNDING else 0.0
        lines.append(f"{k:>2} {m['damped_frequency_hz']:>14.6g} {m['undamped_frequency_hz']:>14.6g} "
                     f"{zeta:>8.4f} {m['whirl']:>9} {m['label']:>12}")
    if "critical_speeds" in rec:
        lines += critical_lines(rec)
    return "\n".join(lines)


def critical_lines(rec):
    """Text lines of the critical speeds in a records() dict."""
    lo, hi = rec["critical_speed_search_hz"]
    crit = rec["critical_speeds"]
    head = (f"critical speeds (damped frequency = excitation line) between {lo:.4g} and {hi:.4g} Hz: "
            + ("" if crit else "none"))
    rows = [f"{'speed [Hz]':>14} {'f_d [Hz]':>14} {'line':>16} {'mode':>4} {'whirl':>9} {'label':>12}"] if crit else []
    rows += [f"{c['speed_hz']:>14.6g} {c['frequency_hz']:>14.6g} {c['line']:>16} {c['mode']:>4} "
             f"{c['whirl']:>9} {c['label']:>12}" for c in crit]
    return [head] + rows


def command(cfg, at, campbell_speeds=None, output=None, as_json=False):
    """`rotorsweep modes`: the summary at the scene's first grid point (axis values from `at`
    {axis: value} where given) and, with `output`, the Campbell table over `campbell_speeds`
    [Hz] (default: the scene's speed axis) as CSV. Returns the text to print."""
    spec = compute.model_of(cfg.data)
    require_linearization(spec)
    first = {name: float(values[0]) for name, values in cfg.axes.items()}
    values = scene_values(cfg.data, {**first, **at})
    text = json.dumps(records(spec, values), indent=1) if as_json else summary(spec, values)
    if output is not None:
        speeds = _campbell_speeds(spec, cfg, campbell_speeds)
        write_campbell(campbell(spec, values, speeds), output)
        if not as_json:
            text += f"\nCampbell table ({len(speeds)} speeds): {output}"
    return text


def _campbell_speeds(spec, cfg, given):
    if not spec.speed:
        raise ConfigError(f"modes --output: model {spec.name} has no shaft speed, so no Campbell table")
    if given is not None:
        return given
    if spec.speed not in cfg.axes:
        raise ConfigError(f"modes --output: the scene does not sweep {spec.speed}; give --campbell START:STOP:NUM")
    return cfg.axes[spec.speed]

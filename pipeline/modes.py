"""Linear analysis of a scene (`rotorsweep modes`), for every model whose spec has a linearization
(`ModelSpec.linear_system`): its static equilibrium, the linearized modes at one point, and a
Campbell table over shaft speed for the models that name one (`ModelSpec.speed`).

Linearization about the static equilibrium q_s: M q'' + (C + G) q' + K q = 0 (the model's own,
e.g. rigid_preloaded's analytic stiffness of the ball sums). The modes, their damped and undamped
natural frequencies, damping ratios, whirl directions and labels are rotorkernels.modal's
(`modes_of`, whose docstring gives the conventions): eigenvalues s = -zeta w_n +- i w_d, each mode
once (w_d > 0), by increasing damped frequency; the logarithmic decrement is 2 pi zeta / sqrt(1 - zeta^2).
"""
import csv
import json

import numpy as np

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
    }


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
    return "\n".join(lines)


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

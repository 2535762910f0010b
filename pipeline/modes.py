"""Linear analysis of a scene (`rotorsweep modes`), for every model whose spec has a linearization
(`ModelSpec.linear_system`): its static equilibrium, the linearized modes at one point, and a
Campbell table over shaft speed for the models that name one (`ModelSpec.speed`).

Linearization about the static equilibrium q_s: M q'' + (C + G) q' + K q = 0 (the model's own,
e.g. rigid_preloaded's analytic stiffness of the ball sums). The modes, their damped and undamped
natural frequencies, damping ratios, whirl directions and labels are rotorsweep.kernels.modal's
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

from rotorsweep.pipeline import config, fileio, gridsize, point_input
from rotorsweep.pipeline.config import ConfigError
from rotorsweep.kernels import modal


def scene_values(scene, point):
    """The model's values at a point {axis: value} of a scene (rotorsweep.pipeline.scene.Scene; its fixed
    values filled in)."""
    return {**scene.values, **scene.fixed, **point}


def require_linearization(spec):
    """ConfigError saying why, for a model without a linearization (one line, exit status 2)."""
    if not spec.has_linearization:
        raise ConfigError(spec.linearization_problem())


def modes(spec, values, equilibrium=None):
    """The modes at `values` (list of rotorsweep.kernels.modal.LinearMode), by increasing damped
    frequency; `equilibrium`: the static state if already known (it does not depend on speed)."""
    _, system = spec.linear_system(values, equilibrium)
    found = modal.modes_of(system.M, system.C, system.G, system.K, modal.kinds_from_names(system.coordinates))
    upper, noise = zeta_rounding(system)
    return [m._replace(damping_ratio=0.0) if abs(m.damping_ratio) <= noise[np.argmin(np.abs(upper.imag - m.omega))]
            else m for m in found]


def zeta_rounding(system):
    """(eigenvalues s with Im s > 0 of the first-order form, the rounding error of each damping
    ratio -Re s / |s|): below it a damping ratio is the eigen-solver's noise, and modes() gives 0
    (an undamped scene has exactly zero damping). numpy's eig is LAPACK's dgeev, which balances A
    into B first; its computed s is off by about eps ||B||_1 / rcond(s), rcond(s) = |y^H x| of the
    unit left and right eigenvectors (LAPACK Users' Guide, "Error bounds for the nonsymmetric
    eigenproblem", the bound dgeevx returns), times a modest function of the order, here the order
    2n itself. For the 2010 papers' undamped rotors that is 2e-15 to 1.5e-14, their noise 1e-17 to 4e-16."""
    import scipy.linalg  # on first use: `import rotorsweep` loads no scipy solvers

    b, _ = scipy.linalg.matrix_balance(modal.first_order(system.M, system.C + system.G, system.K))
    s, left, right = scipy.linalg.eig(b, left=True, right=True)
    rcond = np.abs(np.sum(left.conj() * right, axis=0))        # columns of unit 2-norm
    upper = s.imag > 0
    return s[upper], (len(b) * np.finfo(float).eps * np.linalg.norm(b, 1) / rcond / np.abs(s))[upper]


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
    from scipy.optimize import brentq  # on first use: `import rotorsweep` loads no scipy solvers

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


DISK_STATION = "disc"


def station_shapes(mode, coordinates, disk=None):
    """{station: (X, Y)}: the complex transverse amplitudes of each station of a mode (a journal
    or bearing centre: the coordinates "x1", "y1" make station "1"); its orbit over one period is
    x = Re(X e^{i theta}), y = Re(Y e^{i theta}), theta in [0, 2 pi). With `disk` = (xi_D, l) of a
    rigid rotor (`ModelSpec.disk_position`), also the disc's station DISK_STATION: a rigid shaft's
    section at xi_D moves as (1 - xi_D / l) times the first station plus xi_D / l times the second."""
    kinds = modal.kinds_from_names(coordinates) or ()
    found = {}
    for value, (axis, station) in zip(mode.shape, kinds):
        if axis in ("x", "y"):
            found.setdefault(station, {})[axis] = complex(value)
    shapes = {station: (c["x"], c["y"]) for station, c in found.items() if len(c) == 2}
    if disk is not None and len(shapes) >= 2:
        s = disk[0] / disk[1]
        (xa, ya), (xb, yb) = list(shapes.values())[:2]
        shapes[DISK_STATION] = ((1 - s) * xa + s * xb, (1 - s) * ya + s * yb)
    return shapes


def disk_of(spec, values):
    """(xi_D, l) [m] of the model's disc at `values`, or None for a model that names none."""
    return spec.disk_position(values) if spec.disk_position is not None else None


def omega_l(scene):
    """omega_l [Hz] of a scene: the model's own (`ModelSpec.omega_l`) at the scene's first grid point."""
    first = {name: float(values[0]) for name, values in scene.axes.items()}
    return scene.model.omega_l(scene_values(scene, first))


CAMPBELL_COLUMNS = ("speed_hz", "mode", "frequency_hz", "damping_ratio", "whirl", "label")


def write_campbell(rows, path):
    """The Campbell table as CSV, atomically (a reader sees no file or the whole table); an OS
    error (a full disk) is one line naming `path`."""
    try:
        with fileio.atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(CAMPBELL_COLUMNS)
            writer.writerows(rows)
    except OSError as exc:
        raise fileio.FileIOError(f"modes -o {path}: {exc.strerror or exc}; the table was not written") from None


# A Campbell table is held in memory as rows (a tuple of six Python objects per speed and mode,
# ~400 bytes) while it is computed and written: at most the machine's memory over this many
# bytes per row and CAMPBELL_COPIES, and at most numerics.max_points speeds (the sweep's guard
# against a typo in a grid).
CAMPBELL_BYTES_PER_ROW = 512
CAMPBELL_COPIES = 2


def campbell_speeds(text, spec, data):
    """The shaft speeds [Hz] of `--campbell START:STOP:NUM`, checked as a config axis: numbers,
    finite, within the speed parameter's limits, NUM >= 1 and within memory and max_points;
    ConfigError naming the option otherwise."""
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        num = int(parts[2])
    except ValueError:
        raise ConfigError(f"--campbell {text}: expected START:STOP:NUM (speeds in Hz or unit strings, NUM an "
                          "integer), e.g. 0:200:101 or \"600 rpm:3000 rpm:9\"") from None
    ends = point_input.flag_values({"start": ("--campbell START", parts[0].strip()),
                                    "stop": ("--campbell STOP", parts[1].strip())}, spec,
                                   unit_of={"start": "Hz", "stop": "Hz"})
    start, stop = ends["start"], ends["stop"]
    key = spec.parameter(spec.speed) if spec.speed else None
    for name, value in (("START", start), ("STOP", stop)):
        problem = config.check_number(value, key) if key else None
        if problem:
            raise ConfigError(f"--campbell {text}: {name} {problem} (the limits of {spec.speed})")
    n_modes = spec.n_position or 1
    cap = min(gridsize.memory_bytes() // (CAMPBELL_COPIES * CAMPBELL_BYTES_PER_ROW * n_modes), data["numerics"]["max_points"])
    if not 1 <= num <= cap:
        raise ConfigError(f"--campbell {text}: NUM must be 1 to {cap} (numerics.max_points, or what this "
                          f"machine's memory holds at {n_modes} modes per speed); got {num}")
    return np.linspace(start, stop, num)


def at_point(cfg, at):
    """The point of `modes --at` {axis: value}: the scene's first grid point with the given axis
    values, each an axis of the model within its limits; ConfigError naming --at otherwise.
    (The scene's own checks of forced orbits, such as a common forcing period, do not apply to
    the linear modes.)"""
    spec = cfg.model
    for name, value in at.items():
        if name not in spec.axes:
            raise ConfigError(f"--at {name}: not an axis of model {spec.name} (axes: {', '.join(spec.axes)})")
        par = spec.parameter(name)
        problem = config.check_number(value, par)
        if problem:
            raise ConfigError(f"--at {name}={value:g}: {problem} (the limits of {name}"
                              f"{f': {par.help}' if par.help else ''})")
    first = {name: float(values[0]) for name, values in cfg.axes.items()}
    return {**first, **at}


def log_decrement(zeta):
    return 2.0 * np.pi * zeta / np.sqrt(1.0 - zeta ** 2)


def records(spec, values):
    """The static state and the modes at one point as plain data (what `modes --json` prints)."""
    eq, system = spec.linear_system(values)
    found = modes(spec, values, eq)
    disk = disk_of(spec, values)
    return {
        "model": spec.name,
        "speed_hz": float(values[spec.speed]) if spec.speed else None,
        "equilibrium": {"coordinates": list(system.coordinates), "position": eq.position.tolist(),
                        "residual": float(eq.residual), "iterations": int(eq.iterations), "note": eq.note},
        "modes": [{"damped_frequency_hz": m.frequency, "undamped_frequency_hz": float(m.undamped_frequency),
                   "damping_ratio": m.damping_ratio, "log_decrement": float(log_decrement(m.damping_ratio)),
                   "whirl": m.whirl, "label": m.label,
                   "shape_real": m.shape.real.tolist(), "shape_imag": m.shape.imag.tolist(),
                   "stations": station_records(m, system.coordinates, disk)} for m in found],
        **({"disk_position_m": disk[0], "bearing_span_m": disk[1]} if disk is not None else {}),
        **(critical_records(spec, values, eq) if spec.speed else {}),
    }


def station_records(mode, coordinates, disk):
    """{station: {"x_real", "x_imag", "y_real", "y_imag"}}: station_shapes as plain numbers."""
    return {str(name): {"x_real": x.real, "x_imag": x.imag, "y_real": y.real, "y_imag": y.imag}
            for name, (x, y) in station_shapes(mode, coordinates, disk).items()}


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
        lines.append(f"{k:>2} {m['damped_frequency_hz']:>14.6g} {m['undamped_frequency_hz']:>14.6g} "
                     f"{m['damping_ratio']:>8.4f} {m['whirl']:>9} {m['label']:>12}")
    lines += shape_lines(rec)
    if "critical_speeds" in rec:
        lines += critical_lines(rec)
    return "\n".join(lines)


def shape_lines(rec):
    """Text lines of the mode shapes in a records() dict: per mode, each station's |X| and |Y|
    (the largest coordinate amplitude of the mode is 1)."""
    if not any(m["stations"] for m in rec["modes"]):
        return []
    disk = (f"; disc at {rec['disk_position_m']:g} m of the {rec['bearing_span_m']:g} m span"
            if "disk_position_m" in rec else "")
    lines = [f"mode shapes: |x|, |y| amplitude of each station (largest coordinate 1){disk}"]
    for k, m in enumerate(rec["modes"]):
        cells = [f"{name} ({abs(complex(c['x_real'], c['x_imag'])):.3f}, {abs(complex(c['y_real'], c['y_imag'])):.3f})"
                 for name, c in m["stations"].items()]
        lines.append(f"  mode {k}: " + "  ".join(cells))
    return lines


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


def command(cfg, at, campbell_text=None, output=None, as_json=False, report=None):
    """`rotorsweep modes`: the summary at the scene's first grid point (axis values from `at`
    {axis: value} where given) and, with `output`, the Campbell table over `--campbell`
    START:STOP:NUM [Hz] (default: the scene's speed axis) as CSV; with `report` (a directory),
    the HTML report (rotorsweep.pipeline.report.modes_report; its Campbell diagram over `--campbell`, default
    the critical-speed search range). Returns the text to print. Every option is checked before
    any work; a linearization that fails at the point asked for (a singular matrix, non-finite
    values) is one line naming --at."""
    spec = cfg.model
    require_linearization(spec)
    point = at_point(cfg, at)
    if campbell_text is not None and output is None and report is None:
        raise ConfigError(f"--campbell {campbell_text}: give -o FILE.csv (the Campbell table as CSV) or --report DIR")
    speeds = _campbell_speeds(spec, cfg, campbell_text) if output is not None else None
    diagram = _campbell_speeds(spec, cfg, campbell_text) if report is not None and campbell_text is not None else None
    values = scene_values(cfg.scene, point)
    try:
        text = json.dumps(records(spec, values), indent=1) if as_json else summary(spec, values)
        rows = campbell(spec, values, speeds) if output is not None else None
        files = _report(cfg, point, report, diagram) if report is not None else None
    except (np.linalg.LinAlgError, ValueError, FloatingPointError) as exc:
        where = ", ".join(f"{k}={v:g}" for k, v in point.items())
        raise ConfigError(f"--at: no linearization at {where}"
                          f"{' over the --campbell speeds' if speeds is not None else ''} ({exc})") from None
    if output is not None:
        write_campbell(rows, output)
        if not as_json:
            text += f"\nCampbell table ({len(speeds)} speeds): {output}"
    if files is not None and not as_json:
        text += f"\nreport: {files['html']}" + "".join(f"\nfigure: {png}" for png in files["png"])
    return text


def _report(cfg, point, out_dir, speeds):
    from rotorsweep.pipeline.report import modes_report    # on first use: the text summary loads no plotting

    return modes_report.make_report(cfg, point, out_dir, speeds)


def _campbell_speeds(spec, cfg, given):
    if not spec.speed:
        raise ConfigError(f"modes --campbell/--output: model {spec.name} has no shaft speed, so no Campbell table")
    if given is not None:
        return campbell_speeds(given, spec, cfg.data)
    if spec.speed not in cfg.axes:
        raise ConfigError(f"modes --output: the scene does not sweep {spec.speed}; give --campbell START:STOP:NUM")
    return cfg.axes[spec.speed]

"""`rotorsweep backbone`: the nonlinear normal modes of a conservative model (symmetric4,
asymmetric5: Filipkovsky 2010) and their backbone curves, two ways, into a netCDF *backbone result*.

For every mode asked for ([backbone] modes) and every combination of the swept axes (a *line*,
one Dask task):

- the Shaw-Pierre invariant manifold to cubic order (rotorsweep.kernels.nnm): its coefficients, the
  reduced one-DOF oscillator, its backbone omega(A) = omega_0 + kappa A^2 on the amplitude grid;
- the reference backbone by pseudo-arclength continuation of the full model's periodic orbits
  (rotorsweep.kernels.continuation.backbone), its frequency at the same amplitudes, their difference
  and the amplitude where they part by 1 %.

Amplitude: the first harmonic of the master coordinate's displacement [m] (the manifold's
amplitude; each continued orbit's is taken from its samples), on a log-spaced grid. The manifold
and the continuation use the same master: the position with the largest component of the mode.
A repeated linear frequency (symmetric4's cylindrical pair) is continued in the model's invariant
plane holding the manifold's planar mode (the spec's `invariant_subspaces`).

The continuation frequency on the grid interpolates the continued points by a cubic spline in A^2
(omega is a smooth function of A^2: omega_0 + kappa A^2 + O(A^4)), inside the amplitudes reached.
"""
import itertools
import json
import re
import sys
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from rotorsweep.pipeline import cluster, plainnc, result_kinds, results
from rotorsweep.pipeline.config import ConfigError, settings_problems
from rotorsweep.kernels import nnm
from rotorsweep.kernels.continuation import backbone as cb
from rotorsweep.kernels.continuation.arclength import Settings

AUTO_FRACTION = 0.25        # default amplitude_max: this fraction of the model's amplitude bound (series: z0)
PART_RTOL = 0.01            # the manifold and the continuation "part" at this relative difference
SURFACE_POINTS = 21         # the report's manifold surface: a SURFACE_POINTS^2 grid in (p, r)
ORBIT_PERIODS, ORBIT_SAMPLES = 10, 32   # the full-system orbit drawn on the surface (the papers' check)


@dataclass(frozen=True)
class Plan:
    modes: tuple | None         # 0-based mode indices; None: all
    amplitude_max: float | None
    amplitude_min: float | None
    points: int
    continuation: bool
    settings: Settings
    surface_mode: int           # 0-based
    lines: tuple                # dicts {swept axis: value}
    axes: tuple                 # names of the swept axes (the result's leading dimensions)


def plan(scene, check_lines=True):
    """The backbones a scene (rotorsweep.pipeline.scene.Scene) asks for; raises ConfigError naming every key
    that cannot work (before any work starts). check_lines: also check every line's modes and
    amplitudes (the driver does; a line's task need not repeat it for all the others)."""
    spec = scene.model
    if spec.polynomial is None:
        raise ConfigError(f"scene.model: {spec.name} is not a conservative polynomial model; backbones are "
                          f"computed for {', '.join(_conservative_models())}")
    sec = scene.backbone
    errors = []
    modes = _modes(sec.modes, errors)
    settings = Settings(ds=sec.ds, ds_max=sec.ds_max, max_steps=sec.max_steps, tol=scene.newton.tol)
    errors += settings_problems(settings.problems(), "backbone", vars(sec))
    a_max, a_min = sec.amplitude_max, sec.amplitude_min
    if a_max is None and not spec.amplitude_bound:
        errors.append(f"backbone.amplitude_max: required for model {spec.name} (it states no amplitude bound "
                      "to take a default from)")
    if a_max is not None and a_min is not None and a_min >= a_max:
        errors.append(f"backbone.amplitude_min: {a_min!r} m must be below backbone.amplitude_max ({a_max!r} m)")
    axes = tuple(scene.axes)
    lines = tuple(dict(zip(axes, map(float, combo))) for combo in itertools.product(*scene.axes.values()))
    pl = Plan(modes, a_max, a_min, sec.amplitude_points, sec.continuation, settings,
              sec.surface_mode - 1, lines, axes)
    if not errors and check_lines:
        errors += _line_problems(scene, pl)
    if errors:
        raise ConfigError("\n".join(errors))
    return pl


def _conservative_models():
    from rotorsweep.kernels import models
    return [name for name, spec in models.REGISTRY.items() if spec.polynomial is not None]


def _modes(text, errors):
    if text.strip() == "all":
        return None
    if not re.fullmatch(r"\s*[0-9]+(\s*[, ]\s*[0-9]+)*\s*", text):
        errors.append(f"backbone.modes: {text!r} is neither \"all\" nor mode numbers such as \"1, 3\" (1 = lowest)")
        return None
    numbers = [int(m) for m in re.split(r"[\s,]+", text.strip())]
    if min(numbers) < 1:
        errors.append(f"backbone.modes: mode numbers start at 1 (the lowest linear frequency); got {min(numbers)}")
    return tuple(sorted({m - 1 for m in numbers}))


def amplitude_bound(spec, values):
    """The model's amplitude bound [m] at `values` (ModelSpec.amplitude_bound; the series rotors'
    preload axial approach z0, where the cubic series, the ball sum's Taylor expansion about the
    preloaded state, loses its meaning); inf for a model without one."""
    return spec.build(values).derived[spec.amplitude_bound] if spec.amplitude_bound else np.inf


def _line_problems(scene, pl):
    """Per line: the modes exist, the amplitudes stay below the model's amplitude bound."""
    spec = scene.model
    out = []
    for where in pl.lines:
        values = line_values(scene, where)
        n = len(nnm.linear_modes(spec.polynomial(values)))
        z0 = amplitude_bound(spec, values)
        label = ", ".join(f"{k} = {v:g}" for k, v in where.items()) or "the scene"
        wanted = list(pl.modes or ()) + [pl.surface_mode]
        if max(wanted) >= n:
            key = "backbone.modes" if pl.modes and max(pl.modes) >= n else "backbone.surface_mode"
            out.append(f"{key}: mode {max(wanted) + 1} does not exist; the model has {n} modes (1 to {n})")
        a_max, a_min = (float(a) for a in amplitudes(pl, z0)[[-1, 0]])
        if a_max >= z0:
            out.append(f"backbone.amplitude_max: {a_max:g} m reaches the {spec.derived[spec.amplitude_bound][1]} = "
                       f"{z0:.4g} m at {label}: the model's law is meaningless there (keep amplitudes well below it)")
        elif a_min >= a_max:
            out.append(f"backbone.amplitude_min: {a_min:g} m must be below the amplitude_max {a_max:.4g} m at {label}")
        if out:
            break
    return out


def line_values(scene, where):
    """The model's parameter values at one line of a scene."""
    return {**scene.values, **scene.fixed, **where}


def amplitudes(pl, z0):
    """The amplitude grid [m] of a line whose amplitude bound is z0."""
    a_max = pl.amplitude_max if pl.amplitude_max is not None else AUTO_FRACTION * z0
    a_min = pl.amplitude_min if pl.amplitude_min is not None else a_max / 100
    return np.geomspace(a_min, a_max, pl.points)


# --- one line ------------------------------------------------------------------------------------

def backbone_line(scene, where):
    """Every mode of one line (a Dask task): a dict of numpy arrays (mode records stacked)."""
    pl = plan(scene, check_lines=False)
    spec = scene.model
    values = line_values(scene, where)
    system = spec.polynomial(values)
    z0 = amplitude_bound(spec, values)
    grid = amplitudes(pl, z0)
    modes = nnm.linear_modes(system)
    chosen = pl.modes if pl.modes is not None else tuple(range(len(modes)))
    opts = scene.integrator
    records = [mode_record(spec, values, system, modes, k, grid, pl, opts) for k in chosen]
    man = records[chosen.index(pl.surface_mode)]["manifold"] if pl.surface_mode in chosen else None
    surface = surface_record(system, man or _manifold_or_none(system, pl.surface_mode), grid[-1])
    return {"grid": grid, "z0": z0 if np.isfinite(z0) else np.nan, "modes": chosen,
            "records": [_plain(r) for r in records], "surface": surface}


def _manifold_or_none(system, k):
    try:
        return nnm.manifold(system, k)
    except ValueError:
        return None


def _plain(record):
    return {k: v for k, v in record.items() if k != "manifold"}


def mode_record(spec, values, system, modes, k, grid, pl, opts):
    """Manifold and continuation backbones of mode k on the amplitude grid."""
    bb = continued_backbone(spec, values, modes, k, grid, pl, opts) if pl.continuation else None
    master = bb.coordinate if bb is not None and bb.status != "start_failed" else None
    f_cont = frequency_on_grid(bb, grid) if bb is not None else np.full(grid.size, np.nan)
    record = {"linear_frequency": modes[k].frequency, "label": modes[k].label, "whirl": modes[k].whirl,
              "frequency_continuation": f_cont, **_continuation_fields(bb)}
    try:
        man = nnm.manifold(system, k, master=master)
    except ValueError as exc:     # an internal resonance the cubic manifold cannot carry: data, not a crash
        n_state = 2 * len(system.coordinates)
        return {**record, "manifold": None, "master": -1 if master is None else master, "kappa": np.nan,
                "sigma": np.nan, "reduced": np.full(len(nnm.MONOMIALS), np.nan),
                "coefficients": np.full((n_state, len(nnm.MONOMIALS)), np.nan), "notes": f"no manifold: {exc}",
                "frequency_manifold": np.full(grid.size, np.nan), "relative_difference": np.full(grid.size, np.nan),
                "parting_amplitude": np.nan, "invariance_distance": np.nan}
    f_man = nnm.backbone(man, grid)
    rel = (f_cont - f_man) / f_cont
    return {
        **record, "manifold": man, "master": man.master, "kappa": nnm.frequency_coefficient(man),
        "sigma": nnm.growth_coefficient(man), "reduced": np.array([man.reduced[m] for m in nnm.MONOMIALS]),
        "coefficients": man.coefficients, "notes": "; ".join(man.notes),
        "frequency_manifold": f_man, "relative_difference": rel, "parting_amplitude": parting_amplitude(grid, rel),
        "invariance_distance": nnm.invariance_error(system, man, grid[-1]),
    }


def continued_backbone(spec, values, modes, k, grid, pl, opts):
    """The continuation backbone of mode k, reaching a little beyond the grid (its amplitude is q_j
    at the turning point, a little above the first harmonic), from half the grid's first value."""
    z0 = amplitude_bound(spec, values)
    subspace = _subspace(spec, modes, k)
    index = _index_in(spec, values, subspace, modes[k].frequency)
    top = min(1.1 * grid[-1], 0.5 * (grid[-1] + z0))
    try:
        return cb.follow_backbone(spec, values, opts, index, top, pl.settings, subspace=subspace,
                                  amplitude_start=grid[0] / 2)
    except ValueError as exc:       # the plan checked the inputs: what is left is the model's own refusal
        empty = (np.zeros(0),) * 5 + (np.zeros((0, spec.n_state), complex), np.zeros(0))
        return cb.Backbone(*empty, coordinate=-1, linear_frequency=modes[k].frequency,
                           status="start_failed", detail=str(exc), n_rhs=0)


def _subspace(spec, modes, k):
    """None for a simple frequency; for a repeated one, the model's invariant subspace holding
    the manifold's (planar) mode, in the kernel's scaled state."""
    others = [m.omega for j, m in enumerate(modes) if j != k]
    if not np.any(np.abs(np.array(others) / modes[k].omega - 1) < cb.REPEATED_RTOL):
        return None
    scale = spec.to_physical(np.ones(spec.n_state), 1.0)
    v = modes[k].vector / scale
    for basis in spec.invariant_subspaces.values():
        q = np.linalg.qr(basis)[0]
        if np.linalg.norm(v - q @ (q.T @ v)) <= 1e-8 * np.linalg.norm(v):
            return basis
    return None     # follow_backbone then refuses the repeated frequency: a status, not a crash


def _index_in(spec, values, subspace, frequency):
    """Index of the linear mode of `frequency` [Hz] among follow_backbone's modes (in the subspace)."""
    built = spec.build(values)
    basis = np.eye(spec.n_state) if subspace is None else np.linalg.qr(subspace)[0]
    omegas, _ = cb.linear_modes(spec, built.p, basis)
    return int(np.argmin(np.abs(omegas / (2 * np.pi * built.period) - frequency)))


def frequency_on_grid(bb, grid):
    """The continued frequencies at the grid amplitudes (cubic spline in A^2; NaN outside the
    amplitudes reached or with fewer than 4 points)."""
    a, f = bb.harmonic_amplitude, bb.frequency
    out = np.full(grid.size, np.nan)
    if a.size < 4 or np.any(np.diff(a) <= 0):
        return out
    inside = (grid >= a[0]) & (grid <= a[-1])
    out[inside] = CubicSpline(a ** 2, f)(grid[inside] ** 2)
    return out


def parting_amplitude(grid, rel):
    """The smallest amplitude where |relative difference| reaches PART_RTOL (log-linear between
    grid points); NaN if it never does on the grid."""
    d = np.abs(rel)
    above = np.flatnonzero(d >= PART_RTOL)
    if above.size == 0:
        return np.nan
    i = above[0]
    if i == 0 or not np.isfinite(d[i - 1]):
        return float(grid[i])
    w = (np.log(PART_RTOL) - np.log(d[i - 1])) / (np.log(d[i]) - np.log(d[i - 1]))
    return float(np.exp(np.log(grid[i - 1]) + w * (np.log(grid[i]) - np.log(grid[i - 1]))))


def _continuation_fields(bb):
    if bb is None:
        return {"points": {}, "status": "not_computed", "detail": "backbone.continuation = false", "n_rhs": 0}
    mult = bb.multipliers
    off_unit = np.where(np.abs(mult - 1) > 1e-4, np.abs(np.abs(mult) - 1), 0.0)
    return {"points": {"amplitude_turning": bb.amplitude, "amplitude": bb.harmonic_amplitude, "frequency": bb.frequency,
                       "energy_drift": bb.energy_drift,
                       "unit_circle_error": off_unit.max(axis=1) if mult.size else np.zeros(0)},
            "status": bb.status, "detail": bb.detail, "n_rhs": bb.n_rhs}


def surface_record(system, man, amplitude):
    """The report's manifold figure: the slave coordinate moving most on the manifold's orbit of
    `amplitude`, over the master's (p, r) plane, and the full system's orbit integrated from the
    manifold there."""
    if man is None:
        return None
    n = len(system.coordinates)
    motion = nnm.coordinate_amplitudes(man, [amplitude])[0, :n]
    motion[man.master] = -1.0
    slave = int(np.argmax(motion))
    span = (-1.2 * amplitude, 1.2 * amplitude)
    p, r, value = nnm.surface(man, slave, span, tuple(man.omega * np.array(span)), SURFACE_POINTS)
    orbit = nnm.orbit_on_manifold(system, man, amplitude, ORBIT_PERIODS, ORBIT_SAMPLES)
    return {"mode": man.mode, "master": man.master, "slave": slave, "p": p[:, 0], "r": r[0], "value": value,
            "orbit_p": orbit.state[:, man.master], "orbit_r": orbit.state[:, n + man.master],
            "orbit_slave": orbit.state[:, slave], "orbit_manifold": orbit.manifold_state[:, slave],
            "t": orbit.t, "amplitude": amplitude}


# --- the result ----------------------------------------------------------------------------------

def to_dataset(scene, pl, lines, provenance):
    """The backbone result as an xarray.Dataset (to_result's variables; imports xarray)."""
    return to_result(scene, pl, lines, provenance).to_xarray()


def to_result(scene, pl, lines, provenance):
    """The backbone result's plain variables (plainnc.Plain; schema: result_kinds.BACKBONE_VARIABLES) of a scene: lines = [line
    dicts] in plan order, dims (swept axes..., mode, ...)."""
    spec = scene.model
    system = spec.polynomial(line_values(scene, pl.lines[0]))
    shape = tuple(len(scene.axes[a]) for a in pl.axes)
    first = lines[0]
    n_mode, n_amp = len(first["modes"]), first["grid"].size
    n_pt = max([len(r["points"].get("frequency", ())) for ln in lines for r in ln["records"]] + [1])
    names = tuple(system.coordinates) + tuple(c + "'" for c in system.coordinates)
    units = state_units(system.units)

    def stack(key, tail=(), dtype=float):
        out = np.empty((len(lines), n_mode) + tail, dtype)
        for i, ln in enumerate(lines):
            for k, r in enumerate(ln["records"]):
                out[i, k] = r[key]
        return out.reshape(shape + (n_mode,) + tail)

    def points(key):
        out = np.full((len(lines), n_mode, n_pt), np.nan)
        for i, ln in enumerate(lines):
            for k, r in enumerate(ln["records"]):
                vals = r["points"].get(key, ())
                out[i, k, :len(vals)] = vals
        return out.reshape(shape + (n_mode, n_pt))

    values = {
        "frequency_manifold": stack("frequency_manifold", (n_amp,)),
        "frequency_continuation": stack("frequency_continuation", (n_amp,)),
        "relative_difference": stack("relative_difference", (n_amp,)),
        "linear_frequency": stack("linear_frequency"), "kappa": stack("kappa"), "growth_rate": stack("sigma"),
        "parting_amplitude": stack("parting_amplitude"), "invariance_distance": stack("invariance_distance"),
        "master": stack("master", dtype="int32"), "mode_label": stack("label", dtype=object),
        "mode_whirl": stack("whirl", dtype=object), "reduced_coefficient": stack("reduced", (len(nnm.MONOMIALS),)),
        "manifold_coefficient": stack("coefficients", (len(names), len(nnm.MONOMIALS))),
        "manifold_notes": stack("notes", dtype=object), "continuation_end": stack("status", dtype=object),
        "continuation_detail": stack("detail", dtype=object), "continuation_rhs": stack("n_rhs", dtype="int64"),
        "point_amplitude": points("amplitude"), "point_amplitude_turning": points("amplitude_turning"),
        "point_frequency": points("frequency"), "point_energy_drift": points("energy_drift"),
        "point_unit_circle_error": points("unit_circle_error"),
        "axial_approach": np.array([ln["z0"] for ln in lines]).reshape(shape),
    }
    attrs = {"parting_amplitude": {"long_name": f"amplitude where manifold and continuation part by {PART_RTOL:.0%} "
                                                "(NaN: not on the grid)"}}
    surface_values, surface_attrs = _surface_variables(lines, pl, shape, names, units)
    values.update(surface_values)
    attrs.update(surface_attrs)
    coords = {a: (a, scene.axes[a], _axis_attrs(spec, a)) for a in pl.axes}
    coords["mode"] = ("mode", np.array(first["modes"]) + 1, {"units": "1", "long_name": "mode number (1 = lowest linear frequency)"})
    coords["amplitude_grid"] = (pl.axes + ("amplitude",), np.array([ln["grid"] for ln in lines]).reshape(shape + (n_amp,)),
                                {"units": "m", "long_name": "master amplitude (first harmonic of its displacement)"})
    coords["monomial"] = ("monomial", list(nnm.MONOMIALS), {"long_name": "monomials of the master displacement p and velocity r"})
    coords["state"] = ("state", list(names), {"long_name": "state components (coordinates, then velocities ')"})
    coords["state_units"] = ("state", list(units), {"long_name": "units of each state component"})
    global_attrs = {**provenance, "result_kind": result_kinds.BACKBONE, "Conventions": "CF-1.10",
                    "coordinates_units": json.dumps(list(system.units))}
    return plainnc.Plain(result_kinds.variables(result_kinds.BACKBONE, values, attrs, pl.axes), coords, global_attrs)


def _axis_attrs(spec, axis):
    par = spec.parameter(axis)
    return {"units": par.unit, "long_name": par.long_name or axis}


def state_units(coordinate_units):
    """Units of the state (coordinates, then their velocities) from the coordinates' units."""
    return tuple(coordinate_units) + tuple("s-1" if u == "1" else f"{u} s-1" for u in coordinate_units)


def _surface_variables(lines, pl, shape, names, units):
    """(values, run-time attrs) of the report's manifold surface; none where surface_mode has no
    manifold on any line (an internal resonance)."""
    drawn = [ln["surface"] for ln in lines if ln["surface"] is not None]
    if not drawn:
        return {}, {}
    s0 = drawn[0]
    n_p, n_t = len(s0["p"]), len(s0["t"])

    def stack(key, tail):
        return np.array([ln["surface"][key] if ln["surface"] is not None else np.full(tail, np.nan)
                         for ln in lines]).reshape(shape + tail)
    values = {"surface_value": stack("value", (n_p, n_p)), "surface_p_values": stack("p", (n_p,)),
              "surface_r_values": stack("r", (n_p,)), "orbit_p": stack("orbit_p", (n_t,)),
              "orbit_r": stack("orbit_r", (n_t,)), "orbit_slave": stack("orbit_slave", (n_t,)),
              "orbit_on_surface": stack("orbit_manifold", (n_t,)), "orbit_time": stack("t", (n_t,)),
              "surface_info": json.dumps({"mode": pl.surface_mode + 1, "master": names[s0["master"]],
                                          "slave": names[s0["slave"]], "amplitude": s0["amplitude"]})}
    slave = {"units": units[s0["slave"]]}
    return values, {name: slave for name in ("surface_value", "orbit_slave", "orbit_on_surface")}


# --- running -------------------------------------------------------------------------------------

def run(cfg, output, workers=None, scheduler=None, overwrite=False, stream=sys.stderr, resume=False):
    """Compute the backbones a config asks for into a netCDF result at `output`; returns its path.
    Line by line, each kept as a part file until the result is written (`resume`: see results.run_result)."""
    pl = plan(cfg.scene)

    def dataset(parts):
        results.say(stream, f"backbones of {cfg.scene.model_name} on {len(pl.lines)} line(s)"
                            f"{'' if pl.continuation else ' (manifold only)'}")
        lines = results.run_lines(cfg, backbone_line, pl.lines, workers, scheduler, stream, _line_summary, parts,
                                  unit="backbone_line")
        return to_result(cfg.scene, pl, lines, cluster.provenance(cfg, result_kinds.BACKBONE))
    return results.run_result(cfg, result_kinds.BACKBONE, output, dataset, stream, overwrite, scheduler, resume)


def _line_summary(line):
    parts = []
    for k, r in zip(line["modes"], line["records"]):
        part = f"{r['parting_amplitude'] * 1e6:.3g} um" if np.isfinite(r["parting_amplitude"]) else "no 1 % parting"
        parts.append(f"mode {k + 1} {r['label']} {r['linear_frequency']:.5g} Hz ({part}; {r['status']})")
    return "; ".join(parts)

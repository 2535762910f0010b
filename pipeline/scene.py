"""The scene: a validated config as one typed, frozen, picklable object, built once.

`rotorsweep.pipeline.config` validates a TOML file into a dict (every problem reported at once); `build`
turns that dict into a `Scene` here, once, in the driver. The tasks receive the scene (or the
piece they need: its integrator settings, its Newton settings, ...), never the config dict, and
nothing downstream looks a section key up again. The config's text and dict stay with the
`config.Config` for the result files' provenance (`cluster.provenance`), exactly as written.

A scene is small on purpose: it is a chunk task's argument (rotorsweep.pipeline.sweep), shipped with every
task, so it holds the axes once (as arrays) and the model by name (`models.get` on the worker).
"""
from dataclasses import dataclass, field, make_dataclass, replace

import numpy as np

from rotorsweep.pipeline import config
from rotorsweep.kernels import attractor, integrators, models

# A Lyapunov run measures at least this many forcing periods before its standard-error stop
# ([analysis] lyapunov_rtol; lowering it would save little: Fig. 13's chaotic runs have a median
# 5.6 % standard error after 1000 periods, so ~10 % -- its scene's tolerance -- at ~300):
# with two multipliers of nearly equal modulus (a gap of ~0.02 per period is common here) the
# tangent frame aligns slowly, and 100 periods left the exponent off by several standard errors
# (Fig. 13 at 1 Hz: 6 of 1032 stable points; 300 periods: none beyond 3 standard errors).
LYAPUNOV_MIN_PERIODS = 300


def _section_type(name, section):
    """A frozen dataclass whose fields are the keys of config.SCHEMA[section] (same names)."""
    return make_dataclass(name, list(config.SCHEMA[section]), frozen=True, namespace={"__module__": __name__})


# [continuation], [backbone] and [report] as the scene gives them (fields = the section's keys)
ContinuationKeys = _section_type("ContinuationKeys", "continuation")
BackboneKeys = _section_type("BackboneKeys", "backbone")
ReportKeys = _section_type("ReportKeys", "report")


@dataclass(frozen=True)
class Newton:
    """Shooting's Newton iteration ([numerics] newton_tol, max_newton_iter, transient_periods)."""
    tol: float
    max_iter: int
    transient_periods: int

    def solve_orbit_args(self, model):
        """Keyword arguments of rotorsweep.kernels.continuation.solve_orbit / natural for `model`."""
        return {"cold_guess": model.cold_guess, "tol": self.tol, "max_iter": self.max_iter,
                "transient_periods": self.transient_periods}


@dataclass(frozen=True)
class Analysis:
    """What every grid point computes ([analysis]): the periodic orbit (floquet), the attractor
    (attractor; `settings`: attractor.Settings from the keys of the same names, with the Lyapunov
    run's minimum length LYAPUNOV_MIN_PERIODS) in `sweep_direction`."""
    floquet: bool
    attractor: bool
    sweep_direction: str
    settings: attractor.Settings


@dataclass(frozen=True, eq=False)      # eq: the axes are arrays, which == does not reduce to a bool
class Scene:
    """One validated scene. values: the model's parameter values the scene's sections give (SI,
    None where not given); fixed: the axis parameters the scene fixes (their `unset` value where
    not given: derived per point); axes: {swept axis: grid values}, along: the continued axis;
    integrator: rotorsweep.kernels.integrators settings (amplitude limit scaled by the model);
    integrator_name: its [numerics] name; in_process_below: [run] in_process_below [s] (where it
    runs, rotorsweep.pipeline.cluster.runs_in_process; None: not given)."""
    name: str
    model_name: str
    description: str
    values: dict
    fixed: dict
    axes: dict = field(repr=False)
    along: str
    integrator: tuple
    integrator_name: str
    newton: Newton
    segment_length: int
    analysis: Analysis
    continuation: ContinuationKeys
    backbone: BackboneKeys
    report: ReportKeys
    in_process_below: float | None = None

    @property
    def model(self):
        """The scene's ModelSpec (looked up by name: a spec holds compiled functions, which a
        task's pickle should not carry)."""
        return models.get(self.model_name)


def analysis_of(section):
    """Analysis of an [analysis] table."""
    settings = attractor.Settings.from_keys(section)
    settings = replace(settings, lyapunov_min_periods=min(LYAPUNOV_MIN_PERIODS, settings.lyapunov_max_periods))
    return Analysis(section["floquet"], section["attractor"], section["sweep_direction"], settings)


def build(cfg):
    """The Scene of a validated config.Config."""
    return from_data(cfg.data, cfg.axes)


def of_result(text, written_version):
    """The Scene of a result file's config_toml, as the model version that wrote it (model_version
    attribute) read it: a key the text does not give takes the default of that version where it
    has changed since (ModelSpec.older_defaults)."""
    data = config.parse_config(text, path="<result config_toml>", allow_large=True).data
    given = config.tomllib.loads(text)
    for version, section, key, value in models.get(data["scene"]["model"]).older_defaults:
        if _version(written_version) < _version(version) and key not in given.get(section, {}):
            value = value(data[section]) if callable(value) else value
            data = {**data, section: {**data[section], key: value}}
    return from_data(data)


def _version(text):
    try:
        return int(text)
    except (TypeError, ValueError):
        return 1        # files before model versions were recorded


def from_data(data, axes=None):
    """The Scene of a validated config dict (a Config's `data`, or one a result file stores);
    axes: the Config's grid arrays (default: the dict's [sweep] values, the same numbers)."""
    spec = models.get(data["scene"]["model"])
    axes = {k: np.asarray(v, float) for k, v in (data["sweep"] if axes is None else axes).items()}
    values = {p.name: data[p.section][p.name] for p in spec.parameters if p.section is not None}
    fixed = {p.name: p.unset if values[p.name] is None else values[p.name]
             for p in spec.parameters if p.axis and p.section is not None}
    num = data["numerics"]
    opts = integrators.settings(num["integrator"], rtol=num["rtol"], atol=num["atol"],
                                steps_per_unit=num["rk4_steps"],
                                amplitude_limit=num["amplitude_limit"] / spec.length_scale)
    return Scene(
        name=data["scene"]["name"], model_name=spec.name, description=data["scene"]["description"],
        values=values, fixed=fixed, axes=axes, along=config.continued_axis(spec, axes),
        integrator=opts, integrator_name=num["integrator"],
        newton=Newton(num["newton_tol"], num["max_newton_iter"], num["transient_periods"]),
        segment_length=num["segment_length"], analysis=analysis_of(data["analysis"]),
        continuation=ContinuationKeys(**data["continuation"]), backbone=BackboneKeys(**data["backbone"]),
        report=ReportKeys(**data["report"]),
        in_process_below=data.get(config.RUN_SECTION, {}).get("in_process_below"))

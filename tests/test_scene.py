"""The scene object (rotorsweep.pipeline.scene): built once from a validated config, typed, frozen, small
when pickled into a chunk task."""
import dataclasses
import pickle
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import config, scene, sweep
from rotorsweep.kernels import attractor, integrators, models

ROOT = Path(__file__).resolve().parents[1]


def test_the_scene_holds_every_section_typed():
    cfg = config.parse_config(config.DEFAULT_CONFIG_TOML)
    s, data = cfg.scene, cfg.data
    assert s is cfg.scene                                   # built once per config
    assert s.name == "demo" and s.model is models.get("jeffcott_clearance") and s.along == "speed"
    assert list(s.axes) == list(cfg.axes) and all(np.array_equal(s.axes[k], cfg.axes[k]) for k in cfg.axes)
    assert s.values["mass"] == 2.0 and s.values["preset"] == "209"
    assert s.fixed == {"clearance": 0.0, "contact_angle": None, "preload": 0.0}   # clearance: swept too
    num = data["numerics"]
    assert s.integrator == integrators.settings(num["integrator"], rtol=num["rtol"], atol=num["atol"],
                                                steps_per_unit=num["rk4_steps"],
                                                amplitude_limit=num["amplitude_limit"] / s.model.length_scale)
    assert s.newton == scene.Newton(num["newton_tol"], num["max_newton_iter"], num["transient_periods"])
    assert s.segment_length == num["segment_length"] and s.integrator_name == num["integrator"]
    assert isinstance(s.analysis.settings, attractor.Settings)
    assert (s.analysis.attractor, s.analysis.floquet, s.analysis.sweep_direction) == (True, True, "up")
    assert s.analysis.settings.lyapunov_max_periods == data["analysis"]["lyapunov_max_periods"] == 500
    assert s.analysis.settings.lyapunov_min_periods == scene.LYAPUNOV_MIN_PERIODS
    for section in ("continuation", "backbone", "report"):
        assert dataclasses.asdict(getattr(s, section)) == data[section]
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.name = "other"


def test_a_scene_from_a_result_files_dict_is_the_configs():
    """A result file stores the config's text; its scene (rebuilt from the dict, axes from [sweep])
    is the one the run used."""
    cfg = config.load_config(ROOT / "configs" / "bai2006_fig13.toml", allow_large=True)
    a, b = cfg.scene, scene.from_data(cfg.data)
    for f in dataclasses.fields(scene.Scene):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if f.name == "axes":
            assert list(x) == list(y) and all(np.array_equal(x[k], y[k]) for k in x)
        else:
            assert x == y, f.name


def test_a_bad_config_raises_the_same_error_before_any_scene():
    bad = config.DEFAULT_CONFIG_TOML.replace("mass = 2.0", "mass = -2.0")
    with pytest.raises(config.ConfigError, match=r"rotor\.mass: must be > 0"):
        config.parse_config(bad)


def test_a_chunk_task_ships_the_scene_smaller_than_the_config_dict_and_axes():
    """A chunk task's arguments are the scene and its segment ids: smaller than the config dict and
    the axes they replace (the dict repeated every axis in [sweep]), and without the model's
    compiled functions (looked up by name on the worker)."""
    cfg = config.load_config(ROOT / "configs" / "bai2006_fig13.toml", allow_large=True)
    segs = sweep.segments(cfg.scene)
    ids = tuple(s.id for s in sweep.chunks_for(cfg.scene, segs, 2)[0])
    now = len(pickle.dumps((cfg.scene, ids), protocol=5))
    before = len(pickle.dumps((cfg.data, cfg.axes, cfg.continued_axis, ids), protocol=5))
    assert now < 0.6 * before
    back = pickle.loads(pickle.dumps(cfg.scene, protocol=5))
    assert back.model is cfg.model and back.newton == cfg.scene.newton
    assert b"dispatch" not in pickle.dumps(cfg.scene, protocol=5)

"""Config validation: shipped scenes parse; every malformed config is rejected with its key and
what is allowed, all problems at once; the scene hash ignores formatting."""
import json
import random
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import config
CLI = [str(Path(sys.executable).with_name("rotorsweep"))]

BASE = """
[scene]
name = "t"
model = "jeffcott_clearance"

[bearing]
preset = "209"
stiffness = "bai2006"

[sweep]
speed = {start = 10.0, stop = 20.0, step = 1.0}
clearance = [3.8e-6, 7.6e-6]
"""


def test_shipped_configs_and_default_parse():
    for name in ("demo", "bai2006_fig13", "atlas4d"):
        config.load_config(f"configs/{name}.toml")
    cfg = config.parse_config(config.DEFAULT_CONFIG_TOML)
    assert cfg.data["bearing"]["stiffness"] == "bai2006"
    assert cfg.data["numerics"]["rtol"] == 1e-10 and cfg.data["rotor"]["mass"] == 2.0


def test_fig13_axis_has_no_float_drift():
    speed = config.load_config("configs/bai2006_fig13.toml").axes["speed"]
    assert len(speed) == 2401 and speed[0] == 10.0 and speed[-1] == 250.0
    np.testing.assert_array_equal(speed, np.round(10.0 + 0.1 * np.arange(2401), 10))


def test_range_forms():
    cfg = config.parse_config(BASE.replace("clearance = [3.8e-6, 7.6e-6]",
                                           "contact_angle = {start = 10, stop = 40, num = 4}"))
    np.testing.assert_array_equal(cfg.axes["contact_angle"], [10, 20, 30, 40])
    assert list(cfg.axes) == ["speed", "contact_angle"]


def test_zero_clearance_without_angle_is_radial_contact():
    """Bai's eq. 6 gives a zero contact angle at zero clearance: a valid deep-groove state."""
    from rotorsweep.pipeline import compute

    cfg = config.parse_config(BASE.replace("clearance = [3.8e-6, 7.6e-6]", "clearance = [0.0, 1e-6]"))
    point = {"speed": 50.0, "clearance": 0.0, "contact_angle": None, "preload": 0.0}
    assert compute.point_params(cfg.scene, point).derived["contact_angle_used"] == 0.0


def test_dependent_defaults_and_path():
    angular = edit('preset = "209"', 'preset = "angular_contact_medium"')
    assert config.parse_config(angular).data["bearing"]["nominal_angle"] == 26
    assert config.parse_config(BASE).data["bearing"]["nominal_angle"] is None
    from pathlib import Path
    assert config.load_config(Path("configs/demo.toml")).path == "configs/demo.toml"


@pytest.mark.parametrize("free_angle, version", [("", "2"), ('free_angle = "nominal"', "2"), ("", "1")])
def test_jeffcott_angular_free_angle_is_the_geometry_s_unless_nominal_or_an_older_result(free_angle, version):
    """angular_contact_medium's 26 deg row without clearance: by default the free angle of its printed
    radii (cos a0 = (R1 + 2 R_K - R2) / (2 R_K - d), R1 = 16.0, R2 = 27.5399, R_K = 5.930, d = 11.510 mm
    typed from the 2016 table: 23.86 deg), with free_angle = "nominal" the label, and so for a result
    file of model version 1 that gives none (scene.of_result). A few flops on numbers of 1e-2 and the
    degrees round trip: 1e-12 relative."""
    from rotorsweep.pipeline import compute, scene

    text = edit('preset = "209"', f'preset = "angular_contact_medium"\nnominal_angle = 26\n{free_angle}')
    sc = scene.of_result(text, version)
    used = compute.point_params(sc, {"speed": 50.0, "clearance": 0.0, "contact_angle": None,
                                     "preload": 0.0}).derived["contact_angle_used"]
    if free_angle or version == "1":
        assert used == pytest.approx(26.0, rel=1e-12)
    else:
        geometry = np.degrees(np.arccos((16.0 + 2 * 5.930 - 27.5399) / (2 * 5.930 - 11.510)))
        assert used == pytest.approx(geometry, rel=1e-12) and round(used, 2) == 23.86


def edit(old, new):
    assert old in BASE
    return BASE.replace(old, new)


MALFORMED = [
    ("unknown section", BASE + "\n[rotr]\nmass = 2\n", ["rotr", "rotor"]),
    ("unknown key, suggestion", edit('preset = "209"', 'preset = "209"\nstifness = 1e9'), ["bearing.stifness", "stiffness"]),
    ("unknown preset", edit('preset = "209"', 'preset = "208"'), ["bearing.preset", '"209"', "angular_contact_medium"]),
    ("wrong type", edit('stiffness = "bai2006"', 'stiffness = "bai2006"\ncage_rotation = "yes"'), ["bearing.cage_rotation", "true or false"]),
    ("bool as number", BASE + "\n[rotor]\nmass = true\n", ["rotor.mass", "number"]),
    ("negative clearance", edit("clearance = [3.8e-6, 7.6e-6]", "clearance = [-1e-6, 7.6e-6]"), ["sweep.clearance", ">= 0"]),
    ("contact angle 0", edit("clearance = [3.8e-6, 7.6e-6]", "contact_angle = [0.0]"), ["sweep.contact_angle", "> 0"]),
    ("contact angle 90", edit("clearance = [3.8e-6, 7.6e-6]", "contact_angle = [90.0]"), ["sweep.contact_angle", "< 90"]),
    ("contact angle 120", edit('stiffness = "bai2006"', 'stiffness = "bai2006"\ncontact_angle = 120.0'), ["bearing.contact_angle", "< 90"]),
    ("negative preload", edit("clearance = [3.8e-6, 7.6e-6]", "preload = [-5.0]\nclearance = [1e-6]"), ["sweep.preload", ">= 0"]),
    ("empty axis", edit("clearance = [3.8e-6, 7.6e-6]", "clearance = []"), ["sweep.clearance", "empty"]),
    ("step <= 0", edit("step = 1.0", "step = 0.0"), ["sweep.speed.step", "> 0"]),
    ("start > stop", edit("start = 10.0, stop = 20.0", "start = 30.0, stop = 20.0"), ["sweep.speed", "start must be <= stop"]),
    ("step and num", edit("step = 1.0", "step = 1.0, num = 3"), ["sweep.speed", "exactly one of step or num"]),
    ("neither step nor num", edit(", step = 1.0", ""), ["sweep.speed", "exactly one of step or num"]),
    ("nan", edit("start = 10.0", "start = nan"), ["sweep.speed.start", "finite"]),
    ("inf rtol", BASE + "\n[numerics]\nrtol = inf\n", ["numerics.rtol", "finite"]),
    ("missing name", edit('name = "t"\n', ""), ["scene.name", "required"]),
    ("unknown model", edit('model = "jeffcott_clearance"', 'model = "jeffcott"'), ["scene.model", "jeffcott_clearance"]),
    ("speed not swept", edit("speed = {start = 10.0, stop = 20.0, step = 1.0}\n", ""), ["sweep.speed", "required"]),
    ("swept and fixed", edit('stiffness = "bai2006"', 'stiffness = "bai2006"\nclearance = 1e-6'), ["bearing.clearance", "also swept"]),
    ("non-increasing list", edit("clearance = [3.8e-6, 7.6e-6]", "clearance = [7.6e-6, 3.8e-6]"), ["sweep.clearance", "increasing"]),
    ("TOML syntax", BASE + "\n[numerics\n", ["not valid TOML", "line"]),
    ("nominal angle with 209", edit('preset = "209"', 'preset = "209"\nnominal_angle = 26'), ["bearing.nominal_angle", "angular_contact_medium"]),
    ("huge grid", edit("clearance = [3.8e-6, 7.6e-6]", "clearance = {start = 1e-6, stop = 2e-5, num = 30000}"), ["max_points", "--yes"]),
    ("nominal angle not a preset angle", edit('preset = "209"', 'preset = "angular_contact_medium"\nnominal_angle = 20'), ["bearing.nominal_angle", "12, 15, 26, 36, 40"]),
    ("float for int", BASE + "\n[numerics]\nmax_newton_iter = 30.0\n", ["numerics.max_newton_iter", "integer"]),
    ("newton below rtol", BASE + "\n[numerics]\nrtol = 1e-6\nnewton_tol = 1e-9\n", ["numerics.newton_tol", "rtol"]),
    ("bad stiffness word", edit('stiffness = "bai2006"', 'stiffness = "soft"'), ["bearing.stiffness", '"hertz"', "a number"]),
    ("integrator", BASE + "\n[numerics]\nintegrator = \"euler\"\n", ["numerics.integrator", '"dop853"', '"rk4"']),
]


@pytest.mark.parametrize("text, fragments", [m[1:] for m in MALFORMED], ids=[m[0] for m in MALFORMED])
def test_malformed_config_is_rejected_with_its_key(text, fragments):
    with pytest.raises(config.ConfigError) as err:
        config.parse_config(text, path="bad.toml")
    message = str(err.value)
    assert message.startswith("bad.toml")
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def test_all_problems_are_reported_together():
    text = edit('preset = "209"', 'preset = "208"\ncage_rotation = 3').replace("step = 1.0", "step = -1.0")
    message = str(pytest.raises(config.ConfigError, config.parse_config, text).value)
    assert {"bearing.preset", "bearing.cage_rotation", "sweep.speed.step"} <= {
        line.split(": ")[1] for line in message.splitlines()}


def test_large_grid_allowed_with_flag():
    text = edit("clearance = [3.8e-6, 7.6e-6]", "clearance = {start = 1e-6, stop = 2e-5, num = 30000}")
    assert config.parse_config(text, allow_large=True).n_points == 11 * 30000


def test_hash_ignores_formatting_and_follows_values():
    a = config.parse_config(BASE).hash()
    assert config.parse_config("# a comment\n" + BASE.replace(" = ", "=")).hash() == a
    assert config.parse_config(edit("step = 1.0", "step = 0.5")).hash() != a


def mutate(text, rng):
    """One random corruption of a valid config: a value, a key, a type or a section."""
    lines = text.splitlines()
    i = rng.choice([k for k, line in enumerate(lines) if line.strip()])
    junk = rng.choice(['"x"', "-1", "1e400", "[]", "{}", "true", "nan", "0", "1e12", '"209"', "[1, 2, 1]"])
    line = lines[i]
    kind = rng.randrange(4)
    if kind == 0 and "=" in line:
        lines[i] = line.split("=")[0] + "= " + junk
    elif kind == 1 and "=" in line:
        lines[i] = "x" + line
    elif kind == 2:
        del lines[i]
    else:
        lines.insert(i, rng.choice(["[extra]", "a = 1", "= 3", "[sweep.speed]", "[[scene]]"]))
    return "\n".join(lines)


def test_fuzzed_configs_never_raise_anything_but_config_error():
    rng = random.Random(7)
    sources = [BASE] + [open(f"configs/{n}.toml").read() for n in ("demo", "atlas4d")]
    for _ in range(400):
        text = mutate(rng.choice(sources), rng)
        try:
            config.parse_config(text)
        except config.ConfigError:
            pass


@pytest.mark.parametrize("text", [MALFORMED[2][1], MALFORMED[11][1], MALFORMED[22][1]])
def test_cli_rejects_bad_config_with_exit_2(tmp_path, capsys, text):
    from rotorsweep.pipeline import cli

    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert cli.main(["run", str(path), "-o", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and str(path) in err
    assert not (tmp_path / "x.nc").exists()


def test_cli_subprocess_bad_config_exits_2_without_traceback(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(MALFORMED[2][1])
    proc = subprocess.run(CLI + ["run", str(path), "-o", str(tmp_path / "x.nc")], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr and str(path) in proc.stderr


@pytest.mark.parametrize("make, message", [
    (lambda d: "/dev/zero", "not a regular file"),
    (lambda d: d, "not a regular file"),
    (lambda d: d / "missing.toml", "no such config file"),
    (lambda d: _written(d / "big.toml", b"# " + b"x" * config.MAX_CONFIG_BYTES), "larger than"),
    (lambda d: _written(d / "latin1.toml", b"name = '\xe9'"), "cannot read as a TOML text file"),
])
def test_config_files_are_read_with_a_size_cap_and_only_when_regular(tmp_path, make, message):
    """/dev/zero as a config was read until memory ran out."""
    with pytest.raises(config.ConfigError, match=message):
        config.load_config(make(tmp_path))


def _written(path, data):
    path.write_bytes(data)
    return path


def test_a_large_grid_refuses_only_the_command_that_computes_it(tmp_path):
    """`point`, `continue`, `backbone` and `modes` said 'pass --yes' (which they do not accept) and
    refused to work on a scene whose sweep grid is large; only `run` computes the grid."""
    huge = edit("clearance = [3.8e-6, 7.6e-6]", "clearance = {start = 1e-6, stop = 2e-5, num = 30000}")
    with pytest.raises(config.ConfigError, match="--yes"):
        config.parse_config(huge)
    assert len(config.parse_config(huge, whole_grid=False).axes["clearance"]) == 30000
    path = tmp_path / "huge.toml"
    path.write_text(huge)
    done = subprocess.run(CLI + ["point", "--config", str(path), "--speed", "100", "--clearance", "7.6e-6", "--json"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["status"] == "converged"


def test_analysis_keys_are_the_attractor_settings_fields():
    """One name per concept: each [analysis] key but the three that choose what runs is a field of
    attractor.Settings, and the settings built from a scene carry the scene's values."""
    from dataclasses import fields

    from rotorsweep.pipeline import scene
    from rotorsweep.kernels import attractor

    keys = set(config.SCHEMA["analysis"]) - {"floquet", "attractor", "sweep_direction"}
    assert keys <= {f.name for f in fields(attractor.Settings)}
    cfg = config.parse_config(config.DEFAULT_CONFIG_TOML)
    data, settings = cfg.data, cfg.scene.analysis.settings
    assert {k: getattr(settings, k) for k in keys} == {k: data["analysis"][k] for k in keys}
    assert settings.lyapunov_min_periods == min(scene.LYAPUNOV_MIN_PERIODS, data["analysis"]["lyapunov_max_periods"])


def test_continuation_messages_name_existing_keys_and_state_the_limits():
    """Issue 36 item 13: the step-order problem names the three config keys (not
    `continuation.steps`), the Newton tolerance is numerics.newton_tol, and a start outside the
    parameter's values states its limits (no empty "()" list)."""
    from rotorsweep.pipeline import continuation
    from tests.test_continue_command import DUFFING

    def message(extra):
        with pytest.raises(config.ConfigError) as err:
            continuation.plan(config.parse_config(DUFFING.replace("ds = 0.02", extra)).scene)
        return str(err.value)

    steps = message("ds = 0.5\nds_max = 0.25")
    assert steps.startswith("continuation.ds_min, continuation.ds, continuation.ds_max: steps must satisfy")
    assert "continuation.steps" not in steps
    start = message("ds = 0.02\nstart = -1.0\nstop = 2.0")
    assert "continuation.start: -1.0 is outside the allowed values of omega: must be > 0" in start and "()" not in start
    assert config.settings_problems(["tol = 0.0: must be > 0"], "continuation", {}) == [
        "numerics.newton_tol: must be > 0 (got 0.0)"]

"""Unit strings in configs and CLI flags (pint): every axis form, fixed keys, each flag; wrong
dimensions rejected with the key named and the unit expected; plain numbers stay SI.
Expected values are exact unit definitions (1 rpm = 1/60 Hz, 1 um = 1e-6 m, one cycle = 2 pi rad);
conversions go through one float multiplication, so they agree to a few ulp (rel 1e-14)."""
import math
import subprocess
import sys

import numpy as np
import pytest

import rotorsweep.pipeline as pipeline
from rotorsweep.pipeline import cli, config, modes, units

from tests.test_config import BASE


@pytest.mark.parametrize("text, unit, expected", [
    ("7.6 um", "m", 7.6e-6),
    ("7.6 µm", "m", 7.6e-6),
    ("600 rpm", "Hz", 10.0),
    ("3000 RPM", "Hz", 50.0),           # ROSS's spelling
    ("2 kHz", "Hz", 2000.0),
    ("20 * pi rad/s", "Hz", 10.0),       # one cycle = 2 pi rad
    ("10 Hz", "rad s-1", 20 * math.pi),
    ("60 rpm", "rad s-1", 2 * math.pi),
    ("0.25 rad", "degree", 0.25 * 180 / math.pi),
    ("1.2 kN", "N", 1200.0),
    ("2.5e9 N/m**1.5", "N m-1.5", 2.5e9),
    ("300 N*s/m", "N s m-1", 300.0),
    ("9.81 m/s**2", "m s-2", 9.81),
    ("4.5e-6", "m", 4.5e-6),             # a bare number in a string: already in the key's unit
])
def test_unit_strings_convert_to_the_keys_unit(text, unit, expected):
    assert units.to_unit(text, unit) == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize("text, unit", [("7.6 Hz", "m"), ("600 rpm", "m"), ("1 kg", "N"), ("15 percent", "degree"),
                                        ("3 um", "degree"), ("fast", "Hz")])
def test_wrong_dimensions_name_the_unit_expected(text, unit):
    with pytest.raises(units.UnitError, match=f"unit {unit}"):
        units.to_unit(text, unit)


def _parse(old, new):
    assert old in BASE
    return config.parse_config(BASE.replace(old, new))


def test_fixed_key_takes_a_unit_string_and_equals_the_si_number():
    with_unit = config.parse_config(BASE + '\n[rotor]\nmass = "2000 g"\ndamping = "0.3 kN*s/m"\n')
    si = config.parse_config(BASE + "\n[rotor]\nmass = 2.0\ndamping = 300.0\n")
    assert with_unit.data == si.data and with_unit.hash() == si.hash()   # the cube stays SI


def test_list_axis_with_unit_strings_and_numbers():
    cfg = _parse("clearance = [3.8e-6, 7.6e-6]", 'clearance = ["3.8 um", 7.6e-6, "0.019 mm"]')
    np.testing.assert_allclose(cfg.axes["clearance"], [3.8e-6, 7.6e-6, 19e-6], rtol=1e-14)


def test_range_axis_with_step_in_rpm():
    cfg = _parse("speed = {start = 10.0, stop = 20.0, step = 1.0}",
                 'speed = {start = "600 rpm", stop = "1200 rpm", step = "60 rpm"}')
    np.testing.assert_allclose(cfg.axes["speed"], np.arange(10.0, 21.0), rtol=1e-14)


def test_range_axis_with_num_in_rpm():
    cfg = _parse("speed = {start = 10.0, stop = 20.0, step = 1.0}",
                 'speed = {start = "600 rpm", stop = "3000 rpm", num = 5}')
    np.testing.assert_allclose(cfg.axes["speed"], [10, 20, 30, 40, 50], rtol=1e-14)


def test_fixed_bearing_key_and_continuation_range_take_units():
    cfg = _parse("clearance = [3.8e-6, 7.6e-6]",
                 'contact_angle = [10, 20]\n\n[continuation]\nstart = "900 rpm"\nstop = "1 kHz"\n')
    assert cfg.data["continuation"]["start"] == pytest.approx(15.0) and cfg.data["continuation"]["stop"] == 1000.0
    cfg = config.parse_config(BASE.replace("clearance = [3.8e-6, 7.6e-6]", "").replace(
        'stiffness = "bai2006"', 'stiffness = "bai2006"\nclearance = "7.6 um"'))
    assert cfg.data["bearing"]["clearance"] == pytest.approx(7.6e-6, rel=1e-14)


@pytest.mark.parametrize("old, new, fragments", [
    ("clearance = [3.8e-6, 7.6e-6]", 'clearance = ["3.8 um", "7.6 Hz"]', ("sweep.clearance[1]", "unit m")),
    ("speed = {start = 10.0, stop = 20.0, step = 1.0}", 'speed = {start = "1 m", stop = 20.0, num = 3}',
     ("sweep.speed.start", "unit Hz")),
    ("speed = {start = 10.0, stop = 20.0, step = 1.0}", 'speed = {start = 10.0, stop = 20.0, step = "1 s"}',
     ("sweep.speed.step", "unit Hz")),
    ('stiffness = "bai2006"', 'stiffness = "bai2006"\ncontact_angle = "3 um"', ("bearing.contact_angle", "unit degree")),
    ('stiffness = "bai2006"', 'stiffness = "bai2006"\n\n[rotor]\nradial_load = "gravit"',
     ("rotor.radial_load", '"gravity"', "unit N")),
])
def test_wrong_dimensions_are_rejected_with_the_key_named(old, new, fragments):
    with pytest.raises(config.ConfigError) as err:
        _parse(old, new)
    for fragment in fragments:
        assert fragment in str(err.value)


def test_a_float_or_key_takes_a_unit_string():
    cfg = _parse('stiffness = "bai2006"', 'stiffness = "bai2006"\n\n[rotor]\nradial_load = "0.02 kN"')
    assert cfg.data["rotor"]["radial_load"] == 20.0


def test_pint_is_imported_only_when_a_unit_string_is_met():
    code = ("import sys; from rotorsweep.pipeline import config; from tests.test_config import BASE; "
            "config.parse_config(BASE); print('pint' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


class Captured(Exception):
    pass


@pytest.fixture
def point_kwargs(monkeypatch):
    """The keywords `rotorsweep point` hands to rotorsweep.pipeline.point (the computation itself skipped)."""
    seen = {}

    def fake_point(config=None, **values):
        seen.update(values)
        raise Captured

    monkeypatch.setattr(pipeline, "point", fake_point)
    return seen


@pytest.mark.parametrize("flags, name, expected", [
    (["--speed", "5100 rpm"], "speed", 85.0),
    (["--clearance", "19 um"], "clearance", 19e-6),
    (["--contact-angle", "0.25 rad"], "contact_angle", 0.25 * 180 / math.pi),
    (["--preload", "0.4 kN"], "preload", 400.0),
    (["--at", "speed=600 rpm"], "speed", 10.0),
    (["--at", 'clearance="7.6 um"'], "clearance", 7.6e-6),
    (["--speed", "85"], "speed", 85.0),                       # plain numbers stay SI
])
def test_point_flags_take_unit_strings(point_kwargs, flags, name, expected):
    with pytest.raises(Captured):
        cli.main(["point", *flags])
    assert point_kwargs[name] == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize("flags, fragments", [
    (["--clearance", "19 Hz"], ("--clearance", "unit m")),
    (["--speed", "3 um"], ("--speed", "unit Hz")),
    (["--at", "preload=1 m"], ("--at preload=1 m", "unit N")),
    (["--at", "speed"], ("--at speed", "AXIS=VALUE")),
])
def test_point_flags_with_wrong_dimensions_exit_2(point_kwargs, capsys, flags, fragments):
    assert cli.main(["point", *flags]) == 2
    err = capsys.readouterr().err
    for fragment in fragments:
        assert fragment in err


def test_modes_at_and_campbell_take_unit_strings(monkeypatch, capsys):
    seen = {}

    def fake_command(cfg, at, campbell_text, output, as_json, report=None):
        seen.update(at=at, speeds=modes.campbell_speeds(campbell_text, cfg.model, cfg.data))
        return ""

    monkeypatch.setattr(modes, "command", fake_command)
    assert cli.main(["modes", "configs/filipkovsky2010_symmetric.toml", "--at", "speed=600 rpm",
                     "--campbell", "600 rpm:1.2 kHz:3", "-o", "c.csv"]) == 0
    assert seen["at"] == {"speed": pytest.approx(10.0)}
    np.testing.assert_allclose(seen["speeds"], [10.0, 605.0, 1200.0], rtol=1e-14)


@pytest.mark.parametrize("value, fragment", [("600 rpm:3000 rpm", "START:STOP:NUM"), ("1:2:x", "START:STOP:NUM"),
                                             ("600 rpm:3 um:5", "unit Hz")])
def test_a_malformed_campbell_range_exits_2(capsys, value, fragment, tmp_path):
    assert cli.main(["modes", "configs/filipkovsky2010_symmetric.toml", "--campbell", value,
                     "-o", str(tmp_path / "c.csv")]) == 2
    err = capsys.readouterr().err
    assert "--campbell" in err and fragment in err and "Traceback" not in err

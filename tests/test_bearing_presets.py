"""The papers' bearing tables as presets (rotorsweep.kernels.models.preloaded_pair): the free angle from
the table's groove geometry under both preload laws (closed form written here), the loaded angle
(a scalar solve written here), every value recorded as given or derived, a table row replaced
consistently (omega_l, the angle axes), the 2010 papers' E; and the disc's orbit in the mode shapes
against a rigid-body computation written here. Numpy-level: no kernel is integrated."""
import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rotorsweep.pipeline import cli, compute, config, modes
from rotorsweep.kernels import bearing, models
from rotorsweep.kernels.models import preloaded_pair as pp, rigid_preloaded as rp

SPEC = models.get("rigid_preloaded")
# The tables as printed, typed here: Filipkovsky 2016 (the paragraph after eq. 13) and both 2010
# papers (section 2).
R1, RK, D, N = 16.0e-3, 5.930e-3, 11.510e-3, 7
R2_2016 = {12: 27.5125e-3, 15: 27.5167e-3, 26: 27.5399e-3, 36: 27.5709e-3, 40: 27.5858e-3}
R2_2010, E_2016, E_2010 = 27.53e-3, 2.1e11, 2e11
LAWS = ("hertz", "as_printed")


def values(**over):
    v = {p.name: (p.unset if p.axis else p.default) for p in SPEC.parameters}
    v.update(speed=250.0)
    v.update(over)
    return v


def free_angle(r2):
    """Eq. 10 at zero load: (2 R_K - d) cos(a0) = R1 + 2 R_K - R2."""
    return math.acos((R1 + 2 * RK - r2) / (2 * RK - D))


def loaded_angle(r2, p0, e):
    """Eqs. 8-10 solved here by brentq in alpha: (2 R_K - d + w) cos a = A cos a0 with the Hertz
    approach w of a ball carrying P0 / (N sin a) (w = (P / K(a))^(2/3), K the series Hertz constant
    of the loaded contact at angle a)."""
    geom = bearing.BearingGeometry("t", D, R1 + r2, RK, RK, N, e, 0.3, inner_race_radius=R1, outer_race_radius=r2)

    def w(a):
        return (p0 / (N * math.sin(a) * bearing.hertz_constant(geom, a))) ** (2 / 3)

    a0 = free_angle(r2)
    return brentq(lambda a: (2 * RK - D + w(a)) * math.cos(a) - (2 * RK - D) * math.cos(a0),
                  a0, math.radians(80.0), xtol=1e-15, rtol=1e-15)


# The free angle's rounding: cos(a0) is a ratio of differences of mm-sized lengths (relative
# rounding ~ 1e-16 x (R1 + 2 R_K) / (2 R_K - d) ~ 1e-14), acos amplifies it by 1 / sin(a0) <= 9 at
# 6.85 deg: 1e-12 relative is an honest bound. The loaded angle: both solves to ~1e-15 rad.
@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("row", sorted(R2_2016))
def test_the_2016_rows_take_their_free_angle_from_the_groove_geometry_under_both_laws(law, row):
    derived = SPEC.build(values(nominal_angle=float(row), preload_law=law)).derived
    assert derived["free_contact_angle"] == pytest.approx(math.degrees(free_angle(R2_2016[row])), rel=1e-12)
    assert derived["free_angle_from_geometry"] == 1.0
    assert math.radians(derived["contact_angle_used"]) == pytest.approx(
        loaded_angle(R2_2016[row], 300.0, E_2016), rel=1e-11)


@pytest.mark.parametrize("law", LAWS)
def test_the_2010_table_is_its_papers_bearing_with_e_2e11(law):
    v = values(table="filipkovsky2010", preload_law=law)
    derived = SPEC.build(v).derived
    assert derived["bearing_youngs_modulus"] == E_2010 and derived["bearing_outer_race_radius"] == R2_2010
    assert derived["free_contact_angle"] == pytest.approx(math.degrees(free_angle(R2_2010)), rel=1e-12)
    assert math.radians(derived["contact_angle_used"]) == pytest.approx(loaded_angle(R2_2010, 300.0, E_2010), rel=1e-11)


@pytest.mark.parametrize("path", ["configs/filipkovsky2010_symmetric.toml", "configs/filipkovsky2010_axial.toml"])
def test_the_2010_scenes_use_their_papers_printed_bearing(path):
    cfg = config.load_config(path)
    derived = compute.point_params(cfg.scene, cfg.scene.fixed | {"speed": 100.0}).derived
    printed = {"inner_race_radius": R1, "outer_race_radius": R2_2010, "groove_radius": RK, "ball_diameter": D,
               "youngs_modulus": E_2010, "poisson_ratio": 0.3}
    for key, value in printed.items():
        assert derived[f"bearing_{key}"] == pytest.approx(value, rel=1e-15)
        assert derived[f"bearing_{key}_given"] == 0.0


def test_the_nominal_reading_is_explicit_and_recorded():
    derived = SPEC.build(values(free_angle="nominal", preload_law="hertz")).derived
    assert derived["free_contact_angle"] == pytest.approx(15.0, rel=1e-15)   # degrees -> radians -> degrees
    assert derived["free_angle_from_geometry"] == 0.0


def test_every_bearing_value_is_recorded_as_given_or_derived():
    derived = SPEC.build(values()).derived
    flags = [k for k in derived if k.endswith("_given")] + ["contact_angle_imposed"]
    assert len(flags) == 9 and all(derived[k] == 0.0 for k in flags)
    given = dict(inner_race_radius=16.01e-3, outer_race_radius=27.52e-3, groove_radius=5.94e-3, ball_diameter=11.5e-3,
                 youngs_modulus=2.05e11, poisson_ratio=0.29)
    derived = SPEC.build(values(**given)).derived
    for key, value in given.items():
        assert (derived[f"bearing_{key}"], derived[f"bearing_{key}_given"]) == (value, 1.0)
    assert derived["free_contact_angle"] == pytest.approx(
        math.degrees(math.acos((16.01e-3 + 2 * 5.94e-3 - 27.52e-3) / (2 * 5.94e-3 - 11.5e-3))), rel=1e-12)
    for name in pp.BEARING_DERIVED:   # CF: every variable has units and a long name
        unit, long_name = SPEC.derived[name]
        assert unit and long_name


# --- a table row replaced: omega_l and the angle axes re-derive every bearing value -------------

SCENE = ('[scene]\nname = "x"\nmodel = "rigid_preloaded"\n[bearing]\npreload_law = "{law}"\n{bearing}\n'
         '[sweep]\nspeed = [250.0]\n{sweep}\n')


def derived_at(text, point):
    cfg = config.parse_config(text)
    return compute.point_params(cfg.scene, cfg.scene.fixed | point).derived


@pytest.mark.parametrize("law", LAWS)
def test_omega_l_replaces_the_whole_row_as_a_fresh_scene_of_that_row(law):
    """A scene on the 26 deg row with every value of its bearing given: omega_l's bearing is the
    15 deg row as printed, the same derived values and frequency as a scene with that row only."""
    scene = values(nominal_angle=26.0, preload_law=law, contact_angle=30.0, contact_constant=5e9,
                   axial_approach=80e-6, inner_race_radius=16.01e-3, outer_race_radius=27.55e-3,
                   groove_radius=5.94e-3, ball_diameter=11.5e-3, youngs_modulus=2.05e11, poisson_ratio=0.29)
    fresh = values(nominal_angle=15.0, preload_law=law)
    row = pp.with_row(scene, rp.OMEGA_L_ANGLE)
    assert rp.bearing_derived(row, rp.bearing_state(row)) == rp.bearing_derived(fresh, rp.bearing_state(fresh))
    lowest = modes.modes(SPEC, fresh)[0].frequency
    assert rp.omega_l(scene) == rp.omega_l(fresh) == pytest.approx(lowest, rel=1e-15)


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("axis, swept, at", [("nominal_angle", "[12.0, 26.0]", 26.0), ("contact_angle", "[14.0, 18.0]", 18.0)])
def test_a_point_of_an_angle_axis_is_a_fresh_scene_with_that_angle(law, axis, swept, at):
    on_axis = derived_at(SCENE.format(law=law, bearing="", sweep=f"{axis} = {swept}"), {"speed": 250.0, axis: at})
    fresh = derived_at(SCENE.format(law=law, bearing=f"{axis} = {at}", sweep=""), {"speed": 250.0})
    assert on_axis == fresh


def test_a_row_sweep_with_a_given_r2_is_refused():
    with pytest.raises(config.ConfigError, match="bearing.outer_race_radius: replaces the R2 of every row"):
        config.parse_config(SCENE.format(law="hertz", bearing="outer_race_radius = 0.02755",
                                         sweep="nominal_angle = [12.0, 26.0]"))


# --- the disc in the mode shapes -----------------------------------------------------------------

def rigid_body_disc(shape, disk, span):
    """The disc's (X, Y) from the rigid shaft's centre and tilt: x_c = (x1 + x2) / 2, theta_x =
    (x2 - x1) / l, x_disc = x_c + (xi_D - l / 2) theta_x (the same in y)."""
    x1, y1, x2, y2 = shape[:4]
    arm = disk - span / 2
    return (x1 + x2) / 2 + arm * (x2 - x1) / span, (y1 + y2) / 2 + arm * (y2 - y1) / span


# Interpolation and the rigid-body form differ only in rounding (a few eps of a shape of size 1).
@pytest.mark.parametrize("model, over", [("rigid_preloaded", {"speed": 250.0}),
                                         ("rigid_preloaded", {"speed": 0.0, "disk_position": 0.4}),
                                         ("symmetric4", {}), ("asymmetric5", {})])
def test_the_disc_station_moves_as_the_rigid_shaft_section(model, over):
    spec = models.get(model)
    v = {p.name: (p.unset if p.axis else p.default) for p in spec.parameters} | over
    disk, span = spec.disk_position(v)
    expected = {"rigid_preloaded": v.get("disk_position"), "symmetric4": 0.25, "asymmetric5": 0.125}[model]
    assert (disk, span) == (expected, 0.5)
    _, system = spec.linear_system(v)
    for mode in modes.modes(spec, v):
        stations = modes.station_shapes(mode, system.coordinates, spec.disk_position(v))
        assert list(stations) == ["1", "2", modes.DISK_STATION]
        np.testing.assert_allclose(stations[modes.DISK_STATION], rigid_body_disc(mode.shape, disk, span),
                                   rtol=0, atol=8 * np.finfo(float).eps)


def test_modes_json_and_text_carry_the_disc(capsys):
    assert cli.main(["modes", "configs/filipkovsky2016_quick.toml", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert (rec["disk_position_m"], rec["bearing_span_m"]) == (0.125, 0.5)
    for m in rec["modes"]:
        shape = np.array(m["shape_real"]) + 1j * np.array(m["shape_imag"])
        disc = m["stations"][modes.DISK_STATION]
        want = rigid_body_disc(shape, 0.125, 0.5)
        got = (complex(disc["x_real"], disc["x_imag"]), complex(disc["y_real"], disc["y_imag"]))
        np.testing.assert_allclose(got, want, rtol=0, atol=8 * np.finfo(float).eps)
    assert cli.main(["modes", "configs/filipkovsky2016_quick.toml"]) == 0
    text = capsys.readouterr().out
    assert "mode shapes:" in text and "disc at 0.125 m of the 0.5 m span" in text and " disc (" in text and "  mode 0: 1 (" in text


def test_info_shows_each_bearing_value_and_whether_it_was_given():
    """A cube of two points holding the model's derived values (as a sweep writes them):
    `rotorsweep info` prints each value used and its given flag where they are the same at
    every point."""
    from rotorsweep.pipeline import cube
    points = [SPEC.build(values(speed=s, groove_radius=5.94e-3)).derived for s in (250.0, 260.0)]
    results = {name: np.array([p[name] for p in points]) for name in points[0]}
    ds = cube.build_dataset({"speed": [250.0, 260.0]}, {}, results, {"model": "rigid_preloaded"})
    lines = cube.describe(ds).splitlines()

    def line(name):
        return next(x for x in lines if x.split()[:1] == [name])

    assert line("bearing_groove_radius").endswith("[m] = 0.00594")
    assert line("bearing_groove_radius_given").endswith("= 1")
    assert line("bearing_youngs_modulus").endswith("[Pa] = 2.1e+11")
    assert line("bearing_youngs_modulus_given").endswith("= 0")
    assert line("contact_constant_given").endswith("= 0")


# --- results written before version 2 are recomputed as they were --------------------------------

@pytest.mark.parametrize("bearing_keys, before", [("", "nominal"), ("outer_race_radius = 27.52e-3", "geometry")])
def test_a_result_of_model_version_1_keeps_the_free_angle_it_was_computed_with(bearing_keys, before):
    """A Hertz scene on the 2016 table that gives no free_angle meant the row's label before model
    version 2 unless a groove dimension was given (aace0b1's free_angle_source); a result file of
    version 1 is rebuilt that way (rotorsweep.pipeline.scene.of_result), one of version 2 from the geometry.
    Checked against the same scene with free_angle given explicitly."""
    from rotorsweep.pipeline import scene

    text = SCENE.format(law="hertz", bearing=bearing_keys, sweep="nominal_angle = [15.0]")

    def explicit(src):
        keys = bearing_keys if src == "geometry" else ""
        return config.parse_config(SCENE.format(law="hertz", bearing=f'{keys}\nfree_angle = "{src}"',
                                                sweep="nominal_angle = [15.0]")).scene

    def free(sc):
        return compute.point_params(sc, sc.fixed | {"speed": 250.0}).derived["free_contact_angle"]
    assert free(scene.of_result(text, "1")) == free(explicit(before))
    assert free(scene.of_result(text, "2")) == free(explicit("geometry"))
    assert free(explicit("nominal")) == pytest.approx(15.0, rel=1e-14)      # degrees(radians(15)): a rounding
    assert abs(free(explicit("nominal")) - free(explicit("geometry"))) > 1e-3


def test_a_nominal_free_angle_with_a_groove_dimension_is_refused():
    with pytest.raises(config.ConfigError, match="bearing.free_angle: \"nominal\" .* bearing.outer_race_radius"):
        config.parse_config(SCENE.format(law="hertz", bearing='outer_race_radius = 27.52e-3\nfree_angle = "nominal"',
                                         sweep=""))

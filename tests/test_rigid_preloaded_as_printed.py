"""rigid_preloaded with the Filipkovsky papers' bearing law exactly as printed (preload_law =
"as_printed") against values written here from the papers: eqs. 6-10 and the ball sum of eq. 5
(2016: eq. 1) in numpy, the rotor's M, G from SPEC 2.2's kinetic energy and the bearing stiffness
at the static equilibrium; the bearing table's given/derived bookkeeping; the arrangement's sign;
the removed `stiffness` key."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rotorsweep.pipeline import config, cube, modes
from rotorsweep.pipeline.report import points
from rotorsweep.kernels import bearing, models
from rotorsweep.kernels.models import preloaded_pair, rigid_preloaded as rp
from tests.synthetic import synthetic_cube

SPEC = models.get("rigid_preloaded")
L = rp.LENGTH_SCALE
# Filipkovsky 2016's rotor and bearing table as printed (the paragraph after its eq. 13), typed here.
LENGTH, DISK_AT, M_B, I_C1, I_C0, M_0, I_1, I_0 = 0.5, 0.125, 1.963, 0.04098, 0.00015, 10.0, 0.1, 0.2
R1, RK, D, N = 16.0e-3, 5.930e-3, 11.510e-3, 7
R2 = {12: 27.5125e-3, 15: 27.5167e-3, 26: 27.5399e-3, 36: 27.5709e-3, 40: 27.5858e-3}


def values(**over):
    """The model's default values with the law as printed, at 250 Hz."""
    v = {p.name: (p.unset if p.axis else p.default) for p in SPEC.parameters}
    v.update(speed=250.0, preload_law="as_printed")
    v.update(over)
    return v


def printed_bearing(angle, p0):
    """(alpha, z0, K) of the law as printed, solved here: eq. 10 (2 R_K - d + w) cos a =
    R1 + 2 R_K - R2 for a by brentq, w from eqs. 8-9 with the Hertz constant of the loaded contact
    (eq. 11), z0 from eq. 7, K from eq. 6."""
    geom = bearing.table_geometry("filipkovsky2016", angle)

    def w_of(a):
        return (p0 / (N * math.sin(a) * bearing.hertz_constant(geom, a))) ** (2 / 3)

    alpha = brentq(lambda a: (2 * RK - D + w_of(a)) * math.cos(a) - (R1 + 2 * RK - R2[angle]),
                   math.radians(1.0), math.radians(80.0), xtol=1e-15, rtol=1e-15)
    z0 = (2 * RK - D + w_of(alpha)) * math.sin(alpha)
    return alpha, z0, 1.5 * p0 / N * z0 ** -1.5 * math.sin(alpha) ** -2.5


def ball_sum(k, alpha, z0, x, y, z):
    """One bearing, eq. 5 as printed: force K sum [.]_+^{3/2} u and stiffness K sum 1.5 [.]_+^{1/2} u u^T
    with [.] = x cos a cos b + y cos a sin b + (z + z0) sin a, u = (cos a cos b, cos a sin b, sin a)."""
    beta = 2 * np.pi * np.arange(N) / N
    u = np.stack([np.cos(alpha) * np.cos(beta), np.cos(alpha) * np.sin(beta), np.full(N, np.sin(alpha))])
    delta = np.maximum(x * u[0] + y * u[1] + (z + z0) * np.sin(alpha), 0.0)
    return k * u @ delta ** 1.5, 1.5 * k * (u * np.sqrt(delta)) @ u.T


def pair(k, alpha, z0, q, sign=1.0):
    """Generalized force and stiffness of the two bearings: A sees (x1, y1, s z), B (x2, y2, -s z)."""
    maps = np.zeros((2, 3, 5))
    maps[0, 0, 0] = maps[0, 1, 1] = maps[1, 0, 2] = maps[1, 1, 3] = 1.0
    maps[0, 2, 4], maps[1, 2, 4] = sign, -sign
    force, stiffness = np.zeros(5), np.zeros((5, 5))
    for t in maps:
        f, k_loc = ball_sum(k, alpha, z0, *(t @ q))
        force += t.T @ f
        stiffness += t.T @ k_loc @ t
    return force, stiffness


def test_bearing_forces_and_stiffness_are_the_printed_ball_sum():
    """The kernel's bearing loads (rp.bearing_load: the njit ball sum in scaled units, back to SI)
    against the numpy sum of eq. 5 with eq. 6-10's K, z0, alpha solved here, at random states with
    unloaded balls. Rounding of two summation orders and the scaling: 1e-12 relative to the largest."""
    for angle in (15, 36):
        alpha, z0, k = printed_bearing(angle, 300.0)
        state = rp.bearing_state(values(nominal_angle=angle))
        assert state.contact_angle == pytest.approx(alpha, rel=1e-10)
        assert (state.axial_approach, state.contact_constant) == (pytest.approx(z0, rel=1e-10), pytest.approx(k, rel=1e-10))
        rng = np.random.default_rng(angle)
        unloaded = 0
        for _ in range(8):
            q = rng.normal(0, 0.8 * z0 * math.sin(alpha), 5)
            got_f, got_k = rp.bearing_load(q, state, N)
            want_f, want_k = pair(state.contact_constant, state.contact_angle, state.axial_approach, q)
            np.testing.assert_allclose(got_f, want_f, rtol=0, atol=1e-12 * np.abs(want_f).max())
            np.testing.assert_allclose(got_k, want_k, rtol=0, atol=1e-12 * np.abs(want_k).max())
            unloaded += (got_k[0, 0] != got_k[2, 2])       # the two bearings differ: balls left
        assert unloaded > 0


def test_static_thrust_at_rest_is_one_and_a_half_preload_and_the_rotor_stays_centred():
    """Closed form: N K (z0 sin a)^{3/2} sin a with K = 3 P0 / (2N) z0^{-3/2} sin^{-5/2} a is 1.5 P0;
    the two bearings' thrusts oppose, so q = 0 is the static equilibrium (no weight) and Newton
    with the weight on converges to the printed sum's balance."""
    for p0 in (100.0, 300.0, 1000.0):
        state = rp.bearing_state(values(preload=p0))
        f, _ = ball_sum(state.contact_constant, state.contact_angle, state.axial_approach, 0.0, 0.0, 0.0)
        assert f[2] == pytest.approx(1.5 * p0, rel=1e-12)
        assert SPEC.build(values(preload=p0)).derived["static_thrust"] == pytest.approx(1.5 * p0, rel=1e-12)
    eq = rp.static_equilibrium(values())
    assert np.array_equal(eq.position, np.zeros(5)) and eq.iterations == 0
    v = values(gravity=9.81)
    eq = rp.static_equilibrium(v)
    state = rp.bearing_state(v)
    force, _ = pair(state.contact_constant, state.contact_angle, state.axial_approach, eq.position)
    assert np.abs(force - rp.weight(rp.Rotor.of(v))).max() <= 1e-12 * 300.0


def rotor_matrices():
    """M and G (per rad/s) from SPEC 2.2's T, written out here: tilt (q2 - q1) / l with I_d,
    shaft mass at mid-span, disk at xi_D; gyroscopic term I_p Omega (y1' - y2')(x2 - x1) / l^2."""
    s, i_d, g = DISK_AT / LENGTH, (I_C1 + I_1) / LENGTH ** 2, (I_C0 + I_0) / LENGTH ** 2
    block = (i_d * np.array([[1, -1], [-1, 1]]) + M_B / 4 * np.ones((2, 2))
             + M_0 * np.array([[(1 - s) ** 2, s * (1 - s)], [s * (1 - s), s ** 2]]))
    m = np.zeros((5, 5))
    for idx in ((0, 2), (1, 3)):
        m[np.ix_(idx, idx)] = block
    m[4, 4] = M_B + M_0
    gyro = np.zeros((5, 5))           # rows: d/dt dT/dq' - dT/dq of the gyroscopic term, per q'
    gyro[0, [1, 3]] = g, -g
    gyro[1, [0, 2]] = -g, g
    gyro[2, [1, 3]] = -g, g
    gyro[3, [0, 2]] = g, -g
    return m, gyro


@pytest.mark.parametrize("speed", [0.0, 250.0])
@pytest.mark.parametrize("angle", [15, 40])
def test_linear_frequencies_equal_eigenvalues_of_independent_m_g_k(speed, angle):
    """All five modes of the law as printed, at rest and at 250 Hz: rotorsweep.pipeline.modes (and the
    kernel's Jacobian at rest) against eig of [[0, I], [-M^-1 K, -M^-1 (C + Omega G)]] with M, G
    written from T and K the printed sum's stiffness at q = 0 (alpha, z0, K solved here). Two
    eigen-solves of matrices equal to rounding: 1e-9 relative."""
    alpha, z0, k = printed_bearing(angle, 300.0)
    m, gyro = rotor_matrices()
    damping = 500.0
    _, stiffness = pair(k, alpha, z0, np.zeros(5))
    omega = 2 * np.pi * speed
    m_inv = np.linalg.inv(m)
    a = np.block([[np.zeros((5, 5)), np.eye(5)],
                  [-m_inv @ stiffness, -m_inv @ (damping * np.eye(5) + omega * gyro)]])
    s = np.linalg.eigvals(a)
    want = np.sort(s.imag[s.imag > 0]) / (2 * np.pi)
    v = values(nominal_angle=angle, damping=damping, speed=speed)
    got = np.array([mode.frequency for mode in modes.modes(SPEC, v)])
    assert got.shape == (5,)
    np.testing.assert_allclose(got, want, rtol=1e-9)
    if speed:
        built = SPEC.build(values(nominal_angle=angle, damping=damping, speed=speed, eccentricity=0.0))
        jac = np.zeros((10, 10))
        models.dispatch.jac(SPEC.kernel[0], 0.0, np.zeros(10), built.p, jac)
        lam = np.linalg.eigvals(jac) / built.period
        np.testing.assert_allclose(np.sort(lam.imag[lam.imag > 0]) / (2 * np.pi), want, rtol=1e-9)


def test_face_to_face_is_back_to_back_mirrored_in_z():
    """face_to_face: +z compresses B. Its loads at q are those of back_to_back at q with z -> -z
    and the axial force reversed (the sum written here with the sign s = -1), exactly."""
    state = rp.bearing_state(values())
    mirror = np.diag([1.0, 1, 1, 1, -1])
    rng = np.random.default_rng(3)
    for _ in range(4):
        q = rng.normal(0, 5e-6, 5)
        f_df, k_df = rp.bearing_load(q, state, N, arrangement="face_to_face")
        f_db, k_db = rp.bearing_load(mirror @ q, state, N)
        np.testing.assert_allclose(f_df, mirror @ f_db, rtol=1e-15, atol=1e-12 * np.abs(f_db).max())
        np.testing.assert_allclose(k_df, mirror @ k_db @ mirror, rtol=1e-15, atol=1e-12 * np.abs(k_db).max())
        want, _ = pair(state.contact_constant, state.contact_angle, state.axial_approach, q, sign=-1.0)
        np.testing.assert_allclose(f_df, want, rtol=0, atol=1e-12 * np.abs(want).max())
    built = SPEC.build(values(arrangement="face_to_face"))
    assert built.p[rp.P_ARR] == -1.0


def test_given_values_are_used_and_recorded_as_given():
    derived = SPEC.build(values()).derived
    assert (derived["contact_constant_given"], derived["axial_approach_given"], derived["contact_angle_imposed"]) == (0, 0, 0)
    assert derived["free_angle_from_geometry"] == 1
    assert derived["free_contact_angle"] == pytest.approx(math.degrees(math.acos((R1 + 2 * RK - R2[15]) / (2 * RK - D))),
                                                          rel=1e-12)
    derived = SPEC.build(values(contact_constant=3e9, axial_approach=90e-6, contact_angle=16.0)).derived
    assert (derived["contact_constant"], derived["axial_approach"], derived["contact_angle_used"]) == (3e9, 90e-6, 16.0)
    assert (derived["contact_constant_given"], derived["axial_approach_given"], derived["contact_angle_imposed"]) == (1, 1, 1)
    # the 2010 table: its E and R2, the free angle from the geometry
    state = rp.bearing_state(values(table="filipkovsky2010", preload_law="hertz"))
    geom = rp.table_geometry(preloaded_pair.bearing_inputs(values(table="filipkovsky2010")))
    assert (geom.youngs_modulus, geom.outer_race_radius) == (2e11, 27.53e-3)
    assert state.static_thrust == pytest.approx(300.0, rel=1e-12)
    # hertz, too, takes the free angle from the table's geometry; the row's label only when told
    assert SPEC.build(values(preload_law="hertz")).derived["free_contact_angle"] == \
        pytest.approx(derived_free(15), rel=1e-12)
    assert SPEC.build(values(preload_law="hertz", free_angle="nominal")).derived["free_contact_angle"] == \
        pytest.approx(15.0, rel=1e-15)


def derived_free(angle):
    return math.degrees(math.acos((R1 + 2 * RK - R2[angle]) / (2 * RK - D)))


SCENE = '[scene]\nname = "x"\nmodel = "{model}"\n[bearing]\n{bearing}\n[sweep]\nspeed = [250.0]\n'


@pytest.mark.parametrize("model", ["rigid_preloaded", "symmetric4", "asymmetric5"])
@pytest.mark.parametrize("bearing_keys, message", [
    ('stiffness = "paper"', 'preload_law = "as_printed"'),
    ('stiffness = "hertz"', 'preload_law = "hertz"'),
    ('table = "filipkovsky2010"\nnominal_angle = 15.0', "without a nominal angle"),
    ('contact_constant = 3e9\naxial_approach = 2e-5', "not both"),
    ('ball_diameter = 0.0125', "bearing.ball_diameter"),
])
def test_bearing_config_errors_name_the_key_and_the_replacement(model, bearing_keys, message):
    with pytest.raises(config.ConfigError, match=message):
        config.parse_config(SCENE.format(model=model, bearing=bearing_keys))


def test_a_cube_written_with_the_removed_hybrid_opens_and_says_what_it_was(tmp_path):
    """A cube's scene lives in its config_toml attribute; it opens (no re-validation) and
    recomputing one of its points says what `stiffness = "paper"` was and what replaces it."""
    ds = synthetic_cube(speed=[250.0, 260.0], clearance=[1e-6])
    ds.attrs["config_toml"] = SCENE.format(model="rigid_preloaded", bearing='preload = 300.0\nstiffness = "paper"')
    path = tmp_path / "old.nc"
    ds.to_netcdf(path, engine="netcdf4")
    opened = cube.open_cube(path)
    assert 'stiffness = "paper"' in cube.describe(opened)
    with pytest.raises(Exception, match=r"K x 1.5.*as_printed"):
        points.scene_of(opened)


def test_the_printed_scene_config_validates():
    cfg = config.load_config("configs/filipkovsky2016_fig2a_printed.toml")
    assert cfg.data["bearing"]["preload_law"] == "as_printed"
    assert list(cfg.axes["nominal_angle"]) == [12.0, 15.0, 26.0, 36.0, 40.0]


def test_jeffcott_preload_constant_filipkovsky_is_the_law_as_printed_without_clearance():
    """jeffcott_clearance's `preload_constant = "filipkovsky"` is bearing.as_printed_state (its
    thrust 1.5 P0), and a clearance with it is a config error (the printed law has none)."""
    text = ('[scene]\nname = "j"\nmodel = "jeffcott_clearance"\n[bearing]\npreset = "angular_contact_medium"\n'
            'nominal_angle = 15\nfree_angle = "nominal"\npreload = 300.0\npreload_constant = "filipkovsky"\n{extra}[sweep]\nspeed = [100.0]\n')
    with pytest.raises(config.ConfigError, match="has no clearance"):
        config.parse_config(text.format(extra="clearance = 1e-6\n"))
    cfg = config.parse_config(text.format(extra=""))
    from rotorsweep.pipeline import compute
    derived = compute.point_params(cfg.scene, {**cfg.scene.fixed, "speed": 100.0}).derived
    geom = bearing.preset("angular_contact_medium", 15)
    want = bearing.as_printed_state(geom, 300.0, math.radians(15.0))
    assert derived["contact_angle_used"] == pytest.approx(math.degrees(want.contact_angle), rel=1e-15)
    assert want.static_thrust == pytest.approx(450.0, rel=1e-12)

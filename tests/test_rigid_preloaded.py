"""Model rigid_preloaded (Filipkovsky 2016) against independent values: the sympy derivation
of Lagrange's equations from the kinetic energy, a numpy ball sum written from the paper's
eq. 1, Hertz static equilibrium, finite differences, Hamiltonian structure (zero damping), the
frequency-ratio rules, config errors, and a small scene end to end."""
import math

import numpy as np
import pytest
import sympy as sp

from rotorsweep.pipeline import compute, config, modes, scene
from rotorsweep.kernels import integrators as ig, modal, models, shooting, continuation
from rotorsweep.kernels.attractor.poincare import _poincare
from rotorsweep.kernels.models import rigid_preloaded as rp

SPEC = models.get("rigid_preloaded")
L = rp.LENGTH_SCALE
QUICK = "configs/filipkovsky2016_quick.toml"


def values(**over):
    """The model's default values at 250 Hz (as a scene without keys would give)."""
    v = {p.name: (p.unset if p.axis else p.default) for p in SPEC.parameters}
    v["speed"] = 250.0
    v.update(over)
    return v


# --- the kinetic energy of SPEC 2.2, symbolically --------------------------------------------

def _lagrange():
    """Symbols, coordinates and Lagrange's left-hand sides d/dt dT/dq' - dT/dq (+ Rayleigh)."""
    t = sp.symbols("t")
    l, xi, m_b, m_0, i_c1, i_c0, i_1, i_0, a, om, c = sp.symbols(
        "l xi_D m_B m_0 I_C1 I_C0 I_1 I_0 a Omega C", positive=True)
    x1, y1, x2, y2, z = (sp.Function(n)(t) for n in ("x1", "y1", "x2", "y2", "z"))
    d = sp.diff
    i_d, i_p = i_c1 + i_1, i_c0 + i_0
    kin = (i_d / 2 * (((d(y1, t) - d(y2, t)) / l) ** 2 + ((d(x2, t) - d(x1, t)) / l) ** 2)
           + i_p * om * (d(y1, t) - d(y2, t)) * (x2 - x1) / l ** 2
           + m_b / 2 * (((d(x1, t) + d(x2, t)) / 2) ** 2 + ((d(y1, t) + d(y2, t)) / 2) ** 2)
           + m_0 / 2 * ((d(x1, t) * (1 - xi / l) + d(x2, t) * xi / l - a * om * sp.sin(om * t)) ** 2
                        + (d(y1, t) * (1 - xi / l) + d(y2, t) * xi / l + a * om * sp.cos(om * t)) ** 2)
           + (m_b + m_0) / 2 * d(z, t) ** 2)
    q = [x1, y1, x2, y2, z]
    rayleigh = c / 2 * sum(d(qi, t) ** 2 for qi in q)
    lhs = [sp.expand(d(d(kin, d(qi, t)), t) - d(kin, qi) + d(rayleigh, d(qi, t))) for qi in q]
    syms = dict(l=l, xi=xi, m_b=m_b, m_0=m_0, i_c1=i_c1, i_c0=i_c0, i_1=i_1, i_0=i_0, a=a, om=om, c=c, t=t)
    return syms, q, lhs


PAPER = dict(l=0.5, xi=0.125, m_b=1.963, m_0=10.0, i_c1=0.04098, i_c0=0.00015, i_1=0.1, i_0=0.2)


def _rotor(**over):
    v = values(**over)
    return rp.Rotor.of(v)


def _symbolic_matrices():
    """M, the velocity coefficients (C + Omega G) and the explicit-time terms of the equations."""
    syms, q, lhs = _lagrange()
    t = syms["t"]
    acc = [sp.diff(qi, t, 2) for qi in q]
    vel = [sp.diff(qi, t) for qi in q]
    mass = sp.Matrix([[sp.diff(e, a) for a in acc] for e in lhs])
    damp = sp.Matrix([[sp.diff(e, v) for v in vel] for e in lhs])
    rest = sp.Matrix([sp.expand(e - sum(mass[i, j] * acc[j] + damp[i, j] * vel[j] for j in range(5)))
                      for i, e in enumerate(lhs)])
    return syms, mass, damp, rest


def test_mass_and_gyroscopic_matrices_equal_the_sympy_derivation_from_T():
    """Entry by entry: the symbolic M, G and unbalance force evaluated at the paper's values equal
    the coded ones to rounding (1e-15 relative: both are a few float operations on the same
    inputs). Rayleigh gives C I; the velocity coefficients minus C I, over Omega, are G."""
    syms, mass, damp, rest = _symbolic_matrices()
    subs = {syms[k]: v for k, v in PAPER.items()}
    rotor = _rotor()
    m_sym = np.array(mass.subs(subs).evalf(), float)
    assert np.allclose(rp.mass_matrix(rotor), m_sym, rtol=1e-15, atol=1e-15 * np.abs(m_sym).max())
    g_sym = (damp - syms["c"] * sp.eye(5)) / syms["om"]
    g_sym = np.array(sp.simplify(g_sym).subs(subs).evalf(), float)
    assert np.allclose(rp.gyroscopic_matrix(rotor), g_sym, rtol=1e-15, atol=1e-15 * np.abs(g_sym).max())
    assert np.all(rp.mass_matrix(rotor) == rp.mass_matrix(rotor).T)
    # the explicit-time terms are minus the unbalance force m0 a Omega^2 u_D(t)
    t0, a, om = 0.37e-3, 3e-6, 2 * np.pi * 250
    force = -np.array(rest.subs({**subs, syms["a"]: a, syms["om"]: om, syms["t"]: t0}).evalf(), float).ravel()
    cos_part, sin_part = rp.unbalance_shape(rotor)
    coded = PAPER["m_0"] * a * om ** 2 * (cos_part * np.cos(om * t0) + sin_part * np.sin(om * t0))
    assert np.allclose(force, coded, rtol=1e-14, atol=1e-14 * np.abs(coded).max())


def _paper_forces(q, alpha, z0, k, n):
    """Generalized bearing forces written from the paper's eq. 1 with the back-to-back signs:
    +z in bearing A, -z in B; the axial generalized force is P_zA - P_zB. Loops, no shared code."""
    out = np.zeros(5)
    for k_ball in range(n):
        b = 2 * np.pi * k_ball / n
        for v, (jx, jy), sign in ((0, (0, 1), 1.0), (1, (2, 3), -1.0)):
            delta = (q[jx] * np.cos(alpha) * np.cos(b) + q[jy] * np.cos(alpha) * np.sin(b)
                     + (z0 + sign * q[4]) * np.sin(alpha))
            load = k * max(delta, 0.0) ** 1.5
            out[jx] += load * np.cos(alpha) * np.cos(b)
            out[jy] += load * np.cos(alpha) * np.sin(b)
            out[4] += sign * load * np.sin(alpha)
    return out


def _si_acceleration(built, u, tau):
    du = np.zeros(10)
    models.dispatch.rhs(SPEC.kernel.tag, tau, u, built.p, du)
    return du[5:] * L / built.period ** 2


@pytest.mark.parametrize("preload_law", ["hertz", "as_printed"])
def test_coded_equations_equal_lagrange_with_the_bearing_forces(preload_law):
    """At random states (some balls unloaded) and times: kernel accelerations (SI) = M^-1 of
    [unbalance + support - (C + Omega G) q' - P(q) + weight] from the symbolic M and G and the
    paper-formula ball sum, to 1e-11 relative (M^-1 and the scaling cost a few ulps each)."""
    syms, mass, damp, rest = _symbolic_matrices()
    v = values(preload_law=preload_law, support_frequency=150.0, support_acceleration=7.0, gravity=9.81,
               eccentricity=4e-6, support_direction="x")
    built = SPEC.build(v)
    state = rp.bearing_state(v)
    om = 2 * np.pi * v["speed"]
    subs = {**{syms[k]: val for k, val in PAPER.items()}, syms["a"]: v["eccentricity"], syms["om"]: om,
            syms["c"]: v["damping"]}
    m = np.array(mass.subs(subs).evalf(), float)
    cg = np.array(damp.subs(subs).evalf(), float)
    rng = np.random.default_rng(13)
    unloaded = 0
    # 4 um for the Hertz bracket (~5 um at rest); the printed law's bracket z0 sin a is ~4x larger
    spread = 4e-6 * state.normal_approach / rp.preload_of(15, 300.0).normal_approach
    for _ in range(6):
        q = rng.normal(0, spread, 5)
        qd = rng.normal(0, 0.05, 5)
        tau = rng.uniform(0, 1)
        t = tau * built.period
        forcing = -np.array(rest.subs({**subs, syms["t"]: t}).evalf(), float).ravel()
        support = np.array([7.0, 0, 7.0, 0, 0]) * np.sin(2 * np.pi * 150.0 * t)
        weight = -9.81 * np.array([0, 1.963 / 2 + 10 * 0.75, 0, 1.963 / 2 + 10 * 0.25, 0])
        bearing_force = _paper_forces(q, state.contact_angle, state.axial_approach, state.contact_constant, 7)
        expected = np.linalg.solve(m, forcing - cg @ qd - bearing_force + weight) - support
        u = np.concatenate([q / L, qd * built.period / L])
        got = _si_acceleration(built, u, tau)
        assert np.allclose(got, expected, rtol=0, atol=1e-11 * np.abs(expected).max())
        unloaded += _n_unloaded(u, built.p)
    assert unloaded > 0


def _deltas(u, p):
    """Scaled deformations of all balls of both bearings."""
    b = 2 * np.pi * np.arange(int(p[rp.P_NBALLS])) / p[rp.P_NBALLS]
    ca, sa = p[rp.P_COS_A], p[rp.P_SIN_A]
    da = (u[0] * np.cos(b) + u[1] * np.sin(b)) * ca + u[4] * sa + p[rp.P_OFFSET]
    db = (u[2] * np.cos(b) + u[3] * np.sin(b)) * ca - u[4] * sa + p[rp.P_OFFSET]
    return np.concatenate([da, db])


def _n_unloaded(u, p):
    return int(np.sum(_deltas(u, p) <= 0))


def test_static_equilibrium_under_preload():
    """hertz: N K delta^{3/2} sin(a) = P0 per bearing to 1e-12 (the brentq solve of the preload
    equations is converged to 4 ulp in ln u); as_printed: 1.5 P0 (its K as printed, SPEC 1 note).
    With gravity, Newton's equilibrium balances the weight to 1e-12 x P0 against the paper-
    formula ball sum; the imposed-angle state holds the preload too."""
    for angle in rp.NOMINAL_ANGLES:
        for law, factor in (("hertz", 1.0), ("as_printed", 1.5)):
            s = rp.bearing_state(values(nominal_angle=angle, preload_law=law))
            axial = 7 * s.contact_constant * (s.axial_approach * math.sin(s.contact_angle)) ** 1.5 * math.sin(s.contact_angle)
            assert abs(axial - factor * 300.0) <= 1e-12 * 300.0
    s = rp.bearing_state(values(contact_angle=20.0))
    assert s.contact_angle == pytest.approx(math.radians(20.0), rel=1e-15)
    assert abs(_paper_forces(np.zeros(5), s.contact_angle, s.axial_approach, s.contact_constant, 7)[4]) == 0.0
    single = 7 * s.contact_constant * (s.axial_approach * math.sin(s.contact_angle)) ** 1.5 * math.sin(s.contact_angle)
    assert abs(single - 300.0) <= 1e-12 * 300.0
    v = values(gravity=9.81)
    eq = rp.static_equilibrium(v)
    s = rp.bearing_state(v)
    force = _paper_forces(eq.position, s.contact_angle, s.axial_approach, s.contact_constant, 7)
    assert np.abs(force - rp.weight(rp.Rotor.of(v))).max() <= 1e-12 * 300.0
    assert eq.position[1] < 0 and eq.position[3] < 0


def test_analytic_jacobian_equals_central_differences_including_unloaded_balls():
    """At random states where 1-6 balls carry nothing (every |delta| > 0.05 um, so a central
    step h = 1e-4 um never crosses a contact kink): the truncation error of the central
    difference of delta^{3/2} is h^2 / 6 x 0.375 delta^{-3/2} <= 6e-8 (times the gain) on
    derivatives whose largest is >= 10 (x the gain), so 1e-7 relative to max |J| holds with a
    margin of ~15; roundoff (eps |f| / h) is ~1e-10. rhs_jac gives the same as rhs and jac."""
    built = SPEC.build(values(support_frequency=150.0, support_acceleration=7.0))
    p = built.p
    rng = np.random.default_rng(7)
    tested = 0
    h = 1e-4
    while tested < 8:
        u = np.concatenate([rng.normal(0, 3.0, 5), rng.normal(0, 50.0, 5)])
        d = _deltas(u, p)
        if np.abs(d).min() < 0.05 or not 1 <= np.sum(d <= 0) <= 6:
            continue
        tested += 1
        jac = np.zeros((10, 10))
        models.dispatch.jac(SPEC.kernel.tag, 0.3, u, p, jac)
        fd = np.zeros((10, 10))
        for j in range(10):
            up, dn, e = np.zeros(10), np.zeros(10), np.zeros(10)
            e[j] = h
            models.dispatch.rhs(SPEC.kernel.tag, 0.3, u + e, p, up)
            models.dispatch.rhs(SPEC.kernel.tag, 0.3, u - e, p, dn)
            fd[:, j] = (up - dn) / (2 * h)
        assert np.abs(fd - jac).max() <= 1e-7 * np.abs(jac).max()
        du, du2, jac2 = np.zeros(10), np.zeros(10), np.zeros((10, 10))
        models.dispatch.rhs(SPEC.kernel.tag, 0.3, u, p, du)
        models.dispatch.rhs_jac(SPEC.kernel.tag, 0.3, u, p, du2, jac2)
        assert np.array_equal(du, du2) and np.array_equal(jac, jac2)


def test_linear_frequencies_analytic_equal_eigenvalues_of_the_finite_difference_jacobian():
    """Analytic linearization: k_r = (3/4) N K delta^{1/2} cos^2 a per journal and direction and
    2 k_a axially (bearing.preload_state's closed forms; sum cos^2 b_k = N / 2, the cross terms
    vanish for N >= 3). Against the eigenvalues of the central-difference Jacobian of the full
    kernel at the static state (h = 1e-3 um, delta = 5 um: truncation (h/delta)^2 / 8 ~ 5e-9 on
    the stiffness, half of it on the frequency): 1e-8 relative on every frequency."""
    for angle in (15, 36):
        v = values(nominal_angle=angle, eccentricity=0.0)
        s = rp.bearing_state(v)
        stiffness = np.diag([s.radial_stiffness] * 4 + [2 * s.axial_stiffness])
        r = rp.Rotor.of(v)
        damping = r.damping * np.eye(5) + 2.0 * np.pi * v["speed"] * rp.gyroscopic_matrix(r)
        analytic = np.linalg.eigvals(modal.first_order(rp.mass_matrix(r), damping, stiffness))
        built = SPEC.build(v)
        h, fd = 1e-3, np.zeros((10, 10))
        for j in range(10):
            up, dn, e = np.zeros(10), np.zeros(10), np.zeros(10)
            e[j] = h
            models.dispatch.rhs(SPEC.kernel.tag, 0.0, e, built.p, up)
            models.dispatch.rhs(SPEC.kernel.tag, 0.0, -e, built.p, dn)
            fd[:, j] = (up - dn) / (2 * h)
        numeric = np.linalg.eigvals(fd) / built.period
        f_a = np.sort(analytic.imag[analytic.imag > 0])
        f_n = np.sort(numeric.imag[numeric.imag > 0])
        assert np.allclose(f_n, f_a, rtol=1e-8, atol=0)
        assert np.allclose(np.sort(numeric.real), np.sort(analytic.real), rtol=0, atol=1e-8 * np.abs(analytic).max())


def test_gyroscopic_splitting_grows_with_speed_and_vanishes_at_rest():
    """Forward minus backward frequency of the conical pair: 0 at rest (to eigen-solver
    rounding), increasing with speed; forward whirl stiffens (the gyroscopic sign)."""
    v = values()
    eq = rp.static_equilibrium(v)
    split = []
    for f in (0.0, 100.0, 300.0, 1000.0):
        conical = [m for m in modes.modes(SPEC, {**v, "speed": f}, eq) if m.label == "conical"]
        assert len(conical) == 2
        split.append(conical[1].frequency - conical[0].frequency)
        if f > 0:
            assert [m.whirl for m in conical] == ["backward", "forward"]
    assert abs(split[0]) <= 1e-9 * conical[0].frequency
    assert all(b > a for a, b in zip(split, split[1:]))
    labels = [m.label for m in modes.modes(SPEC, {**v, "speed": 250.0}, eq)]
    assert labels == ["axial", "cylindrical", "cylindrical", "conical", "conical"]


def test_zero_damping_multipliers_on_the_unit_circle_and_energy_conserved():
    """Conservative rotor (C = 0): a forced orbit with a tiny unbalance (1e-12 m) is the static
    state to first order, its monodromy symplectic up to the integration error (rtol 1e-12 over
    one period: ~1e-11), so every |multiplier| = 1 to 1e-8. Unforced, a free vibration of 1 um
    conserves E = (1/2) q'M q' + (2/5) K sum [delta]^{5/2} (gyroscopic forces do no work) to 1e-9
    of its vibration energy."""
    opts = ig.settings(rtol=1e-12, atol=1e-14)
    v = values(damping=0.0, eccentricity=1e-12)
    built = SPEC.build(v)
    sol = continuation.solve_orbit(SPEC, built.p, opts, cold_guess=SPEC.cold_guess, tol=1e-10)
    assert sol.status == shooting.CONVERGED
    assert np.abs(np.abs(sol.multipliers) - 1.0).max() <= 1e-8
    free = SPEC.build(values(damping=0.0, eccentricity=0.0))
    s = rp.bearing_state(values())
    u0 = np.array([1.0, -0.5, 0.3, 0.8, 0.2, 0, 0, 0, 0, 0])
    traj = shooting.sample_orbit(SPEC.kernel, u0, free.p, 20.0, 400, opts)
    x = traj * L
    q, qd = x[:, :5], x[:, 5:] / free.period
    m = rp.mass_matrix(rp.Rotor.of(values()))

    def energy(qi, qdi):
        d = _deltas(qi / L, free.p) * L
        return 0.5 * qdi @ m @ qdi + 0.4 * s.contact_constant * np.sum(np.maximum(d, 0) ** 2.5)
    e = np.array([energy(qi, qdi) for qi, qdi in zip(q, qd)])
    e_static = energy(np.zeros(5), np.zeros(5))
    assert np.abs(e - e[0]).max() <= 1e-9 * (e[0] - e_static)


def test_rational_ratio_gives_the_common_period_and_golden_ratio_is_quasi_periodic():
    assert rp.frequency_ratio(0.6, 64) == rp.Ratio(rp.RATIONAL, 3, 5)
    built = SPEC.build(values(support_frequency=150.0, support_acceleration=5.0))
    assert built.periodic and built.period == pytest.approx(5 / 250.0, rel=1e-15)
    assert built.p[rp.P_WU] == pytest.approx(2 * np.pi * 5) and built.p[rp.P_WS] == pytest.approx(2 * np.pi * 3)
    assert built.derived["frequency_ratio_p"] == 3 and built.derived["frequency_ratio_q"] == 5
    golden = (1 + 5 ** 0.5) / 2
    assert rp.frequency_ratio(golden, 64).kind == rp.IRRATIONAL
    assert rp.frequency_ratio(251 / 250, 64) == rp.Ratio(rp.LONG_PERIOD, 251, 250)
    quasi = SPEC.build(values(support_frequency=250.0 * golden, support_acceleration=5.0))
    assert not quasi.periodic and quasi.period == pytest.approx(1 / 250.0)
    # only one forcing on: its own period, whatever the other frequency
    assert SPEC.build(values(support_frequency=250.0 * golden)).period == pytest.approx(1 / 250.0)


def test_quasi_periodic_point_has_no_orbit_and_its_samples_run_on_in_time():
    """Golden-ratio forcing: orbit_status not_applicable (quasi_periodic_forcing), multipliers
    NaN; the stroboscopic samples of a quasi-periodic point follow the continuous-time flow
    (not a flow restarted at tau = 0 each period), to the integration tolerance."""
    cfg = config.load_config(QUICK)
    data = scene.from_data({**cfg.data, "analysis": {**cfg.data["analysis"], "attractor": False}})
    pts = [{**data.fixed, "speed": 250.0, "support_frequency": f} for f in cfg.axes["support_frequency"]]
    out = compute.solve_segment(data, pts)
    from rotorsweep.pipeline import schema
    status = [schema.ORBIT_STATUS[k] for k in out["orbit_status"]]
    reason = [schema.ORBIT_REASON[k] for k in out["orbit_reason"]]
    assert status == ["converged", "not_applicable", "converged"]
    assert reason[1] == "quasi_periodic_forcing"
    assert np.isnan(out["multiplier_real"][1]).all() and np.isfinite(out["multiplier_real"][0]).all()
    assert list(out["periodic_forcing"]) == [1.0, 0.0, 1.0]
    built = compute.point_params(data, pts[1])
    opts = data.integrator
    u0 = np.zeros(10)
    samples, status, _ = _poincare(SPEC.kernel, u0, built.p, opts, 0, 6, 0.0, 1.0)
    flow = shooting.sample_orbit(SPEC.kernel, u0, built.p, 5.0, 5, opts)
    continuous = np.vstack([flow[1:], _advance(built, flow[-1], 4.0, opts)])
    assert np.allclose(samples[1:], continuous, atol=1e-6)
    restarted, _, _ = _poincare(SPEC.kernel, u0, built.p, opts, 0, 6, 0.0, 0.0)
    assert np.abs(restarted[2:] - continuous[1:]).max() > 1e-3   # the test tells the two apart


def _advance(built, u, t0, opts):
    z, _, _, _ = ig.flow(SPEC.kernel, t0, t0 + 1.0, u.copy(), built.p, False, opts, 0.0)
    return z[None, :]


@pytest.mark.parametrize("toml, key", [
    ("[bearing]\npreload = 0.0", "bearing.preload"),
    ("[bearing]\npreload = -5.0", "bearing.preload"),
    ("[bearing]\ncontact_angle = 95.0", "bearing.contact_angle"),
    ("[bearing]\ncontact_angle = 0.0", "bearing.contact_angle"),
    ("[bearing]\nouter_race_radius = 0.0285", "bearing.outer_race_radius"),
    ("[bearing]\nnominal_angle = 20.0", "bearing.nominal_angle"),
    ("[forcing]\nsupport_acceleration = 5.0\nsupport_frequency = 251.0", "forcing.support_frequency"),
])
def test_invalid_input_is_a_config_error_naming_the_key(toml, key):
    text = f'[scene]\nname = "bad"\nmodel = "rigid_preloaded"\n{toml}\n[sweep]\nspeed = [250.0]\n'
    with pytest.raises(config.ConfigError) as exc:
        config.parse_config(text)
    assert key in str(exc.value)


def test_long_common_period_is_only_an_error_when_orbits_are_requested():
    base = ('[scene]\nname = "x"\nmodel = "rigid_preloaded"\n[forcing]\nsupport_acceleration = 5.0\n'
            '[sweep]\nspeed = [250.0]\nsupport_frequency = [150.0, 251.0]\n')
    with pytest.raises(config.ConfigError, match="251/250 has a common period of 250 shaft revolutions"):
        config.parse_config(base)
    cfg = config.parse_config(base + "[analysis]\nfloquet = false\nattractor = true\n")
    assert cfg.continued_axis == "support_frequency"
    assert config.parse_config(base.replace("support_acceleration = 5.0",
                                            "support_acceleration = 5.0\nmax_denominator = 250"))


def test_small_scene_sweeps_end_to_end(tmp_path):
    """configs/filipkovsky2016_quick.toml through rotorsweep.pipeline.sweep.run: the 3/5 point has a
    stable orbit whose attractor is that period-1 orbit, the golden-ratio point an attractor
    but no orbit; the cube says which case each point is."""
    from rotorsweep.pipeline import cube, schema, sweep
    cfg = config.load_config(QUICK)
    ds = cube.open_cube(sweep.run(cfg, tmp_path / "quick.nc", workers=1, progress=False))
    pt = ds.isel(speed=0)
    assert list(pt["periodic_forcing"].values) == [1, 0, 1]
    assert schema.ORBIT_REASON[int(pt["orbit_reason"][1])] == "quasi_periodic_forcing"
    assert int(pt["stable"][0]) == 1 and np.isnan(pt["max_abs_multiplier"][1])
    assert schema.ATTRACTOR[int(pt["attractor"][0])] == "periodic"
    assert np.isfinite(pt["lle"][1]) and np.isfinite(pt["poincare_y_B"][1]).all()
    assert float(pt["amplitude_y_B"][0]) > 0 and pt["contact_angle_used"][0] == pytest.approx(17.78, abs=0.01)


def test_a_point_imports_no_heavy_module():
    """`rotorsweep point` on the quick scene (the kernels are in the disk cache after the sweep
    above): its answer, without importing what a point does not need (each 0.1-0.6 s of a warm
    point's ~1 s): scipy.optimize (the preload's and the Hertz ellipticity's roots are
    rotorsweep.kernels.roots), scipy.special (the Hertz constant's elliptic integrals are the AGM's),
    xarray, pandas, Dask."""
    import json
    import subprocess
    import sys

    heavy = ("scipy.optimize", "scipy.special", "xarray", "pandas", "dask", "distributed")
    script = ("import json, sys; from rotorsweep.pipeline.cli import main; "
              f"main(['point', '--config', {QUICK!r}, '--at', 'speed=250', '--at', 'support_frequency=150', '--json']); "
              f"print(json.dumps(sorted(m for m in {heavy!r} if m in sys.modules)))")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    *point, loaded = proc.stdout.strip().splitlines()
    assert json.loads(loaded) == []
    assert json.loads("\n".join(point))["status"] == "converged"

"""Kernel numerics against independent values: finite differences, linear algebra, scipy."""
import os
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.optimize import linear_sum_assignment

from rotorsweep.kernels import continuation, floquet, integrators as ig, models, shooting
from rotorsweep.kernels.continuation import events as boundary
from rotorsweep.kernels.models import jeffcott_clearance as jc
from tests.reference import BAI, BaiPoint

JEFF = models.get("jeffcott_clearance")
TIGHT = ig.settings(rtol=1e-13, atol=1e-15)


def bai_params(point, **overrides):
    kw = dict(speed=point.speed, stiffness=point.K, clearance=point.clearance, contact_angle=point.alpha,
              axial_approach=0.0, mass=point.mass, damping=point.damping, radial_load=point.load,
              n_balls=point.n_balls, ball_diameter=BAI["Db"], pitch_diameter=BAI["Dm"])
    kw.update(overrides)
    return jc.jeffcott_params(**kw)


def solve_bai(point, opts=TIGHT, tol=1e-12):
    p, period = bai_params(point)
    sol = continuation.solve_orbit(JEFF, p, opts, cold_guess=jc.static_guess, tol=tol,
                                   transient_periods=100)
    assert sol.status == shooting.CONVERGED, sol
    return sol, period


def match(a, b):
    """Pair two multiplier sets by nearest values; return the largest pair distance."""
    cost = np.abs(np.subtract.outer(a, b))
    rows, cols = linear_sum_assignment(cost)
    return cost[rows, cols].max()


def scaled_rhs(p, tau, u):
    du = np.empty(4)
    models.dispatch.rhs(JEFF.kernel.tag, tau, np.asarray(u, float), p, du)
    return du


# --- Jacobian ------------------------------------------------------------------------------

def grazing_states(p, rng, n):
    """States where one ball's deformation is 1e-4 (scaled, i.e. 1e-10 m) on either side of zero:
    the finite-difference step stays on one side, so the C^1 kink does not blur the comparison."""
    states = []
    for _ in range(n):
        tau = rng.uniform(0, 1)
        theta = p[jc.P_PHI0] + 2 * np.pi * tau / p[jc.P_NBALLS]
        phi = theta + 2 * np.pi * rng.integers(9) / 9
        radius = (1e-4 * rng.choice([-1, 1]) - p[jc.P_OFFSET]) / p[jc.P_COS_A]
        u = np.array([radius * np.cos(phi), radius * np.sin(phi), *rng.normal(size=2)])
        states.append((tau, u))
    return states


def test_analytic_jacobian_matches_finite_differences():
    rng = np.random.default_rng(1)
    p, _ = bai_params(BaiPoint(120.0, 7.6e-6))
    cases = [(rng.uniform(0, 1), rng.normal(scale=15.0, size=4)) for _ in range(40)]
    cases += grazing_states(p, rng, 20)
    for tau, u in cases:
        jac = np.empty((4, 4))
        models.dispatch.jac(JEFF.kernel.tag, tau, u, p, jac)
        h = 1e-7
        fd = np.column_stack([(scaled_rhs(p, tau, u + h * e) - scaled_rhs(p, tau, u - h * e)) / (2 * h)
                              for e in np.eye(4)])
        np.testing.assert_allclose(jac, fd, rtol=0, atol=1e-6 * max(1.0, np.abs(fd).max()))


# --- Floquet multipliers of linear systems --------------------------------------------------

LINEAR = models.get("linear_oscillator")
MATHIEU = models.get("damped_mathieu")


@pytest.mark.parametrize("opts, tol", [(ig.settings(rtol=1e-12, atol=1e-14), 1e-10),
                                      (ig.settings("rk4", steps_per_unit=400), 1e-7)])
def test_linear_oscillator_multipliers_are_exp_of_eigenvalues(opts, tol):
    p = np.array([40.0, 5.0, 90.0, 0.4, 0.9])
    a = np.zeros((4, 4))
    models.dispatch.jac(LINEAR.kernel.tag, 0.0, np.zeros(4), p, a)
    orbit = shooting.periodic_orbit(LINEAR, np.array([1.0, -2.0, 0.5, 0.3]), p, opts, tol=1e-12)
    assert orbit.status == shooting.CONVERGED and orbit.iterations <= 2
    np.testing.assert_allclose(orbit.state, 0.0, atol=1e-10)
    analytic = np.exp(np.linalg.eigvals(a))           # multipliers of a constant-coefficient system
    assert match(floquet.multipliers(orbit.monodromy), analytic) < tol
    np.testing.assert_allclose(orbit.monodromy, expm(a), atol=tol)


def test_damped_mathieu_multipliers_match_scipy_and_liouville():
    p = np.array([0.05, 4.0, 2.5])
    orbit = shooting.periodic_orbit(MATHIEU, np.full(4, 0.1), p, ig.settings(rtol=1e-12, atol=1e-14),
                                    tol=1e-12)
    lam = floquet.multipliers(orbit.monodromy)

    def variational(t, y):
        k = p[1] + p[2] * np.cos(2 * np.pi * t)
        return np.array([[0, 1], [-k, -2 * p[0]]]) @ y.reshape(2, 2)

    sol = solve_ivp(lambda t, y: variational(t, y).ravel(), (0, 1), np.eye(2).ravel(),
                    method="DOP853", rtol=1e-13, atol=1e-15)
    reference = np.linalg.eigvals(sol.y[:, -1].reshape(2, 2))
    assert match(lam, np.concatenate([reference, reference])) < 1e-9
    assert abs(np.prod(lam).real - np.exp(-4 * p[0])) < 1e-11   # det = exp(trace) per unit time


# --- the Bai 2006 model against an independent scipy computation ---------------------------

BAI_POINTS = [BaiPoint(60.0, 3.8e-6), BaiPoint(100.0, 7.6e-6), BaiPoint(150.0, 11.4e-6),
              BaiPoint(200.0, 19.0e-6)]


def reference_map_error(point, u, scale):
    """Error of the reference period map P(u) (scipy DOP853 at rtol 1e-13), in units of `scale`:
    the spread of P(u) over tolerances around 1e-13. Near roundoff the error is not monotone in
    rtol and depends on the CPU's rounding (FMA, libm): at 60 Hz it is 1.1e-9 at rtol 1e-13 on
    some machines and 5e-12 at 1e-12, so it is measured here, not assumed."""
    maps = np.array([point.period_map(u, rtol=r) for r in (1e-12, 1e-13, 3e-14)])
    return np.max(np.ptp(maps, axis=0) / scale)


def fd_monodromy_error(point, u, scale, rel_step=1e-4):
    """Richardson estimate of the central-difference monodromy's O(h^2) error, 2-norm in scaled
    coordinates: (M(2h) - M(h)) / 3."""
    coarse = point.fd_monodromy(u, scale, rel_step=2 * rel_step)
    fine = point.fd_monodromy(u, scale, rel_step=rel_step)
    return np.linalg.norm((coarse - fine) * scale[None, :] / scale[:, None], 2) / 3


@pytest.mark.parametrize("point", BAI_POINTS, ids=lambda pt: f"{pt.speed}Hz-{pt.clearance * 1e6}um")
def test_bai_orbit_and_multipliers_match_scipy_reference(point):
    """Error model (scaled units: lengths in um). Our orbit solves to Newton tol 1e-12 on a
    1e-13 integration; the reference takes one Newton step from it with its own map P (error
    eps(u), measured) and a finite-difference monodromy. That step carries the map error at the
    start into the new point and adds the one at the end: residual <= 2 (eps(ours) + eps(ref)),
    the 2 for a spread that may underestimate one map's error. The reference then differs from
    the true orbit by |(M - I)^-1| * residual, and from ours by that plus the same amount again.
    Its multipliers are those of the FD monodromy: by Bauer-Fike within cond(V) |dM| of the true
    ones (V: eigenvectors, dM: the FD error, 2x its Richardson estimate)."""
    sol, period = solve_bai(point)
    ours = jc.to_physical(sol.state, period)
    ref_state, ref_mono, ref_residual = point.periodic_orbit(ours, iterations=1)
    scale = jc.to_physical(np.ones(4), period)
    eps = reference_map_error(point, ours, scale) + reference_map_error(point, ref_state, scale)
    assert ref_residual < 2 * eps + 1e-12
    scaled_mono = ref_mono * scale[None, :] / scale[:, None]
    inverse = np.linalg.norm(np.linalg.inv(scaled_mono - np.eye(4)), np.inf)
    np.testing.assert_allclose(ours / scale, ref_state / scale, rtol=0, atol=2 * inverse * (2 * eps + 1e-12))
    cond_v = np.linalg.cond(np.linalg.eig(scaled_mono)[1])
    assert match(sol.multipliers, np.linalg.eigvals(ref_mono)) < cond_v * 2 * fd_monodromy_error(point, ref_state, scale)


@pytest.mark.parametrize("speed, clearance", [(20.0, 3.8e-6), (90.0, 7.6e-6), (130.0, 15.2e-6),
                                              (240.0, 19.0e-6)])
def test_product_of_multipliers_obeys_liouville(speed, clearance):
    point = BaiPoint(speed, clearance)
    sol, period = solve_bai(point, opts=ig.settings(rtol=1e-11, atol=1e-13), tol=1e-10)
    expected = np.exp(-point.damping * period / point.mass) ** 2
    assert abs(np.prod(sol.multipliers).real - expected) < 1e-9


def test_rk4_converges_towards_dop853_at_reduced_order_across_contact_switching():
    point = BaiPoint(60.0, 3.8e-6)
    exact, _ = solve_bai(point)
    p, _ = bai_params(point)
    errors = []
    for steps in (256, 512, 1024):
        sol = continuation.solve_orbit(JEFF, p, ig.settings("rk4", steps_per_unit=steps), [exact.state],
                                       cold_guess=jc.static_guess, tol=1e-12)
        errors.append(match(sol.multipliers, exact.multipliers))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    # a smooth problem gives 2^4 = 16 per halving; the C^1 contact force (the Jacobian has a
    # square-root kink where a ball loses contact) brings RK4 down to an order of about 2.3-2.8
    orders = np.log2(ratios)
    assert np.all((orders > 2.0) & (orders < 4.5)), (errors, orders)


# --- reduced physics and limits -------------------------------------------------------------

def test_zero_preload_law_is_bai_law():
    rng = np.random.default_rng(3)
    point = BaiPoint(130.0, 11.4e-6)
    p, period = bai_params(point)
    scale = jc.to_physical(np.ones(4), period)
    for _ in range(30):
        tau, u = rng.uniform(0, 3), rng.normal(scale=12.0, size=4)
        ours = scaled_rhs(p, tau, u)
        ref = np.array(point.rhs(tau * period, u * scale))
        np.testing.assert_allclose(ours, ref / scale * period, rtol=1e-12, atol=1e-9)


def test_zero_clearance_law_is_filipkovsky_preloaded_law():
    """c = 0, s0 = z0: delta_k = x cos a cos b_k + y cos a sin b_k + z0 sin a (2016 paper)."""
    rng = np.random.default_rng(4)
    alpha, z0, K, n = np.radians(26.0), 4e-6, 8e9, 7
    p, period = jc.jeffcott_params(speed=100.0, stiffness=K, clearance=0.0, contact_angle=alpha,
                                       axial_approach=z0, mass=3.0, damping=50.0, radial_load=0.0,
                                       n_balls=n, ball_diameter=11.51e-3, pitch_diameter=43.5e-3,
                                       cage_rotation=False)
    scale = jc.to_physical(np.ones(4), period)
    b = 2 * np.pi * np.arange(n) / n
    for _ in range(20):
        u = rng.normal(scale=3.0, size=4)
        x, y = u[:2] * 1e-6
        delta = x * np.cos(alpha) * np.cos(b) + y * np.cos(alpha) * np.sin(b) + z0 * np.sin(alpha)
        q = K * np.clip(delta, 0, None) ** 1.5
        fx, fy = np.sum(q * np.cos(alpha) * np.cos(b)), np.sum(q * np.cos(alpha) * np.sin(b))
        ref_acc = np.array([-50.0 * u[2] * scale[2] - fx, -50.0 * u[3] * scale[3] - fy]) / 3.0
        ours = scaled_rhs(p, 0.37, u)
        np.testing.assert_allclose(ours[2:] * scale[2:] / period, ref_acc, rtol=1e-11)


def test_frozen_cage_orbit_is_static_equilibrium_with_expm_monodromy():
    """Without cage rotation the system is autonomous: the 'periodic orbit' is the equilibrium
    and the monodromy over one period is expm(A) of the linearization (FD of the reference)."""
    point = BaiPoint(80.0, 7.6e-6)
    p, period = bai_params(point, cage_rotation=False)
    sol = continuation.solve_orbit(JEFF, p, TIGHT, cold_guess=jc.static_guess, tol=1e-12,
                                   transient_periods=200)
    assert sol.status == shooting.CONVERGED
    scale = jc.to_physical(np.ones(4), period)
    eq = sol.state * scale
    frozen = lambda u: np.array(point.rhs(0.0, u))  # noqa: E731 - reference rhs at t = 0 (balls fixed)
    np.testing.assert_allclose(frozen(eq)[2:] / (scale[2] / period), 0.0, atol=1e-9)
    h = 1e-4 * scale
    a = np.column_stack([(frozen(eq + h[i] * e) - frozen(eq - h[i] * e)) / (2 * h[i])
                         for i, e in enumerate(np.eye(4))])
    assert match(sol.multipliers, np.exp(np.linalg.eigvals(a) * period)) < 1e-7


# --- stability boundary ---------------------------------------------------------------------

def test_boundary_is_located_far_below_the_grid_step():
    clearance = 7.6e-6
    opts = ig.settings(rtol=1e-12, atol=1e-14)

    def solve(speed, guess):
        p, _ = bai_params(BaiPoint(speed, clearance))
        return continuation.solve_orbit(JEFF, p, opts, [guess], cold_guess=jc.static_guess, tol=1e-11)

    start = solve(70.0, jc.static_guess(bai_params(BaiPoint(70.0, clearance))[0]))
    grid = np.arange(70.0, 110.0, 2.0)
    states, mus = [start.state], []
    for speed in grid:
        sol = solve(speed, states[-1])
        states.append(sol.state)
        mus.append(sol.max_abs)
    i = int(np.argmax(np.array(mus) > 1.0))
    assert i > 0, "the grid must bracket a crossing"
    found = boundary.locate_boundary(solve, grid[i - 1], grid[i], states[i], states[i + 1], xtol_rel=1e-8)
    assert abs(found.solution.max_abs - 1.0) < 1e-5
    assert floquet.crossing_type(found.solution.multipliers[0]) == floquet.PERIOD_DOUBLING
    # independent check: the scipy reference sees the crossing within 1e-6 relative
    below = BaiPoint(found.value * (1 - 1e-6), clearance)
    above = BaiPoint(found.value * (1 + 1e-6), clearance)
    mu = []
    for pt, state in ((below, found.solution.state), (above, found.solution.state)):
        _, period = bai_params(pt)
        _, mono, _ = pt.periodic_orbit(jc.to_physical(state, period), iterations=2)
        mu.append(np.abs(np.linalg.eigvals(mono)).max())
    assert mu[0] < 1.0 < mu[1], mu


@pytest.mark.parametrize("preload", [50.0, 300.0, 1500.0])
def test_preloaded_law_linearizes_to_the_bearing_radial_stiffness(preload):
    """Two independent routes to the radial stiffness of a preloaded bearing: the closed form of
    rotorsweep.kernels.bearing ((3/4) N K delta_n^{1/2} cos^2 a) and the kernel's analytic Jacobian of
    the ball-by-ball force law at the centred journal."""
    from rotorsweep.kernels import bearing

    geom = bearing.preset("angular_contact_medium", 26)
    state = bearing.preload_state(geom, preload)
    mass = 3.0
    p, period = jc.jeffcott_params(
        speed=100.0, stiffness=state.contact_constant, clearance=0.0, contact_angle=state.contact_angle,
        axial_approach=state.axial_approach, mass=mass, damping=0.0, radial_load=0.0,
        n_balls=geom.n_balls, ball_diameter=geom.ball_diameter, pitch_diameter=geom.pitch_diameter)
    jac = np.empty((4, 4))
    models.dispatch.jac(JEFF.kernel.tag, 0.3, np.zeros(4), p, jac)
    np.testing.assert_allclose(-jac[2, 0] * mass / period ** 2, state.radial_stiffness, rtol=1e-12)
    np.testing.assert_allclose(-jac[3, 1] * mass / period ** 2, state.radial_stiffness, rtol=1e-12)
    np.testing.assert_allclose(scaled_rhs(p, 0.3, np.zeros(4)), 0.0, atol=1e-9)


# --- fused and structured kernels (issue 5) --------------------------------------------------

def _model_cases(rng):
    """(model, p, tau, u) over all three models; Bai states include grazing contacts."""
    p_bai, _ = bai_params(BaiPoint(120.0, 7.6e-6))
    cases = [(JEFF, p_bai, rng.uniform(0, 1), rng.normal(scale=15.0, size=4)) for _ in range(20)]
    cases += [(JEFF, p_bai, tau, u) for tau, u in grazing_states(p_bai, rng, 10)]
    cases += [(LINEAR, np.array([40.0, 5.0, 90.0, 0.4, 0.9]), rng.uniform(0, 1), rng.normal(size=4))
              for _ in range(5)]
    cases += [(MATHIEU, np.array([0.05, 4.0, 2.5]), rng.uniform(0, 3), rng.normal(size=4))
              for _ in range(5)]
    return cases


def test_fused_rhs_jac_equals_rhs_and_jac():
    rng = np.random.default_rng(5)
    for model, p, tau, u in _model_cases(rng):
        du, jac = np.empty(4), np.empty((4, 4))
        models.dispatch.rhs(model.kernel.tag, tau, u, p, du)
        models.dispatch.jac(model.kernel.tag, tau, u, p, jac)
        du2, jac2 = np.full(4, np.nan), np.full((4, 4), np.nan)
        models.dispatch.rhs_jac(model.kernel.tag, tau, u, p, du2, jac2)
        np.testing.assert_allclose(du2, du, rtol=1e-15, atol=1e-15 * np.abs(du).max())
        np.testing.assert_allclose(jac2, jac, rtol=1e-15, atol=1e-15 * np.abs(jac).max())
        assert model.velocity_form
        np.testing.assert_array_equal(jac[:2], [[0, 0, 1, 0], [0, 0, 0, 1]])   # [[0, I], [A, B]]


def test_force_only_contact_sum_equals_ring_load():
    from rotorsweep.kernels.contact import ring_force, ring_load

    rng = np.random.default_rng(6)
    for _ in range(50):
        x, y, z = rng.normal(scale=10.0, size=3)
        a, t = rng.uniform(0, 0.6), rng.uniform(0, 2 * np.pi)
        n = int(rng.integers(5, 15))
        args = (x, y, z, rng.normal(scale=3.0), np.cos(a), np.sin(a), n, np.cos(t), np.sin(t),
                np.cos(2 * np.pi / n), np.sin(2 * np.pi / n))
        assert ring_force(*args) == ring_load(*args)[:3]


def test_variational_derivative_is_rhs_and_dense_j_phi():
    """The structured J Phi (only the lower block rows multiplied) equals the dense product."""
    rng = np.random.default_rng(7)
    for model, p, tau, u in _model_cases(rng):
        phi = rng.normal(size=(4, 4))
        z = np.concatenate([u, phi.ravel()])
        dz, jbuf = np.full(20, np.nan), np.empty((4, 4))
        ig.derivative(model.kernel, tau, z, p, True, dz, jbuf)
        du, jac = np.empty(4), np.empty((4, 4))
        models.dispatch.rhs(model.kernel.tag, tau, u, p, du)
        models.dispatch.jac(model.kernel.tag, tau, u, p, jac)
        np.testing.assert_allclose(dz[:4], du, rtol=1e-15, atol=1e-15 * np.abs(du).max())
        dense = (jac @ phi).ravel()
        np.testing.assert_allclose(dz[4:], dense, rtol=1e-14, atol=1e-14 * np.abs(dense).max())
        ds = np.full(4, np.nan)
        ig.derivative(model.kernel, tau, u, p, False, ds, jbuf)
        np.testing.assert_array_equal(ds, du)


# One variational period at 80 Hz, 7.6 um from (0.3, -10.5, 0.2, 1.9), computed by the kernels
# before the fused/structured variational derivative (commit 73176ef): the restructured kernels
# perform the same floating-point operations in the same order.
_VARIATIONAL_BEFORE = {
    "dop853": (1489, [
        -0.4786083401041246, -11.027756101025354, 0.6360193953077452, -0.1000950555210518,
        -0.6333562127564384, -0.3407560098170526, -0.02590697887323954, -0.04793946070988128,
        0.01448395045667758, -0.06739382358807527, -0.061218110470487315, 0.1054046925214338,
        -0.09787864135038835, -0.10955364498906833, -0.8955914799213586, -0.11004242589337478,
        0.5941883841592004, -5.252598300603283, -0.2851028008545152, -0.16387524251740226]),
    "rk4": (1024, [
        -0.4786084932056083, -11.02775626431948, 0.6360208524170916, -0.1000931160459049,
        -0.6333809308592169, -0.34080467443887974, -0.025914363623428627, -0.047937727799874125,
        0.014503261784605304, -0.0673529678235188, -0.06122052633425472, 0.1054064449093561,
        -0.09800225555338954, -0.10981947828181537, -0.8955659854357525, -0.1100574957622642,
        0.5942072691721154, -5.252580424259392, -0.2850440899743956, -0.16389673942869354]),
}


@pytest.mark.parametrize("method", ["dop853", "rk4"])
def test_variational_flow_is_unchanged_by_the_fast_kernels(method):
    p, _ = bai_params(BaiPoint(80.0, 7.6e-6))
    opts = ig.settings(rtol=1e-10, atol=1e-12) if method == "dop853" else ig.settings("rk4", steps_per_unit=256)
    z0 = ig.initial_state(np.array([0.3, -10.5, 0.2, 1.9]), 4, True)
    z, status, n_rhs, _ = ig.flow(JEFF.kernel, 0.0, 1.0, z0, p, True, opts, 0.0)
    n_before, z_before = _VARIATIONAL_BEFORE[method]
    assert status == ig.STATUS_OK and n_rhs == n_before
    np.testing.assert_allclose(z, z_before, rtol=0, atol=1e-12)


def test_step_loops_without_reference_counting_do_not_leak():
    """The step loops are compiled with _nrt=False: every array they use is owned by the caller,
    so repeated flows allocate and free the same number of arrays."""
    from numba.core.runtime import _nrt_python, rtsys

    p, _ = bai_params(BaiPoint(80.0, 7.6e-6))
    z0 = ig.initial_state(np.array([0.3, -10.5, 0.2, 1.9]), 4, True)
    was_enabled = _nrt_python.memsys_stats_enabled()
    _nrt_python.memsys_enable_stats()
    try:
        for opts in (ig.settings(), ig.settings("rk4", steps_per_unit=64)):
            ig.flow(JEFF.kernel, 0.0, 1.0, z0, p, True, opts, 0.0)
            before = rtsys.get_allocation_stats()
            for _ in range(5):
                z, *_ = ig.flow(JEFF.kernel, 0.0, 1.0, z0, p, True, opts, 0.0)
            del z
            after = rtsys.get_allocation_stats()
            assert after.alloc - before.alloc > 0
            assert after.alloc - before.alloc == after.free - before.free
            assert after.mi_alloc - before.mi_alloc == after.mi_free - before.mi_free
    finally:
        if not was_enabled:
            _nrt_python.memsys_disable_stats()


def test_numba_cache_is_keyed_on_all_kernel_sources(tmp_path):
    """Editing any kernel module moves the cache: cached callers never keep a stale callee."""
    import shutil

    import numba
    import rotorsweep.kernels as rotorkernels

    src = Path(rotorkernels.__file__).parent
    shutil.copytree(src, tmp_path, dirs_exist_ok=True, ignore=shutil.ignore_patterns("__pycache__"))
    assert rotorkernels._cache_dir(tmp_path) == rotorkernels._cache_dir(src)
    if os.environ["NUMBA_CACHE_DIR"] == os.environ.get("ROTORSWEEP_NUMBA_CACHE_DIR"):   # not the user's
        assert numba.config.CACHE_DIR == os.environ["NUMBA_CACHE_DIR"] == rotorkernels._cache_dir(src)
        os.environ["SOME_UNRELATED_VARIABLE"] = "1"   # Numba re-reads its config from the environment
        try:
            numba.core.config.reload_config()
            assert numba.config.CACHE_DIR == rotorkernels._cache_dir(src)
        finally:
            del os.environ["SOME_UNRELATED_VARIABLE"]
    model = tmp_path / "models" / "jeffcott_clearance.py"
    model.write_text(model.read_text() + "\n# edited\n")
    assert rotorkernels._cache_dir(tmp_path) != rotorkernels._cache_dir(src)


def test_vendored_dop853_tableau_is_scipys():
    """rotorkernels/dop853_tableau.py holds scipy's (private) DOP853 floats digit for digit."""
    ref = pytest.importorskip("scipy.integrate._ivp.dop853_coefficients")
    from rotorsweep.kernels import dop853_tableau as tab

    n = tab.N_STAGES
    assert n == ref.N_STAGES
    for ours, theirs in ((tab.A, ref.A[:n, :n]), (tab.B, ref.B), (tab.C, ref.C[:n]), (tab.E3, ref.E3),
                         (tab.E5, ref.E5)):
        np.testing.assert_array_equal(ours, theirs)

"""A torus whose Fourier decay fails because a ball loses contact along it (configs/
filipkovsky2016_map_tori.toml at 36 deg): the tail falls only algebraically as the nodes double
(torus.power_law, checked on closed-form tails), and the point ends `contact_loss` with its contact
margin, the lift-off confirmed by an independent scipy DOP853 run from the circle."""
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rotorsweep.pipeline import compute, config, schema, torus_points
from rotorsweep.kernels import torus as tr
from rotorsweep.kernels.models import rigid_preloaded as rp
from rotorsweep.kernels.models import rigid_preloaded_kernels as rpk

MAP = Path(__file__).resolve().parents[1] / "configs" / "filipkovsky2016_map_tori.toml"
COUNTS = np.array([15, 31, 63, 127])


def test_power_law_reads_an_algebraic_decay_and_not_a_geometric_one():
    """tail = N^-3 at N = 15, 31, 63: the drop per doubling is log2((2N + 1) / N)^3, 3.14 at most;
    exp(-N / 2) accelerates (its drop doubles with N): no power law; neither at the rounding level."""
    assert tr.power_law(COUNTS[:3] ** -3.0) == pytest.approx(3.0 * np.log2(31 / 15), rel=1e-12)
    assert tr.power_law(np.exp(-COUNTS[:3] / 2.0)) is None
    assert tr.power_law(COUNTS[:2] ** -3.0) is None                 # one doubling says nothing
    assert tr.power_law(np.array([1e-9, 1e-15, 1e-16])) is None


@pytest.fixture(scope="module")
def point():
    data = config.load_config(MAP).scene
    built = compute.builder(data)({**data.fixed, "speed": 250.0, "support_frequency": 323.6067977,
                                   "nominal_angle": 36.0})
    assert not built.periodic
    circle = torus_points.solve(data.model, built, data.integrator, data.newton.tol)
    return data, built, circle


def test_the_36_deg_torus_ends_contact_loss_with_its_margin(point):
    """The decay fails algebraically (non_smooth_circle at 63 nodes: 15 -> 31 -> 63 cut the tail by
    a power of N), the contact margin is negative: the point's status is contact_loss, and `point`
    says so in words."""
    data, built, circle = point
    assert circle.status == tr.NON_SMOOTH and circle.nodes.shape[0] == torus_points.MAX_NODES
    row = torus_points.variables(data.model, circle, built, data.integrator)
    assert schema.TORUS_STATUS[row["torus_status"]] == "contact_loss"
    assert -0.5 < row["torus_contact_margin"] < 0.0
    text = torus_points.summary_text(torus_points.summary(row))
    assert "contact_loss" in text and "a contact opens along the torus" in text


def test_a_ball_lifts_off_on_an_independent_run_from_the_circle(point):
    """scipy DOP853 (rtol 1e-10) over one shaft turn from 16 phases of the circle, the deflections
    delta_k = (x cos b_k + y sin b_k) cos a +- z sin a + z0 sin a (SPEC 2.2, written again here) of
    every ball: some fall below zero, by about what the margin says (both sample the minimum; the
    circle's error estimate, ~1e-2 um, is far below the 0.1 um lift-off)."""
    data, built, circle = point
    p = built.p.copy()
    margin = torus_points.variables(data.model, circle, built, data.integrator)["torus_contact_margin"]
    angles = 2.0 * np.pi * np.arange(int(p[rp.P_NBALLS])) / p[rp.P_NBALLS]
    lowest = np.inf
    for theta in tr.node_phases(16):
        p[rp.P_PHASE] = theta

        def f(tau, u):
            du = np.empty_like(u)
            rpk.rhs(tau, u, p, du)
            return du
        sol = solve_ivp(f, (0.0, 1.0), circle.at(theta)[0], method="DOP853", rtol=1e-10, atol=1e-12,
                        t_eval=np.linspace(0.0, 1.0, 257))
        assert sol.success
        x1, y1, x2, y2, z = sol.y[:5, :, None]
        axial = p[rp.P_ARR] * z * p[rp.P_SIN_A]
        for x, y, sign in ((x1, y1, 1.0), (x2, y2, -1.0)):
            delta = (x * np.cos(angles) + y * np.sin(angles)) * p[rp.P_COS_A] + sign * axial + p[rp.P_OFFSET]
            lowest = min(lowest, delta.min() / p[rp.P_OFFSET])
    assert lowest < 0.0
    assert lowest == pytest.approx(margin, abs=0.02)


def test_a_branch_ending_torus_breakdown_there_says_contact_loss(point):
    """A torus branch that ends torus_breakdown at that circle: its detail names the lift-off
    (torus_branches.contact_note, the same margin as the point's)."""
    from rotorsweep.kernels.continuation import engine, tori
    from rotorsweep.pipeline import torus_branches

    data, built, circle = point
    fam = tori.TorusFamily(data.model.kernel, lambda lam: built.p, lambda lam: built.p[rp.P_WS], rp.P_PHASE,
                           data.integrator, circle.nodes.shape[0])
    last = tori.Point(fam.unknowns(circle.nodes, 0.0), 0.0, None, 0, circle.residual, circle.tail,
                      tr.stability(circle), circle.monodromies)
    note = torus_branches.contact_note(data.model, fam, engine.Run([last], [], engine.TORUS_BREAKDOWN, ""))
    assert note.startswith("; contact_loss: a contact opens along the last circle (smallest deflection -0.03")
    assert torus_branches.contact_note(data.model, fam, engine.Run([last], [], engine.LEFT_RANGE, "")) == ""

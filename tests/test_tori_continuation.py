"""Continuation of invariant tori (rotorsweep.kernels.continuation.tori) through a rational frequency
ratio, checked point by point against the torus solver, and ending with a reason."""
import numpy as np

from rotorsweep.kernels import integrators as ig, torus as tr
from rotorsweep.kernels.continuation import engine, tori
from rotorsweep.kernels.models import duffing2, get
from tests.reference import duffing2_strobe

MODEL = get("duffing2")
OPTS = ig.settings(rtol=1e-11, atol=1e-13)
TWO_PI = 2.0 * np.pi


def params(w2):
    p = np.array([2.0, 0.1, 0.5, 1.0, 0.5, 0.0, 0.0])
    p[duffing2.P_W2] = w2
    return p


def family(decay_tol=1e-8, n_nodes=15):
    return tori.TorusFamily(MODEL.kernel, params, lambda w2: w2, duffing2.P_PHASE, OPTS, n_nodes,
                            scale=0.1 * TWO_PI, decay_tol=decay_tol)


def first_point(fam, w2):
    tor = tr.solve_torus(MODEL.kernel, np.zeros((fam.n_nodes, 2)), params(w2), duffing2.P_PHASE, w2, OPTS,
                         max_nodes=fam.n_nodes)
    return tori.start(fam, w2, tor.nodes)


def test_tori_continue_through_a_rational_ratio():
    """omega / Omega from 0.55 to 0.65 through 3/5: every point's circle is the torus solver's at
    its lambda (to the Newton tolerances, 1e-10 amplified by ||J^-1|| ~ 40), the tori are stable
    (an attracting Duffing response) and the branch leaves the range."""
    fam = family()
    first = first_point(fam, TWO_PI * 0.55)
    run = tori.follow_tori(fam, first, (TWO_PI * 0.55, TWO_PI * 0.65),
                           engine.Settings(ds=0.2, ds_max=0.5, max_steps=40))
    assert run.end == engine.LEFT_RANGE, run.detail
    lams = np.array([p.lam for p in run.points])
    assert lams.min() < TWO_PI * 0.6 < lams.max()
    for p in run.points[::3]:
        ref = tr.solve_torus(MODEL.kernel, fam.nodes(p.X), params(p.lam), duffing2.P_PHASE, p.lam, OPTS,
                             max_nodes=fam.n_nodes)
        assert np.abs(ref.nodes - fam.nodes(p.X)).max() < 1e-8
        assert p.stability.status == tr.STABLE


def test_a_failed_fourier_decay_ends_the_branch_with_a_reason():
    fam = family(decay_tol=1e-30, n_nodes=7)
    first = first_point(fam, TWO_PI * 0.55)
    run = tori.follow_tori(fam, first, (TWO_PI * 0.55, TWO_PI * 0.65), engine.Settings(ds=0.2, max_steps=10))
    assert run.end == engine.TORUS_BREAKDOWN
    assert "Fourier decay failed" in run.detail


GOLDEN_W2 = TWO_PI * (np.sqrt(5.0) - 1.0) / 2.0


def f2_params(f2):
    """The nonlinear oscillator at a golden-mean ratio with the second forcing's amplitude f2 the
    continued parameter: its circle gains harmonics as f2 grows (solve_torus's tail at 15 nodes:
    3e-13 at f2 = 1, 1e-9 at 4, 2e-7 at 8; at 31 nodes below 1e-13 throughout)."""
    return np.array([2.0, 0.1, 0.5, 1.0, f2, GOLDEN_W2, 0.0])


def f2_branch(f2_from, f2_to, n_nodes, bounds, decay_tol=1e-9, breakdown_tol=0.0):
    fam = tori.TorusFamily(MODEL.kernel, f2_params, lambda f2: GOLDEN_W2, duffing2.P_PHASE, OPTS, n_nodes,
                           scale=1.0, decay_tol=decay_tol, min_nodes=bounds[0], max_nodes=bounds[1],
                           breakdown_tol=breakdown_tol)
    tor = tr.solve_torus(MODEL.kernel, np.zeros((n_nodes, 2)), f2_params(f2_from), duffing2.P_PHASE, GOLDEN_W2,
                         OPTS, max_nodes=n_nodes)
    first = tori.start(fam, f2_from, tor.nodes, direction=1 if f2_to > f2_from else -1)
    return fam, tori.follow_tori(fam, first, sorted((f2_from, f2_to)), engine.Settings(ds=0.3, ds_max=1.0, max_steps=80))


def node_counts(fam, run):
    return [fam.nodes(p.X).shape[0] for p in run.points]


def test_the_node_count_grows_where_the_spectrum_widens():
    """f2 from 1 to 8 with 15 nodes: a fixed count ends torus_breakdown (tail > 1e-9 near f2 =
    4); adaptive (7 to 63 nodes) it grows once, to 31, reaches f2 = 8 with every point's tail
    within the tolerance, and the last circle holds 2000 stroboscopic iterates of an independent
    DOP853 run (rtol 1e-12) within its error estimate (torus.error_estimate: the residual
    defect amplified by ||dR/dU^-1||, not below the tail)."""
    fam, fixed = f2_branch(1.0, 8.0, 15, (15, 15))
    assert fixed.end == engine.TORUS_BREAKDOWN and "at most 15" in fixed.detail
    assert 3.0 < fixed.points[-1].lam < 5.0 and fixed.points[-1].tail > 1e-9
    fam, run = f2_branch(1.0, 8.0, 15, (7, 63))
    assert run.end == engine.LEFT_RANGE, run.detail
    counts = node_counts(fam, run)
    assert counts[0] == 15 and counts[-1] == 31 and np.count_nonzero(np.diff(counts)) == 1
    assert max(p.tail for p in run.points) <= 1e-9
    last = run.points[-1]
    assert last.lam == 8.0
    p = f2_params(last.lam)
    circle = tr.solve_torus(MODEL.kernel, fam.nodes(last.X), p, duffing2.P_PHASE, GOLDEN_W2, OPTS,
                            max_nodes=counts[-1])
    assert np.abs(circle.nodes - fam.nodes(last.X)).max() < 1e-8    # the branch's circle is the solver's
    n = 2000
    states = duffing2_strobe(p, circle.nodes[0], n)
    on_circle = circle.at(np.fmod(GOLDEN_W2 * np.arange(1, n + 1), TWO_PI))
    assert np.abs(states - on_circle).max() <= circle.error < 1e-9


def test_the_node_count_shrinks_once_where_the_spectrum_narrows():
    """Back from f2 = 8 to 0.5 from 31 nodes: the count shrinks to 15 (where 15 nodes keep the
    tail below torus.COARSEN times the tolerance) and no further (7 nodes leave a tail ~1e-5), once:
    the hysteresis keeps it from going back and forth; the tail stays within the tolerance."""
    fam, run = f2_branch(8.0, 0.5, 31, (7, 63))
    assert run.end == engine.LEFT_RANGE, run.detail
    counts = node_counts(fam, run)
    assert counts[0] == 31 and counts[-1] == 15 and np.count_nonzero(np.diff(counts)) == 1
    assert max(p.tail for p in run.points) <= 1e-9


def test_at_the_top_count_the_tail_may_rise_to_the_breakdown_tolerance():
    """Capped at 15 nodes with a breakdown tolerance of 1e-6: the branch keeps 15 nodes to f2 = 8
    (tail 1.7e-7 there) instead of ending where the tail passes the decay tolerance (1e-9)."""
    fam, run = f2_branch(1.0, 8.0, 15, (7, 15), breakdown_tol=1e-6)
    assert run.end == engine.LEFT_RANGE, run.detail
    assert set(node_counts(fam, run)) == {15}
    assert 1e-9 < max(p.tail for p in run.points) <= 1e-6

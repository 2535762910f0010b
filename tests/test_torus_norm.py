"""The torus branch's arclength (rotorsweep.kernels.continuation.tori: the node values weighted by
1 / sqrt(N)) counts the circle like one orbit's state, whatever its node count."""
import numpy as np
import pytest

from rotorsweep.kernels import integrators as ig, torus as tr
from rotorsweep.kernels.continuation import engine, tori
from rotorsweep.kernels.models import duffing2, get

MODEL = get("duffing2")
OPTS = ig.settings(rtol=1e-11, atol=1e-13)
TWO_PI = 2.0 * np.pi
RANGE = (TWO_PI * 0.55, TWO_PI * 0.65)      # omega / Omega through 3/5
SETTINGS = engine.Settings(ds=0.005, ds_max=0.01, max_steps=100)
SCALE = 4.0 * TWO_PI         # the circle's change dominates the arclength


def params(w2):
    p = np.array([2.0, 0.1, 0.5, 1.0, 0.5, 0.0, 0.0])
    p[duffing2.P_W2] = w2
    return p


class Unweighted(tori.TorusFamily):
    """The family with the node values unweighted in the unknowns (the arclength before the weight)."""

    def weight(self, n_nodes):
        return 1.0


def branch(n_nodes, cls=tori.TorusFamily):
    fam = cls(MODEL.kernel, params, lambda w2: w2, duffing2.P_PHASE, OPTS, n_nodes, scale=SCALE)
    tor = tr.solve_torus(MODEL.kernel, np.zeros((n_nodes, 2)), params(RANGE[0]), duffing2.P_PHASE, RANGE[0], OPTS,
                         max_nodes=n_nodes)
    return fam, tori.follow_tori(fam, tori.start(fam, RANGE[0], tor.nodes), RANGE, SETTINGS, max_q=5)


def test_the_unknowns_hold_the_circle_weighted_and_give_it_back():
    fam = tori.TorusFamily(MODEL.kernel, params, lambda w2: w2, duffing2.P_PHASE, OPTS, 15, scale=2.0)
    nodes = np.arange(30.0).reshape(15, 2)
    X = fam.unknowns(nodes, 3.0)
    assert np.allclose(X[:-1], nodes.ravel() / np.sqrt(15)) and X[-1] == 1.5
    assert np.array_equal(fam.nodes(X), nodes) and fam.lam(X) == 3.0


def test_the_steps_do_not_depend_on_the_node_count():
    """The same branch (15 and 31 nodes, both resolving its circle: tails below 1e-12) takes the
    same parameter steps: the nodes' mean square equals the circle's mean square over theta when N
    resolves it (Parseval; |u|^2 has at most 2K < N modes), so the arclength, the tangents and
    with them the steps agree to the tails and the corrector's tolerance (1e-10 amplified by
    ||dR/dU^-1|| ~ 40 into the circles, hence 1e-7 in lambda). Unweighted, the 31-node branch's
    steps are sqrt(31 / 15) times shorter where the circle moves."""
    fam15, run15 = branch(15)
    fam31, run31 = branch(31)
    assert run15.end == run31.end == engine.LEFT_RANGE, (run15.detail, run31.detail)
    assert max(p.tail for p in run15.points + run31.points) < 1e-12
    lam15, lam31 = (np.array([p.lam for p in run.points]) for run in (run15, run31))
    assert lam15.size == lam31.size and np.abs(lam15 - lam31).max() < 1e-7
    _, old15 = branch(15, Unweighted)
    _, old31 = branch(31, Unweighted)
    assert len(old31.points) > len(old15.points)


def error(fam, point):
    """The point's error estimate (torus.error_estimate: its invariance defect between the nodes
    amplified by ||dR/dU^-1||)."""
    jac = fam.circle_jacobian(point.X, fam.residual(point.X, True)[1])
    err, ok, _ = tr.error_estimate(MODEL.kernel, fam.nodes(point.X), jac, params(point.lam), duffing2.P_PHASE,
                                   point.lam, 1.0, OPTS, point.tail)
    assert ok
    return err


def test_the_weighted_branch_is_the_unweighted_one_at_common_parameters():
    """At the parameters both branches solve exactly (the locked ratio 3/5 and the range's end) the
    circles agree within the sum of their error estimates (each circle is within its own of the
    invariant one)."""
    fam, run = branch(15)
    old_fam, old = branch(15, Unweighted)
    locked = [f.point for f in run.found if isinstance(f.event, tori.Locked)]
    old_locked = [f.point for f in old.found if isinstance(f.event, tori.Locked)]
    assert len(locked) == len(old_locked) == 1
    for a, b in ((locked[0], old_locked[0]), (run.points[-1], old.points[-1])):
        assert a.lam == pytest.approx(b.lam, rel=1e-12)
        bound = error(fam, a) + error(old_fam, b)
        assert np.abs(fam.nodes(a.X) - old_fam.nodes(b.X)).max() <= bound < 1e-8


def slow_circle(thetas, amplitude, r):
    """cos theta + amplitude sum_{m >= 1} r^m cos m theta (closed form): a geometric spectrum that
    no finite N holds; its modes beyond K alias onto all lower ones."""
    c = np.cos(thetas)
    return (c + amplitude * (r * c - r * r) / (1.0 - 2.0 * r * c + r * r))[:, None]


def interpolation_error(values_at, n_nodes):
    """max |interpolant on n_nodes - the function| on 2N + 1 nodes (an independent measure of how
    far n_nodes resolve the function: its values between the nodes)."""
    fine = tr.node_phases(2 * n_nodes + 1)
    return np.abs(tr.interpolation_matrix(n_nodes, fine) @ values_at(tr.node_phases(n_nodes)) - values_at(fine)).max()


def top_quarter(values):
    amps = tr.mode_amplitudes(values)
    k = amps.size - 1
    return amps[k + 1 - max(1, (k + 1) // 4):].max()


def test_the_tail_sees_the_modes_that_alias_below_the_top_quarter():
    """A slowly decaying spectrum (r = 0.95) on 31 nodes: the top quarter's largest mode (1.7e-8)
    passes a tolerance of 1e-7, but the interpolant misses the function by 2.7e-7 between the
    nodes; the tail (the modes beyond K extrapolated from the decay) fails it, and is the miss
    to a factor 2 (the sum of the modes K + 1 .. 2K + 1 against the aliasing error, which counts
    each about twice: once missing, once folded onto a lower mode)."""
    tol = 1e-7
    values_at = lambda th: slow_circle(th, 3e-8, 0.95)     # noqa: E731
    values = values_at(tr.node_phases(31))
    miss = interpolation_error(values_at, 31)
    assert top_quarter(values) < tol < miss
    assert tol < miss / 2.0 <= tr.fourier_tail(values) <= 2.0 * miss


def test_a_resolved_circle_keeps_a_small_tail():
    """A fast spectrum (r = 0.3) on 31 nodes is resolved to 7e-9 between the nodes: its tail stays
    within 1e-6, as the top quarter's (the extrapolation adds nothing beyond it there)."""
    values_at = lambda th: slow_circle(th, 1.0, 0.3)       # noqa: E731
    values = values_at(tr.node_phases(31))
    assert interpolation_error(values_at, 31) < 1e-8
    assert tr.fourier_tail(values) == top_quarter(values) < 1e-6


def test_a_band_limited_circle_keeps_a_rounding_level_tail():
    """A trigonometric polynomial of degree 2 on 7 nodes (K = 3) is interpolated exactly: mode 3 is
    the DFT's rounding, so the tail must be too, though modes 1 and 2 give a decay fit whose line,
    extrapolated past K, would claim O(0.1) (the extrapolation starts from the top mode itself)."""
    th = tr.node_phases(7)
    values = np.stack([np.cos(th) + 0.5 * np.cos(2 * th), np.sin(2 * th)], axis=1)
    assert tr.fourier_tail(values) < 1e-14


def test_the_coarser_tail_counts_the_modes_it_drops():
    """A circle with a mode 12 bump on 31 nodes: resampled to 15 nodes (K = 7) it has no trace of
    it, so its own tail is tiny, but coarsening would lose 1e-6: coarser_tail says so, and
    coarsened keeps the 31 nodes."""
    th = tr.node_phases(31)
    values = np.stack([np.cos(th), np.sin(th) + 2e-6 * np.cos(12 * th)], axis=1)
    assert tr.fourier_tail(tr.resample(values, 15)) < 1e-14
    assert tr.coarser_tail(values) == pytest.approx(1e-6, rel=1e-9)
    assert tr.coarsened(values, 1e-8, 7).shape[0] == 31
    assert tr.coarsened(np.stack([np.cos(th), np.sin(th)], axis=1), 1e-8, 7).shape[0] == 7

"""Continuation of invariant tori (rotorsweep.kernels.continuation.tori) through a rational frequency
ratio, checked point by point against the torus solver, and ending with a reason."""
import numpy as np

from rotorsweep.kernels import integrators as ig, torus as tr
from rotorsweep.kernels.continuation import engine, tori
from rotorsweep.kernels.models import duffing2, get

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

"""The per-point record of a torus branch (rotorsweep.pipeline.torus_branches.polished): the polish
starts from the point's own monodromies and hands its last Jacobian to the error estimate, instead
of collocating again. Checked against the record computed the plain way: Newton on a fresh
variational collocation at every step, and the error estimate from a fresh collocation at the
polished circle (torus.error_estimate)."""
import numpy as np
import pytest

from rotorsweep.kernels import integrators as ig, torus as tr
from rotorsweep.kernels.continuation import engine, tori
from rotorsweep.kernels.models import duffing2, get
from rotorsweep.pipeline import torus_branches

MODEL = get("duffing2")
OPTS = ig.settings(rtol=1e-11, atol=1e-13)
TWO_PI = 2.0 * np.pi
RANGE = (TWO_PI * 0.55, TWO_PI * 0.58)
N_NODES = 15
# the corrector's tolerance well above POLISH_TOL, so that every point takes polish steps
SETTINGS = engine.Settings(ds=0.01, ds_max=0.02, max_steps=20, tol=1e-7)


def params(w2):
    p = np.array([2.0, 0.1, 0.5, 1.0, 0.5, 0.0, 0.0])
    p[duffing2.P_W2] = w2
    return p


@pytest.fixture(scope="module")
def branch():
    fam = tori.TorusFamily(MODEL.kernel, params, lambda w2: w2, duffing2.P_PHASE, OPTS, N_NODES, scale=4.0 * TWO_PI)
    tor = tr.solve_torus(MODEL.kernel, np.zeros((N_NODES, 2)), params(RANGE[0]), duffing2.P_PHASE, RANGE[0], OPTS,
                         max_nodes=N_NODES)
    run = tori.follow_tori(fam, tori.start(fam, RANGE[0], tor.nodes, settings=SETTINGS), RANGE, SETTINGS)
    assert run.end == engine.LEFT_RANGE and len(run.points) >= 3, run.detail
    return fam, run


def plain_polish(fam, X, tol=torus_branches.POLISH_TOL, max_iter=3):
    """Newton at fixed lambda from a fresh variational collocation at every iterate (the polish
    before it reused the point's monodromies)."""
    X = X.copy()
    for _ in range(max_iter):
        r, jac, _, ok, _ = fam.residual(X, True)
        assert ok
        if np.abs(r).max() <= tol * max(1.0, np.abs(fam.nodes(X)).max()):
            break
        X[:-1] += np.linalg.solve(jac, -r.ravel())
    return X


def plain_error(fam, X, tail):
    """The error estimate from a fresh variational collocation at X."""
    lam = fam.lam(X)
    jac = fam.circle_jacobian(X, fam.residual(X, True)[1])
    err, ok, _ = tr.error_estimate(MODEL.kernel, fam.nodes(X), jac, params(lam), duffing2.P_PHASE, lam, 1.0, OPTS, tail)
    assert ok
    return err, jac


def test_the_record_is_the_plain_polish_and_estimate_within_their_tolerance(branch):
    """Both circles solve R = 0 to POLISH_TOL relative, so they lie within 2 POLISH_TOL max(1, |U|)
    ||dR/dU^-1|| of each other (Newton's error bound; the same iterates in fact, up to rounding).
    The estimate is the midpoint defect times ||dR/dU^-1||: the defect moves by at most the
    circle's change times (1 + ||M|| + ||S_mid||) (the shots' Lipschitz constant, the monodromy's
    norm, plus the interpolation to the midpoints, whose norm is below 1 + sum_k |D(theta - theta_k)|
    <= N), and the amplification is the same matrix up to that change; the tolerance is that bound."""
    fam, run = branch
    polished, errors = torus_branches.polished(fam, run)
    assert len(errors) == len(run.points)
    for before, after, err in zip(run.points, polished.points, errors):
        X = plain_polish(fam, before.X)
        ref, jac = plain_error(fam, X, tr.fourier_tail(fam.nodes(X)))
        nodes = fam.nodes(X)
        amplification = np.abs(np.linalg.inv(jac)).sum(axis=1).max()
        dU = 2.0 * torus_branches.POLISH_TOL * max(1.0, np.abs(nodes).max()) * amplification
        assert after.lam == before.lam
        assert np.abs(fam.nodes(after.X) - nodes).max() <= dU
        monos = fam.residual(X, True)[2]
        lipschitz = 1.0 + np.abs(monos).sum(axis=2).max() + N_NODES
        assert err == pytest.approx(ref, abs=2.0 * amplification * lipschitz * dU)
        assert err < 1e-8


def test_the_polish_hands_back_the_jacobian_at_its_circle(branch):
    """tori.polish's Jacobian is the variational collocation's at the circle it returns (the one
    the error estimate needs), to rounding: its monodromies are integrated along the same u."""
    fam, run = branch
    for point in run.points[:2]:
        done, jac = tori.polish(fam, point, torus_branches.POLISH_TOL)
        fresh = fam.residual(done.X, True)[1]
        assert np.abs(jac - fresh).max() <= 1e-8 * np.abs(fresh).max()


def test_a_point_without_a_jacobian_has_an_infinite_error(branch):
    """Where the polish's shots failed (no Jacobian) the estimate is inf, never a traceback."""
    fam, run = branch
    assert torus_branches.torus_error(fam, run.points[0], None) == np.inf

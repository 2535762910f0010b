"""The per-point record of a torus branch (rotorsweep.pipeline.torus_branches.polished): the polish
hands its last Jacobian to the error estimate instead of collocating again. Checked against the
record computed the plain way: Newton on a fresh variational collocation at every step, and the
error estimate from a fresh collocation at the polished circle (torus.error_estimate). On the two-frequency Duffing and on a short stretch of the
Filipkovsky Fig. 3a scene (the preloaded rotor, 10 states)."""
import numpy as np
import pytest

from rotorsweep.kernels import integrators as ig, torus as tr
from rotorsweep.kernels.continuation import engine, tori
from rotorsweep.kernels.models import duffing2, get
from rotorsweep.pipeline import config, continuation, torus_branches

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


def duffing_branch():
    fam = tori.TorusFamily(MODEL.kernel, params, lambda w2: w2, duffing2.P_PHASE, OPTS, N_NODES, scale=4.0 * TWO_PI)
    tor = tr.solve_torus(MODEL.kernel, np.zeros((N_NODES, 2)), params(RANGE[0]), duffing2.P_PHASE, RANGE[0], OPTS,
                         max_nodes=N_NODES)
    run = tori.follow_tori(fam, tori.start(fam, RANGE[0], tor.nodes, settings=SETTINGS), RANGE, SETTINGS)
    assert run.end == engine.LEFT_RANGE and len(run.points) >= 3, run.detail
    return fam, run


def fig3a_branch():
    """The Fig. 3a scene's torus branch over 380-382 Hz (15 nodes), unpolished."""
    text = open("configs/filipkovsky2016_fig3a.toml").read().replace("start = 100.0", "start = 380.0").replace(
        "stop = 1300.0", "stop = 382.0")
    scene = config.parse_config(text).scene
    pl = continuation.plan(scene)
    circle, fam, _ = torus_branches.first_torus(scene, pl, pl.lines[0])
    assert circle is not None and circle.status == tr.CONVERGED
    first = tori.start(fam, pl.start, circle.nodes, 1, pl.settings, engine.Counter())
    run = tori.follow_tori(fam, first, pl.range, pl.settings, engine.Counter())
    assert run.end == engine.LEFT_RANGE and len(run.points) >= 2, run.detail
    return fam, run


@pytest.fixture(scope="module", params=[duffing_branch, fig3a_branch], ids=["duffing2", "fig3a"])
def branch(request):
    return request.param()


def plain_polish(fam, X, tol=torus_branches.POLISH_TOL, max_iter=3):
    """Newton at fixed lambda from a fresh variational collocation at every iterate."""
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
    err, ok, _ = tr.error_estimate(fam.kernel, fam.nodes(X), jac, fam.params(lam), fam.phase_index, fam.rotation(lam),
                                   fam.period, fam.opts, tail)
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
        lipschitz = 1.0 + np.abs(monos).sum(axis=2).max() + len(nodes)
        assert err == pytest.approx(ref, abs=2.0 * amplification * lipschitz * dU)
        assert err < 1e-6      # a sanity bound: the estimates are 1e-12 (Duffing) and 1e-9 to 1e-7 (Fig. 3a)


def test_the_polish_hands_back_the_jacobian_at_its_circle(branch):
    """tori.polish's Jacobian is the variational collocation's at the circle it returns (the one
    the error estimate needs): the same deterministic integration from the same X, bit for bit."""
    fam, run = branch
    for point in run.points[:2]:
        done, jac = tori.polish(fam, point, torus_branches.POLISH_TOL)
        assert np.array_equal(jac, fam.residual(done.X, True)[1])


def test_a_point_without_a_jacobian_has_an_infinite_error(branch):
    """Where the polish's shots failed (no Jacobian) the estimate is inf, never a traceback."""
    fam, run = branch
    assert torus_branches.torus_error(fam, run.points[0], None) == np.inf

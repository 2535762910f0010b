"""The torus continuation's cheaper step: the chord corrector (tori.TorusFamily.correct) against a
full Newton on the same arclength hyperplane, and the compiled QR iteration of the normal
stability (torus.stability) against a closed form and numpy's QR loop."""
import numpy as np
import pytest

from rotorsweep.kernels import integrators as ig, torus as tr
from rotorsweep.kernels.continuation import engine, tori
from rotorsweep.kernels.models import duffing2, get

MODEL = get("duffing2")
OPTS = ig.settings(rtol=1e-11, atol=1e-13)
TWO_PI = 2.0 * np.pi
W2 = TWO_PI * 0.57


def params(w2):
    p = np.array([2.0, 0.1, 0.5, 1.0, 0.5, 0.0, 0.0])
    p[duffing2.P_W2] = w2
    return p


def family():
    return tori.TorusFamily(MODEL.kernel, params, lambda w2: w2, duffing2.P_PHASE, OPTS, 15, scale=0.1 * TWO_PI)


def newton(fam, X, c, target, tol, max_iter=10):
    """The reference: full Newton on the bordered system, a variational collocation and a central
    dR/dmu at every iterate, to a residual far below the corrector's (the converged X and the
    bordered matrix there)."""
    for _ in range(max_iter):
        r, jac, _, ok, _ = fam.residual(X, True)
        col, _ = fam.dr_dmu(X, 1e-5)
        bordered = np.block([[jac, col[:, None]], [c[None, :]]])
        if np.abs(r).max() <= tol and abs(c @ X - target) <= tol:
            return X, bordered
        X = X + np.linalg.solve(bordered, np.append(-r.ravel(), target - c @ X))
    raise AssertionError("reference Newton did not converge")


def test_the_chord_corrector_lands_on_newtons_solution(monkeypatch):
    """From the predictor a.X + ds t_a the chord solution (matrix from a's monodromies) and a full
    Newton's (to 1e-14) on the hyperplane t_a . (X - X_a) = ds differ by at most the chord's
    residual amplified by ||B^-1||_inf (B: the bordered matrix at the solution; a residual r
    moves the root by B^-1 r to first order, doubled for the second-order rest), and the chord
    evaluated the variational equations once (to confirm the solution)."""
    fam = family()
    tor = tr.solve_torus(MODEL.kernel, np.zeros((15, 2)), params(W2), duffing2.P_PHASE, W2, OPTS, max_nodes=15)
    a = tori.start(fam, W2, tor.nodes)
    ds, settings = 0.2, engine.Settings(tol=1e-9)
    calls = []
    collocation = tr.collocation
    monkeypatch.setattr(tr, "collocation", lambda *args: calls.append(args[-1]) or collocation(*args))
    sol, failure = engine.on_arclength(fam, a, ds, settings, engine.Counter())
    monkeypatch.undo()
    assert failure is None and sol.residual <= settings.tol
    assert calls.count(True) == 1
    ref, bordered = newton(fam, a.X + ds * a.tangent, a.tangent, a.tangent @ a.X + ds, 1e-14)
    bound = 2.0 * sol.residual * max(1.0, np.abs(fam.nodes(ref)).max()) * np.abs(np.linalg.inv(bordered)).sum(axis=1).max()
    assert np.abs(sol.X - ref).max() <= bound
    mono = fam.residual(sol.X, True)[2]
    assert np.abs(sol.monodromies - mono).max() == 0.0     # the solution's own, not a's


def test_the_chord_corrector_from_a_seed_and_on_a_branch():
    """Without a last point (a Seed: the start) the first matrix is variational; along a branch
    every point meets the tolerance, and the branch crosses 3/5 as the full Newton's did
    (tests/test_tori_continuation.py)."""
    fam = family()
    tor = tr.solve_torus(MODEL.kernel, np.zeros((15, 2)), params(W2), duffing2.P_PHASE, W2, OPTS, max_nodes=15)
    first = tori.start(fam, W2, tor.nodes)
    assert first is not None and first.residual <= engine.Settings().tol
    run = tori.follow_tori(fam, first, (W2, TWO_PI * 0.62), engine.Settings(ds=0.2, ds_max=0.5, max_steps=40))
    assert run.end == engine.LEFT_RANGE, run.detail
    assert max(p.residual for p in run.points) <= engine.Settings().tol
    assert all(p.stability.status == tr.STABLE for p in run.points)


def rotation(theta):
    return np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])


def test_stability_exponents_of_a_conjugated_diagonal_map():
    """M(theta) = Rot(theta + rho) diag(e^a, e^b) Rot(theta)^T (b > a): the products telescope to
    P = Rot(theta_K) diag(e^Ka, e^Kb) Rot(theta_0)^T, whose QR has log R_11 = K b + log |sin
    theta_0| (to e^{2K(a - b)}) and log R_22 = K (a + b) - log R_11, so the K-step exponents are
    b + log |sin theta_0| / K and a - log |sin theta_0| / K in closed form; M's entries are
    trigonometric polynomials of degree 2, interpolated exactly by 7 nodes. The means of 4000
    logs of O(1) carry rounding only (1e-12)."""
    rho, a, b, theta0, steps = TWO_PI * (np.sqrt(5.0) - 1.0) / 2.0, -0.3, 0.1, 1.0, 4000
    thetas = tr.node_phases(7)
    monos = np.array([rotation(t + rho) @ np.diag(np.exp([a, b])) @ rotation(t).T for t in thetas])
    torus = tr.Torus(np.zeros((7, 2)), rho, 1.0, tr.CONVERGED, 0, 0.0, 0.0, 0.0, monos, 0)
    st = tr.stability(torus, n_steps=steps, theta0=theta0)
    shift = np.log(abs(np.sin(theta0))) / steps
    assert st.exponents == pytest.approx([b + shift, a - shift], abs=1e-12)
    assert st.status == tr.UNSTABLE


def test_qr_logs_and_dirichlet_matrix_against_numpy():
    """The compiled QR iteration against numpy's qr loop (Householder both): the exponents (the
    logs' means) agree to rounding, 1e-12 (single steps differ by up to ~1e-9 in the weakest
    direction, its R_kk rounded relative to the largest; the Q's stay close, the differences
    do not accumulate), and the closed-form
    Dirichlet kernel against interpolation_matrix's cosine sum: both carry the rounding of
    d = theta - theta_k, eps |theta| (~4e-12 at theta ~ 2e4), times the kernel's slope (< N)."""
    rng = np.random.default_rng(3)
    n_nodes, n, steps = 63, 10, 4000
    thetas = 0.3 + TWO_PI * 0.61803398875 * np.arange(steps)
    weights = tr.dirichlet_matrix(n_nodes, thetas)
    bound = n_nodes * np.finfo(float).eps * thetas.max()
    assert np.abs(weights - tr.interpolation_matrix(n_nodes, thetas)).max() <= bound
    base = rng.normal(size=(n, n)) * 0.3
    nodes = np.array([base + 0.05 * np.cos(t) * rng.normal(size=(n, n)) for t in tr.node_phases(n_nodes)])
    monos = (weights @ nodes.reshape(n_nodes, -1)).reshape(steps, n, n)
    q, logs = np.eye(n), np.empty((steps, n))
    for k in range(steps):
        q, r = np.linalg.qr(monos[k] @ q)
        logs[k] = np.log(np.abs(np.diag(r)))
    assert np.abs(tr.qr_logs(monos).mean(axis=0) - logs.mean(axis=0)).max() < 1e-12

"""A fold of tori and the unstable tori between two folds (rotorsweep.kernels.continuation.tori): the
two-frequency Duffing oscillator (validation model duffing2) with its second forcing near the
hardening resonance, continued in that forcing's frequency over a short range that passes both
folds. Checked against harmonic balance (the fold's frequency), against theory (at a fold of tori
a normal exponent crosses 0: the stability changes in the fold's step, and is located there), against
a brute-force search (the located fold is the extremum of lambda along the branch) and against the
flow (a perturbed unstable circle is left, a perturbed stable one is approached, at the rate of the
largest normal exponent)."""
import numpy as np
import pytest

from rotorsweep.kernels import integrators as ig, torus as tr
from rotorsweep.kernels.continuation import engine, events as ev, tori
from rotorsweep.kernels.models import duffing2, get

MODEL = get("duffing2")
OPTS = ig.settings(rtol=1e-11, atol=1e-13)
K, C, GAMMA, F1, F2 = 2.0, 0.1, 0.5, 1.0, 0.2
SETTINGS = engine.Settings(ds=0.1, ds_max=0.4, max_steps=120)


def params(w2):
    return np.array([K, C, GAMMA, F1, F2, w2, 0.0])


def settled_guess(w2, settle=300, fit=60):
    """15 node values fitted to stroboscopic samples after a transient (the attracting torus)."""
    u, theta, samples, phases = np.zeros(2), 0.0, [], []
    for k in range(settle + fit):
        if k >= settle:
            samples.append(u)
            phases.append(theta)
        ends, _, ok, _ = tr.node_maps(MODEL.kernel, u[None, :], [theta], params(w2), duffing2.P_PHASE, 1.0, OPTS, False)
        u, theta = ends[0], (theta + w2) % (2.0 * np.pi)
    return tr.fitted_guess(np.array(samples), np.array(phases), 15)


@pytest.fixture(scope="module")
def run():
    """From w2 = 1.5 (one torus: below the lower fold) over [1.5, 1.62]: up the resonant branch,
    round the upper fold, back along the unstable tori, round the lower fold, out on the
    non-resonant branch."""
    start = tr.solve_torus(MODEL.kernel, settled_guess(1.5), params(1.5), duffing2.P_PHASE, 1.5, OPTS, max_nodes=63)
    assert start.status == tr.CONVERGED
    fam = tori.TorusFamily(MODEL.kernel, params, lambda w2: w2, duffing2.P_PHASE, OPTS, start.nodes.shape[0],
                           decay_tol=1e-7)
    first = tori.start(fam, 1.5, start.nodes)
    return fam, tori.follow_tori(fam, first, (1.5, 1.62), SETTINGS)


def harmonic_balance_fold():
    """The upper fold of one-harmonic balance: x ~ A cos(w t) + B cos(2 pi t) with B the linear
    response to f1 (far from resonance); the w-component's balance [(k_eff - w^2)^2 + (c w)^2] A^2 =
    f2^2 with k_eff = k + 3/4 gamma A^2 + 3/2 gamma B^2; the fold is the largest w over A."""
    b = F1 / (K - (2.0 * np.pi) ** 2)
    a = np.linspace(0.5, 2.0, 200001)
    k_eff = K + 0.75 * GAMMA * a ** 2 + 1.5 * GAMMA * b ** 2
    disc = (2 * k_eff - C ** 2) ** 2 - 4 * (k_eff ** 2 - (F2 / a) ** 2)
    w2 = ((2 * k_eff - C ** 2) + np.sqrt(np.where(disc >= 0, disc, np.nan))) / 2
    return float(np.sqrt(np.nanmax(w2)))


def test_both_folds_are_flagged_with_the_stability_change(run):
    fam, r = run
    assert r.end == engine.LEFT_RANGE, r.detail
    flags = [(f.event.code, f.index) for f in r.found]
    folds = [i for code, i in flags if code == ev.TORUS_FOLD]
    changes = [i for code, i in flags if code == ev.TORUS_STABILITY]
    assert len(folds) == 2 and folds == changes      # the normal exponent crosses 0 at each fold
    lams = np.array([p.lam for p in r.points])
    upper, lower = folds
    assert lams[upper:upper + 2].max() == lams[:lower + 1].max()        # the turning points of lambda
    assert lams[lower:lower + 2].min() == lams[upper:].min()
    status = [p.stability.status for p in r.points]
    assert set(status[upper + 1:lower + 1]) == {tr.UNSTABLE}
    assert set(status[:upper + 1]) == set(status[lower + 1:]) == {tr.STABLE}


def test_the_upper_fold_is_where_harmonic_balance_puts_it(run):
    """One-harmonic balance neglects the 3 w and combination harmonics (gamma A^2 / k ~ 0.4 at
    the fold, their amplitude a few % of A): its fold frequency is good to ~1 %."""
    fam, r = run
    fold = max(p.lam for p in r.points)       # the branch's steps near the fold are ~1e-4
    assert fold == pytest.approx(harmonic_balance_fold(), rel=1e-2)


def _drift(fam, point, n_maps):
    """Distance from the circle after n_maps stroboscopic maps from a point 1e-7 off it (the flow,
    not the linearization), and the initial distance."""
    circle = fam.torus(point)
    theta = 0.3
    u = circle.at(theta)[0] + 1e-7 * np.array([1.0, -0.5])
    p = params(point.lam)
    for _ in range(n_maps):
        ends, _, ok, _ = tr.node_maps(MODEL.kernel, u[None, :], [theta], p, duffing2.P_PHASE, 1.0, OPTS, False)
        assert ok
        u, theta = ends[0], theta + point.lam
    return np.abs(u - circle.at(theta)[0]).max()


def test_the_flow_leaves_an_unstable_torus_and_returns_to_a_stable_one(run):
    """After N maps the distance has grown (unstable) or shrunk (stable) as exp(N * exponent) up to
    a bounded factor (the perturbation's projection on the leading direction and, for a complex
    pair of exponents, the rotation of the offset between x and x', whose sizes differ by ~w2):
    the rate log(ratio) / N matches the exponent to log(5) / N."""
    fam, r = run
    upper, lower = [f.index for f in r.found if f.event.code == ev.TORUS_FOLD]
    middle = r.points[(upper + lower) // 2]
    n_maps = 100
    for point in (r.points[0], middle):
        ratio = _drift(fam, point, n_maps) / 1e-7
        assert (ratio > 1) == (point.stability.status == tr.UNSTABLE)
        assert np.log(ratio) / n_maps == pytest.approx(point.stability.exponents[0], abs=np.log(5.0) / n_maps)


def _located(r, code):
    return [f for f in r.found if f.event.code == code]


def _extreme_lambda(fam, a, b, sign, xtol=1e-4):
    """sign * the largest sign * lambda of the corrected points on the arclength between points a
    and b (the hyperplanes t_a . (X - X_a) = sigma), by a golden-section search on sigma to xtol:
    the fold by brute force, from lambda alone (no tangent, no test function)."""
    def lam(sigma):
        sol, failure = engine.on_arclength(fam, a, sigma, SETTINGS, engine.Counter())
        assert failure is None
        return sign * sol.X[-1] * fam.scale
    lo, hi, g = 0.0, float(a.tangent @ (b.X - a.X)), (np.sqrt(5.0) - 1.0) / 2.0
    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = lam(x1), lam(x2)
    while hi - lo > xtol:
        if f1 > f2:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - g * (hi - lo)
            f1 = lam(x1)
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + g * (hi - lo)
            f2 = lam(x2)
    return sign * max(f1, f2)


def test_the_folds_are_located_at_the_extremum_of_lambda(run):
    """TF located (tangent's d mu / ds = 0 by Brent) against a golden-section search for the
    extremum of lambda over corrected points: both are corrected points, each within its
    corrector error of the branch (twice tori.corrector_error for the two), plus the search's own
    error: lambda ~ lambda* - a (sigma - sigma*)^2 near the fold (a ~ 2e-4 here: lambda changes by
    ~3e-5 over the fold's 0.4-long step) is resolved to a xtol^2 ~ 2e-12 by sigma to 1e-4."""
    fam, r = run
    folds = _located(r, ev.TORUS_FOLD)
    assert len(folds) == 2 and all(f.point is not None and not f.event.location.reason for f in folds)
    for f in folds:
        a, b = r.points[f.index], r.points[f.index + 1]
        fam_n = fam._replace(n_nodes=fam.nodes(a.X).shape[0])
        sign = 1.0 if a.tangent[-1] > 0 else -1.0      # the upper fold turns from increasing lambda
        brute = _extreme_lambda(fam_n, a, b, sign)
        tol = 2.0 * tori.corrector_error(fam_n, f.point, SETTINGS) + 1e-11
        assert abs(f.point.lam - brute) <= tol, (f.point.lam, brute, tol)
        assert sign * f.point.lam >= max(sign * a.lam, sign * b.lam)     # beyond both ends of its step
        assert abs(f.point.tangent[-1]) < 1e-8           # the located point's d mu / ds: Brent to locate_xtol


def test_the_stability_change_is_located_at_the_fold_within_its_stated_error(run):
    """At a fold of tori a normal multiplier is 1 (theory): the largest normal exponent's zero,
    located by TS to its stated error (from the exponent's own error estimate), is the fold TF
    locates independently (from the tangent) to the corrector's tolerance."""
    fam, r = run
    changes, folds = _located(r, ev.TORUS_STABILITY), _located(r, ev.TORUS_FOLD)
    assert [f.index for f in changes] == [f.index for f in folds]
    for ts, tf in zip(changes, folds):
        where = ts.event.location
        assert ts.point is not None and not where.reason and 0 < where.lam_error < 1e-4
        assert 0 < tf.event.location.lam_error < 1e-7      # the corrector's error: tol 1e-10 times ~20
        assert abs(ts.point.lam - tf.point.lam) <= where.lam_error + tf.event.location.lam_error


def test_a_stability_change_hidden_by_the_exponents_error_is_placed_with_that_error(run):
    """Where the exponent's error estimate exceeds half its change over the step, Brent has nothing
    to refine: TS is placed at the secant's zero (one corrector) with an error of at least the
    step (2 ds_e = 1.2 steps in arclength here), never without a value."""
    fam, r = run
    ts = _located(r, ev.TORUS_STABILITY)[0]
    a, b = r.points[ts.index], r.points[ts.index + 1]
    change = abs(b.stability.exponents[0] - a.stability.exponents[0])
    noisy = b._replace(stability=b.stability._replace(spread=0.6 * change))
    point, spent, where = tori.StabilityChange().place(fam, a, noisy, SETTINGS, engine.Counter())
    assert point is not None and spent == 1 and not where.reason
    sigma_b = a.tangent @ (b.X - a.X)
    assert 0.0 <= a.tangent @ (point.X - a.X) <= sigma_b       # within the step (lambda is not: a fold)
    assert where.lam_error > ts.event.location.lam_error        # wider than where Brent could refine

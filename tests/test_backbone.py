"""Backbone curves by pseudo-arclength continuation of conservative periodic orbits
(rotorsweep.kernels.continuation.backbone): the undamped Duffing oscillator against its elliptic-function
period, the linear limit of symmetric4 / asymmetric5 against the eigen-analysis of the polynomial
form, multipliers and energy of every continued orbit, invalid input. About 15 s once compiled."""
import numpy as np
import pytest
from scipy.special import ellipk

from rotorsweep.kernels import integrators as ig, models
from rotorsweep.kernels.continuation.arclength import Settings
from rotorsweep.kernels.continuation.backbone import follow_backbone
from rotorsweep.kernels.models import series_rotor as sr, symmetric4

TIGHT = ig.settings("dop853", rtol=1e-12, atol=1e-14, amplitude_limit=1e6)
# ds in units of the largest amplitude; the velocities of the state (scaled by tau's unit) make
# the tangent a few times longer than its amplitude part, hence the generous ds_max.
STEPS = Settings(ds=0.2, ds_max=2.0, max_steps=60, tol=1e-11)
CYLINDRICAL_X = symmetric4.PLANAR_SUBSPACES["cylindrical_x"]
# (model, mode, subspace): every linear mode; symmetric4's double one in its planar subspace.
MODES = [("symmetric4", 0, CYLINDRICAL_X), ("symmetric4", 2, None), ("symmetric4", 3, None)] + \
        [("asymmetric5", k, None) for k in range(5)]


def values(spec):
    """The model's defaults on the bearing these tests were written with (z0 = 16 um): the 2016
    table's 15 deg row with its label as the free angle, explicitly (the models' default is the
    2010 papers' bearing, its free angle from the groove geometry: z0 = 12.6 um)."""
    v = {p.name: (p.unset if p.axis else p.default) for p in spec.parameters}
    return {**v, "table": "filipkovsky2016", "nominal_angle": 15.0, "free_angle": "nominal"}


def test_duffing_backbone_is_the_elliptic_function_period():
    """x'' + x + gamma x^3 = 0 from x = A, x' = 0: T = 4 K(m) / sqrt(1 + gamma A^2) with
    m = gamma A^2 / (2 (1 + gamma A^2)). Every continued point: the period error is the
    integration error over a period (DOP853 at rtol 1e-12: ~1e-11) plus Newton's (tol 1e-11
    relative, divided by |f| ~ 2 pi |s|): 1e-9 relative bounds both."""
    duffing = models.get("duffing")
    gamma = 0.1
    bb = follow_backbone(duffing, {"omega": 1.0, "zeta": 0.0, "gamma": gamma, "force": 0.0}, TIGHT, 0, 3.0, STEPS)
    assert bb.status == "left_range" and bb.amplitude[-1] == pytest.approx(3.0, rel=1e-12)
    a2 = gamma * bb.amplitude ** 2
    exact = 4 * ellipk(a2 / (2 * (1 + a2))) / np.sqrt(1 + a2)
    np.testing.assert_allclose(bb.period, exact, rtol=1e-9)    # omega = 1: tau = t / 2 pi, period in s
    # x = A cn(w t | m): first Fourier coefficient 2 pi sqrt(q) / (K sqrt(m) (1 + q)) A, q the nome
    # (Abramowitz-Stegun 16.23.2); the DFT of 64 samples is exact to rounding for this spectrum
    m = a2 / (2 * (1 + a2))
    nome = np.exp(-np.pi * ellipk(1 - m) / ellipk(m))
    first = 2 * np.pi * np.sqrt(nome) / (ellipk(m) * np.sqrt(m) * (1 + nome)) * bb.amplitude
    np.testing.assert_allclose(bb.harmonic_amplitude, first, rtol=1e-9)
    assert len(bb.amplitude) > 3 and np.all(np.diff(bb.frequency) > 0)     # hardening


@pytest.mark.parametrize("name, mode, subspace", MODES)
def test_backbone_starts_at_the_linear_natural_frequency(name, mode, subspace):
    """At q_j = 1e-10 m the nonlinear correction omega_2 a^2 is below (a / z0)^2 = 4e-11 relative
    (z0 = 16 um, series coefficients O(1) in a / z0), the period error is Newton's tolerance 1e-10 over |f T| ~ 2 pi |s|: the
    first point's frequency equals the eigenvalue of the linearized gyroscopic system (numpy, from
    the PolynomialSystem, independent of the kernel) to 1e-9 relative."""
    spec = models.get(name)
    v = values(spec)
    system = spec.polynomial(v)
    linear = sr.linear_frequencies(system) / (2 * np.pi)
    if subspace is not None:   # the planar cylindrical mode is the double first frequency
        linear = linear[:1]
    # atol far below the state (1e-4 in units of 1 um): a relative integration error of 1e-12
    # (1e-22, near the smallest double step, makes DOP853's step underflow on the whirl pair)
    tiny = ig.settings("dop853", rtol=1e-12, atol=1e-18, amplitude_limit=1e6)
    bb = follow_backbone(spec, v, tiny, mode, 1e-8, Settings(max_steps=1, tol=1e-10), subspace=subspace,
                         amplitude_start=1e-10)
    assert bb.amplitude[0] == pytest.approx(1e-10, rel=1e-12)
    assert bb.frequency[0] == pytest.approx(linear[mode if subspace is None else 0], rel=1e-9)


@pytest.mark.parametrize("name, mode, subspace", [MODES[0], MODES[1], ("asymmetric5", 0, None),
                                                         ("asymmetric5", 1, None)])
def test_continued_orbits_are_conservative_and_soften(name, mode, subspace):
    """Every orbit up to 4 um (0.25 z0): multipliers away from +1 on the unit circle to 1e-8 and
    the monodromy's determinant 1 to 1e-10 (the flow preserves volume: trace M^-1 G = 0; the
    trivial multipliers at +1 form Jordan blocks that rounding splits by ~sqrt(eps), so they are
    checked through the determinant), T + V constant along the orbit to 1e-10 relative (DOP853 at
    rtol 1e-12 over one period), frequency decreasing with amplitude (the papers: softening)."""
    spec = models.get(name)
    bb = follow_backbone(spec, values(spec), TIGHT, mode, 4e-6, STEPS, subspace=subspace)
    assert bb.status == "left_range", bb.detail
    mult = bb.multipliers
    away = np.abs(mult - 1) > 1e-4
    assert np.all(np.abs(np.abs(mult[away]) - 1) < 1e-8)
    np.testing.assert_allclose(np.prod(mult, axis=1).real, 1.0, atol=1e-10)
    assert np.all(bb.energy_drift < 1e-10)
    assert np.all(np.diff(bb.frequency) < 0)


@pytest.mark.parametrize("kwargs, match", [
    ({"amplitude_max": 2e-5}, "amplitude_max = 2e-05 m: must be in \\(0, 1.6"),
    ({"amplitude_max": -1e-6}, "amplitude_max"),
    ({"amplitude_max": 1e-6, "amplitude_start": 2e-6}, "amplitude_start"),
    ({"mode": 0}, "mode = 0: its linear frequency is repeated"),
    ({"mode": 4}, "mode = 4: must be in \\[0, 3\\]"),
    ({"settings": Settings(ds=-0.1)}, "ds = -0.1: must be > 0"),
])
def test_invalid_backbone_input_raises_before_any_work(kwargs, match):
    spec = models.get("symmetric4")
    args = {"mode": 2, "amplitude_max": 1e-6, **kwargs}
    with pytest.raises(ValueError, match=match):
        follow_backbone(spec, values(spec), TIGHT, **args)

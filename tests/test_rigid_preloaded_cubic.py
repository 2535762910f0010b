"""`rigid_preloaded` with `[bearing] law = "cubic"` (the 2010 papers' power series) against the
exact ball sum it expands: the same rotor, where they must coincide and how they part.

The series is the third-order Taylor expansion of the ball sum (tests/test_nnm_models.py checks
that at bearing level), so:
- the static state and the linearization at rest are identical: equal natural frequencies;
- an unbalance orbit of amplitude a differs by the remainder of the force. Through degree 4 of
  the force (5 of the potential) the 7-ball sum is isotropic (trigonometric polynomials of
  degree <= 5 sum over 7 equally spaced balls to 7 times their mean), so on the circular whirl
  of the unbalance response the radial force is odd in a and the remainder is O(a^5): relative
  to the linear force O((a / z0)^4). Halving the unbalance (a halves, off resonance) divides the
  relative response difference by 2^4."""
import numpy as np
import pytest

from rotorsweep.pipeline import modes
from rotorsweep.kernels import continuation, integrators as ig, models, shooting

SPEC = models.get("rigid_preloaded")
OPTS = ig.settings(rtol=1e-12, atol=1e-12)


def values(**over):
    v = {p.name: (p.unset if p.axis else p.default) for p in SPEC.parameters}
    v.update(speed=250.0, **over)
    return v


@pytest.mark.parametrize("preload_law", ["hertz", "as_printed"])
def test_linear_frequencies_of_the_series_equal_those_of_the_ball_sum(preload_law):
    """Same stiffness matrix at rest (the series' linear terms are the sum's derivatives, exact
    up to rounding of two different formulas: 1e-10 relative)."""
    exact = modes.modes(SPEC, values(preload_law=preload_law))
    series = modes.modes(SPEC, values(preload_law=preload_law, law="cubic"))
    f_exact = np.array([m.frequency for m in exact])
    f_series = np.array([m.frequency for m in series])
    assert np.allclose(f_series, f_exact, rtol=1e-10, atol=0)


def _half_p2p_y_b(v):
    """Half peak-to-peak of y_B [m] of the forced orbit, 256 samples over the period (both laws
    sampled alike, so the sampling error cancels in their difference)."""
    built = SPEC.build(v)
    sol = continuation.solve_orbit(SPEC, built.p, OPTS, cold_guess=SPEC.cold_guess, tol=1e-11)
    assert sol.status == shooting.CONVERGED
    samples = shooting.sample_orbit(SPEC.kernel, sol.state, built.p, 1.0, 256, OPTS)
    y_b = SPEC.observe(samples, built.period)[:, 3]
    return 0.5 * (y_b.max() - y_b.min())


def test_forced_response_parts_from_the_ball_sum_at_fourth_order():
    """Unbalance response at 250 Hz (below the first resonance at 15 deg, 300 N, damped): the
    relative difference of the two laws' y_B amplitudes at eccentricity e and e / 2 has ratio
    2^4 = 16. Amplitudes 0.22 and 0.11 um (z0 = 16.5 um); the next terms (the sum's anisotropic
    degree-6 part, the orbit's departure from a circle) move the ratio by a few percent (measured
    16.2 here, 16.8 an octave up), so it must lie in 16 (1 +- 0.2); a series with a wrong cubic
    term would give 2^2, one without the sum's isotropy through degree 5 2^3."""
    diffs = []
    for e in (4e-6, 2e-6):
        exact = _half_p2p_y_b(values(eccentricity=e))
        series = _half_p2p_y_b(values(eccentricity=e, law="cubic"))
        diffs.append(abs(series - exact) / exact)
    assert diffs[0] > 1e-9, "the laws must differ at this amplitude, else the test shows nothing"
    assert 12.8 <= diffs[0] / diffs[1] <= 19.2

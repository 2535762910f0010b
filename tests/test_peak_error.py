"""A located peak's error estimate (arclength.Family.peak_error, issue 32): the peak moves by less
than its stated error when the orbits are solved 100 times tighter, and a "peak" on a jump of
the slope (no smooth maximum) is dropped."""
import numpy as np

from rotorsweep.kernels import integrators as ig, models
from rotorsweep.kernels.continuation import arclength as al

DUFFING = models.get("duffing")


def hardening(w):
    return DUFFING.build({"omega": w, "zeta": 0.05, "gamma": 1.0, "force": 0.3}).p


def peaks(family, settings):
    branch = al.continue_orbit(family, 0.5, np.zeros(2), (0.5, 5.0), settings)
    return [e for e in branch.events if e.kind == al.PEAK]


def family(rtol, cls=al.Family):
    return cls(DUFFING, hardening, ig.settings(rtol=rtol, atol=rtol * 1e-2), weights=np.array([[1.0]]), peak=0)


def test_duffing_peak_moves_less_than_its_error_at_tighter_tolerances():
    """The hardening peak at the default tolerances (rtol 1e-10, Newton 1e-10) and at rtol 1e-12,
    Newton 1e-12, continued independently: the peak moves by less than the error stated at the
    default ones (measured: moves 4.5e-12, stated 1.4e-11), and the stated error is small (the
    orbits' 1e-10 over a curvature O(1): below 1e-9), so the bound is not vacuous."""
    (coarse,) = peaks(family(1e-10), al.Settings(tol=1e-10))
    (fine,) = peaks(family(1e-12), al.Settings(tol=1e-12))
    assert 0.0 < coarse.lam_error < 1e-9 * coarse.point.lam
    assert abs(fine.point.lam - coarse.point.lam) <= coarse.lam_error
    assert fine.lam_error < coarse.lam_error


class Kinked(al.Family):
    """The hardening Duffing with its peak slope pushed down by JUMP between omega KINK and
    KINK + 0.1: at KINK the slope jumps from positive to negative (a corner opening downward, as a
    jump of the amplitude would give), no smooth maximum; at KINK + 0.1 it jumps back up."""
    KINK, JUMP = 1.2, 100.0

    def measures(self, X, t, along=None):
        amplitudes, slope, n_rhs = super().measures(X, t, along)
        return amplitudes, slope - self.JUMP * (self.KINK <= self.lam(X) < self.KINK + 0.1), n_rhs


def test_a_peak_on_a_jump_of_the_slope_is_dropped():
    """Brent locates the sign change at the jump (KINK) as it would a zero; the guard (|slope|
    there stays at the jump's size, not the location tolerance's) drops it, and the smooth
    hardening peak is still located where the plain family locates it."""
    (plain,) = peaks(family(1e-10), al.Settings())
    found = peaks(family(1e-10, Kinked), al.Settings())
    assert [e.point.lam for e in found] == [plain.point.lam]
    # without the guard the jump is located (its bracket closes on KINK)
    settings = al.Settings()
    kinked = family(1e-10, Kinked)
    branch = al.continue_orbit(kinked, 0.5, np.zeros(2), (0.5, 5.0), settings)
    a, b = next((a, b) for a, b in zip(branch.points, branch.points[1:]) if a.lam < Kinked.KINK <= b.lam)
    point, _ = al.engine.locate_zero(kinked, a, b, lambda s: s.slope if hasattr(s, "slope") else
                                     kinked.point(s, a, settings, al.Counter()).slope, settings, al.Counter())
    assert abs(point.lam - Kinked.KINK) < 1e-8
    assert not kinked.peak_error(point, a, b, settings, al.Counter())[1]


def test_peak_error_in_the_result_info_and_events_table():
    """The hardening peak's error estimate is the event's event_parameter_error (the folds': NaN,
    not estimated here), shown in `info` as "omega <value> +- <error>" and in the events table's
    omega_error column."""
    from rotorsweep.pipeline import config, continuation, continuation_result
    from tests.test_extrema import DUFFING_SCENE

    cfg = config.parse_config(DUFFING_SCENE.format(gamma=1.0, force=0.3, lo=0.5, hi=5.0))
    pl = continuation.plan(cfg.scene)
    ds = continuation.to_dataset(cfg.scene, pl, [(w, continuation.continue_line(cfg.scene, w)) for w in pl.lines], {})
    kinds, errors = ds["event_type"].values, ds["event_parameter_error"].values
    (k,) = np.flatnonzero(kinds == al.PEAK)
    assert 0.0 < errors[k] < 1e-9 and np.isnan(errors[kinds != al.PEAK]).all()
    assert f"omega {ds['event_parameter'].values[k]:.10g} +- {errors[k]:.2g}" in continuation_result.describe(ds)
    cols = continuation_result.events_table(ds)
    row = cols["type"].index("PK")
    assert cols["omega_error"][row] == errors[k]

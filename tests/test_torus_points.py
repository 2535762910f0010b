"""Tori at sweep grid points (rotorsweep.pipeline.torus_points): a tiny grid of the map scene
(configs/filipkovsky2016_map_tori.toml) with one periodically and one quasi-periodically forced
point, run end to end; the torus point checked against the torus solver run directly and against
a long scipy DOP853 run (a second method: the flow integrated, not the collocation solved)."""
import numpy as np
import pytest

from rotorsweep.pipeline import cli, compute, config, cube, query, schema, torus_points
from rotorsweep.pipeline.report import stability
from rotorsweep.kernels import torus as tr

SCENE = "configs/filipkovsky2016_map_tori.toml"
PERIODIC, QUASI = 300.0, 323.6067977     # 6/5 of 250 Hz; no ratio of small integers


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    d = tmp_path_factory.mktemp("torus_points")
    text = open(SCENE).read().replace("{start = 300.0, stop = 700.0, step = 23.6067977}",
                                      f"[{PERIODIC}, {QUASI}]").replace("[15, 26]", "[15]")
    (d / "map.toml").write_text(text)
    assert cli.main(["run", str(d / "map.toml"), "-o", str(d / "map.nc"), "--in-process"]) in (0, None)
    data = config.parse_config(text).scene
    built = compute.builder(data)({**data.fixed, "speed": 250.0, "support_frequency": QUASI,
                                   "nominal_angle": 15.0})
    return cube.open_cube(d / "map.nc"), data, built


def at(ds, f):
    return ds.sel(support_frequency=f).squeeze()


def test_a_quasi_periodic_point_gets_its_torus_and_a_periodic_one_its_orbit(result):
    ds, _, built = result
    assert not built.periodic
    per, qp = at(ds, PERIODIC), at(ds, QUASI)
    assert int(per["orbit_status"]) == 0 and int(per["torus_status"]) == schema.INT_FILL
    assert int(qp["orbit_status"]) == schema.ORBIT_STATUS.index("not_applicable")
    assert int(qp["torus_status"]) == schema.TORUS_STATUS.index("converged")
    assert int(qp["torus_stability"]) == schema.TORUS_STABILITY.index("stable") and float(qp["torus_exponent"]) < 0
    assert float(qp["torus_rotation_number"]) == pytest.approx(QUASI / 250.0, rel=1e-12)
    assert int(qp["torus_modes"]) >= 7 and float(qp["torus_error"]) < 1e-6
    assert np.isfinite(float(qp["amplitude_y_B"])) and np.isfinite(float(per["amplitude_y_B"]))
    assert ds["torus_exponent"].attrs["units"] == "s-1" and "flag_meanings" in ds["torus_status"].attrs


def test_the_classes_name_the_torus_in_the_query_and_the_map(result):
    ds, _, _ = result
    classes = query.point_classes(ds)
    assert at(classes, QUASI).item() == "quasi_periodic_stable" and at(classes, PERIODIC).item() == "stable"
    _, by_class = stability.counts(ds)
    assert by_class["quasi-periodic stable"] == 1 and by_class["stable"] == 1
    assert "torus_status" in cube.describe(ds) and "points per torus_status" in cube.describe(ds)


def test_the_sweep_amplitude_is_the_torus_solvers(result):
    """The sweep's first torus of a segment is solved from the transient (no neighbour's circle):
    the same as the torus solver and extrema run directly, to round-off."""
    ds, data, built = result
    model = data.model
    opts = data.integrator
    phase, freq, _ = model.torus_forcing
    circle = tr.torus_from_transient(model.kernel, model.cold_guess(built.p), built.p, phase, built.p[freq], opts,
                                     torus_points.SETTLE_PERIODS, torus_points.FIT_PERIODS, torus_points.FIRST_NODES,
                                     tol=data.newton.tol, decay_tol=torus_points.DECAY_TOL)
    hi, lo = tr.phase_extremes(model, circle, built.p, phase, opts, built.period, torus_points.AMPLITUDE_PHASES)
    j = [o.name for o in model.observables].index("y_B")
    direct = 0.5 * (hi[:, j].max() - lo[:, j].min())
    assert float(at(ds, QUASI)["amplitude_y_B"]) == pytest.approx(direct, rel=1e-12)


def test_the_torus_amplitude_against_a_long_dop853_run(result):
    """From the circle at phase 0, 10^3 shaft turns of scipy's DOP853 (rtol 1e-12) stay on the
    stable torus and cover it densely (irrational rotation); the half-swing of y_B over that run,
    sampled 256 times per turn and refined by the parabola through each extreme sample
    (tr.phase_sampling_error on the time series: its sampling error is then O(h^4)), is the
    torus's. The cube's value is low by its phase sampling, estimated by torus_amplitude_error
    (~1e-4 relative); the run's samples miss the torus's extreme phase by at most half their phase
    spacing (~pi / 1000 per turn, a shortfall ~1e-5 relative), hence tolerance: 2x the cube's
    estimate plus 2e-5 relative."""
    from scipy.integrate import solve_ivp

    from rotorsweep.kernels.models import rigid_preloaded_kernels as rp

    ds, data, built = result
    model = data.model
    opts = data.integrator
    circle = torus_points.solve(model, built, opts, data.newton.tol)
    p = built.p.copy()

    def f(tau, u):
        du = np.empty_like(u)
        rp.rhs(tau, u, p, du)
        return du
    turns, per_turn = 1000, 256
    sol = solve_ivp(f, (0.0, turns), circle.nodes[0], method="DOP853", rtol=1e-12, atol=1e-14,
                    t_eval=np.linspace(0.0, turns, per_turn * turns + 1))
    assert sol.success
    j = [o.name for o in model.observables].index("y_B")
    y = model.observe(sol.y.T, built.period)[:, j][:, None]
    top = y.max() + tr.phase_sampling_error(y)[0]
    bottom = y.min() - tr.phase_sampling_error(-y)[0]
    reference = 0.5 * (top - bottom)
    qp = at(ds, QUASI)
    rel = 2.0 * float(qp["torus_amplitude_error"]) + 2e-5
    assert float(qp["amplitude_y_B"]) == pytest.approx(reference, rel=rel)


def test_a_failed_torus_is_a_status_not_a_traceback(result):
    """A transient that cannot be integrated (the amplitude limit hit at once) leaves the point
    integration_failed with no values, its class torus_failed."""
    _, data, built = result
    model = data.model
    opts = data.integrator._replace(amplitude_limit=1e-12)
    circle = torus_points.solve(model, built, opts, data.newton.tol)
    out = torus_points.variables(model, circle, built, opts)
    assert out["torus_status"] == schema.TORUS_STATUS.index("integration_failed")
    assert out["torus_stability"] == schema.INT_FILL and np.isnan(out["torus_exponent"])


def test_point_prints_the_torus_of_a_quasi_periodic_point(capsys):
    """`rotorsweep point` at the quick scene's golden-ratio point: its torus, converged and stable
    (the attractor there is that torus: tests/test_torus_preloaded.py's kind of check)."""
    import json

    assert cli.main(["point", "--config", "configs/filipkovsky2016_quick.toml", "--at", "speed=250",
                     "--at", "support_frequency=404.508497187474", "--json"]) in (0, None)
    torus = json.loads(capsys.readouterr().out)["torus"]
    assert torus["status"] == "converged" and torus["stability"] == "stable" and torus["exponent"] < 0
    assert torus["rotation_number"] == pytest.approx((5 ** 0.5 + 1) / 2, rel=1e-12)


def test_cf_checkers_find_no_error_with_the_torus_variables(result, tmp_path):
    """The cube with torus variables under cfchecker and the IOOS compliance-checker
    (tests/cfcheck.py; skipped where they are not installed)."""
    from tests import cfcheck

    path = result[0].encoding["source"]
    messages = cfcheck.cfchecker_messages(path, tmp_path)
    assert messages["FATAL"] == messages["ERROR"] == []
    assert cfcheck.ioos_failures(path, tmp_path) == []

"""Issue 31's acceptance: a throwaway forced model and a throwaway conservative model, added through
$ROTORSWEEP_MODELS (modules written here, never a file of rotorsweep), run through `run`,
`continue`, `backbone` (the conservative one), `modes`, `info`, `query` and `report`; what the
pipeline needs to know about them it reads from their specs' capabilities."""
import json

import numpy as np
import pytest

from tests import plugin_models

FORCED_SCENE = """
[scene]
name = "tw_forced"
model = "tw_forced"

[sweep]
speed = [3.0, 4.0, 6.0]

[continuation]
ds = 0.1

[numerics]
amplitude_limit = 1.0
"""

PAIR_SCENE = """
[scene]
name = "tw_pair"
model = "tw_pair"

[sweep]
coupling = [0.5]

[backbone]
amplitude_max = 0.2
amplitude_points = 5
surface_mode = 2

[numerics]
rtol = 1e-11
atol = 1e-13
newton_tol = 1e-10
amplitude_limit = 10.0
"""


@pytest.fixture(scope="module")
def plugin_env(tmp_path_factory):
    d = tmp_path_factory.mktemp("plugins")
    modules = {"tw_forced_model": plugin_models.FORCED, "tw_pair_model": plugin_models.CONSERVATIVE}
    env = plugin_models.plugin_env(d, modules, {"forced.toml": FORCED_SCENE, "pair.toml": PAIR_SCENE})
    return d, env


def _cli(env, *args, rc=0):
    proc = plugin_models.cli(env, *args, rc=rc)
    return proc.stdout + proc.stderr


def _response(f, m=1.0, k=1000.0, c=4.0, force=1.0):
    """Closed form of the linear forced model: a circular orbit of radius F / |k - m w^2 + i c w|."""
    w = 2 * np.pi * f
    return force / abs(k - m * w * w + 1j * c * w)


# slow: the plugins' dispatch compiles the kernels of both models' groups (minutes on 2 cores)
@pytest.mark.slow
def test_a_forced_plugin_model_runs_through_run_continue_modes_info_query_report(plugin_env):
    d, env = plugin_env
    cube, line = d / "forced.nc", d / "forced_line.nc"
    _cli(env, "run", d / "forced.toml", "-o", cube, "--workers", "1", "-q")
    assert "tw_forced" in _cli(env, "info", cube)
    rows = json.loads(_cli(env, "query", cube, "--var", "amplitude_x", "--format", "json"))
    # half peak-to-peak of 32 orbit samples: relative error <= 1 - cos(pi / 32) = 4.8e-3 (test_models)
    for r in rows:
        assert r["amplitude_x"] == pytest.approx(_response(r["speed"]), rel=5e-3)
    _cli(env, "report", cube, "-o", d / "cube_report", "-q")
    assert (d / "cube_report" / "report.html").exists()
    _cli(env, "continue", d / "forced.toml", "-o", line, "--workers", "1", "-q")
    assert "tw_forced" in _cli(env, "info", line)
    _cli(env, "query", line)
    _cli(env, "report", line, "-o", d / "line_report", "-q")
    assert (d / "line_report" / "report.html").exists()
    # Modes from the spec's linearization: s = -c / 2m +- i sqrt(k/m - (c/2m)^2), a double pair
    # (one per plane); closed form to rounding (a 4x4 eigenproblem: 1e-12).
    out = json.loads(_cli(env, "modes", d / "forced.toml", "--json"))
    zeta = 4.0 / (2 * np.sqrt(1000.0))
    f_n = np.sqrt(1000.0) / (2 * np.pi)
    assert [m["whirl"] for m in out["modes"]] == ["none", "none"]
    for m in out["modes"]:
        assert m["undamped_frequency_hz"] == pytest.approx(f_n, rel=1e-12)
        assert m["damped_frequency_hz"] == pytest.approx(f_n * np.sqrt(1 - zeta ** 2), rel=1e-12)
        assert m["damping_ratio"] == pytest.approx(zeta, rel=1e-12)


@pytest.mark.slow
def test_a_conservative_plugin_model_runs_through_backbone_modes_info_query_report(plugin_env):
    d, env = plugin_env
    result = d / "pair_backbone.nc"
    _cli(env, "backbone", d / "pair.toml", "-o", result, "--workers", "1", "-q")
    assert "tw_pair" in _cli(env, "info", result)
    _cli(env, "query", result)
    _cli(env, "report", result, "-o", d / "pair_report", "-q")
    assert (d / "pair_report" / "report.html").exists()
    # Modes from `polynomial`'s linear part: w^2 = k / m and (k + 2 kc) / m, undamped
    out = json.loads(_cli(env, "modes", d / "pair.toml", "--json"))
    freqs = [m["damped_frequency_hz"] for m in out["modes"]]
    np.testing.assert_allclose(freqs, np.sqrt([1.0, 2.0]) / (2 * np.pi), rtol=1e-12)
    assert all(abs(m["damping_ratio"]) <= 1e-12 for m in out["modes"])
    # what a model without amplitude bound needs: a clear config error, rc 2
    (d / "pair_no_max.toml").write_text(PAIR_SCENE.replace("amplitude_max = 0.2\n", ""))
    err = _cli(env, "backbone", d / "pair_no_max.toml", "-o", d / "x.nc", "--workers", "1", rc=2)
    assert "backbone.amplitude_max: required for model tw_pair" in err

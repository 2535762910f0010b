"""Issue 31's acceptance: a throwaway forced model and a throwaway conservative model, added through
$ROTORSWEEP_MODELS (modules written here, never a file of rotorsweep), run through `run`,
`continue`, `backbone` (the conservative one), `modes`, `info`, `query` and `report`; what the
pipeline needs to know about them it reads from their specs' capabilities."""
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

# A forced 2-DOF rotor: isotropic linear spring (plus an optional cubic one) turning at `speed`
# with a rotating force F (cos, sin)(2 pi speed t); scaled time tau = speed t. Its linearization
# (declared on the spec) is M = m I, C = c I, K = k I.
FORCED = '''
import numpy as np
from numba import njit

from rotorkernels.models.spec import Built, LinearSystem, ModelSpec, Observable, Parameter
from rotorkernels.models.velocity import upper_rows, velocity_rows


@njit(cache=True, nogil=True, inline="always")
def rhs(tau, u, p, du):
    velocity_rows(u, du, 2)
    c, s = np.cos(2.0 * np.pi * tau), np.sin(2.0 * np.pi * tau)
    du[2] = p[0] * (p[4] * c - p[2] * u[0] - p[3] * u[0] ** 3) - p[1] * u[2]
    du[3] = p[0] * (p[4] * s - p[2] * u[1] - p[3] * u[1] ** 3) - p[1] * u[3]


@njit(cache=True, nogil=True, inline="always")
def jac(tau, u, p, out):
    upper_rows(out, 2)
    for i in range(2):
        for j in range(4):
            out[2 + i, j] = 0.0
        out[2 + i, i] = -p[0] * (p[2] + 3.0 * p[3] * u[i] ** 2)
        out[2 + i, 2 + i] = -p[1]


@njit(cache=True, nogil=True, inline="always")
def rhs_jac(tau, u, p, du, out):
    rhs(tau, u, p, du)
    jac(tau, u, p, out)


def build(v):
    T = 1.0 / v["speed"]
    m = v["mass"]
    return Built(np.array([T * T / m, T * v["damping"] / m, v["stiffness"], v["cubic"], v["force"]]), T, {})


def linearization(v, equilibrium):
    eye = np.eye(2)
    return LinearSystem(v["mass"] * eye, v["damping"] * eye, 0 * eye, v["stiffness"] * eye, ("x", "y"))


SPEC = ModelSpec(
    name="tw_forced", id=91, module=__name__, n_position=2,
    description="throwaway test model: forced isotropic 2-DOF rotor",
    parameters=(
        Parameter(name="speed", unit="Hz", long_name="shaft speed", axis=True, lo=0, lo_open=True),
        Parameter(name="mass", section="tw", unit="kg", default=1.0, lo=0, lo_open=True),
        Parameter(name="stiffness", section="tw", unit="N m-1", default=1000.0, lo=0, lo_open=True),
        Parameter(name="damping", section="tw", unit="N s m-1", default=4.0, lo=0),
        Parameter(name="cubic", section="tw", unit="N m-3", default=0.0),
        Parameter(name="force", section="tw", unit="N", default=1.0),
    ),
    continuation=("speed",),
    build=build, cold_guess=lambda p: np.zeros(4), length_scale=1.0,
    observables=(Observable("x", (1.0, 0.0), "m", "x displacement"),
                 Observable("y", (0.0, 1.0), "m", "y displacement")),
    linearization=linearization, speed="speed",
)
'''

# A conservative 2-DOF chain: two unit masses on springs k to ground, coupled by `coupling`, each
# with a hardening cubic spring; no damping, no forcing. Its capabilities come from `polynomial`.
CONSERVATIVE = '''
import numpy as np
from numba import njit

from rotorkernels.models.spec import Built, ModelSpec, Observable, Parameter, PolynomialSystem
from rotorkernels.models.velocity import upper_rows, velocity_rows


@njit(cache=True, nogil=True, inline="always")
def rhs(tau, u, p, du):
    velocity_rows(u, du, 2)
    du[2] = -p[0] * ((p[1] + p[2]) * u[0] - p[2] * u[1] + p[3] * u[0] ** 3)
    du[3] = -p[0] * ((p[1] + p[2]) * u[1] - p[2] * u[0] + p[3] * u[1] ** 3)


@njit(cache=True, nogil=True, inline="always")
def jac(tau, u, p, out):
    upper_rows(out, 2)
    for i in range(2):
        out[2 + i, 2] = 0.0
        out[2 + i, 3] = 0.0
        out[2 + i, i] = -p[0] * (p[1] + p[2] + 3.0 * p[3] * u[i] ** 2)
        out[2 + i, 1 - i] = p[0] * p[2]


@njit(cache=True, nogil=True, inline="always")
def rhs_jac(tau, u, p, du, out):
    rhs(tau, u, p, du)
    jac(tau, u, p, out)


def build(v):
    T = 2.0 * np.pi * np.sqrt(v["mass"] / v["stiffness"])     # the lowest linear period
    return Built(np.array([T * T / v["mass"], v["stiffness"], v["coupling"], v["cubic"]]), T, {})


def polynomial(v):
    k, kc = v["stiffness"], v["coupling"]
    q3 = np.zeros((2, 2, 2, 2))
    q3[0, 0, 0, 0] = q3[1, 1, 1, 1] = v["cubic"]
    return PolynomialSystem(M=v["mass"] * np.eye(2), G=np.zeros((2, 2)), K=np.array([[k + kc, -kc], [-kc, k + kc]]),
                            Q2=np.zeros((2, 2, 2)), Q3=q3, coordinates=("q1", "q2"), units=("m", "m"))


SPEC = ModelSpec(
    name="tw_pair", id=92, module=__name__, n_position=2, forced=False,
    description="throwaway test model: conservative coupled pair of hardening oscillators",
    parameters=(
        Parameter(name="coupling", section="pair", unit="N m-1", long_name="coupling stiffness", axis=True,
                  lo=0, unset=0.5),
        Parameter(name="mass", section="pair", unit="kg", default=1.0, lo=0, lo_open=True),
        Parameter(name="stiffness", section="pair", unit="N m-1", default=1.0, lo=0, lo_open=True),
        Parameter(name="cubic", section="pair", unit="N m-3", default=1.0),
    ),
    continuation=("coupling",),
    build=build, cold_guess=lambda p: np.zeros(4), length_scale=1.0,
    observables=(Observable("q1", (1.0, 0.0), "m", "first mass"), Observable("q2", (0.0, 1.0), "m", "second mass")),
    polynomial=polynomial,
)
'''

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
    (d / "tw_forced_model.py").write_text(textwrap.dedent(FORCED))
    (d / "tw_pair_model.py").write_text(textwrap.dedent(CONSERVATIVE))
    (d / "forced.toml").write_text(FORCED_SCENE)
    (d / "pair.toml").write_text(PAIR_SCENE)
    env = {**os.environ, "ROTORSWEEP_MODELS": "tw_forced_model, tw_pair_model",
           "PYTHONPATH": os.pathsep.join([str(d), str(ROOT), os.environ.get("PYTHONPATH", "")])}
    return d, env


def _cli(env, *args, rc=0):
    proc = subprocess.run([sys.executable, "-m", "pipeline.cli", *map(str, args)], env=env,
                          capture_output=True, text=True, timeout=900, cwd=ROOT)
    assert proc.returncode == rc, f"rotorsweep {args}:\n{proc.stdout}\n{proc.stderr}"
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

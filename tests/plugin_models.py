"""Throwaway model modules for the tests that add models through $ROTORSWEEP_MODELS (written to a
test's directory, never a file of rotorsweep), their environment and the CLI run in it.

Each source is the shared imports and rhs_jac around a model's own equations and spec; the text is
what the kernel cache hashes (rotorsweep.kernels), so an edit here compiles the plugins' kernels again."""
import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

RHS_JAC = '''@njit(cache=True, nogil=True, inline="always")
def rhs_jac(tau, u, p, du, out):
    rhs(tau, u, p, du)
    jac(tau, u, p, out)


'''


def model_source(spec_names, equations, spec):
    """A model module: numpy, njit and `spec_names` of rotorsweep.kernels.models.spec imported, the
    model's rhs and jac (`equations`), the shared rhs_jac, then its build and SPEC (`spec`)."""
    return ("\nimport numpy as np\nfrom numba import njit\n\n"
            f"from rotorsweep.kernels.models.spec import {spec_names}\n"
            "from rotorsweep.kernels.models.velocity import upper_rows, velocity_rows\n\n\n"
            + equations + RHS_JAC + spec)


# A 3-mass chain (wall-k-m-k-m-k-m), proportional damping c, force F cos(2 pi f t) on the first
# mass; scaled time tau = f t, state (q, dq/dtau) in m. Linear, so its orbit and multipliers are
# known in closed form (tests/test_models.py).
CHAIN = model_source(
    "Built, ModelSpec, Observable, Parameter",
    equations='''\
@njit(cache=True, nogil=True, inline="always")
def rhs(tau, u, p, du):
    velocity_rows(u, du, 3)
    du[3] = -p[0] * (2.0 * u[0] - u[1]) - p[1] * u[3] + p[2] * np.cos(2.0 * np.pi * tau)
    du[4] = -p[0] * (-u[0] + 2.0 * u[1] - u[2]) - p[1] * u[4]
    du[5] = -p[0] * (u[2] - u[1]) - p[1] * u[5]


@njit(cache=True, nogil=True, inline="always")
def jac(tau, u, p, out):
    upper_rows(out, 3)
    k = ((2.0, -1.0, 0.0), (-1.0, 2.0, -1.0), (0.0, -1.0, 1.0))
    for i in range(3):
        for j in range(3):
            out[3 + i, j] = -p[0] * k[i][j]
            out[3 + i, 3 + j] = -p[1] if i == j else 0.0


''',
    spec='''def build(v):
    T = 1.0 / v["frequency"]
    m = v["mass"]
    return Built(np.array([T * T * v["stiffness"] / m, T * v["damping"] / m, T * T * v["force"] / m]), T, {})


SPEC = ModelSpec(
    name="chain3", id=90, module=__name__, n_position=3,
    description="throwaway test model: forced linear 3-mass chain",
    parameters=(
        Parameter(name="frequency", unit="Hz", long_name="forcing frequency", axis=True, lo=0, lo_open=True),
        Parameter(name="stiffness", section="chain", unit="N m-1", long_name="spring stiffness",
                  axis=True, unset=1000.0, lo=0, lo_open=True),
        Parameter(name="mass", section="chain", unit="kg", default=1.0, lo=0, lo_open=True),
        Parameter(name="damping", section="chain", unit="N s m-1", default=2.0, lo=0),
        Parameter(name="force", section="chain", unit="N", default=1.0),
    ),
    continuation=("frequency",),
    build=build, cold_guess=lambda p: np.zeros(6), length_scale=1.0,
    observables=(Observable("q1", (1.0, 0.0, 0.0), "m", "first mass displacement"),
                 Observable("q3", (0.0, 0.0, 1.0), "m", "last mass displacement")),
)
''')

# A forced 2-DOF rotor: isotropic linear spring (plus an optional cubic one) turning at `speed`
# with a rotating force F (cos, sin)(2 pi speed t); scaled time tau = speed t. Its linearization
# (declared on the spec) is M = m I, C = c I, K = k I.
FORCED = model_source(
    "Built, LinearSystem, ModelSpec, Observable, Parameter",
    equations='''\
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


''',
    spec='''def build(v):
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
''')

# A conservative 2-DOF chain: two unit masses on springs k to ground, coupled by `coupling`, each
# with a hardening cubic spring; no damping, no forcing. Its capabilities come from `polynomial`.
CONSERVATIVE = model_source(
    "Built, ModelSpec, Observable, Parameter, PolynomialSystem",
    equations='''\
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


''',
    spec='''def build(v):
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
''')


def plugin_env(directory, modules, files=None):
    """The environment of a CLI that loads `modules` ({module name: source}) as models, written
    into `directory` with `files` ({file name: text}) beside them."""
    directory = Path(directory)
    for name, source in modules.items():
        (directory / f"{name}.py").write_text(textwrap.dedent(source))
    for name, text in (files or {}).items():
        (directory / name).write_text(text)
    return {**os.environ, "ROTORSWEEP_MODELS": ", ".join(modules),
            "PYTHONPATH": os.pathsep.join([str(directory), str(ROOT), os.environ.get("PYTHONPATH", "")])}


def cli(env, *args, rc=0):
    """`rotorsweep ARGS` in `env`, which must exit with `rc`; the finished process."""
    proc = subprocess.run([sys.executable, "-m", "rotorsweep.pipeline.cli", *map(str, args)], env=env,
                          capture_output=True, text=True, timeout=900, cwd=ROOT)
    assert proc.returncode == rc, f"rotorsweep {args}:\n{proc.stdout}\n{proc.stderr}"
    return proc

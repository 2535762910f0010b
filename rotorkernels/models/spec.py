"""What a model declares to the rest of rotorsweep: its parameters (config keys and sweep axes),
how to build the kernel's parameter vector, its observables and checks, and its capabilities (a
static equilibrium, a linearization, a shaft speed, omega_l, ...: what `pipeline/` reads instead of
the model's name).

`pipeline/` knows a model only through its `ModelSpec` (looked up in `models.REGISTRY`); the
kernels know it only through `ModelSpec.kernel`, whose tag the generated `models.dispatch` turns
into the model's functions when Numba compiles a kernel for the tag's kernel group.
"""
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, NamedTuple

import numpy as np


@dataclass(frozen=True)
class Parameter:
    """One input of a model (or of the generic config sections, which use the same type).

    kind: "str", "bool", "int", "float", "choice", "float_or" (a number or one of `choices`).
    section: the config table the key lives in; None for a parameter that is only swept.
    axis: the parameter may be swept (it becomes a cube dimension, in declaration order)."""
    kind: str = "float"
    default: object = None
    required: bool = False
    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple = ()
    pattern: str = ""
    help: str = ""
    name: str = ""
    section: str | None = None
    unit: str = "1"
    long_name: str = ""
    axis: bool = False
    unset: float | None = None   # value of an axis neither given nor swept (None: derived per point)


@dataclass(frozen=True)
class Observable:
    """A linear function of the physical state, reported per orbit (mean, half peak-to-peak) and
    per Poincare sample: value = weights . to_physical(u)."""
    name: str
    weights: tuple
    unit: str
    long_name: str


class PolynomialSystem(NamedTuple):
    """M q'' + G q' + K q + f2(q) + f3(q) = 0 in SI units; f2_i = sum_jk Q2[i,j,k] q_j q_k,
    f3_i = sum_jkl Q3[i,j,k,l] q_j q_k q_l (G already multiplied by the shaft speed; G skew)."""
    M: np.ndarray
    G: np.ndarray
    K: np.ndarray
    Q2: np.ndarray
    Q3: np.ndarray
    coordinates: tuple     # names, e.g. ("x1", "y1", "x2", "y2"); units m or rad as the model uses
    units: tuple


class KernelId(NamedTuple):
    """The kernel identity every njit function takes (`ModelSpec.kernel`), read by field name
    in jitted and Python code alike. tag: its type names the model's kernel group, so Numba
    compiles and caches each kernel once per group; its value is the model's id within the group.
    velocity_form: 1 when the state is (positions, velocities), as `ModelSpec.velocity_form`."""
    tag: object
    n_state: int
    n_position: int
    velocity_form: int


class Equilibrium(NamedTuple):
    """A model's static equilibrium at one parameter point (what its linearization is about)."""
    position: np.ndarray     # q_s, SI
    residual: float = 0.0    # the static balance's relative residual (0: exact by construction)
    iterations: int = 0      # Newton iterations it took (0: known in closed form)
    note: str = ""           # the model's own lines about its static state (`rotorsweep modes` prints them)


class LinearSystem(NamedTuple):
    """M q'' + (C + G) q' + K q = 0 about a static equilibrium, SI (G already times the shaft speed)."""
    M: np.ndarray
    C: np.ndarray
    G: np.ndarray
    K: np.ndarray
    coordinates: tuple       # names as PolynomialSystem's ("x1", "y1", ... give the mode labels)


class Built(NamedTuple):
    """A model's kernel inputs at one parameter point."""
    p: np.ndarray       # kernel parameter vector (scaled units)
    period: float       # the period [s] that scaled time tau = t / period refers to
    derived: dict       # extra per-point values for the cube, e.g. {"contact_angle_used": 15.2}
    periodic: bool = True   # False: quasi-periodic forcing, no orbit to shoot (attractor only)


@dataclass(frozen=True)
class ModelSpec:
    name: str
    id: int                         # kernel dispatch id (unique; the generated dispatch uses it)
    module: str                     # module holding the njit rhs, jac, rhs_jac (imported only to integrate:
    #                                 a built-in model's is `kernel_module` of its spec's module)
    n_position: int
    description: str
    version: str = "1"
    # (version, section, key, value): a scene written by a model version below `version` that
    # gives no section.key meant `value` (the default then; a callable: value(the scene's section)),
    # so that results written before a default changed are recomputed as they were
    # (rotorsweep.pipeline.scene.of_result)
    older_defaults: tuple = ()
    velocity_form: bool = True      # u = (q, q'), dq/dtau = q': Jacobian [[0, I], [A, B]]
    n_state_override: int = 0       # only for models not in velocity form
    forced: bool = True             # periodic forcing of known period (shooting over it)
    parameters: tuple = ()          # Parameter, in the order of the cube's dimensions for axes
    continuation: tuple = ()        # parameters a sweep continues orbits along (first: default)
    build: Callable = None          # build(values: {parameter name: value}) -> Built
    cold_guess: Callable = None     # cold_guess(p) -> a scaled state to start a transient from
    length_scale: float = 1e-6      # m per scaled length unit
    observables: tuple = ()         # Observable
    derived: dict = field(default_factory=dict)   # name -> (unit, long_name) of Built.derived
    check: Callable = None          # check(data, axes) -> list of error strings (config level)
    fill_defaults: Callable = None  # fill_defaults(data): defaults that depend on other keys
    references: str = ""            # the model's sources (the cube's CF `references` attribute)
    polynomial: Callable = None     # polynomial(values) -> PolynomialSystem (conservative models)
    kernel_group: str = ""          # models compiled together (default: the model alone), see models.dispatch
    # capabilities (pipeline/ reads these, never a model's name):
    equilibrium: Callable = None    # equilibrium(values) -> Equilibrium (None: q = 0); independent of the
    #                                 shaft speed (Campbell tables solve it once)
    linearization: Callable = None  # linearization(values, Equilibrium) -> LinearSystem (None: `polynomial`'s
    #                                 linear part if given, else no linear analysis)
    no_linearization: str = ""      # why a model without one has none (what `rotorsweep modes` says)
    speed: str = ""                 # the parameter that is the shaft speed [Hz] (Campbell diagrams, the 1x line)
    support_frequency: str = ""     # the parameter that is a support excitation frequency [Hz] (where > 0: a
    #                                 horizontal line of Campbell diagrams, its crossings critical speeds)
    omega_l: Callable = None        # omega_l(values) -> [Hz]: the reports' frequency unit (None: Hz only)
    disk_position: Callable = None  # disk_position(values) -> (xi_D, l) [m]: a rigid rotor's disc at xi_D from
    #                                 bearing A, l between the bearings (its motion is interpolated from theirs)
    derived_axes: dict = field(default_factory=dict)   # axis -> how it is derived per point when neither
    #                                                    given nor swept ("derived from X ...")
    amplitude_bound: str = ""       # a Built.derived value [m] the amplitudes must stay below (the
    #                                 series law's axial approach); "": no bound
    torus_forcing: tuple = ()       # (phase slot, frequency slot, values): a second forcing whose phase is
    #                                 p[phase slot] and frequency p[frequency slot] [rad per unit tau]; the build
    #                                 at {**values, ...} keeps tau one first-forcing period (tori: rotorsweep.pipeline.tori)
    contact_margin: Callable = None  # contact_margin(states (m, n_state), p) -> the smallest contact deflection over
    #                                 the states relative to its static value (< 0: a contact opens, the force is not
    #                                 smooth in the state there); None: a model without unilateral contacts
    invariant_subspaces: dict = field(default_factory=dict)   # name -> basis (n_state x k) of an invariant
    #                                 subspace in which a repeated linear frequency is simple (backbones)

    @property
    def n_state(self):
        return 2 * self.n_position if self.velocity_form else self.n_state_override

    @property
    def group(self):
        """The kernel group's name: models of one group share one compiled copy of each kernel."""
        return self.kernel_group or self.name

    @cached_property
    def kernel(self):
        """The model's `KernelId`, which every njit function takes (kept: a continuation asks for it
        at every integration, 6 us each, 16 ms of the Bai 7.6 um line)."""
        from rotorsweep.kernels.models import kernel_tag   # the registry imports this module

        return KernelId(kernel_tag(self), self.n_state, self.n_position, int(self.velocity_form))

    @property
    def axes(self):
        return tuple(p.name for p in self.parameters if p.axis)

    def parameter(self, name):
        return next(p for p in self.parameters if p.name == name)

    @property
    def has_linearization(self):
        return self.linearization is not None or self.polynomial is not None

    def linearization_problem(self):
        """"" for a model with a linearization, else one line saying why it has none."""
        if self.has_linearization:
            return ""
        return f"model {self.name} has no linearization" + (f": {self.no_linearization}" if self.no_linearization else "")

    def linear_system(self, values, equilibrium=None):
        """(Equilibrium, LinearSystem) at `values` (the equilibrium solved unless given);
        ValueError saying why for a model without a linearization."""
        if not self.has_linearization:
            raise ValueError(self.linearization_problem())
        if self.linearization is None:
            system = self.polynomial(values)
            eq = Equilibrium(np.zeros(self.n_position))
            n = len(system.coordinates)
            return eq, LinearSystem(system.M, np.zeros((n, n)), system.G, system.K, system.coordinates)
        eq = equilibrium if equilibrium is not None else (
            self.equilibrium(values) if self.equilibrium is not None else Equilibrium(np.zeros(self.n_position)))
        return eq, self.linearization(values, eq)

    def to_physical(self, u, period):
        """Scaled state(s) (..., n_state) -> SI: positions in m, velocities in m/s (velocity form)."""
        u = np.asarray(u, float)
        scale = np.full(self.n_state, self.length_scale)
        if self.velocity_form:
            scale[self.n_position:] /= period
        return u * scale

    def observe(self, u, period):
        """Observables of scaled state(s) (..., n_state): array (..., n_observables) in SI."""
        weights = np.array([o.weights for o in self.observables], float)
        return self.to_physical(u, period)[..., :weights.shape[1]] @ weights.T


def kernel_module(spec_module):
    """The module of a built-in model's njit kernels: `models.duffing` -> `models.duffing_kernels`.
    A built-in model's spec module imports no Numba, so reading a result (the registry) does not
    either (issue 35); a plugin may keep its SPEC and kernels in one module."""
    return f"{spec_module}_kernels"


VALIDATION_GROUP = "validation"


def validation_spec(name, id, module, names, description):
    """The spec of a 2-DOF validation model in scaled time (period 1) whose kernel parameters are
    its values `names` in order; such a model has no sweep axis and is used by the kernels' tests.
    The validation models share one kernel group: compiled once for both."""
    def build(v):
        return Built(np.array([float(v[k]) for k in names]), 1.0, {})
    return ModelSpec(name=name, id=id, module=module, n_position=2, description=description,
                     parameters=tuple(Parameter(name=k, default=0.0) for k in names), build=build,
                     cold_guess=lambda p: np.zeros(4), length_scale=1.0, kernel_group=VALIDATION_GROUP)

"""Validation model `duffing`: x'' + 2 zeta x' + x + gamma x^3 = F cos(omega t), in scaled time
tau = t / T with T = 2 pi / omega, state (x, dx/dtau). With F = 0 and zeta = 0 it is conservative
and autonomous (free oscillation, backbone); hardening for gamma > 0, softening for gamma < 0."""
import numpy as np

from rotorsweep.kernels.models.spec import Built, LinearSystem, ModelSpec, Observable, Parameter, kernel_module

P_T2, P_DAMP, P_GAMMA, P_FORCE = range(4)   # T^2, 2 zeta T, gamma, F


def build(v):
    period = 2.0 * np.pi / v["omega"]
    p = np.array([period * period, 2.0 * v["zeta"] * period, v["gamma"], v["force"]])
    return Built(p, period, {})


def linearization(v, equilibrium):
    """x'' + 2 zeta x' + x = 0 about x = 0 (time in the model's unit: linear natural frequency 1)."""
    return LinearSystem(np.eye(1), np.array([[2.0 * v["zeta"]]]), np.zeros((1, 1)), np.eye(1), ("x",))


SPEC = ModelSpec(
    name="duffing", id=3, module=kernel_module(__name__), n_position=1,
    description="validation: forced Duffing oscillator (scaled time tau = omega t / 2 pi)",
    parameters=(
        Parameter(name="omega", unit="rad s-1", long_name="forcing frequency", axis=True, lo=0,
                  lo_open=True, help="forcing circular frequency (linear natural frequency 1)"),
        Parameter(default=0.05, name="zeta", section="duffing", lo=0, help="damping ratio"),
        Parameter(default=0.1, name="gamma", section="duffing", help="cubic stiffness"),
        Parameter(default=0.1, name="force", section="duffing", help="forcing amplitude"),
    ),
    continuation=("omega",),
    build=build, cold_guess=lambda p: np.zeros(2), length_scale=1.0,
    observables=(Observable("x", (1.0,), "1", "displacement"),),
    linearization=linearization,
    # its own kernel group, not the test-only validation models': it has a scene of its own
    # (configs/duffing_resonance.toml), whose first point would otherwise compile their
    # equations too (docs/benchmarks/compile.md)
)

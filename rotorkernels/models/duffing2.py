"""Validation model `duffing2`: a Duffing oscillator under two-frequency forcing, in scaled time
tau = Omega t / 2 pi (the first forcing's period is 1):

    x'' + c x' + k x + gamma x^3 = f1 cos(2 pi tau) + f2 cos(w2 tau + theta),

p = (k, c, gamma, f1, f2, w2, theta), state (x, x'). The second forcing's phase theta at tau = 0 is
a parameter: the torus solver (rotorsweep.kernels.torus) shoots one forcing period from each phase node.
With gamma = 0 it is linear and its quasi-periodic response is the sum of two periodic ones."""
import numpy as np

from rotorsweep.kernels.models.spec import VALIDATION_GROUP, Built, ModelSpec, Observable, Parameter, kernel_module

P_K, P_C, P_GAMMA, P_F1, P_F2, P_W2, P_PHASE = range(7)
NAMES = ("k", "c", "gamma", "f1", "f2", "w2", "theta")


def build(v):
    return Built(np.array([float(v[k]) for k in NAMES]), 1.0, {}, periodic=False)


SPEC = ModelSpec(
    name="duffing2", id=7, module=kernel_module(__name__), n_position=1,
    description="validation: Duffing oscillator under two-frequency forcing (scaled time)",
    parameters=tuple(Parameter(name=k, default=0.0) for k in NAMES), build=build,
    cold_guess=lambda p: np.zeros(2), length_scale=1.0, kernel_group=VALIDATION_GROUP,
    observables=(Observable("x", (1.0,), "1", "displacement"),), torus_forcing=(P_PHASE, P_W2, {}),
)

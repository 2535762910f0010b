"""Validation model `damped_mathieu`: x'' + 2 zeta x' + (delta + eps cos 2 pi tau) x = 0, twice
(uncoupled), p = (zeta, delta, eps); period 1 in scaled time."""
from rotorsweep.kernels.models.spec import kernel_module, validation_spec

SPEC = validation_spec("damped_mathieu", 2, kernel_module(__name__), ("zeta", "delta", "eps"),
                       "validation: damped Mathieu equation, twice (scaled time)")

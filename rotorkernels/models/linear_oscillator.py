"""Validation model `linear_oscillator`: u'' + C u' + K u = 0 with K = [[p0, p1], [p1, p2]],
C = diag(p3, p4) (scaled time); its flow is expm(A t), its spectra the eigenvalues of A."""
from rotorsweep.kernels.models.spec import kernel_module, validation_spec

SPEC = validation_spec("linear_oscillator", 1, kernel_module(__name__), ("k11", "k12", "k22", "c1", "c2"),
                       "validation: 2-DOF linear oscillator (scaled time)")

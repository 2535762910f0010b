"""Normal modes of the linear part of a conservative gyroscopic PolynomialSystem (the nonlinear
normal modes' starting point): `rotorsweep.kernels.modal.modes_of` with D = G, which also gives the
labels, whirl directions and degenerate-pair conventions."""
import numpy as np

from rotorsweep.kernels import modal
from rotorsweep.kernels.modal import LinearMode, kinds_from_names  # noqa: F401 (the package's API)
from rotorsweep.kernels.nnm import system as ps

# Relative size of Re(s) to |s| above which an eigenvalue is not on the imaginary axis.
CONSERVATIVE_RTOL = 1e-8


def linear_modes(system, kinds=None):
    """The normal modes of a conservative system's linear part, by increasing frequency (list of
    LinearMode); ValueError when it has none (an eigenvalue off the imaginary axis or at zero)."""
    ps.validate(system)
    n = len(system.coordinates)
    kinds = kinds if kinds is not None else kinds_from_names(system.coordinates)
    modes = modal.modes_of(system.M, np.zeros((n, n)), system.G, system.K, kinds)
    if len(modes) < n or any(abs(m.damping_ratio) > CONSERVATIVE_RTOL for m in modes):
        raise ValueError("the linear system has eigenvalues off the imaginary axis or at zero "
                         "(K not positive definite): it has no normal modes")
    return [m._replace(damping_ratio=0.0) for m in modes]

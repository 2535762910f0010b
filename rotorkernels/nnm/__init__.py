"""Nonlinear normal modes of conservative gyroscopic polynomial systems (Filipkovsky 2010):
linear modes with labels (linear), the Shaw-Pierre invariant manifold to cubic order and its
reduced oscillator (shaw_pierre), backbone curves, the invariance check and figure data (curves).
Pure Python (PYTHON_ONLY): nothing here is compiled.
"""
from rotorsweep.kernels.nnm.curves import (angular_frequency, backbone, coordinate_amplitudes, frequency_coefficient,
                                       growth_coefficient, invariance_error, orbit, orbit_on_manifold, surface)
from rotorsweep.kernels.nnm.linear import LinearMode, kinds_from_names, linear_modes
from rotorsweep.kernels.nnm.shaw_pierre import MONOMIALS, Manifold, manifold
from rotorsweep.kernels.nnm.system import PolynomialSystem, validate

__all__ = ["LinearMode", "MONOMIALS", "Manifold", "PolynomialSystem", "angular_frequency", "backbone",
           "coordinate_amplitudes", "frequency_coefficient", "growth_coefficient", "invariance_error",
           "kinds_from_names", "linear_modes", "manifold", "orbit", "orbit_on_manifold", "surface", "validate"]

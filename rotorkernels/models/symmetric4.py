"""Model `symmetric4` (Filipkovsky 2010, symmetric rotor, SPEC 2.3): a rigid shaft with
distributed mass and a disk at mid-span on two preloaded angular-contact ball bearings with the
cubic series law; 4 DOF q = (x1, y1, x2, y2), no axial motion (z = 0 by the symmetry), no damping,
no forcing. Conventions, choices and scaling: `series_rotor`.

The first linear frequency is double (the cylindrical modes in the x and y planes, which the
gyroscopic coupling leaves untouched); the conical modes split into backward and forward whirl.
`polynomial(values)` gives the PolynomialSystem for the invariant-manifold code.
"""
import numpy as np

from rotorsweep.kernels.models import series_rotor as sr
from rotorsweep.kernels.models.spec import ModelSpec, kernel_module

N_POS = 4


def _planar(position):
    """Orthonormal basis (8 x 2) of the invariant subspace q = (w, 0, w, 0) or (0, w, 0, w): both
    journals in phase in one plane. Invariant: the mid-span mirror (swapping the bearings) and,
    within the cylindrical motion, which the gyroscopic forces do not reach, y -> -y are symmetries."""
    b = np.zeros((2 * N_POS, 2))
    b[[position, position + 2], 0] = b[[N_POS + position, N_POS + position + 2], 1] = np.sqrt(0.5)
    return b


# The double linear frequency's planar modes, where its backbone is well-posed (backbone.py).
PLANAR_SUBSPACES = {"cylindrical_x": _planar(0), "cylindrical_y": _planar(1)}


def disk_position(v):
    """(xi_D, l) [m]: the symmetric paper, section 1: "диск закреплен посередине между опорами"
    (the disc is fixed midway between the supports)."""
    return v["length"] / 2, v["length"]


def polynomial(v):
    return sr.polynomial_system(v, N_POS, disk_position(v)[0])


SPEC = ModelSpec(
    name="symmetric4", id=5, version="2",   # 2: the 2010 papers' bearing (E = 2e11 Pa) by default
    module=kernel_module(__name__), older_defaults=sr.OLDER_DEFAULTS,
    n_position=N_POS, forced=False, continuation=("speed",),
    description="Filipkovsky 2010: symmetric 4-DOF rotor on preloaded ball bearings, cubic series law, conservative",
    parameters=sr.ROTOR_PARAMETERS + sr.BEARING_PARAMETERS,
    build=sr.build_for(N_POS, lambda v: disk_position(v)[0]), cold_guess=lambda p: np.zeros(2 * N_POS),
    length_scale=sr.LENGTH_SCALE, observables=sr.observables(N_POS), derived=sr.DERIVED, check=sr.check,
    references=sr.REFERENCES, polynomial=polynomial, speed="speed", amplitude_bound="axial_approach",
    invariant_subspaces=PLANAR_SUBSPACES, disk_position=disk_position,
)

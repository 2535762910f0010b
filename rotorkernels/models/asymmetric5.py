"""Model `asymmetric5` (Filipkovsky 2010, coupled transverse-axial vibration, SPEC 2.3): a rigid
shaft with distributed mass and a disk at l1 (default 0.125 m) from bearing A on two preloaded
angular-contact ball bearings with the cubic series law; 5 DOF q = (x1, y1, x2, y2, z) with the
series' quadratic transverse-axial couplings, no damping, no forcing. Conventions, choices and
scaling: `series_rotor`.

The lowest mode is axial (the axial stiffness 2 c_a is below the radial one at the papers'
angles); `polynomial(values)` gives the PolynomialSystem for the invariant-manifold code.
"""
import numpy as np

from rotorsweep.kernels.models import series_rotor as sr
from rotorsweep.kernels.models.spec import ModelSpec, Parameter, kernel_module

N_POS = 5


def disk_position(v):
    """(xi_D, l) [m]: the axial paper, section 2: "l_1 = 0,125 м" from support A (the rotor key)."""
    return v["disk_position"], v["length"]


def polynomial(v):
    return sr.polynomial_system(v, N_POS, disk_position(v)[0])


SPEC = ModelSpec(
    name="asymmetric5", id=6, version="2",   # 2: the 2010 papers' bearing (E = 2e11 Pa) by default
    module=kernel_module(__name__), older_defaults=sr.OLDER_DEFAULTS,
    n_position=N_POS, forced=False, continuation=("speed",),
    description="Filipkovsky 2010: asymmetric 5-DOF rotor (transverse-axial coupling) on preloaded ball "
                "bearings, cubic series law, conservative",
    parameters=sr.ROTOR_PARAMETERS + (
        # the axial paper, section 2: "l_1 = 0,125 м" from support A
        Parameter(default=0.125, name="disk_position", section="rotor", lo=0, unit="m",
                  help="disk position l1 from bearing A (paper: 0.125 m)"),) + sr.BEARING_PARAMETERS,
    build=sr.build_for(N_POS, lambda v: disk_position(v)[0]), cold_guess=lambda p: np.zeros(2 * N_POS),
    length_scale=sr.LENGTH_SCALE, observables=sr.observables(N_POS), derived=sr.DERIVED, check=sr.check,
    references=sr.REFERENCES, polynomial=polynomial, speed="speed", amplitude_bound="axial_approach",
    disk_position=disk_position,
)

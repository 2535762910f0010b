"""What `symmetric4` and `asymmetric5` (Filipkovsky 2010) share: a rigid shaft with distributed
mass and one disk on two preloaded angular-contact bearings with the cubic series law
(`rotorsweep.kernels.cubic_law`), conservative (no damping, no forcing).

Coordinates q = (x1, y1, x2, y2[, z]) [m]: journal displacements of bearing A (at xi = 0) and B
(xi = l), and for the 5-DOF model the axial displacement z. Lagrange's equations

    M q'' + Omega G q' + P(q) = 0

with the papers' kinetic energy (shaft: rho I / 2 int (theta1'^2 + theta2'^2) - 2 rho I Omega
int theta2' theta1 + rho S / 2 int (u_x'^2 + u_y'^2); disk: I1 / 2 (theta1'^2 + theta2'^2) -
I0 Omega theta2' theta1 + m0 / 2 (u_x'^2 + u_y'^2) at the disk), theta1 = -(y2 - y1) / l,
theta2 = (x2 - x1) / l, I = pi d^4 / 64, S = pi d^2 / 4. It is the kinetic energy of
`rigid_preloaded` with shaft mass rho S l, diametral inertia rho S l^3 / 12 + rho I l and polar
inertia 2 rho I l, so its `mass_matrix` and `gyroscopic_matrix` are reused (a sympy test derives
them from the 2010 integrals).

Choices where the papers are ambiguous or inconsistent:
* The papers print u_x = x1 z / l + x2 (l - z) / l, which puts x1 at z = l although the origin is
  at support A and the supports are numbered from it. We put x1 at A (u_x = x1 (l - z) / l +
  x2 z / l), the disk of asymmetric5 at l1 from A: a mirror relabelling, no frequency changes.
* The symmetric paper's M_13 = rho S l / 3 - ... is a misprint of rho S l / 6 (its own T).
* The axial kinetic energy (rho S l + m0) z'^2 / 2 is not written in the axial paper; it is
  the rigid rotor's (a rigid shaft moves axially as a whole).
* The shaft is rigid (the papers: "the rotor is a rigid body", the potential energy is the
  bearings' only); "flexible shaft" in the issue refers to its distributed mass.
* Bearings: `rigid_preloaded`'s pair (`preloaded_pair`): back-to-back by default, +z compresses A
  and relieves B (the papers write one z; with equal signs the two static preload forces would add
  instead of cancel); `bearing.arrangement = "face_to_face"` flips it.
* Bearing constants: `bearing.table = "filipkovsky2010"` (the default here) is these papers'
  bearing as printed (section 2 of both: R1 = 16.00, R2 = 27.53, R_K = 5.93, d = 11.51 mm, N = 7,
  E = 2e11 Pa, sigma = 0.3, Q = 300 N; free angle 19.5 deg from the groove geometry by eq. 10).
* Rotor constants (ROTOR_PARAMETERS) as both papers print them in section 2: l = 0.5 m,
  l1 = 0.125 m (axial paper), d = 0.025 m, m0 = 10 kg, I1 = 0.1, I0 = 0.2 kg m^2,
  omega = 628.3 rad/s. The density is not printed: steel, 7800 kg/m^3 (ours).

Kernel (`series_rotor_kernels`, the models' `<model>_kernels`): tau = t / T with T = 2 pi / (the lowest linear natural frequency at the point), positions
in units of L = 1 um; u = (q / L, dq/dtau / L). The right-hand side does not depend on tau.
"""
import math
from dataclasses import replace

import numpy as np

from rotorsweep.kernels import modal
from rotorsweep.kernels.cubic_law import cubic_coefficients, derivative_tensor, potential_monomials
from rotorsweep.kernels.models import rigid_preloaded as rp
from rotorsweep.kernels.models.spec import Built, Observable, Parameter, PolynomialSystem

LENGTH_SCALE = 1e-6
STEEL_DENSITY = 7800.0      # kg/m^3 (not in the papers)
SHAFT_DIAMETER = 0.025      # m (papers)
COORDINATES = ("x1", "y1", "x2", "y2", "z")

# version 2 took the 2010 papers' table as the default (it was the 2016 one, 15 deg row) and the
# free angle from the groove geometry (ModelSpec.older_defaults)
OLDER_DEFAULTS = (("2", "bearing", "table", "filipkovsky2016"),
                  ("2", "bearing", "free_angle", rp.free_angle_before_version_2))


def p_layout(n):
    """Offsets in the kernel vector of an n-position model: gain T^2 M^-1 (n x n), gyroscopic
    T M^-1 Omega G (n x n), then c_r, c_a [N/m], z0 / L, tan^2 a and the arrangement's sign s
    (bearing A shifted by s z, B by -s z)."""
    return 0, n * n, 2 * n * n


def n_params(n):
    return 2 * n * n + 5


# --- SI model ----------------------------------------------------------------------------------

def rotor_of(v, disk_position):
    """rigid_preloaded.Rotor of the 2010 rotor: a steel shaft of diameter d (distributed mass)."""
    length, d = v["length"], v["shaft_diameter"]
    area, second_moment = math.pi * d * d / 4, math.pi * d ** 4 / 64
    rho = v["shaft_density"]
    return rp.Rotor(length=length, disk_position=disk_position, shaft_mass=rho * area * length,
                    shaft_diametral=rho * area * length ** 3 / 12 + rho * second_moment * length,
                    shaft_polar=2 * rho * second_moment * length, disk_mass=v["disk_mass"],
                    disk_diametral=v["disk_diametral"], disk_polar=v["disk_polar"], damping=0.0, gravity=0.0)


def coefficients(v):
    """The series coefficients (SI) at the point's preload state."""
    state = rp.bearing_state(v)
    n_balls = rp.n_balls_of(v)
    return cubic_coefficients(state.contact_constant, state.axial_approach, state.contact_angle, n_balls), state


def _bearing_maps(n, sign=1.0):
    """Local (x, y, z) of bearings A and B as linear maps of q: A = (x1, y1, s z), B = (x2, y2, -s z)
    with s the arrangement's sign (rp.ARRANGEMENTS)."""
    maps = np.zeros((2, 3, n))
    maps[0, 0, 0] = maps[0, 1, 1] = maps[1, 0, 2] = maps[1, 1, 3] = 1.0
    if n == 5:
        maps[0, 2, 4], maps[1, 2, 4] = sign, -sign
    return maps


def polynomial_system(v, n, disk_position):
    """PolynomialSystem (SI) of the n-position model: the potential of both bearings pulled back
    to q, K = d2V, Q2 = d3V / 2, Q3 = d4V / 6 (fully symmetric: f = dV/dq)."""
    rotor = rotor_of(v, disk_position)
    coef, _ = coefficients(v)
    monomials = potential_monomials(coef)
    local = [derivative_tensor(monomials, m) for m in (1, 2, 3, 4)]
    tensors = [np.zeros((n,) * m) for m in (1, 2, 3, 4)]
    for a in _bearing_maps(n, rp.ARRANGEMENTS[rp.arrangement_of(v)]):
        for m, t in enumerate(local, start=1):
            tensors[m - 1] += np.einsum(t, list(range(m)), *[x for k in range(m) for x in (a, [k, m + k])],
                                        list(range(m, 2 * m)))
    if np.abs(tensors[0]).max() > 1e-12 * coef.static_force:
        raise AssertionError("the static preload forces of the bearing pair do not cancel")
    omega = 2 * math.pi * v["speed"]
    return PolynomialSystem(M=rp.mass_matrix(rotor)[:n, :n], G=omega * rp.gyroscopic_matrix(rotor)[:n, :n],
                            K=tensors[1], Q2=tensors[2] / 2, Q3=tensors[3] / 6,
                            coordinates=COORDINATES[:n], units=("m",) * n)


def linear_frequencies(system):
    """Natural frequencies [rad/s] of M q'' + G q' + K q = 0, ascending, each pair once."""
    return modal.eigenpairs(modal.first_order(system.M, system.G, system.K))[0].imag


def build_for(n, disk_position):
    def build(v):
        system = polynomial_system(v, n, disk_position(v))
        coef, state = coefficients(v)
        period = 2 * math.pi / linear_frequencies(system)[0]
        m_inv = np.linalg.inv(system.M)
        gain, gyro, law = p_layout(n)
        p = np.empty(n_params(n))
        p[gain:gyro] = (period ** 2 * m_inv).ravel()
        p[gyro:law] = (period * m_inv @ system.G).ravel()
        p[law:] = (coef.radial, coef.axial, coef.approach / LENGTH_SCALE, coef.tan2,
                   rp.ARRANGEMENTS[rp.arrangement_of(v)])
        return Built(p, period, rp.bearing_derived(v, state))
    return build


# --- spec pieces -------------------------------------------------------------------------------

def check(data, axes):
    """The bearing pair's rules and the disk on the shaft (as rigid_preloaded)."""
    return rp.bearing_problems(data, axes) + rp.rotor_problems(data)


def _rotor(name, default, unit, help):
    return Parameter(default=default, name=name, section="rotor", lo=0, lo_open=True, unit=unit, help=help)


# The 2010 papers' bearing (their section 2, `bearing.ANGULAR_TABLES["filipkovsky2010"]`) is these
# models' default table; the other keys are rigid_preloaded's.
BEARING_PARAMETERS = tuple(rp.SPEC.parameter(k) for k in ("nominal_angle", "contact_angle", "preload")) \
    + tuple(replace(k, default="filipkovsky2010") if k.name == "table" else k for k in rp.BEARING_KEYS)
ROTOR_PARAMETERS = (
    Parameter(name="speed", unit="Hz", long_name="shaft speed", axis=True, lo=0, hi=1e5,
              unset=628.3 / (2 * math.pi), help="shaft speed [Hz] (papers: 628.3 rad/s = 100.0 Hz); a sweep axis"),
    # Both 2010 papers, section 2 ("Численный анализ колебаний"): l = 0,5 м, d = 0,025 м,
    # m_0 = 10 кг, I_1 = 0,1 кг м2, I_0 = 0,2 кг м2, omega = 628,3 рад/с (the speed above).
    rp.shaft_length(0.5),
    _rotor("shaft_diameter", SHAFT_DIAMETER, "m", "shaft diameter d (distributed mass)"),
    _rotor("shaft_density", STEEL_DENSITY, "kg m-3", "shaft density (steel; not in the papers)"),
    _rotor("disk_mass", 10.0, "kg", "disk mass m_0"),
    _rotor("disk_diametral", 0.1, "kg m2", "disk diametral inertia I_1"),
    _rotor("disk_polar", 0.2, "kg m2", "disk polar inertia I_0"),
)
DERIVED = rp.BEARING_DERIVED
REFERENCES = "Filipkovsky S.V. (2010), nonlinear normal modes of a rotor on ball bearings (symmetric, axial)"
def observables(n):
    names = (("x_A", "journal A horizontal displacement"), ("y_A", "journal A vertical displacement"),
             ("x_B", "journal B horizontal displacement"), ("y_B", "journal B vertical displacement"),
             ("z", "axial displacement"))[:n]
    return tuple(Observable(name, tuple(float(i == k) for i in range(n)), "m", long_name)
                 for k, (name, long_name) in enumerate(names))

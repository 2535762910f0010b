"""Ball-bearing contact mechanics: geometry presets, Hertz load-deflection constant, contact angles.

Pure Python/numpy functions in SI units (m, N, Pa, rad). They are evaluated once per grid point
to set up a scene, never inside an integrator, so clarity wins over speed here.

Conventions (Harris, *Rolling Bearing Analysis*; Hamrock & Brewe 1983):

* One ball carries ``Q = K delta^{3/2}`` for an elastic approach ``delta > 0`` along its contact
  line. ``K`` combines the inner and outer ball-race contacts in series (Bai 2006, eq. 2).
* Each contact is a Hertz point contact between two bodies with principal curvatures in the
  rolling plane (``x``) and across the groove (``y``); concave surfaces have negative curvature.
  ``1/R_x``, ``1/R_y`` are the summed curvatures per plane, ``R = 1/(1/R_x + 1/R_y)`` the
  curvature-sum radius, ``kappa = a/b >= 1`` the ellipticity of the contact ellipse.
* ``A = r_i + r_o - D_b`` is the distance between the inner and outer groove curvature centres
  when the ball just touches both races (Harris's ``B D``); the contact line runs through both
  centres and the ball centre, at angle ``alpha`` to the radial plane.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from rotorsweep.kernels.roots import brent_root

_EPS = float(np.finfo(float).eps)

# The constant that reproduces Bai 2006's published stability results (SPEC 2.1); the paper never
# states its K. The Hertz value from the 209 geometry is about 4x larger (see hertz_constant).
BAI2006_CONTACT_CONSTANT = 2.883e9  # N/m^1.5


@dataclass(frozen=True)
class BearingGeometry:
    """Geometry and material of one ball bearing (identical steel balls and rings)."""

    name: str
    ball_diameter: float  # D_b [m]
    pitch_diameter: float  # D_m [m]
    inner_groove_radius: float  # r_i [m], cross-groove curvature radius of the inner race
    outer_groove_radius: float  # r_o [m]
    n_balls: int
    youngs_modulus: float  # [Pa]
    poisson_ratio: float
    nominal_contact_angle: float = 0.0  # [rad], free contact angle; 0 for a deep-groove bearing
    # Groove-bottom radii from the bearing axis (Filipkovsky's R1, R2); None where not given.
    inner_race_radius: float | None = None  # R1 [m]
    outer_race_radius: float | None = None  # R2 [m]

    def __post_init__(self):
        for field in ("ball_diameter", "pitch_diameter", "inner_groove_radius",
                      "outer_groove_radius", "youngs_modulus"):
            value = getattr(self, field)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{self.name}: {field} must be a positive finite number, got {value}")
        if int(self.n_balls) != self.n_balls or self.n_balls < 3:
            raise ValueError(f"{self.name}: n_balls must be an integer >= 3, got {self.n_balls}")
        if not 0.0 <= self.poisson_ratio < 0.5:
            raise ValueError(f"{self.name}: poisson_ratio must be in [0, 0.5), got {self.poisson_ratio}")
        if self.pitch_diameter <= self.ball_diameter:
            raise ValueError(f"{self.name}: pitch_diameter {self.pitch_diameter} m must exceed "
                             f"ball_diameter {self.ball_diameter} m")
        # A conforming groove must be wider than the ball, else the contact is not a Hertz point.
        for field in ("inner_groove_radius", "outer_groove_radius"):
            if getattr(self, field) <= self.ball_diameter / 2:
                raise ValueError(f"{self.name}: {field} {getattr(self, field)} m must exceed the ball "
                                 f"radius {self.ball_diameter / 2} m")
        if not 0.0 <= self.nominal_contact_angle < math.pi / 2:
            raise ValueError(f"{self.name}: nominal_contact_angle must be in [0, pi/2) rad, got "
                             f"{self.nominal_contact_angle}")

    @property
    def groove_center_distance(self) -> float:
        """A = r_i + r_o - D_b [m]: distance of the two groove curvature centres at first contact."""
        return self.inner_groove_radius + self.outer_groove_radius - self.ball_diameter


# ----------------------------------------------------------------------------------------------
# Presets

class AngularTable(NamedTuple):
    """One paper's angular-contact bearing as printed (SI): shared geometry and material, and the
    outer groove-bottom radius R2 per row, keyed by the row's nominal angle [deg] (a label)."""

    source: str
    inner_race_radius: float  # R1 [m]
    groove_radius: float  # R_K [m], both rings
    ball_diameter: float  # d [m]
    n_balls: int
    youngs_modulus: float  # E [Pa]
    poisson_ratio: float
    outer_race_radius: dict  # {nominal angle [deg] or None (no label printed): R2 [m]}


ANGULAR_TABLES = {
    # Filipkovsky 2016, "Результаты численных исследований" (the paragraph after eq. 13): medium
    # series, GOST 831-75; "R_2 для углов alpha = 12, 15, 26, 36 и 40 deg соответственно равны
    # 27,5125; 27,5167; 27,5399; 27,5709 и 27,5858 мм", R_1 = 16,0 мм, R_K = 5,930 мм,
    # d_B = 11,510 мм, N_B = 7, E = 2,1e11 Па, mu = 0,3.
    "filipkovsky2016": AngularTable(
        "Filipkovsky 2016", inner_race_radius=16.0e-3, groove_radius=5.930e-3, ball_diameter=11.510e-3,
        n_balls=7, youngs_modulus=2.1e11, poisson_ratio=0.3,
        outer_race_radius={12: 27.5125e-3, 15: 27.5167e-3, 26: 27.5399e-3, 36: 27.5709e-3, 40: 27.5858e-3}),
    # Filipkovsky 2010, both papers, section 2 "Численный анализ колебаний": R_1 = 0,01600 м,
    # R_2 = 0,02753 м, R_K = 0,00593 м, d_ш = 0,01151 м, N = 7, E = 2e11 Па, sigma = 0,3 (Q = 300 Н).
    # One bearing, no nominal angle printed (R2 gives a free angle of 19.5 deg by eq. 10).
    "filipkovsky2010": AngularTable(
        "Filipkovsky 2010", inner_race_radius=16.00e-3, groove_radius=5.93e-3, ball_diameter=11.51e-3,
        n_balls=7, youngs_modulus=2e11, poisson_ratio=0.3, outer_race_radius={None: 27.53e-3}),
}
_ANGULAR_R2_MM = {k: v * 1e3 for k, v in ANGULAR_TABLES["filipkovsky2016"].outer_race_radius.items()}
_ANGULAR_DEFAULT_DEG = 26

# How R1/R2 encode the nominal angle (worked out from Filipkovsky 2010 eq. 10 at zero load):
# the groove curvature centres sit at radii R1 + R_K (inner) and R2 - R_K (outer), so
#     (2 R_K - d) cos(alpha0) = R1 + 2 R_K - R2,
# which is Harris's cos(alpha0) = 1 - P_d / (2 A) with diametral clearance P_d = 2 (R2 - R1 - d).
# With the stated R1 = 16.0, R_K = 5.930, d = 11.510 mm this gives 6.85 / 11.23 / 23.86 / 34.31 /
# 38.42 deg for the five R2 values, NOT the nominal 12 / 15 / 26 / 36 / 40 deg: each R2 is
# 5.1-6.1 um smaller than the value that would give its nominal angle. The five R2 do follow the
# same law exactly (to their 0.1 um rounding) with different constants:
#     R2 = 27.85048 mm - 0.34555 mm * cos(alpha_nominal),
# i.e. R1 + 2 R_K = 27.8505 mm and 2 R_K - d = 0.3455 mm (e.g. R_K ~ 5.9253, d ~ 11.505 mm) instead
# of 27.86 and 0.35 mm. The published angles are therefore the geometric free angles of a slightly
# different ball/groove pair than the one printed. `table_geometry` takes the printed values as
# printed (nominal angle = a label, free angle from R1, R2, R_K, d: groove_free_angle), and so does
# `preset("angular_contact_medium", angle, free_angle="geometry")`; `preset`'s default keeps the
# label as the free angle (FREE_ANGLE_SOURCES), jeffcott_clearance's `bearing.free_angle = "nominal"`
# (its default before model version 2).
PRESETS = {
    "209": "Bai 2006 deep-groove ball bearing 209: D_m = 65.0 mm, D_b = 12.7 mm, "
           "r_i = r_o = 6.6 mm, 9 balls, E = 2.08e11 Pa, nu = 0.3; contact angle from clearance",
    "angular_contact_medium": "Filipkovsky 2010/2016 medium-series angular-contact bearing: "
           "R1 = 16.0 mm, R2 = 27.5125/27.5167/27.5399/27.5709/27.5858 mm for nominal angles "
           "12/15/26/36/40 deg (default 26), R_K = 5.930 mm, ball 11.510 mm, 7 balls, "
           "E = 2.1e11 Pa, nu = 0.3",
}


# Where an angular-contact preset's free (unloaded) contact angle comes from: its row's label, or its
# groove geometry (groove_free_angle), as rigid_preloaded's `bearing.free_angle` says it.
FREE_ANGLE_SOURCES = ("nominal", "geometry")


def preset(name: str, nominal_angle_deg: float | None = None, free_angle: str = "nominal") -> BearingGeometry:
    """Named bearing geometry. ``nominal_angle_deg`` selects the angular-contact variant (a row of
    the 2016 table); ``free_angle`` (FREE_ANGLE_SOURCES) its nominal_contact_angle: "nominal", the
    row's label (1.6 to 5.1 deg above what the printed radii give), or "geometry", from R1, R2, R_K, d as
    table_geometry has it. The deep-groove 209 has no free angle of its own (0: from the clearance)."""
    if free_angle not in FREE_ANGLE_SOURCES:
        raise ValueError(f"free_angle must be one of {FREE_ANGLE_SOURCES}, got {free_angle!r}")
    if name == "209":
        if nominal_angle_deg not in (None, 0, 0.0):
            raise ValueError("preset '209' is a deep-groove bearing: its contact angle follows from "
                             "the clearance (free_contact_angle); nominal_angle_deg must be None or 0, "
                             f"got {nominal_angle_deg}")
        return BearingGeometry(name="209", ball_diameter=12.7e-3, pitch_diameter=65.0e-3,
                               inner_groove_radius=6.6e-3, outer_groove_radius=6.6e-3, n_balls=9,
                               youngs_modulus=2.08e11, poisson_ratio=0.3)
    if name == "angular_contact_medium":
        angle = _ANGULAR_DEFAULT_DEG if nominal_angle_deg is None else nominal_angle_deg
        key = next((k for k in _ANGULAR_R2_MM if k == angle), None)
        if key is None:
            raise ValueError(f"preset 'angular_contact_medium': nominal_angle_deg must be one of "
                             f"{sorted(_ANGULAR_R2_MM)} deg, got {nominal_angle_deg}")
        geom = replace(table_geometry("filipkovsky2016", key), name=f"angular_contact_medium_{key}deg")
        return geom if free_angle == "geometry" else replace(geom, nominal_contact_angle=math.radians(key))
    raise ValueError(f"unknown bearing preset {name!r}; allowed: {sorted(PRESETS)}")


GEOMETRY_OVERRIDES = ("inner_race_radius", "outer_race_radius", "groove_radius", "ball_diameter",
                      "youngs_modulus", "poisson_ratio")


def table_geometry(table: str, nominal_angle=None, **overrides) -> BearingGeometry:
    """The bearing of one row of a paper's table (ANGULAR_TABLES), any printed value replaced by
    ``overrides`` (GEOMETRY_OVERRIDES, SI; None: as printed). Its nominal_contact_angle is the
    free angle from R1, R2, R_K, d (groove_free_angle): the row's nominal angle is only a label."""
    if table not in ANGULAR_TABLES:
        raise ValueError(f"unknown bearing table {table!r}; allowed: {sorted(ANGULAR_TABLES)}")
    t = ANGULAR_TABLES[table]
    rows = t.outer_race_radius
    label = None if None in rows else nominal_angle
    if label not in rows:
        raise ValueError(f"table {table!r}: nominal_angle_deg must be one of {sorted(rows)} deg, got {nominal_angle}")
    unknown = set(overrides) - set(GEOMETRY_OVERRIDES)
    if unknown:
        raise ValueError(f"table_geometry: unknown override(s) {sorted(unknown)}; allowed: {GEOMETRY_OVERRIDES}")
    given = {k: v for k, v in overrides.items() if v is not None}
    v = {**t._asdict(), "outer_race_radius": rows[label], **given}
    r1, r2 = v["inner_race_radius"], v["outer_race_radius"]
    # Equal groove radii put the ball centre midway between the groove centres R1 + R_K and
    # R2 - R_K, so the pitch diameter is exactly R1 + R2 (about 43.5 mm).
    geom = BearingGeometry(name=f"{table}_{label}deg" if label is not None else table,
                           ball_diameter=v["ball_diameter"], pitch_diameter=r1 + r2,
                           inner_groove_radius=v["groove_radius"], outer_groove_radius=v["groove_radius"],
                           n_balls=t.n_balls, youngs_modulus=v["youngs_modulus"],
                           poisson_ratio=v["poisson_ratio"], inner_race_radius=r1, outer_race_radius=r2)
    return replace(geom, nominal_contact_angle=groove_free_angle(geom))


def groove_free_angle(geom: BearingGeometry) -> float:
    """Free contact angle [rad] from the groove-bottom radii R1, R2 (Filipkovsky 2010 eq. 10, no
    load): cos(alpha0) = (R1 + r_i + r_o - R2) / (r_i + r_o - D_b). Needs R1 and R2."""
    if geom.inner_race_radius is None or geom.outer_race_radius is None:
        raise ValueError(f"{geom.name}: groove_free_angle needs inner_race_radius and outer_race_radius")
    radial = (geom.inner_race_radius + geom.inner_groove_radius + geom.outer_groove_radius
              - geom.outer_race_radius)
    cos_a0 = radial / geom.groove_center_distance
    if not 0.0 <= cos_a0 <= 1.0:
        raise ValueError(f"{geom.name}: R1/R2 give cos(alpha0) = {cos_a0}, outside [0, 1]")
    return math.acos(cos_a0)


# ----------------------------------------------------------------------------------------------
# Hertz point contact

class ContactConstant(NamedTuple):
    """One Hertz point contact: Q = stiffness * delta^{3/2}."""

    stiffness: float  # k [N/m^1.5]
    ellipticity: float  # kappa = a/b >= 1 (a across the larger radius of relative curvature)
    ellip_k: float  # complete elliptic integral of the first kind, modulus e^2 = 1 - 1/kappa^2
    ellip_e: float  # complete elliptic integral of the second kind, same modulus
    curvature_sum: float  # sum rho = 1/R_x + 1/R_y [1/m]
    curvature_difference: float  # F(rho) = |1/R_x - 1/R_y| / sum rho, in [0, 1)


def _elliptic_integrals(log_kappa: float) -> tuple[float, float]:
    """(K(m), E(m)) for m = 1 - 1/kappa^2 by the arithmetic-geometric mean (Abramowitz & Stegun
    17.6.1-4): a0 = 1, b0 = sqrt(1 - m) = 1/kappa, c0 = sqrt(m); K = pi / (2 a_N),
    E = K (1 - sum 2^{n-1} c_n^2). Started from ln(kappa), so m near 1 (large kappa) keeps its
    precision; c_{n+1} = c_n^2 / (4 a_{n+1}) instead of (a_n - b_n) / 2, which cancels. Converges
    quadratically (5-6 steps). Written out rather than scipy.special's ellipkm1 / ellipe: their
    import took 0.12-0.19 s of a warm point's ~1 s."""
    a, b = 1.0, math.exp(-log_kappa)
    c = math.sqrt(-math.expm1(-2.0 * log_kappa))
    weight, total = 0.5, 0.5 * c * c
    while c > _EPS * a:
        a, b = 0.5 * (a + b), math.sqrt(a * b)
        c = c * c / (4.0 * a)
        weight *= 2.0
        total += weight * c * c
    ellip_k = math.pi / (2.0 * a)
    return ellip_k, ellip_k * (1.0 - total)


def _curvature_difference_of(log_kappa: float) -> float:
    """F(rho) implied by an ellipticity: ((kappa^2 + 1) E - 2 K) / ((kappa^2 - 1) E) (Harris)."""
    ellip_k, ellip_e = _elliptic_integrals(log_kappa)
    kappa2 = math.exp(2.0 * log_kappa)
    return ((kappa2 + 1.0) * ellip_e - 2.0 * ellip_k) / ((kappa2 - 1.0) * ellip_e)


def ellipticity(curvature_difference: float) -> float:
    """Solve the Hertz ellipticity kappa = a/b from the curvature difference F(rho) in [0, 1)."""
    f_rho = float(curvature_difference)
    if not 0.0 <= f_rho < 1.0:
        raise ValueError(f"curvature difference F(rho) must be in [0, 1), got {f_rho}")
    if f_rho == 0.0:
        return 1.0  # circular contact; the general formula is 0/0 there
    # F(rho) ~ 0.75 ln(kappa) near kappa = 1 and -> 1 as kappa -> inf: bracket in ln(kappa).
    lo, hi = f_rho / 10.0, 40.0
    log_kappa = brent_root(lambda u: _curvature_difference_of(u) - f_rho, lo, hi, xtol=1e-15, maxiter=200)
    return math.exp(log_kappa)


def contact_constant(curvatures_1, curvatures_2, youngs_modulus: float,
                     poisson_ratio: float) -> ContactConstant:
    """Load-deflection constant of one Hertz point contact between two bodies of one material.

    ``curvatures_1`` and ``curvatures_2`` are the (x, y) principal curvatures [1/m] of the two
    bodies in common principal planes (concave negative). Hamrock & Brewe's exact form:
        k = pi kappa E' sqrt(2 E R / (9 K^3)),   E' = E / (1 - nu^2),  R = 1/sum(rho),
    which is Filipkovsky 2010 eq. 11 inverted (w = b P^{2/3}) and, for kappa = 1, the Hertz sphere
    law (4/3) E* sqrt(R_eff)."""
    inv_rx = float(curvatures_1[0]) + float(curvatures_2[0])
    inv_ry = float(curvatures_1[1]) + float(curvatures_2[1])
    if inv_rx <= 0.0 or inv_ry <= 0.0:
        raise ValueError(f"summed curvatures must be positive for a point contact, got "
                         f"1/R_x = {inv_rx}, 1/R_y = {inv_ry} 1/m")
    curv_sum = inv_rx + inv_ry
    curv_diff = abs(inv_rx - inv_ry) / curv_sum
    kappa = ellipticity(curv_diff)
    ellip_k, ellip_e = _elliptic_integrals(math.log(kappa))
    e_prime = youngs_modulus / (1.0 - poisson_ratio ** 2)
    k = math.pi * kappa * e_prime * math.sqrt(2.0 * ellip_e / (9.0 * ellip_k ** 3 * curv_sum))
    return ContactConstant(k, kappa, ellip_k, ellip_e, curv_sum, curv_diff)


def raceway_curvatures(geom: BearingGeometry, contact_angle: float | None = None):
    """Principal curvatures (x = rolling plane, y = across the groove) [1/m] of the ball and both
    races: returns (ball, inner_race, outer_race), each an (x, y) tuple.

    The raceway's rolling-plane radius is measured along the contact line to the bearing axis,
    which gives Harris's gamma = D_b cos(alpha) / D_m."""
    alpha = geom.nominal_contact_angle if contact_angle is None else contact_angle
    d_b = geom.ball_diameter
    gamma = d_b * math.cos(alpha) / geom.pitch_diameter
    ball = (2.0 / d_b, 2.0 / d_b)
    inner = (2.0 / d_b * gamma / (1.0 - gamma), -1.0 / geom.inner_groove_radius)
    outer = (-2.0 / d_b * gamma / (1.0 + gamma), -1.0 / geom.outer_groove_radius)
    return ball, inner, outer


def ball_contacts(geom: BearingGeometry, contact_angle: float | None = None):
    """(inner, outer) ContactConstant of one ball at the given (or nominal) contact angle."""
    ball, inner, outer = raceway_curvatures(geom, contact_angle)
    e, nu = geom.youngs_modulus, geom.poisson_ratio
    return contact_constant(ball, inner, e, nu), contact_constant(ball, outer, e, nu)


def series_constant(k_inner: float, k_outer: float) -> float:
    """Two Hertz contacts in series share Q, their approaches add: (Bai 2006 eq. 2)."""
    return ((1.0 / k_inner) ** (2.0 / 3.0) + (1.0 / k_outer) ** (2.0 / 3.0)) ** -1.5


def hertz_constant(geom: BearingGeometry, contact_angle: float | None = None) -> float:
    """Load-deflection constant K [N/m^1.5] of one ball, inner and outer contacts in series."""
    inner, outer = ball_contacts(geom, contact_angle)
    return series_constant(inner.stiffness, outer.stiffness)


# ----------------------------------------------------------------------------------------------
# Contact angles

def free_contact_angle(geom: BearingGeometry, clearance: float) -> float:
    """Free contact angle [rad] of a bearing with radial clearance c (Bai 2006 eq. 6):
    cos(alpha0) = 1 - c / (r_i + r_o - D_b). Allowed: 0 <= c <= r_i + r_o - D_b (alpha0 <= 90 deg)."""
    big_a = geom.groove_center_distance
    c = float(clearance)
    if not (np.isfinite(c) and 0.0 <= c <= big_a):
        raise ValueError(f"{geom.name}: radial clearance {c} m is outside the allowed range "
                         f"[0, {big_a}] m (0 <= c <= r_i + r_o - D_b, free contact angle 0..90 deg)")
    return math.acos(1.0 - c / big_a)


@dataclass(frozen=True)
class PreloadState:
    """Static state of one axially preloaded bearing (the point the force law linearizes about).

    The force law of each ball is Q = K [delta]_+^{3/2} with delta = (x cos b + y sin b) cos(alpha)
    + s0 sin(alpha) - c; ``normal_approach`` ("bracket" below) is that delta at x = y = 0."""

    contact_angle: float  # loaded contact angle alpha [rad]
    axial_approach: float  # s0 [m], the axial shift that enters the force law (the papers' z0)
    # the deformation of each ball at rest in the force law [m]: the Hertz approach w for
    # "hertz", z0 sin(alpha) for "as_printed" (SPEC 1 note)
    normal_approach: float
    ball_load: float  # K bracket^{3/2} [N] per ball at rest
    radial_stiffness: float  # [N/m], linearized at zero radial displacement
    axial_stiffness: float  # [N/m], linearized
    contact_constant: float  # K used [N/m^1.5]
    hertz_approach: float = 0.0  # w = w1 + w2 [m], the Hertz approach of each ball under the preload
    static_thrust: float = 0.0  # N K bracket^{3/2} sin(alpha) [N]: P0 for "hertz", 1.5 P0 as printed


def _loaded_geometry(big_a: float, cos_a0: float, u: float) -> tuple[float, float]:
    """Contact angle and normal approach for a relative stretch u = cos(a0)/cos(a) - 1 of the
    groove-centre distance: the centres move apart axially only, so A cos(a0) is fixed."""
    alpha = math.acos(cos_a0 / (1.0 + u))
    return alpha, big_a * u


def _solve_stretch(p0, n_balls, big_a, cos_a0, constant_of) -> float:
    """u > 0 with N K(alpha) (A u)^{3/2} sin(alpha) = P0 (Harris / Filipkovsky eqs. 7-10).

    Solved in ln(u): the residual is then well scaled from grazing (u ~ 1e-9) to heavy loads."""
    def residual(log_u):
        alpha, delta = _loaded_geometry(big_a, cos_a0, math.exp(log_u))
        return math.log(n_balls * constant_of(alpha) * delta ** 1.5 * math.sin(alpha) / p0)

    lo, hi = math.log(1e-6), math.log(1e-3)
    while residual(lo) > 0.0:  # expand until the root is bracketed (monotonic in u)
        lo -= 5.0
    while residual(hi) < 0.0:
        hi += 2.0
    return math.exp(brent_root(residual, lo, hi, xtol=1e-15, maxiter=500))


def _check_preload(preload, allow_zero=True) -> float:
    p0 = float(preload)
    if not (np.isfinite(p0) and (p0 >= 0.0 if allow_zero else p0 > 0.0)):
        raise ValueError(f"axial preload must be a finite force {'>=' if allow_zero else '>'} 0 N, got {preload}")
    return p0


def _check_positive(value, what):
    if value is not None and not (np.isfinite(value) and value > 0):
        raise ValueError(f"{what} must be a positive number, got {value}")


def preload_state(geom: BearingGeometry, preload: float, clearance: float = 0.0,
                  free_angle: float | None = None, stiffness: float | None = None) -> PreloadState:
    """The consistent Hertz model: loaded contact angle, approaches, ball load and linear
    stiffnesses under axial preload P0.

    The rings shift axially until N K delta_n^{3/2} sin(alpha) = P0, with
    delta_n = A (cos(alpha0)/cos(alpha) - 1) (the 2010 papers' eqs. 8-10 with w = delta_n).
    ``stiffness`` fixes K; by default K = hertz_constant(geom, alpha) at the loaded angle. The
    force law then carries P0 exactly (static_thrust = P0).

    Linearized about x = y = 0 (alpha frozen, as in the force law), using sum cos^2 phi_j = N/2:
        k_r = (3/4) N K delta_n^{1/2} cos^2(alpha),   k_a = (3/2) N K delta_n^{1/2} sin^2(alpha).
    """
    p0 = _check_preload(preload)
    c = float(clearance)
    if not (np.isfinite(c) and c >= 0.0):
        raise ValueError(f"radial clearance must be >= 0 m, got {clearance}")
    if free_angle is None:
        alpha0 = free_contact_angle(geom, c) if c > 0.0 else geom.nominal_contact_angle
    else:
        alpha0 = float(free_angle)
    if not 0.0 <= alpha0 < math.pi / 2:
        raise ValueError(f"free contact angle must be in [0, pi/2) rad, got {alpha0}")
    _check_positive(stiffness, "stiffness K [N/m^1.5]")

    def constant_of(alpha):
        return float(stiffness) if stiffness is not None else hertz_constant(geom, alpha)

    n = geom.n_balls
    if p0 == 0.0:  # rings just touching: no load, no contact stiffness
        s0 = c / math.sin(alpha0) if alpha0 > 0.0 else 0.0
        return PreloadState(alpha0, s0, 0.0, 0.0, 0.0, 0.0, constant_of(alpha0))

    big_a = geom.groove_center_distance
    u = _solve_stretch(p0, n, big_a, math.cos(alpha0), constant_of)
    alpha, delta_n = _loaded_geometry(big_a, math.cos(alpha0), u)
    return state_at(alpha, (delta_n + c) / math.sin(alpha), delta_n, constant_of(alpha), n, delta_n)


def preload_at_angle(geom: BearingGeometry, preload: float, contact_angle: float,
                     stiffness: float | None = None) -> PreloadState:
    """The consistent Hertz model with the contact angle imposed (not solved from the groove
    geometry): N K delta_n^{3/2} sin(alpha) = P0 with K = ``stiffness`` or hertz_constant(geom,
    alpha), no clearance."""
    p0, alpha = _check_preload(preload, allow_zero=False), _check_angle(contact_angle)
    _check_positive(stiffness, "stiffness K [N/m^1.5]")
    k = hertz_constant(geom, alpha) if stiffness is None else float(stiffness)
    delta_n = (p0 / (geom.n_balls * k * math.sin(alpha))) ** (2.0 / 3.0)
    return state_at(alpha, delta_n / math.sin(alpha), delta_n, k, geom.n_balls, delta_n)


def _check_angle(contact_angle) -> float:
    alpha = float(contact_angle)
    if not 0.0 < alpha < math.pi / 2:
        raise ValueError(f"contact angle must be in (0, pi/2) rad, got {contact_angle}")
    return alpha


def preload_with_approach(geom: BearingGeometry, preload: float, contact_angle: float,
                          axial_approach: float) -> PreloadState:
    """The consistent Hertz model with z0 given: K from N K (z0 sin a)^{3/2} sin a = P0."""
    p0, alpha = _check_preload(preload, allow_zero=False), _check_angle(contact_angle)
    _check_positive(axial_approach, "axial approach z0 [m]")
    bracket = axial_approach * math.sin(alpha)
    k = p0 / (geom.n_balls * bracket ** 1.5 * math.sin(alpha))
    return state_at(alpha, axial_approach, bracket, k, geom.n_balls, bracket)


def as_printed_state(geom: BearingGeometry, preload: float, free_angle: float,
                     contact_angle: float | None = None, stiffness: float | None = None,
                     axial_approach: float | None = None) -> PreloadState:
    """The Filipkovsky papers' preloaded bearing exactly as printed (2010 papers eqs. 6-10, 2016
    eq. 1; SPEC 1 note):

    * eq. 10, (2 R_K - d + w) cos(alpha) = R1 + 2 R_K - R2 = A cos(alpha0), with the Hertz
      approach w = w1 + w2 of each ball under P_k = P0 / (N sin alpha) (eqs. 8, 9, 11): the loaded
      angle (unless ``contact_angle`` is given; then w follows from eqs. 8-9 at that angle).
      Eq. 8 prints w = b P_k^{3/2}; eq. 11's b [m N^-2/3] makes it w = b P_k^{2/3}, used here;
    * eq. 7, z0 = (2 R_K - d + w) sin(alpha): the axial separation of the two groove-curvature
      centres (unless ``axial_approach`` is given);
    * eq. 6, K = (3 P0 / (2 N)) z0^{-3/2} sin^{-5/2}(alpha) (unless ``stiffness`` is given);
    * eq. 5 / 2016 eq. 1: each ball's bracket at rest is z0 sin(alpha).

    Its static thrust N K (z0 sin a)^{3/2} sin a is 1.5 P0 whatever z0 is (the powers of z0 and
    sin a cancel): the law as printed does not carry the preload that defines it."""
    p0 = _check_preload(preload, allow_zero=False)
    _check_positive(stiffness, "stiffness K [N/m^1.5]")
    _check_positive(axial_approach, "axial approach z0 [m]")
    n, big_a = geom.n_balls, geom.groove_center_distance
    if contact_angle is None:
        hertz = preload_state(geom, p0, free_angle=free_angle)
        alpha, w = hertz.contact_angle, hertz.normal_approach
    else:
        alpha = _check_angle(contact_angle)
        w = (p0 / (n * math.sin(alpha) * hertz_constant(geom, alpha))) ** (2.0 / 3.0)
    sin_a = math.sin(alpha)
    z0 = (big_a + w) * sin_a if axial_approach is None else float(axial_approach)
    k = 1.5 * p0 / n * z0 ** -1.5 * sin_a ** -2.5 if stiffness is None else float(stiffness)
    return state_at(alpha, z0, z0 * sin_a, k, n, w)


def state_at(alpha, axial_approach, bracket, k, n, hertz_approach) -> PreloadState:
    """PreloadState of a force law with constant K, contact angle alpha and the deformation
    ``bracket`` of each ball at rest."""
    sin_a, cos_a = math.sin(alpha), math.cos(alpha)
    root = math.sqrt(bracket)
    return PreloadState(
        contact_angle=alpha,
        axial_approach=axial_approach,
        normal_approach=bracket,
        ball_load=k * bracket * root,
        radial_stiffness=0.75 * n * k * root * cos_a ** 2,
        axial_stiffness=1.5 * n * k * root * sin_a ** 2,
        contact_constant=k,
        hertz_approach=hertz_approach,
        static_thrust=n * k * bracket * root * sin_a,
    )

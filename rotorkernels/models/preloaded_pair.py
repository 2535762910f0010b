"""The preloaded bearing pair of the Filipkovsky models (`rigid_preloaded`, and through it
`symmetric4` / `asymmetric5`): the bearing table of each paper as printed, the scene's bearing
keys, and the static state of each bearing (`bearing.PreloadState`) they give.

What a scene may give and what is derived (the cube records which: BEARING_DERIVED):

* the table row (`table`, `nominal_angle` a label) and any geometry value (R1, R2, R_K, d, E, nu);
* the free contact angle: from the groove geometry (eq. 10 at zero load; the default, under both
  preload laws), or the row's label (`free_angle = "nominal"`, explicit);
* the loaded contact angle: from the preload (eqs. 8-10), or imposed (`contact_angle`);
* z0 and K: from the preload law (`preload_law`: "hertz", the consistent Hertz model, or
  "as_printed", the papers' eqs. 6-10), or given (`axial_approach`, `contact_constant`);
* the arrangement of the pair (`arrangement`): the sign with which z enters each bearing.
"""
import math
from functools import lru_cache
from typing import NamedTuple

from rotorsweep.kernels import bearing
from rotorsweep.kernels.models.spec import Parameter

NOMINAL_ANGLES = tuple(bearing.ANGULAR_TABLES["filipkovsky2016"].outer_race_radius)
DEFAULT_TABLE = "filipkovsky2016"
DEFAULT_NOMINAL_ANGLE = 15.0     # the row a scene without nominal_angle gets (the paper's Figs. 3, 5, 6)
PRELOAD_LAWS = ("hertz", "as_printed")
FREE_ANGLES = ("geometry", "nominal")
# Sign s of the axial coordinate in each bearing: bearing A is shifted by s z, B by -s z.
ARRANGEMENTS = {"back_to_back": 1.0, "face_to_face": -1.0}
GEOMETRY_KEYS = bearing.GEOMETRY_OVERRIDES
GROOVE_KEYS = ("inner_race_radius", "outer_race_radius", "groove_radius", "ball_diameter")   # what fixes the free angle
REMOVED_STIFFNESS = (
    "bearing.stiffness: removed. \"hertz\" is now bearing.preload_law = \"hertz\" (the default); "
    "\"paper\" was the Hertz model with K x 1.5 (z0 the Hertz approach w / sin a), which no longer "
    "exists; the papers' law exactly as printed (eq. 7's z0 with their K) is bearing.preload_law = "
    "\"as_printed\"; a number for K is bearing.contact_constant")


class BearingInputs(NamedTuple):
    """What a scene says about its bearings (None: not given, derived); hashable for the cache."""
    table: str = DEFAULT_TABLE
    nominal_angle: float | None = None       # row label [deg]
    preload: float = 300.0                   # P0 [N]
    preload_law: str = "hertz"
    free_angle: str | None = None            # "geometry", "nominal"; None: see free_angle_source
    contact_angle: float | None = None       # loaded angle imposed [deg]
    contact_constant: float | None = None    # K [N/m^1.5]
    axial_approach: float | None = None      # z0 [m]
    inner_race_radius: float | None = None   # R1 [m]
    outer_race_radius: float | None = None   # R2 [m]
    groove_radius: float | None = None       # R_K [m]
    ball_diameter: float | None = None       # d [m]
    youngs_modulus: float | None = None      # E [Pa]
    poisson_ratio: float | None = None


def _optional(v, name):
    x = v.get(name)
    return None if x is None or (isinstance(x, float) and not math.isfinite(x)) else x


def bearing_inputs(v):
    """BearingInputs from a model's values (missing or NaN keys: not given)."""
    given = {name: _optional(v, name) for name in BearingInputs._fields}
    return BearingInputs(**{k: x for k, x in given.items() if x is not None})


@lru_cache(maxsize=64)
def table_geometry(inputs):
    """bearing.BearingGeometry of the scene's table row with its geometry overrides."""
    return bearing.table_geometry(inputs.table, inputs.nominal_angle,
                                  **{k: getattr(inputs, k) for k in GEOMETRY_KEYS})


def geometry(nominal_angle, table=DEFAULT_TABLE):
    """The bearing of a table row as printed (its n_balls, radii, material)."""
    return table_geometry(BearingInputs(table=table, nominal_angle=nominal_angle))


def free_angle_source(inputs):
    """Where the free contact angle comes from: "geometry" (R1, R2, R_K, d by eq. 10 at zero load:
    what the papers' tables mean, under either preload law) unless the scene asks for "nominal"
    (the row's label taken as the free angle, an explicit departure from the table)."""
    return inputs.free_angle or "geometry"


def free_angle_before_version_2(section):
    """The free-angle source a scene giving none meant before model version 2 ([bearing] section,
    validated): the row's label under the Hertz law on a labelled table without groove overrides,
    else the geometry (ModelSpec.older_defaults)."""
    labelled = None not in bearing.ANGULAR_TABLES[section["table"]].outer_race_radius
    groove = any(section.get(k) is not None for k in GROOVE_KEYS)
    return "nominal" if section["preload_law"] == "hertz" and labelled and not groove else "geometry"


def free_angle(inputs):
    """The free contact angle [rad] (see free_angle_source)."""
    if free_angle_source(inputs) == "geometry":
        return table_geometry(inputs).nominal_contact_angle
    return math.radians(DEFAULT_NOMINAL_ANGLE if inputs.nominal_angle is None else inputs.nominal_angle)


@lru_cache(maxsize=256)
def preload_from(inputs):
    """bearing.PreloadState of each bearing of the scene (angles in the inputs in degrees)."""
    geom, alpha0 = table_geometry(inputs), free_angle(inputs)
    alpha = None if inputs.contact_angle is None else math.radians(inputs.contact_angle)
    k, z0, p0 = inputs.contact_constant, inputs.axial_approach, inputs.preload
    if inputs.preload_law == "as_printed":
        return bearing.as_printed_state(geom, p0, alpha0, alpha, k, z0)
    if z0 is not None:
        if k is not None:
            raise ValueError("preload_law \"hertz\" fixes K from z0 (or z0 from K): give one of "
                             "contact_constant and axial_approach")
        alpha = bearing.preload_state(geom, p0, free_angle=alpha0).contact_angle if alpha is None else alpha
        return bearing.preload_with_approach(geom, p0, alpha, z0)
    if alpha is not None:
        return bearing.preload_at_angle(geom, p0, alpha, k)
    return bearing.preload_state(geom, p0, free_angle=alpha0, stiffness=k)


def preload_of(nominal_angle, preload, preload_law="hertz", **given):
    """bearing.PreloadState of a table row under a preload (other BearingInputs as keywords)."""
    return preload_from(BearingInputs(nominal_angle=nominal_angle, preload=preload, preload_law=preload_law,
                                      **given))


# What a scene may give in place of a table row's value or of what derives from it: replacing the
# row, all of them are unset, so that each is derived again from the new row.
ROW_VALUES = ("contact_angle", "contact_constant", "axial_approach") + GEOMETRY_KEYS


def with_row(v, nominal_angle):
    """Values `v` with the bearing replaced by a table row as printed (label `nominal_angle`):
    its geometry and material, and the loaded angle, K and z0 derived from them under the scene's
    preload, preload law, free-angle source and arrangement (which stay)."""
    return {**v, "nominal_angle": nominal_angle, **{k: None for k in ROW_VALUES}}


def bearing_state(v):
    """bearing.PreloadState of each bearing at a point's values."""
    return preload_from(bearing_inputs(v))


def n_balls_of(v):
    return table_geometry(bearing_inputs(v)).n_balls


def arrangement_of(v):
    return v.get("arrangement") or "back_to_back"


# The table values a scene may override: (attribute of bearing.BearingGeometry, unit, long name).
GEOMETRY_VALUES = {
    "inner_race_radius": ("inner_race_radius", "m", "inner groove-bottom radius R1"),
    "outer_race_radius": ("outer_race_radius", "m", "outer groove-bottom radius R2"),
    "groove_radius": ("inner_groove_radius", "m", "groove radius R_K of both rings"),
    "ball_diameter": ("ball_diameter", "m", "ball diameter d"),
    "youngs_modulus": ("youngs_modulus", "Pa", "Young's modulus E"),
    "poisson_ratio": ("poisson_ratio", "1", "Poisson ratio"),
}


def bearing_derived(v, state):
    """The bearing's per-point values for the cube, and for each whether the scene gave it (1) or
    the model derived it (0: from the table row, or from the preload law): the table's geometry
    and material, the free angle, loaded angle, z0, K, Hertz approach and static thrust."""
    inputs = bearing_inputs(v)
    geom = table_geometry(inputs)
    table = {}
    for key, (attribute, _, _) in GEOMETRY_VALUES.items():
        table[f"bearing_{key}"] = float(getattr(geom, attribute))
        table[f"bearing_{key}_given"] = float(getattr(inputs, key) is not None)
    return {
        **table,
        "free_contact_angle": math.degrees(free_angle(inputs)),
        "free_angle_from_geometry": float(free_angle_source(inputs) == "geometry"),
        "contact_angle_used": math.degrees(state.contact_angle),
        "contact_angle_imposed": float(inputs.contact_angle is not None),
        "axial_approach": state.axial_approach,
        "axial_approach_given": float(inputs.axial_approach is not None),
        "contact_constant": state.contact_constant,
        "contact_constant_given": float(inputs.contact_constant is not None),
        "hertz_approach": state.hertz_approach,
        "static_thrust": state.static_thrust,
    }


def _geometry_variables():
    out = {}
    for key, (_, unit, long_name) in GEOMETRY_VALUES.items():
        out[f"bearing_{key}"] = (unit, f"bearing {long_name} used")
        out[f"bearing_{key}_given"] = ("1", f"1: {long_name} given by the scene; 0: the table row's")
    return out


BEARING_DERIVED = {
    **_geometry_variables(),
    "free_contact_angle": ("degree", "free (unloaded) contact angle: from R1, R2, R_K, d, or the nominal angle"),
    "free_angle_from_geometry": ("1", "1: free angle derived from R1, R2, R_K, d (eq. 10 at zero load); 0: the "
                                 "nominal angle given as the free angle (bearing.free_angle = nominal)"),
    "contact_angle_used": ("degree", "contact angle in the force law (loaded, or imposed)"),
    "contact_angle_imposed": ("1", "1: contact angle given by the scene (imposed); 0: derived from the preload solve"),
    "axial_approach": ("m", "axial approach z0 of each bearing in the force law"),
    "axial_approach_given": ("1", "1: z0 given by the scene; 0: derived (hertz: equilibrium, as_printed: eq. 7)"),
    "contact_constant": ("N m-1.5", "ball contact constant K"),
    "contact_constant_given": ("1", "1: K given by the scene; 0: derived (hertz: Hertz theory, as_printed: eq. 6)"),
    "hertz_approach": ("m", "Hertz approach w = w1 + w2 of each ball under the preload (always derived)"),
    "static_thrust": ("N", "axial force of one bearing's force law at rest (hertz: P0; as printed: 1.5 P0; "
                      "always derived)"),
}


def bearing_problems(data, axes):
    """Config rules of the bearing pair (shared with the series models): the removed key, the
    table's rows, a geometry with a free contact angle, and K and z0 not both fixed for hertz."""
    b = data["bearing"]
    if b.get("stiffness") is not None:
        return [REMOVED_STIFFNESS]
    where = "sweep" if "nominal_angle" in axes else "bearing"
    rows = bearing.ANGULAR_TABLES[b["table"]].outer_race_radius
    if "nominal_angle" in axes:
        given = [float(a) for a in axes["nominal_angle"]]
    else:
        given = [b["nominal_angle"]] if b["nominal_angle"] is not None else []
    if None in rows:
        if given or b.get("free_angle") == "nominal":
            return [f"{where}.nominal_angle: table {b['table']!r} prints one bearing without a nominal angle: "
                    "leave bearing.nominal_angle and bearing.free_angle = \"nominal\" out"]
        angles = [None]
    else:
        angles = given or [DEFAULT_NOMINAL_ANGLE]
        odd = [a for a in angles if a not in rows]
        if odd:
            return [f"{where}.nominal_angle: must be one of {', '.join(map(str, rows))} deg (the paper's "
                    f"bearing table; got {odd[0]:g})"]
    errors = []
    if len(set(angles)) > 1 and b.get("outer_race_radius") is not None:
        errors.append("bearing.outer_race_radius: replaces the R2 of every row of sweep.nominal_angle, whose rows "
                      "would then differ only in their label: sweep the rows or give R2, not both")
    groove = [k for k in GROOVE_KEYS if b.get(k) is not None]
    if b.get("free_angle") == "nominal" and groove:
        errors.append(f"bearing.free_angle: \"nominal\" takes the row's label as the free angle, which then does not "
                      f"follow from bearing.{groove[0]}: give free_angle = \"nominal\" or groove dimensions, not both")
    if b.get("preload_law") == "hertz" and b.get("contact_constant") is not None \
            and b.get("axial_approach") is not None:
        errors.append("bearing.axial_approach: preload_law \"hertz\" derives z0 from K and the preload (or K "
                      "from z0): give contact_constant or axial_approach, not both")
    try:
        for angle in angles:
            table_geometry(bearing_inputs({**b, "nominal_angle": angle}))
    except ValueError as exc:
        keys = ", ".join(f"bearing.{k}" for k in GEOMETRY_KEYS if b.get(k) is not None) or "bearing.table"
        errors.append(f"{keys}: the groove geometry gives no free contact angle (2010 papers, eq. 10 at "
                      f"zero load): {exc}")
    return errors


def _bearing_key(name, unit, help, kind="float", default=None, choices=()):
    return Parameter(kind, default, name=name, section="bearing", unit=unit, choices=choices,
                     lo=0, lo_open=kind == "float", help=help)


# The [bearing] keys of the preloaded pair besides nominal_angle, contact_angle and preload
# (shared with the series models, symmetric4 and asymmetric5). Geometry keys: None = the table's.
BEARING_KEYS = (
    _bearing_key("table", "1", "the bearing table: filipkovsky2016 (five rows, E = 2.1e11 Pa) or filipkovsky2010 "
                 "(R2 = 27.53 mm, E = 2e11 Pa), each as its paper prints it", "choice", DEFAULT_TABLE,
                 tuple(bearing.ANGULAR_TABLES)),
    _bearing_key("preload_law", "1", "hertz: the consistent Hertz model (K from Hertz theory, z0 from "
                 "N K (z0 sin a)^1.5 sin a = P0); as_printed: the papers' eqs. 6-10 as printed (z0 from "
                 "eq. 7, K = 3 P0 / (2N) z0^-1.5 sin^-2.5 a; static thrust 1.5 P0)", "choice", "hertz",
                 PRELOAD_LAWS),
    _bearing_key("free_angle", "1", "free contact angle from: geometry (R1, R2, R_K, d; eq. 10 at zero "
                 "load; the default, as the papers' tables mean it) or nominal (the row's label taken as the "
                 "free angle)", "choice", "geometry", FREE_ANGLES),
    _bearing_key("arrangement", "1", "back_to_back: +z (toward bearing B) compresses A and relieves B; "
                 "face_to_face: +z compresses B", "choice", "back_to_back", tuple(ARRANGEMENTS)),
    _bearing_key("contact_constant", "N m-1.5", "ball contact constant K given (unset: derived)"),
    _bearing_key("axial_approach", "m", "axial approach z0 given (unset: derived)"),
    _bearing_key("inner_race_radius", "m", "inner groove-bottom radius R1 (unset: the table's)"),
    _bearing_key("outer_race_radius", "m", "outer groove-bottom radius R2 (unset: the table row's)"),
    _bearing_key("groove_radius", "m", "groove radius R_K of both rings (unset: the table's)"),
    _bearing_key("ball_diameter", "m", "ball diameter d (unset: the table's)"),
    _bearing_key("youngs_modulus", "Pa", "Young's modulus E (unset: the table's)"),
    Parameter(name="poisson_ratio", section="bearing", lo=0, hi=0.5, hi_open=True,
              help="Poisson ratio (unset: the table's)"),
    _bearing_key("stiffness", "1", "removed (a config with it is told its replacement: preload_law, "
                 "contact_constant)", "str"),
)

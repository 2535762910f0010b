"""What a cube holds, as the report needs it: the continued axis and the other swept axes, lines
of the cube, the scene it was run from, and its attractor diagnostics."""
import numpy as np

from rotorsweep.pipeline import schema


def continued_axis(ds):
    """The swept axis the sweep continues solutions along, the x axis of every figure: the cube's
    `continued_axis` attribute, else (cubes written before it) the first swept axis among the
    cube's point dimensions."""
    return schema.continued_axis(ds)


def other_axes(ds):
    """The swept axes other than the continued one, in the cube's order."""
    axis = continued_axis(ds)
    return [a for a in schema.point_axes(ds) if a != axis and a in ds.dims]


def select(ds, where):
    """ds at the given values of swept axes, with every size-1 other swept dim squeezed out."""
    sub = ds.sel(where) if where else ds
    extra = [d for d in other_axes(sub) if sub.sizes[d] == 1]
    return sub.isel({d: 0 for d in extra})


def axis_edges(values):
    """Outer edges of a grid along the continued axis: half a step beyond the first and last
    value (1 unit wide for a single value), as the cells of a map centred on the grid values."""
    if values.size == 1:
        return float(values[0]) - 0.5, float(values[0]) + 0.5
    return (float(values[0] - 0.5 * (values[1] - values[0])),
            float(values[-1] + 0.5 * (values[-1] - values[-2])))


def scene_toml(ds):
    """The cube's scene (config_toml) as a dict; {} when it has none or it does not parse."""
    try:
        import tomllib
    except ImportError:          # Python 3.10
        import tomli as tomllib
    try:
        return tomllib.loads(ds.attrs.get("config_toml", ""))
    except Exception:
        return {}


def scene_name(ds):
    name = scene_toml(ds).get("scene", {}).get("name")
    return name or ds.attrs.get("scene") or ds.attrs.get("title") or "rotorsweep cube"


def has_attractor(ds):
    """Whether the cube holds the attractor diagnostics ([analysis] attractor = true)."""
    return all(v in ds.variables for v in ("attractor", "period", "lle", "poincare_x"))


def has_orbits(ds):
    """Whether any grid point has a converged periodic orbit (a cube of tori alone has none: no
    multipliers to draw)."""
    return bool((ds["orbit_status"].values == 0).any())


def has_down(ds):
    return "poincare_x" + schema.DOWN_SUFFIX in ds.variables


def sweep_labels(ds):
    """Legend labels of the plain and the _down variables: the plain ones sweep up, unless the
    scene swept only down."""
    direction = scene_toml(ds).get("analysis", {}).get("sweep_direction", "up")
    return ("sweep down" if direction == "down" else "sweep up"), "sweep down"


def attractor_counts(ds, suffix=""):
    """{label: n} of the attractor classes of one sweep direction: periodic by period k (and
    'period not resolved' for a periodic class without k, as cubes before not_settled hold),
    quasi-periodic, chaotic, diverged (always listed), not settled, integration failed and not
    computed (when any)."""
    cls = ds["attractor" + suffix].values.ravel()
    per = ds["period" + suffix].values.ravel()
    periodic = cls == schema.ATTRACTOR.index("periodic")
    out = {}
    for k in sorted(int(v) for v in np.unique(per[periodic & (per > 0)])):
        out[f"periodic, period {k}"] = int((periodic & (per == k)).sum())
    unresolved = int((periodic & (per <= 0)).sum())
    if unresolved:
        out["periodic, period not resolved"] = unresolved
    for name in ("quasi_periodic", "chaotic", "diverged"):
        out[name.replace("_", "-")] = int((cls == schema.ATTRACTOR.index(name)).sum())
    for name in ("not_settled", "integration_failed"):
        n = int((cls == schema.ATTRACTOR.index(name)).sum())
        if n:
            out[name.replace("_", " ")] = n
    missing = int((cls == schema.ATTRACTOR.index("not_computed")).sum()
                  + (~np.isin(cls, range(len(schema.ATTRACTOR)))).sum())
    if missing:
        out["not computed"] = missing
    return out


# What a branch can show per observable o of the model: (name pattern, label pattern)
BRANCH_KINDS = {"section": ("section_{o}", "Poincaré {o} of the orbit"),
                "amplitude": ("amplitude_{o}", "amplitude of {o}"),
                "mean": ("{o}_mean", "mean {o}")}


def branch_observables(ds):
    """{name: (label, units)} of the observables a branch diagram can show: per observable o of
    the model its orbit's Poincare coordinate section_o, amplitude_o and o_mean."""
    out = {}
    for o in schema.model_of(ds).observables:
        for name, label in BRANCH_KINDS.values():
            out[name.format(o=o.name)] = (label.format(o=o.name), o.unit)
    return out


def default_observable(ds):
    """The first observable's Poincare coordinate where the attractor diagram can lie behind it,
    else its amplitude."""
    o = schema.model_of(ds).observables[0].name
    return f"section_{o}" if has_attractor(ds) else f"amplitude_{o}"


def branch_values(line, observable):
    """The observable at every point of (a line of) the cube, an array over its point dims (SI
    units; NaN where no orbit was found; an amplitude at a converged torus is over the torus). A section_o value is the periodic orbit's state at
    t = 0 (orbit_state) seen through o."""
    spec = schema.model_of(line)
    if observable.startswith("section_"):
        k = [o.name for o in spec.observables].index(observable[len("section_"):])
        states = line["orbit_state"].transpose(..., "state").values
        periods = line["forcing_period"].values
        flat = [spec.observe(u, T)[k] for u, T in zip(states.reshape(-1, states.shape[-1]), periods.ravel())]
        values = np.reshape(flat, periods.shape)
    else:
        values = line[observable].values.astype(float)
    found = line["orbit_status"].values == 0
    if "torus_status" in line and not observable.startswith("section_"):
        found = found | (line["torus_status"].values == 0)     # a torus point's amplitude: over its torus
    return np.where(found, values, np.nan)


def stable_response(line):
    """Where a point's response is stable (bool over the point dims): its periodic orbit, or at a
    quasi-periodically forced point its torus (rotorsweep.pipeline.torus_points)."""
    stable = line["stable"].values == 1
    return stable | (line["torus_stability"].values == 1) if "torus_stability" in line else stable

"""Stability classes of the periodic orbit at each grid point, and their runs along the
continued axis with edges at the refined boundaries of the cube's boundary table."""
import numpy as np

from rotorsweep.pipeline import query, schema
from rotorsweep.pipeline.report.cubeinfo import axis_edges, continued_axis, select

# Stability classes of a grid point, in colour order. Okabe-Ito colours (colour-blind safe) for
# the instabilities, a pale grey-blue for the stable background, near-black for "no orbit".
# Bistable (a stable orbit where another stable one coexists, between a jump's folds): bluish green.
# Quasi-periodically forced points with their torus (rotorsweep.pipeline.torus_points): sky blue stable,
# vermillion unstable, yellow undecided, mid grey where the torus failed.
CLASSES = ("stable", "fold", "period doubling", "Neimark-Sacker", "no periodic orbit", "bistable",
           "quasi-periodic stable", "quasi-periodic unstable", "quasi-periodic undecided", "torus failed")
PALETTE = ("#D6E4F0", "#E69F00", "#0072B2", "#CC79A7", "#333333", "#009E73",
           "#56B4E9", "#D55E00", "#F0E442", "#777777")
TORUS_CLASSES = CLASSES.index("quasi-periodic stable")     # the first of the torus points' classes
UNCLASSIFIED = "unclassified"   # converged but unstable with no bifurcation code (should not occur)
UNCLASSIFIED_COLOUR = "#BBBBBB"


# query.point_classes' names -> CLASSES (NaN: unclassified)
NAME_CLASS = {"stable": 0, "fold": 1, "period_doubling": 2, "neimark_sacker": 3, "no_orbit": 4, "not_applicable": 4,
              "bistable": 5, "quasi_periodic_stable": 6, "quasi_periodic_unstable": 7, "quasi_periodic_undecided": 8,
              "torus_failed": 9}
CLASS_MEANING = ("stable and no periodic orbit say what the grid point is; fold, period doubling and "
                 "Neimark-Sacker say how stability was lost at the start of the point's unstable interval "
                 "(the same class as `rotorsweep query --unstable`); bistable: a stable orbit between the "
                 "folds of a jump, where another stable orbit coexists (`rotorsweep query --bistable`); "
                 "quasi-periodic: the point's forcing has two incommensurate frequencies, its response a torus "
                 "(stable, unstable or undecided by the sign of its largest normal exponent; torus failed: not solved)")


def stability_class(ds):
    """Float array over the point dims (orbit_status' order): index into CLASSES, NaN where
    unclassifiable; query.point_classes mapped to CLASSES (one vocabulary with the query)."""
    names = query.point_classes(ds).values
    return np.vectorize(lambda n: NAME_CLASS.get(n, np.nan), otypes=[float])(names)


BISTABLE = CLASSES.index("bistable")
# A bistable band is drawn at least this fraction of the continued axis wide (a few pixels of a
# report's map: the demo's 7.6 um fold pair spans 0.1 Hz of 240, half a pixel): a marker, drawn
# over the class beneath, centred on the interval between the folds.
MIN_BAND_FRACTION = 0.004


def class_keys(ds):
    """Stability classes present anywhere in the cube, in CLASSES order (NaN last); bistable also
    where a bistable interval holds no grid point (its band and legend entry are drawn)."""
    cls = stability_class(ds)
    keys = [float(i) for i in range(len(CLASSES)) if (cls == i).any() or (i == BISTABLE and query.bistable_intervals(ds))]
    return keys + ([np.nan] if np.isnan(cls).any() else [])


def bistable_bands(ds, where, intervals):
    """[(lo, hi)] drawn for the bistable intervals of the line `where` (intervals: the cube's
    query.bistable_intervals, taken once per figure: between the folds, else the jump's grid
    points), widened about their middle to at least MIN_BAND_FRACTION of the continued axis."""
    grid = ds[continued_axis(ds)].values.astype(float)
    least = 0.5 * MIN_BAND_FRACTION * float(np.ptp(grid) if grid.size > 1 else 1.0)
    out = []
    for iv in intervals:
        if not all(np.isclose(iv[a], v, rtol=1e-9, atol=0.0) for a, v in where.items() if a in iv):
            continue
        lo, hi = (iv["start"], iv["end"]) if np.isfinite([iv["start"], iv["end"]]).all() else (iv["grid_low"], iv["grid_high"])
        mid, half = 0.5 * (lo + hi), max(0.5 * (hi - lo), least)
        out.append((mid - half, mid + half))
    return out


def class_name(c):
    return UNCLASSIFIED if np.isnan(c) else CLASSES[int(c)]


def class_colour(c):
    return UNCLASSIFIED_COLOUR if np.isnan(c) else PALETTE[int(c)]


def counts(ds):
    """({orbit_status name: n}, {stability class name: n}) over all points."""
    status = ds["orbit_status"].values.ravel()
    by_status = {name: int((status == code).sum()) for code, name in enumerate(schema.ORBIT_STATUS)}
    missing = int((~np.isin(status, range(len(schema.ORBIT_STATUS)))).sum())
    if missing:
        by_status["missing"] = missing
    cls = stability_class(ds).ravel()
    shown = CLASSES if "torus_status" in ds else CLASSES[:TORUS_CLASSES]    # no torus classes without tori
    by_class = {name: int((cls == i).sum()) for i, name in enumerate(shown)}
    if np.isnan(cls).any():
        by_class[UNCLASSIFIED] = int(np.isnan(cls).sum())
    return by_status, by_class


def refined_boundaries(ds, where):
    """The refined boundaries of the line `where` (values of the other swept axes; axes left out
    must have one value) from the cube's boundary table (boundary_<continued axis>, ...):
    [(grid_low, grid_high, refined value, type name)], only entries that were refined and lie
    inside their grid bracket."""
    name = f"boundary_{continued_axis(ds)}"
    if name not in ds or not ds.sizes.get("boundary", 0):
        return []
    value = ds[name].values.astype(float)
    low, high = ds["boundary_grid_low"].values, ds["boundary_grid_high"].values
    ok = (ds["boundary_status"].values == 0) & np.isfinite(value) & (low <= value) & (value <= high)
    for axis, v in where.items():
        if f"boundary_{axis}" in ds:
            ok &= np.isclose(ds[f"boundary_{axis}"].values.astype(float), v, rtol=1e-9, atol=0.0)
    kinds = [schema.BIFURCATION[int(k)] for k in ds["boundary_type"].values[ok]]
    return [(float(a), float(b), float(c), k) for a, b, c, k in zip(low[ok], high[ok], value[ok], kinds)]


def refined_edges(ds, where):
    """refined_boundaries without the type: [(grid_low, grid_high, refined value)]."""
    return [row[:3] for row in refined_boundaries(ds, where)]


def classified(ds):
    """ds with its point classes as a variable (point_class: stability_class). The classes are
    taken over the whole cube, so a figure drawing line by line classifies once (per line, a map of
    the 4-D atlas took time quadratic in its lines)."""
    if "point_class" in ds:
        return ds
    return ds.assign(point_class=(ds["orbit_status"].dims, stability_class(ds)))


def line_segments(ds, where):
    """Runs of one stability class along the line `where`: ([(lo, hi, class), ...], [refined
    edges]). class indexes CLASSES (NaN: unclassified). An edge between two runs is the refined
    boundary of the boundary table where it has one for that pair of grid values, else midway
    between them; the outer edges lie half a grid step beyond the grid."""
    line = select(classified(ds), where)
    grid = line[continued_axis(ds)].values.astype(float)
    cls = line["point_class"].values
    code = np.where(np.isnan(cls), -1.0, cls)
    table = refined_edges(ds, where)
    first, last = axis_edges(grid)
    segments, refined, lo = [], [], first
    for i in range(grid.size):
        if i < grid.size - 1 and code[i + 1] == code[i]:
            continue
        if i == grid.size - 1:
            hi = last
        else:
            hits = [c for a, b, c in table if np.isclose(a, grid[i], rtol=1e-12, atol=0.0)
                    and np.isclose(b, grid[i + 1], rtol=1e-12, atol=0.0)]
            hi = hits[0] if hits else 0.5 * (grid[i] + grid[i + 1])
            if hits:
                refined.append(hi)
        segments.append((lo, hi, float(cls[i])))
        lo = hi
    return segments, refined

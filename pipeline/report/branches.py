"""Branch drawing from plain arrays: a solution branch stable solid and unstable dashed, with its
special points marked and labelled (LP for a fold, PD, NS), and a hover that reads the parameter
and the value at every point.

The arrays follow the branch, not the parameter: a continuation branch that turns back at a fold
has a non-monotonic x, so runs of one stability are cut along the branch order and never by
sorting x. Nothing here knows about cubes (the report's cube figures and the continuation report
share it)."""
from typing import NamedTuple

import numpy as np

from rotorsweep.pipeline.report import style

# AUTO / MatCont labels of the special points, by the cube's bifurcation names
SPECIAL_LABELS = {"fold": "LP", "period_doubling": "PD", "neimark_sacker": "NS"}
SPECIAL_COLOUR = "#C00000"


class Special(NamedTuple):
    """A special point of a branch: where (x, y) and its label, e.g. "PD"."""
    x: float
    y: float
    label: str


def stability_runs(stable):
    """[(start, stop, stable)] slices of the runs of equal stability in branch order, each
    reaching one point into the next run so that the drawn branch has no gap."""
    stable = np.asarray(stable, bool)
    if not stable.size:
        return []
    cuts = np.flatnonzero(stable[1:] != stable[:-1]) + 1
    starts = np.concatenate(([0], cuts))
    stops = np.concatenate((cuts, [stable.size]))
    return [(int(a), int(min(b + 1, stable.size)), bool(stable[a])) for a, b in zip(starts, stops)]


def _joined(x, y, runs, want):
    """(x, y) of the runs of one stability joined into one line, NaN between runs: one legend
    entry (hv.Path has none), the line broken between runs."""
    parts = [np.column_stack((x[a:b], y[a:b])) for a, b, s in runs if s == want]
    gap = np.full((1, 2), np.nan)
    xy = np.concatenate([p for part in parts for p in (part, gap)][:-1]) if parts else np.empty((0, 2))
    return xy[:, 0], xy[:, 1]


def branch_elements(x, y, stable, special=(), backend="bokeh", dims=("x", "y"), labels=("x", "y"),
                    colour="#0072B2", name="periodic orbit", legend_unstable=True, width=1.8):
    """HoloViews elements of one branch: the stable parts solid (legend: `name`, or `name`
    stable), the unstable parts dashed, its points (hover: parameter and value, bokeh), the
    special points as markers with their labels.

    x, y, stable: arrays in branch order (NaN in y breaks the line); special: Special (or
    (x, y, label)) tuples; dims: names of the x and y dimensions; labels: their axis labels with
    units, shown in the hover; legend_unstable: False gives the dashed parts no legend entry
    (several branches in one panel, told apart by colour)."""
    hv = style.holoviews()
    x, y = np.asarray(x, float), np.asarray(y, float)
    stable = np.asarray(stable, bool)
    runs = stability_runs(stable)
    solid = f"{name}, stable" if legend_unstable else name
    elements = [
        hv.Curve(_joined(x, y, runs, True), *dims, label=solid)
        .opts(color=colour, **style.line_style(backend, width), backend=backend),
        hv.Curve(_joined(x, y, runs, False), *dims, label=f"{name}, unstable" if legend_unstable else "")
        .opts(color=colour, **style.line_style(backend, width, dash=True), backend=backend),
    ]
    if backend == "bokeh":
        state = np.where(stable, "stable", "unstable")
        pts = hv.Points((x, y, state), list(dims), ["orbit"])
        elements.append(pts.opts(color=colour, size=3, tools=["hover"], hover_tooltips=hover(dims, labels)
                                 + [("orbit", "@{orbit}")], backend=backend))
    return elements + special_elements(special, backend, dims)


def hover(dims, labels):
    """Bokeh tooltips naming each dimension by its axis label (with units)."""
    return [(label, f"@{{{dim}}}") for dim, label in zip(dims, labels)]


def special_elements(special, backend, dims=("x", "y")):
    """Markers and text labels of special points [(x, y, label)]; none when there are none."""
    hv = style.holoviews()
    special = [Special(*s) for s in special if np.isfinite(s[0]) and np.isfinite(s[1])]
    if not special:
        return []
    xs, ys, _ = (np.array(v) for v in zip(*special))
    marks = hv.Points((xs, ys), list(dims), label="special point (LP fold, PD, NS)").opts(
        **style.marker_style(backend, SPECIAL_COLOUR, 9 if backend == "bokeh" else 6, "D"), backend=backend)
    lx, ly, texts = (np.array(v) for v in zip(*merged_labels(special)))
    # left-aligned from the point: a label at the left edge of the frame is not cut
    text = hv.Labels((lx, ly, texts), list(dims), "label")
    if backend == "bokeh":
        text = text.opts(text_color=SPECIAL_COLOUR, text_font_size="10pt", text_font_style="bold",
                         text_baseline="bottom", text_align="left", xoffset=0, backend=backend)
    else:
        text = text.opts(color=SPECIAL_COLOUR, size=9, weight="bold", verticalalignment="bottom",
                         horizontalalignment="left", backend=backend)
    return [marks, text]


# two special points closer than this, relative to the specials' span (or their size), share a label
SAME_PLACE_RTOL = 1e-3


def merged_labels(special):
    """One label per place: special points at (nearly) the same (x, y) -- a period doubling found
    on a branch and again on the branch switched there -- get one text, their distinct labels
    joined in order ("PD", "PD/LP"), not "PDPD" drawn over each other."""
    xs, ys = (np.array([getattr(s, a) for s in special]) for a in ("x", "y"))
    tol = [SAME_PLACE_RTOL * max(np.ptp(v), np.abs(v).max(), 1e-300) for v in (xs, ys)]
    places = []
    for s in special:
        near = next((p for p in places if abs(p[0] - s.x) <= tol[0] and abs(p[1] - s.y) <= tol[1]), None)
        if near is None:
            places.append([s.x, s.y, [s.label]])
        elif s.label not in near[2]:
            near[2].append(s.label)
    return [(x, y, "/".join(labels)) for x, y, labels in places]

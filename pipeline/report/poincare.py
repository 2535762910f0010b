"""Poincare samples drawn along the continued axis: thinned per grid value, as dots per sweep
direction (the bifurcation diagram, the attractors behind a branch diagram)."""
import numpy as np

from rotorsweep.pipeline.report import style

# Poincare points per panel of the bifurcation diagram: per grid value the distinct values (at a
# resolution of 1/THIN_LEVELS of the panel's range), evenly thinned to at most budget / values.
# 2401 speeds x 128 samples per line (Bai's Fig. 13) would be 1.5 M points: slow to draw with
# matplotlib and tens of MB in the HTML.
BIF_POINTS = {"matplotlib": 200_000, "bokeh": 40_000}
THIN_LEVELS = 1500


def thin_points(grid, values, cap, resolution):
    """(grid value, value) pairs to draw from values[grid, sample]: per grid value the distinct
    finite values at `resolution`, and where there are more than `cap` of them every k-th in
    sorted order (an even thinning that keeps the spread of a chaotic cloud)."""
    values = np.asarray(values, float)
    if not values.size:
        return np.array([]), np.array([])
    q = np.round(values / resolution)
    q = np.where(np.isfinite(q), q, np.inf)
    order = np.argsort(q, axis=1, kind="stable")
    qs = np.take_along_axis(q, order, axis=1)
    vs = np.take_along_axis(values, order, axis=1)
    first = np.ones(qs.shape, bool)
    first[:, 1:] = qs[:, 1:] != qs[:, :-1]
    first &= np.isfinite(qs)
    rank = np.cumsum(first, axis=1) - 1
    stride = np.maximum(1, -(-first.sum(axis=1) // max(int(cap), 1)))
    keep = first & (rank % stride[:, None] == 0)
    at = np.broadcast_to(np.asarray(grid, float)[:, None], values.shape)
    return at[keep], vs[keep]


def bif_range(values):
    finite = values[np.isfinite(values)]
    if not finite.size:
        return -1.0, 1.0
    lo, hi = float(finite.min()), float(finite.max())
    pad = 0.06 * (hi - lo) if hi > lo else max(0.05 * abs(hi), 0.05)
    return lo - pad, hi + pad


def sweep_dots(hv, x, grid, sweeps, labels, backend, resolution, tooltips, ydim="poincare_x"):
    """The thinned Poincare points of each sweep, down first: the up sweep is drawn on top.
    tooltips: the bokeh hover's (label, field) pairs."""
    cap = int(np.clip(BIF_POINTS[backend] // max(grid.size * len(sweeps), 1), 4, sweeps[0].shape[1]))
    dot = float(np.clip(300.0 / max(grid.size, 1), 1.0, 5.0))
    elements = []
    for k in reversed(range(len(sweeps))):
        at, val = thin_points(grid, sweeps[k], cap, resolution)
        pts = style.legend_points(hv, at, val, [x, ydim], labels[k])
        if backend == "bokeh":
            pts = pts.opts(color=style.SWEEP_COLOURS[k], size=dot + (1 if k else 0), line_width=0,
                           tools=["hover"], hover_tooltips=tooltips, backend=backend)
        else:
            size = float(np.clip(28.0 / np.sqrt(max(grid.size, 1)), 0.55, 3.2)) * (1.3 if k else 1.0)
            pts = pts.opts(color=style.SWEEP_COLOURS[k], s=size ** 2, linewidth=0, backend=backend)
        elements.append(pts)
    return elements

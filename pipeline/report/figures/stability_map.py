"""Stability-region map: runs of one stability class along the continued axis as rectangles,
one band per value of the first other swept axis, one panel per facet combination.

Not hvplot: its rectangles have the refined boundaries as edges; hvplot's grid kinds (quadmesh,
heatmap) put edges midway between grid values (rotorsweep.pipeline.explore.stability_map draws that)."""
import numpy as np

from rotorsweep.pipeline import query
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.figures.panels import Sizes, facet_figure, panel_opts
from rotorsweep.pipeline.report.plan import axes_plan, axis_display, axis_label, fmt, where_label
from rotorsweep.pipeline.report.registry import Figure, register
from rotorsweep.pipeline.report.stability import (BISTABLE, bistable_bands, class_colour, class_keys, class_name,
                                                   classified, line_segments, refined_edges)

RECT_HALF = 0.45        # half height of a band in the stability map (gaps between lines)


def map_rectangles(ds, plan, where, bistable):
    """What one stability-map panel draws: ({class: [(x0, y0, x1, y1), ...]}, [(edge, band), ...]
    of the refined edges). Band i is the i-th value of plan['y'] (0 without one); bistable: the
    cube's query.bistable_intervals."""
    y = plan["y"]
    bands = [None] if y is None else [float(v) for v in ds[y].values]
    ds = classified(ds)
    rects, edges = {}, []
    for i, v in enumerate(bands):
        line = dict(where) if v is None else {**where, y: v}
        segments, refined = line_segments(ds, line)
        for lo, hi, c in segments:
            key = -1.0 if np.isnan(c) else c
            rects.setdefault(key, []).append((lo, i - RECT_HALF, hi, i + RECT_HALF))
        for lo, hi in bistable_bands(ds, line, bistable):       # drawn last: over the class beneath
            rects.setdefault(float(BISTABLE), []).append((lo, i - RECT_HALF, hi, i + RECT_HALF))
        edges += [(e, i) for e in refined]
    return rects, edges


def _class_rectangles(hv, rows, c, x0, bands, labels, backend):
    """The rectangles of one class; an empty class still gets its legend entry (a zero-size
    rectangle). bands: the line's value per band as text; labels: the x and band axis labels,
    for a hover that reads the interval, the line and the class (not the rectangle corners)."""
    data = ([(*r, class_name(c), r[0], r[2], bands[round(r[1] + RECT_HALF)]) for r in rows]
            or [(x0, 0, x0, 0, class_name(c), x0, x0, "")])
    el = hv.Rectangles(data, vdims=["class", "start", "end", "line"], label=class_name(c))
    if backend == "bokeh":
        tips = [(f"{labels[0]} interval", "@{start}{0.[0000]} to @{end}{0.[0000]}"),
                (labels[1], "@{line}"), ("orbit", "@{class}")]
        el = el.opts(tools=["hover"], hover_tooltips=tips, backend=backend)
    return el.opts(**style.fill_style(backend, class_colour(c)), backend=backend)


def _map_panel(hv, ds, where, backend, slot, plan, keys, bistable):
    """One stability-class map: each line's runs of one class as rectangles whose edges are the
    refined stability boundaries (boundary table), categorical colours, a legend."""
    rects, edges = map_rectangles(ds, plan, where, bistable)
    x, y = plan["x"], plan["y"]
    grid = ds[x].values
    x0 = float(grid[0])
    if y is None:
        bands, labels = [where_label(ds, where) or "-"], (axis_label(ds, x), "line")
    else:
        bands, labels = [fmt(ds, y, v) for v in ds[y].values], (axis_label(ds, x), axis_display(ds, y)[2])
    elements = [_class_rectangles(hv, rects.get(-1.0 if np.isnan(c) else c, []), c, x0, bands, labels, backend)
                for c in keys]
    if refined_edges(ds, {}) or edges:
        segs = [(e, i - RECT_HALF, e, i + RECT_HALF) for e, i in edges] or [(x0, 0, x0, 0)]
        seg = hv.Segments(segs, label="refined boundary")
        elements.append(seg.opts(color="#000000", **style.line_style(backend, 1.6 if backend == "bokeh" else 1.1),
                                 backend=backend))
    if y is None:
        yticks, nbands = [(0, "")], 1
    else:
        factor = axis_display(ds, y)[0]
        yticks, nbands = [(i, f"{v * factor:.4g}") for i, v in enumerate(ds[y].values)], ds.sizes[y]
    return hv.Overlay(elements).opts(ylim=(-0.5, nbands - 0.5), yticks=yticks,
                                     **panel_opts(ds, slot, backend, axis_label(ds, y) if y else "", grid))


def fig_stability_map(ds, backend="bokeh"):
    """Stability-class map over the continued axis x (first other swept axis), one panel per
    combination of the remaining swept axes (at most MAX_PANELS). Runs of one class are
    rectangles whose edges are the refined boundaries of the cube's boundary table (midway
    between grid values where there is none); a legend names the classes."""
    ds = classified(ds)
    bistable = query.bistable_intervals(ds)     # the whole cube's, once (each panel keeps its line's)
    plan = axes_plan(ds)
    keys = class_keys(ds)
    strip = plan["y"] is None

    def panel(hv, ds, where, backend, slot):
        return _map_panel(hv, ds, where, backend, slot, plan, keys, bistable)
    sizes = Sizes(bokeh_one=(1150, 230 if strip else 480), bokeh_grid=(600, 300),
                  aspect_one=7 if strip else 2.6, aspect_grid=1.5,
                  inches_one=(11, 2.4 if strip else 4.6), grid_width=10.3)
    return facet_figure(ds, backend, "Stability-region map", panel, sizes)


register(Figure(name="stability_map", filename="stability_map.png", title="Stability-region map",
                build=lambda ds, backend, intervals: fig_stability_map(ds, backend)))

"""Summary figures of cubes with more than two varying axes (the 4-D atlas: speed x clearance x
contact angle x preload), where one stability map per line combination would be 64 maps: per
line, the first loss of stability along the continued axis and the stable fraction of the line,
as heat maps over the last two other axes (contact angle x preload), one panel per value of the
remaining ones (clearance); and the boundary table drawn as the surfaces it samples (every
refined boundary over the last other axis, coloured by the one before).

Not hvplot: heat maps over categorical axes (the preloads are not evenly spaced) with a value
written in every cell, in both backends from one function, as the other figures."""
import itertools

import numpy as np

from rotorsweep.pipeline import schema
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.cubeinfo import continued_axis, other_axes
from rotorsweep.pipeline.report.plan import MAX_PANELS, axis_display, axis_label, where_label
from rotorsweep.pipeline.report.registry import Figure, register
from rotorsweep.pipeline.report.stability import stability_class


# a continuous light ramp (pale to mid blue) so the black value in every cell stays readable
HEAT_COLOURS = ["#{:02X}{:02X}{:02X}".format(*(round(a + (b - a) * t) for a, b in zip((247, 251, 255), (107, 174, 214))))
                for t in np.linspace(0.0, 1.0, 64)]


def is_atlas(ds):
    """More than two swept axes with more than one value: the condition of these figures."""
    return sum(ds.sizes[a] > 1 for a in schema.point_axes(ds)) > 2


def atlas_plan(ds):
    """(heat x axis, heat y axis, [panel {axis: value}] at most MAX_PANELS): the last two varying
    other axes span a heat map, the rest make panels."""
    varying = [a for a in other_axes(ds) if ds.sizes[a] > 1]
    x, y = varying[-2], varying[-1]
    rest = varying[:-2]
    panels = [dict(zip(rest, map(float, v))) for v in itertools.product(*(ds[a].values for a in rest))]
    return x, y, panels[:MAX_PANELS]


def _refined_onsets(ds, along, others):
    """{(other axes' values..., grid_low): refined value} of the stable -> unstable boundaries
    refined inside their bracket."""
    name = f"boundary_{along}"
    if name not in ds or not ds.sizes.get("boundary", 0):
        return {}
    value, low, high = (ds[n].values.astype(float) for n in (name, "boundary_grid_low", "boundary_grid_high"))
    ok = ((ds["boundary_status"].values == 0) & (ds["boundary_direction"].values == 0)
          & (low <= value) & (value <= high))
    keys = zip(*(ds[f"boundary_{a}"].values.astype(float) for a in others), low)
    return {tuple(k): v for k, v, good in zip(keys, value, ok) if good}


def line_summary(ds):
    """(onset, stable fraction) as DataArrays over the other axes: the first value of the
    continued axis where a line is no longer stable (the refined boundary where the table has
    it, else the first unstable grid value; NaN: stable throughout) and the share of the line's
    grid points with a stable orbit."""
    import xarray as xr

    along = continued_axis(ds)
    others = other_axes(ds)
    cls = np.moveaxis(stability_class(ds.transpose(along, *others, ...)), 0, -1)
    grid = ds[along].values.astype(float)
    unstable = cls != 0                                        # NaN (unclassified) counts as not stable
    first = np.argmax(unstable, axis=-1)
    onset = np.where(unstable.any(axis=-1), grid[first], np.nan)
    refined = _refined_onsets(ds, along, others)
    for idx in zip(*np.nonzero(unstable.any(axis=-1) & (first > 0))):
        key = tuple(float(ds[a].values[i]) for a, i in zip(others, idx)) + (grid[first[idx] - 1],)
        onset[idx] = refined.get(key, onset[idx])
    coords = {a: ds[a].values for a in others}
    return (xr.DataArray(onset, coords, others), xr.DataArray((cls == 0).mean(axis=-1), coords, others))


def _heat_panel(hv, ds, values, where, plan, backend, label, fmt_cell):
    """One heat map of `values` (a DataArray over the other axes) at the panel's values, with
    the value written in every cell."""
    x, y, _ = plan
    sub = values.sel(where) if where else values
    grid = sub.isel({d: 0 for d in sub.dims if d not in (x, y)}).transpose(x, y).values   # size-1 axes
    # cells at index positions, the values as tick labels: the axes need not be evenly spaced, and
    # matplotlib cannot place text labels on categorical heat-map axes
    rows = [(i, j, float(grid[i, j])) for i in range(grid.shape[0]) for j in range(grid.shape[1])]
    heat = hv.HeatMap(rows, [x, y], label).opts(
        cmap=HEAT_COLOURS, colorbar=True, clabel=label, backend=backend,
        **({"tools": ["hover"]} if backend == "bokeh" else {"show_values": False}))
    text = hv.Labels([(a, b, fmt_cell(v)) for a, b, v in rows], [x, y], "text").opts(
        backend=backend, **({"text_color": "black", "text_font_size": "8pt"} if backend == "bokeh"
                            else {"color": "black", "size": 7}))
    title = where_label(ds, where, short=True) or label
    return (heat * text).opts(title=title, xlabel=axis_label(ds, x), ylabel=axis_label(ds, y),
                              xticks=_ticks(ds, x), yticks=_ticks(ds, y), fontsize=style.fonts(backend),
                              backend=backend)


def _ticks(ds, axis):
    factor = axis_display(ds, axis)[0]
    return [(i, f"{v * factor:.4g}") for i, v in enumerate(ds[axis].values)]


# 1536 px at the report's 120 dpi: a PNG a page shows without scaling (three 5.6-inch panels would be 2016)
MAX_WIDTH_INCHES = 12.8


def _heat_figure(ds, backend, values, head, label, fmt_cell):
    hv = style.holoviews()
    plan = atlas_plan(ds)
    panels = [_heat_panel(hv, ds, values, where, plan, backend, label, fmt_cell) for where in plan[2]]
    columns = style.ncols(len(panels))
    if backend == "bokeh":
        panels = [p.opts(width=430, height=340, backend=backend) for p in panels]
    else:       # the y label on the first column only: a colour bar sits where the next would go
        panels = [p.opts(aspect=1.25, backend=backend, **({"ylabel": ""} if k % columns else {}))
                  for k, p in enumerate(panels)]
    rows = -(-len(panels) // columns)
    width = min(5.6 * columns, MAX_WIDTH_INCHES)
    return style.layout(hv, panels, backend, columns, head, hspace=0.6,
                        fig_inches=(width, 3.9 * width / (5.6 * columns) * rows + 0.6))


def _cell(decimals):
    return lambda v: "-" if not np.isfinite(v) else f"{v:.{decimals}f}"


def fig_onset(ds, backend="bokeh"):
    """First loss of stability along the continued axis per line ('-': stable throughout)."""
    factor, unit, name = axis_display(ds, continued_axis(ds))
    onset, _ = line_summary(ds)
    return _heat_figure(ds, backend, onset * factor, f"First loss of stability: {name} [{unit}] ('-': stable throughout)",
                        f"{name} [{unit}]", _cell(0))


def fig_stable_fraction(ds, backend="bokeh"):
    """Share of each line's grid points with a stable periodic orbit."""
    _, fraction = line_summary(ds)
    name = axis_display(ds, continued_axis(ds))[2]
    return _heat_figure(ds, backend, 100.0 * fraction, f"Stable share of the {name} range [%]",
                        "stable [%]", _cell(0))


def fig_boundary_surfaces(ds, backend="bokeh"):
    """Every refined boundary of the table: its value of the continued axis over the last other
    axis (by index: its values need not be evenly spaced), one colour per value of the axis
    before it, one panel per remaining combination: the stability boundaries as the surfaces
    they sample."""
    hv = style.holoviews()
    along = continued_axis(ds)
    x, y, wheres = atlas_plan(ds)
    factor, unit, name = axis_display(ds, along)
    table = {k: ds[f"boundary_{k}"].values for k in (along, x, y, "status")} if ds.sizes.get("boundary") else {}
    panels = []
    for k, where in enumerate(wheres):
        ok = np.ones(len(table.get(along, [])), bool) if table else np.zeros(0, bool)
        if table:
            ok &= table["status"] == 0
            for a, v in where.items():
                ok &= np.isclose(ds[f"boundary_{a}"].values.astype(float), v, rtol=1e-9, atol=0.0)
        elements = []
        for i, xv in enumerate(ds[x].values):
            sel = ok & np.isclose(table[x].astype(float), xv, rtol=1e-9, atol=0.0) if table else ok
            pos = [list(ds[y].values).index(v) for v in table[y][sel]] if table else []
            jitter = (i - (ds.sizes[x] - 1) / 2) * 0.6 / max(1, ds.sizes[x])
            pts = style.legend_points(hv, np.add(pos, jitter), table[along][sel] * factor if table else [],
                                      [y, along], where_label(ds, {x: float(xv)}, short=True))
            colour = style.LINE_COLOURS[i % len(style.LINE_COLOURS)]
            elements.append(pts.opts(**style.marker_style(backend, colour, 5 if backend == "bokeh" else 3.2),
                                     backend=backend))
        ticks = _ticks(ds, y)
        panels.append(hv.Overlay(elements).opts(
            title=where_label(ds, where, short=True) or "boundaries", xticks=ticks, xlim=(-0.5, ds.sizes[y] - 0.5),
            xlabel=axis_label(ds, y),
            ylabel=f"boundary {name} [{unit}]", show_legend=backend == "bokeh" or k == 0, legend_position="right",
            fontsize=style.fonts(backend), backend=backend))
    columns = 1 if len(panels) == 1 else 2
    if backend == "bokeh":
        panels = [p.opts(width=620, height=360, backend=backend) for p in panels]
    else:
        panels = [p.opts(aspect=1.8, backend=backend) for p in panels]
    rows = -(-len(panels) // columns)
    return style.layout(hv, panels, backend, columns, f"Stability boundaries over {axis_display(ds, y)[2]}",
                        fig_inches=(11, 3.3 * rows + 0.6))


register(Figure(name="atlas_onset", filename="atlas_onset.png", title="First loss of stability along {axis} per line",
                applies=is_atlas, build=lambda ds, backend, intervals: fig_onset(ds, backend)))
register(Figure(name="atlas_stable_fraction", filename="atlas_stable_fraction.png",
                title="Stable share of each {axis} line", applies=is_atlas,
                build=lambda ds, backend, intervals: fig_stable_fraction(ds, backend)))
register(Figure(name="atlas_boundaries", filename="atlas_boundaries.png",
                title="Stability boundaries (the boundary table) over the swept parameters", applies=is_atlas,
                build=lambda ds, backend, intervals: fig_boundary_surfaces(ds, backend)))

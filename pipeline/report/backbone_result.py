"""The report of a backbone result (`rotorsweep backbone`): the backbone of every mode as a
bearing engineer reads a resonance (amplitude against frequency), the invariant manifold's
(dashed) over the continuation's (solid, its orbits as dots); the relative difference of the two
against amplitude on log-log axes with the A^4 slope the cubic theory predicts; and the manifold
of one mode as a map of a slave coordinate over the master's (p, p') plane with the full system's
orbit started on it (the papers' check: the orbit stays on the surface)."""
import html
import json

import numpy as np

from rotorsweep.pipeline import backbone, backbone_reader, query
from rotorsweep.pipeline.report import branches, page, style

UM = 1e6


def _lines(ds):
    """[(label, {axis: index})] of the swept axes' combinations."""
    dims = ds["axial_approach"].dims
    out = []
    for idx in np.ndindex(ds["axial_approach"].shape):
        sel = dict(zip(dims, idx))
        label = ", ".join(f"{a} = {float(ds[a].values[i]):g} {ds[a].attrs.get('units', '')}" for a, i in sel.items())
        out.append((label, sel))
    return out


def _mode_title(ds, k, sel):
    line = ds.isel(sel)
    return (f"mode {int(ds['mode'].values[k])}: {line['mode_label'].values[k]} {line['mode_whirl'].values[k]}, "
            f"{float(line['linear_frequency'].values[k]):.5g} Hz")


FORCED_WINDOW = 0.1     # the forced response drawn within +-10 % of the mode's linear frequency


def check_forced(ds, forced):
    """ValueError unless `forced` is a continuation along a frequency in Hz with an observable for
    every backbone master (observable j is coordinate j: the models order their positions alike)."""
    unit = forced["parameter"].attrs.get("units")
    if unit != "Hz":
        raise ValueError(f"--over: the forced response must be continued along a frequency in Hz; "
                         f"{forced.attrs.get('parameter')!r} is in {unit!r}")
    masters = ds["master"].values.ravel()
    if masters.size and masters.max() >= forced.sizes["observable"]:
        raise ValueError(f"--over: the forced model has {forced.sizes['observable']} observables, fewer than the "
                         f"backbone's coordinates ({int(masters.max()) + 1})")


def _forced_elements(hv, ds, forced, k, backend, dims):
    """The forced response's branches (half peak-to-peak of the observable matching mode k's
    master, stable solid, unstable dashed, grey) within FORCED_WINDOW of the mode's frequency."""
    line = ds.isel(_lines(ds)[0][1])
    j = int(line["master"].values[k])
    f0 = float(line["linear_frequency"].values[k])
    out = []
    for b in range(forced.sizes["branch"]):
        x = forced["parameter"].values[b]
        y = forced["amplitude_half_pp"].values[b, :, j] * UM
        near = np.abs(x - f0) <= FORCED_WINDOW * f0
        if near.sum() < 2:
            continue
        name = f"forced response, {forced['observable'].values[j]} half p-p"
        out += branches.branch_elements(np.where(near, x, np.nan), np.where(near, y, np.nan),
                                        forced["stable"].values[b] == 1, (), backend, dims,
                                        ("frequency [Hz]", "amplitude [µm]"), "#999999", name if b == 0 else "",
                                        legend_unstable=False, width=1.2)
    return out


def _backbone_panel(hv, ds, k, backend, show, forced=None):
    dims = (hv.Dimension("frequency", label="frequency [Hz]"), hv.Dimension("amplitude", label="master amplitude [µm]"))
    elements = []
    for j, (label, sel) in enumerate(_lines(ds)):
        line, colour = ds.isel(sel), style.LINE_COLOURS[j % len(style.LINE_COLOURS)]
        grid = line["amplitude_grid"].values * UM
        suffix = f" ({label})" if label else ""
        elements.append(hv.Curve((line["frequency_manifold"].values[k], grid), *dims, label=f"manifold{suffix}")
                        .opts(color=colour, **style.line_style(backend, 1.6, dash=True), backend=backend))
        f, a = line["point_frequency"].values[k], line["point_amplitude"].values[k] * UM
        elements.append(hv.Curve((f, a), *dims, label=f"continuation{suffix}")
                        .opts(color=colour, **style.line_style(backend, 1.2, alpha=0.8), backend=backend))
        elements.append(style.legend_points(hv, f, a, list(dims), f"continued orbits{suffix}")
                        .opts(**style.marker_style(backend, colour, 4), backend=backend))
    if forced is not None:
        elements = _forced_elements(hv, ds, forced, k, backend, dims) + elements
    show_x, show_y = show
    return hv.Overlay(elements).opts(title=_mode_title(ds, k, _lines(ds)[0][1]), show_grid=True, xlabel="frequency [Hz]"
                                     if show_x else "", ylabel="master amplitude [µm]" if show_y else "",
                                     backend=backend)


def _backbones(hv, ds, backend, forced=None):
    n = ds.sizes["mode"]
    # bokeh: at most two 560 px panels a row (the page fits a 1400 px window)
    columns = min(2, style.ncols(n)) if backend == "bokeh" else style.ncols(n)
    panels = []
    for k in range(n):
        panel = _backbone_panel(hv, ds, k, backend, style.grid_opts(k, n, backend, columns), forced)
        size = {"width": 560, "height": 340} if backend == "bokeh" else {}
        # the HTML: a legend on every panel (separate figures); the PNG: one, on the first
        panels.append(panel.opts(legend_position="bottom_left", show_legend=backend == "bokeh" or k == 0, **size,
                                 backend=backend))
    rows = -(-n // columns)
    return style.layout(hv, panels, backend, columns, "Backbone curves: invariant manifold (dashed), continuation (solid)",
                        fig_inches=(5.0 * columns, 3.6 * rows))


def _difference(hv, ds, backend):
    """|relative difference| against amplitude, log-log, one curve per mode (first line), with the
    predicted A^4 slope through the middle of the first curve and the 1 % level."""
    dims = (hv.Dimension("amplitude", label="master amplitude [µm]"),
            hv.Dimension("difference", label="|f_continuation - f_manifold| / f_continuation"))
    sel = _lines(ds)[0][1]
    line = ds.isel(sel)
    grid = line["amplitude_grid"].values * UM
    elements = []
    for k in range(ds.sizes["mode"]):
        d = np.abs(line["relative_difference"].values[k])
        ok = np.isfinite(d) & (d > 0)
        colour = style.LINE_COLOURS[k % len(style.LINE_COLOURS)]
        elements.append(hv.Curve((grid[ok], d[ok]), *dims, label=_mode_title(ds, k, sel))
                        .opts(color=colour, **style.line_style(backend, 1.6), backend=backend))
    ref = np.abs(line["relative_difference"].values[0])
    if np.isfinite(ref).any():
        mid = np.nanargmin(np.abs(np.log(grid) - np.log(grid).mean()))
        slope = ref[mid] * (grid / grid[mid]) ** 4
        elements.append(hv.Curve((grid, slope), *dims, label="slope A^4 (cubic theory)")
                        .opts(color="#777777", **style.line_style(backend, 1.0, dash=True), backend=backend))
    elements.append(hv.Curve((grid[[0, -1]], [backbone.PART_RTOL] * 2), *dims, label="1 %")
                    .opts(color="#C00000", **style.line_style(backend, 1.0, dash=True), backend=backend))
    size = {"width": 900, "height": 420} if backend == "bokeh" else {"fig_inches": (9, 4.6)}
    return hv.Overlay(elements).opts(logx=True, logy=True, show_grid=True, legend_position="bottom_right", **size,
                                     backend=backend)


def _surface(hv, ds, backend):
    """The slave coordinate on the manifold over (p, r), the full orbit's (p, r) path over it, and
    beside it the slave along the orbit against the surface's value at the orbit's (p, r)."""
    info = json.loads(str(ds["surface_info"].values))
    sel = _lines(ds)[0][1]
    line = ds.isel(sel)
    p, r = line["surface_p_values"].values * UM, line["surface_r_values"].values
    master, slave = info["master"], info["slave"]
    kd = [hv.Dimension("p", label=f"{master} [µm]"), hv.Dimension("r", label=f"{master}' [m/s]")]
    vd = hv.Dimension("value", label=f"{slave} on the manifold [SI]")
    mesh = hv.QuadMesh((p, r, line["surface_value"].values.T), kd, vd).opts(cmap="RdBu_r", colorbar=True,
                                                                            clabel=slave, backend=backend)
    path = hv.Curve((line["orbit_p"].values * UM, line["orbit_r"].values), *kd, label="full orbit started on it") \
        .opts(color="black", **style.line_style(backend, 1.2), backend=backend)
    left = (mesh * path).opts(title=f"mode {info['mode']}: {slave} over the master's ({master}, {master}')", backend=backend)
    td = hv.Dimension("t", label="time [ms]")
    sd = hv.Dimension("slave", label=f"{slave} [SI]")
    t = line["orbit_time"].values * 1e3
    right = (hv.Curve((t, line["orbit_slave"].values), td, sd, label="full system")
             .opts(color="black", **style.line_style(backend, 1.6), backend=backend)
             * hv.Curve((t, line["orbit_on_surface"].values), td, sd, label="manifold at its (p, p')")
             .opts(color="#D55E00", **style.line_style(backend, 1.2, dash=True), backend=backend)) \
        .opts(title=f"{slave} along 10 periods at A = {info['amplitude'] * UM:.3g} µm", legend_position="top_right",
              backend=backend)
    size = {"width": 560, "height": 420} if backend == "bokeh" else {}
    return style.layout(hv, [left.opts(**size, backend=backend), right.opts(**size, backend=backend)], backend, 2,
                        "Invariant manifold and an orbit of the full system on it", fig_inches=(13, 4.6))


def with_hover(fig, backend):
    """A hover tool on every curve, point set and mesh of a bokeh figure (the matplotlib one as is)."""
    if backend != "bokeh":
        return fig
    return fig.map(lambda el: el.opts(tools=["hover"], backend=backend), ["Curve", "Points", "QuadMesh"])


def figures(ds, backend, forced=None):
    """(caption, filename, figure) of each figure; forced: a continuation result to draw the
    backbones over."""
    hv = style.holoviews()
    caption = "Backbone curves of every mode" + (" over the forced response" if forced is not None else "")
    out = [(caption, "backbones.png", _backbones(hv, ds, backend, forced)),
           ("Manifold vs continuation: relative frequency difference", "backbone_difference.png",
            _difference(hv, ds, backend))]
    if "surface_info" in ds:
        out.append(("The invariant manifold of one mode with a full-system orbit", "manifold_surface.png",
                    _surface(hv, ds, backend)))
    return [(caption, filename, with_hover(fig, backend)) for caption, filename, fig in out]


def _header_html(ds, title):
    lines = backbone_reader.describe(ds).splitlines()
    return (f"<h1>{html.escape(title)}</h1><p>{html.escape(lines[0])}<br>{html.escape(lines[1])}</p>"
            "<p>Amplitude: the first harmonic of the master coordinate's displacement (the largest in the "
            "mode). Manifold: Shaw-Pierre invariant manifold to cubic order, backbone to second order "
            "in the amplitude. Continuation: periodic orbits of the full conservative model.</p>")


def make_report(ds, out_dir, title=None, forced=None):
    """report.html, one PNG per figure and modes.csv into out_dir; returns the paths as
    rotorsweep.pipeline.report.make_report does. forced: a continuation result of a forced response along a
    frequency (the backbones are drawn over it; `check_forced` first)."""
    title = title or f"Backbone report: {ds.attrs.get('scene', '')}"
    cols = backbone_reader.table(ds)
    return page.write_result_report(out_dir, title, _header_html(ds, title),
                                    lambda backend: figures(ds, backend, forced), page.columns_html("Modes", cols, 6),
                                    ds.attrs.get("config_toml", ""), "modes.csv", query.render(cols, "csv"))

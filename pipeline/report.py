"""Stability-map report of a result cube: one self-contained HTML page plus PNGs and a CSV.

    make_report(ds, out_dir, points=None) -> {"html": Path, "png": [Path, ...], "csv": Path,
                                              "points": [Path, ...]}

Figures: the stability-region map (runs of one stability class as rectangles whose edges are the
refined boundaries of the cube's boundary table), max |multiplier| vs speed, the multipliers
around stability boundaries; for cubes with attractor diagnostics also the bifurcation diagram
(Poincare x vs speed) and the largest Lyapunov exponent vs speed; and per requested point
(`points`, `rotorsweep report --point`) its orbit, Poincare section, spectrum and a table.

Every figure is built by one function `fig_*(ds, backend)` that returns a HoloViews object styled
for that backend. The HTML page (bokeh, JavaScript inlined so it opens offline) and the PNGs
(matplotlib, no browser) call the same functions, building each figure anew per backend: a
bokeh-styled object saved with matplotlib silently loses its colormap, limits and colorbar.
"""
import contextlib
import csv
import html
import itertools
from pathlib import Path

import numpy as np

from pipeline import query, schema

# Stability classes of a grid point, in colour order. Okabe-Ito colours (colour-blind safe) for
# the instabilities, a pale grey-blue for the stable background, near-black for "no orbit".
CLASSES = ("stable", "fold", "period doubling", "Neimark-Sacker", "no periodic orbit")
PALETTE = ("#D6E4F0", "#E69F00", "#0072B2", "#CC79A7", "#333333")
UNCLASSIFIED = "unclassified"   # converged but unstable with no bifurcation code (should not occur)

# Line colours for the values of the first other axis (Okabe-Ito, then Tol's muted).
LINE_COLOURS = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#D55E00", "#56B4E9", "#000000",
                "#882255", "#117733", "#999933", "#44AA99", "#AA4499")

MAX_PANELS = 12        # facet panels per figure; the rest are listed as omitted
MAX_BOUNDARIES = 6     # stability boundaries in the multiplier figure
BOUNDARY_POINTS = 5    # grid speeds drawn on each side of a boundary
DPI = 120

# axis -> (factor from cube units, display unit, short label)
DISPLAY = {
    "speed": (1.0, "Hz", "shaft speed"),
    "clearance": (1e6, "µm", "radial clearance"),
    "contact_angle": (1.0, "deg", "contact angle"),
    "preload": (1.0, "N", "preload"),
}
_VARS = ("orbit_status", "stable", "bifurcation", "max_abs_multiplier", "multiplier_real",
         "multiplier_imag")


# ----------------------------------------------------------------------------- data helpers

def _fmt(axis, value):
    """A swept value in display units, e.g. '7.6 µm'."""
    factor, unit, _ = DISPLAY[axis]
    if value is None or not np.isfinite(value):
        return "from clearance" if axis == "contact_angle" else "n/a"
    return f"{float(value) * factor:.4g} {unit}"


def _axis_label(axis):
    factor, unit, label = DISPLAY[axis]
    return f"{label} [{unit}]"


def _where_label(where, short=False):
    names = {"clearance": "clearance", "contact_angle": "angle"} if short else {}
    return ", ".join(f"{names.get(a, DISPLAY[a][2])} {_fmt(a, v)}" for a, v in where.items())


def stability_class(ds):
    """Float array over the point dims: index into CLASSES, NaN where unclassifiable."""
    status = ds["orbit_status"].values
    stable = ds["stable"].values
    bif = ds["bifurcation"].values
    cls = np.full(status.shape, np.nan)
    converged = status == 0
    cls[converged & (stable == 1)] = 0
    unstable = converged & (stable != 1)
    for code in (1, 2, 3):          # schema.BIFURCATION: fold, period_doubling, neimark_sacker
        cls[unstable & (bif == code)] = code
    cls[~converged] = 4
    return cls


def axes_plan(ds):
    """How the swept axes map onto a figure: x (speed), y (first other swept axis or None),
    facet axes, fixed axes {name: value}, the facet combinations shown and those omitted."""
    swept = [a for a in schema.AXES if a in ds.dims and a != "speed" and ds.sizes[a] > 1]
    y = swept[0] if swept else None
    facets = swept[1:]
    fixed = {}
    for a in schema.AXES:
        if a == "speed" or a in swept or a not in ds.coords:
            continue
        v = ds[a].values
        fixed[a] = float(np.ravel(v)[0])
    combos = [dict(zip(facets, vals)) for vals in itertools.product(*(ds[a].values for a in facets))]
    shown, omitted = _cap(combos)
    return {"y": y, "facets": facets, "fixed": fixed, "shown": shown, "omitted": omitted}


def _cap(combos):
    """(shown, omitted): at most MAX_PANELS combinations, evenly spread over the list."""
    if len(combos) <= MAX_PANELS:
        return combos, []
    keep = sorted(set(np.linspace(0, len(combos) - 1, MAX_PANELS).round().astype(int)))
    return [combos[i] for i in keep], [c for i, c in enumerate(combos) if i not in set(keep)]


def line_plan(ds):
    """Like axes_plan, for figures with one panel per line (every combination of the swept axes
    other than speed, e.g. one per clearance): {"axes", "fixed", "shown", "omitted"}."""
    plan = axes_plan(ds)
    axes = [a for a in (plan["y"], *plan["facets"]) if a]
    combos = [{a: float(v) for a, v in zip(axes, vals)}
              for vals in itertools.product(*(ds[a].values for a in axes))]
    shown, omitted = _cap(combos)
    return {"axes": axes, "fixed": plan["fixed"], "shown": shown, "omitted": omitted}


def _speed_edges(speed):
    """Outer edges of a speed grid: half a step beyond the first and last speed (1 Hz wide for a
    single speed), as the cells of a map centred on the grid speeds."""
    if speed.size == 1:
        return float(speed[0]) - 0.5, float(speed[0]) + 0.5
    return (float(speed[0] - 0.5 * (speed[1] - speed[0])),
            float(speed[-1] + 0.5 * (speed[-1] - speed[-2])))


def refined_edges(ds, where):
    """The refined boundaries of the line `where` (values of the other swept axes; axes left out
    must have one value) from the cube's boundary table: [(grid_low, grid_high, speed)], only
    entries that were refined and lie inside their grid bracket."""
    if "boundary_speed" not in ds or not ds.sizes.get("boundary", 0):
        return []
    speed = ds["boundary_speed"].values.astype(float)
    low, high = ds["boundary_grid_low"].values, ds["boundary_grid_high"].values
    ok = (ds["boundary_status"].values == 0) & np.isfinite(speed) & (low <= speed) & (speed <= high)
    for axis, value in where.items():
        name = f"boundary_{axis}"
        if name in ds:
            ok &= np.isclose(ds[name].values.astype(float), value, rtol=1e-9, atol=0.0)
    return [(float(a), float(b), float(c)) for a, b, c in zip(low[ok], high[ok], speed[ok])]


def line_segments(ds, where):
    """Runs of one stability class along the line `where`: ([(lo, hi, class), ...], [refined
    edge speeds]). class indexes CLASSES (NaN: unclassified). An edge between two runs is the
    refined boundary speed of the boundary table where it has one for that pair of grid speeds,
    else midway between them; the outer edges lie half a grid step beyond the grid."""
    line = _select(ds, where)
    speed = line["speed"].values.astype(float)
    cls = stability_class(line)
    code = np.where(np.isnan(cls), -1.0, cls)
    table = refined_edges(ds, where)
    first, last = _speed_edges(speed)
    segments, refined, lo = [], [], first
    for i in range(speed.size):
        if i < speed.size - 1 and code[i + 1] == code[i]:
            continue
        if i == speed.size - 1:
            hi = last
        else:
            hits = [c for a, b, c in table if np.isclose(a, speed[i], rtol=1e-12, atol=0.0)
                    and np.isclose(b, speed[i + 1], rtol=1e-12, atol=0.0)]
            hi = hits[0] if hits else 0.5 * (speed[i] + speed[i + 1])
            if hits:
                refined.append(hi)
        segments.append((lo, hi, float(cls[i])))
        lo = hi
    return segments, refined


def _select(ds, where):
    """ds at the given values of swept axes, with every size-1 swept dim squeezed out."""
    sub = ds.sel(where) if where else ds
    extra = [d for d in sub.dims if d in schema.AXES and d != "speed" and sub.sizes[d] == 1]
    return sub.isel({d: 0 for d in extra})


def _fixed_note(plan):
    return "; ".join(f"{DISPLAY[a][2]} {_fmt(a, v)}" for a, v in plan["fixed"].items())


def _omitted_note(plan):
    n = len(plan["omitted"])
    if not n:
        return ""
    total = n + len(plan["shown"])
    return f"showing {len(plan['shown'])} of {total} panels ({n} omitted, listed in the HTML report)"


# ----------------------------------------------------------------------------- backends

def _hv():
    import holoviews as hv
    import holoviews.plotting.bokeh  # noqa: F401  (registers the renderers)
    import holoviews.plotting.mpl  # noqa: F401
    return hv


@contextlib.contextmanager
def _backend(name):
    """Make `name` the current HoloViews backend while figures are built, then restore."""
    hv = _hv()
    previous = hv.Store.current_backend
    hv.Store.set_current_backend(name)
    try:
        yield hv
    finally:
        hv.Store.set_current_backend(previous)


def _fonts(backend):
    if backend == "bokeh":
        return {"title": "12pt", "labels": "11pt", "xticks": "10pt", "yticks": "10pt"}
    return {"title": 12, "labels": 11, "xticks": 9.5, "yticks": 9.5, "legend": 9,
            "cticks": 9.5, "clabel": 10}


_MARKERS = {"o": "circle", "^": "triangle", "s": "square", "v": "inverted_triangle", "D": "diamond"}


def _line_style(backend, width=1.5, dash=False, alpha=1.0):
    if backend == "bokeh":
        return {"line_width": width, "line_dash": "dashed" if dash else "solid", "alpha": alpha}
    return {"linewidth": width, "linestyle": "--" if dash else "-", "alpha": alpha}


def _marker_style(backend, colour, size, marker="o", hollow=False, alpha=1.0):
    """size: marker diameter in screen pixels (bokeh) / points (matplotlib)."""
    if backend == "bokeh":
        style = {"color": colour, "size": size, "marker": _MARKERS[marker], "alpha": alpha}
        return {**style, "fill_alpha": 0.0, "line_width": 1.5} if hollow else style
    style = {"s": size ** 2, "marker": marker, "alpha": alpha}
    if hollow:
        return {**style, "facecolors": "none", "edgecolors": colour, "linewidth": 1.1}
    return {**style, "color": colour, "linewidth": 0}


def _legend_markers(plot, element):
    """matplotlib hook: legend markers at a readable size even where the dots are tiny."""
    legend = plot.handles["axis"].get_legend()
    if legend is None:
        return
    for handle in getattr(legend, "legend_handles", getattr(legend, "legendHandles", [])):
        if hasattr(handle, "set_sizes"):
            handle.set_sizes([30.0])
        handle.set_alpha(1.0)


def _layout(hv, panels, backend, ncols, title, fig_inches=None):
    """One panel as is, several as a layout with `ncols` columns and an overall title."""
    if len(panels) == 1:
        obj = panels[0]
        if backend == "matplotlib" and fig_inches:
            obj = obj.opts(fig_inches=fig_inches, backend=backend)
        return obj
    # bokeh: separate figures in a grid; matplotlib: one figure, one title, no A/B/C labels
    lay = hv.Layout(panels).cols(ncols)
    if backend == "bokeh":
        return lay.opts(title=title, shared_axes=False, backend=backend)
    return lay.opts(title=title, sublabel_format="", fig_inches=fig_inches, hspace=0.25,
                    vspace=0.35, fontsize={"title": 13}, backend=backend)


# ----------------------------------------------------------------------------- figures

def _ncols(n):
    return 1 if n == 1 else 2 if n in (2, 4) else 3


def _grid_opts(k, n, backend):
    """Axis labels for panel k of n in a matplotlib grid: x label on the bottom row only,
    y label on the first column only (bokeh panels are separate figures and keep both)."""
    ncols = _ncols(n)
    show_x = backend == "bokeh" or k + ncols >= n
    show_y = backend == "bokeh" or k % ncols == 0
    return show_x, show_y


def _figure_title(head, plan):
    fixed = _fixed_note(plan)
    title = head + (f" ({fixed})" if fixed else "")
    note = _omitted_note(plan)
    return title + (f"\n{note}" if note else "")


UNCLASSIFIED_COLOUR = "#BBBBBB"
RECT_HALF = 0.45        # half height of a band in the stability map (gaps between lines)


def _class_keys(ds):
    """Stability classes present anywhere in the cube, in CLASSES order (NaN last)."""
    cls = stability_class(ds)
    keys = [float(i) for i in range(len(CLASSES)) if (cls == i).any()]
    return keys + ([np.nan] if np.isnan(cls).any() else [])


def _class_name(c):
    return UNCLASSIFIED if np.isnan(c) else CLASSES[int(c)]


def _class_colour(c):
    return UNCLASSIFIED_COLOUR if np.isnan(c) else PALETTE[int(c)]


def map_rectangles(ds, plan, where):
    """What one stability-map panel draws: ({class: [(x0, y0, x1, y1), ...]}, [(speed, band), ...]
    of the refined edges). Band i is the i-th value of plan['y'] (0 without one)."""
    y = plan["y"]
    bands = [None] if y is None else [float(v) for v in ds[y].values]
    rects, edges = {}, []
    for i, v in enumerate(bands):
        line = dict(where) if v is None else {**where, y: v}
        segments, refined = line_segments(ds, line)
        for lo, hi, c in segments:
            key = -1.0 if np.isnan(c) else c
            rects.setdefault(key, []).append((lo, i - RECT_HALF, hi, i + RECT_HALF))
        edges += [(e, i) for e in refined]
    return rects, edges


def _map_panel(hv, ds, plan, where, backend, title, legend, keys, show_x=True, show_y=True):
    """One stability-class map: each line's runs of one class as rectangles whose speed edges are
    the refined stability boundaries (boundary table), categorical colours, a legend."""
    rects, edges = map_rectangles(ds, plan, where)
    y = plan["y"]
    speed = ds["speed"].values
    x0 = float(speed[0])
    nbands = 1 if y is None else ds.sizes[y]
    elements = []
    for c in keys:
        rows = rects.get(-1.0 if np.isnan(c) else c, [])
        # an empty class still gets its legend entry (a zero-size rectangle)
        data = [(*r, _class_name(c), r[0], r[2]) for r in rows] or [(x0, 0, x0, 0, _class_name(c), x0, x0)]
        el = hv.Rectangles(data, vdims=["class", "from [Hz]", "to [Hz]"], label=_class_name(c))
        if backend == "bokeh":
            el = el.opts(color=_class_colour(c), line_width=0, tools=["hover"], backend=backend)
        else:
            el = el.opts(color=_class_colour(c), linewidth=0, backend=backend)
        elements.append(el)
    if refined_edges(ds, {}) or edges:
        segs = [(e, i - RECT_HALF, e, i + RECT_HALF) for e, i in edges] or [(x0, 0, x0, 0)]
        seg = hv.Segments(segs, label="refined boundary")
        elements.append(seg.opts(color="#000000", **_line_style(backend, 1.6 if backend == "bokeh" else 1.1),
                                 backend=backend))
    if y is None:
        yticks = [(0, "")]
    else:
        yticks = [(i, f"{v * DISPLAY[y][0]:.4g}") for i, v in enumerate(ds[y].values)]
    return hv.Overlay(elements).opts(
        xlim=_speed_edges(speed), ylim=(-0.5, nbands - 0.5), yticks=yticks,
        xlabel=_axis_label("speed") if show_x else "",
        ylabel=_axis_label(y) if (y and show_y) else "",
        title=title, show_legend=legend, legend_position="right",
        fontsize=_fonts(backend), backend=backend)


def fig_stability_map(ds, backend="bokeh"):
    """Stability-class map over speed x (first other swept axis), one panel per combination of
    the remaining swept axes (at most MAX_PANELS). Runs of one class are rectangles whose speed
    edges are the refined boundaries of the cube's boundary table (midway between grid speeds
    where there is none); a legend names the classes."""
    hv = _hv()
    plan = axes_plan(ds)
    keys = _class_keys(ds)
    head = "Stability-region map"
    n = len(plan["shown"])
    ncols = _ncols(n)
    strip = plan["y"] is None
    panels = []
    for k, where in enumerate(plan["shown"]):
        show_x, show_y = _grid_opts(k, n, backend)
        # matplotlib grid: one legend, on the first row's last panel
        legend = backend == "bokeh" or n == 1 or k == ncols - 1
        title = _where_label(where) if where else _figure_title(head, plan)
        p = _map_panel(hv, ds, plan, where, backend, title, legend, keys, show_x, show_y)
        if backend == "bokeh":
            size = (1150, 230 if strip else 480) if n == 1 else (600, 300)
            p = p.opts(width=size[0], height=size[1], backend=backend)
        else:
            p = p.opts(aspect=(7 if strip else 2.6) if n == 1 else 1.5, backend=backend)
        panels.append(p)
    rows = -(-n // ncols)
    inches = (11, 2.4 if strip else 4.6) if n == 1 else (10.3, 2.7 * rows + 0.8)
    return _layout(hv, panels, backend, ncols, _figure_title(head, plan), fig_inches=inches)


def _mu_range(ds):
    """(logy, ylim) shared by every panel of the max |multiplier| figure."""
    mu = ds["max_abs_multiplier"].values
    finite = mu[np.isfinite(mu) & (mu > 0)]
    if not finite.size:
        return False, (0.0, 1.5)
    lo, hi = float(finite.min()), float(finite.max())
    if hi > 5.0:        # a diverging orbit would flatten everything else on a linear axis
        return True, (min(lo, 1.0) / 1.3, hi * 1.3)
    return False, (max(0.0, min(lo, 1.0) - 0.05), max(hi, 1.0) + 0.08)


def _mu_panel(hv, sub, y, backend, title, legend, show_x=True, show_y=True):
    """Curves of max |multiplier| vs speed, one per value of y, plus the |lambda| = 1 line."""
    speed = sub["speed"].values
    curves = []
    values = sub[y].values if y else [None]
    for i, v in enumerate(values):
        line = sub.sel({y: v}) if y else sub
        label = f"{DISPLAY[y][2]} {_fmt(y, v)}" if y else "max |λ|"
        c = hv.Curve((speed, line["max_abs_multiplier"].values), "speed", "max_abs_multiplier",
                     label=label)
        width = {"line_width": 2} if backend == "bokeh" else {"linewidth": 1.8}
        curves.append(c.opts(color=LINE_COLOURS[i % len(LINE_COLOURS)], backend=backend, **width))
    ref = hv.Curve(([speed.min(), speed.max()], [1.0, 1.0]), "speed", "max_abs_multiplier",
                   label="|λ| = 1 (stability limit)")
    if backend == "bokeh":
        ref = ref.opts(color="#C00000", line_dash="dashed", line_width=2, backend=backend)
    else:
        ref = ref.opts(color="#C00000", linestyle="--", linewidth=1.5, backend=backend)
    return hv.Overlay(curves + [ref]).opts(
        xlabel=_axis_label("speed") if show_x else "", ylabel="max |multiplier|" if show_y else "",
        title=title, show_legend=legend, legend_position="right", show_grid=True,
        fontsize=_fonts(backend), backend=backend)


def fig_max_multiplier(ds, backend="bokeh"):
    """max |multiplier| vs speed, one line per value of the first other swept axis, the stability
    limit |lambda| = 1 dashed; one panel per facet combination as in the stability map."""
    hv = _hv()
    plan = axes_plan(ds)
    logy, ylim = _mu_range(ds)
    head = "Largest Floquet multiplier modulus vs shaft speed"
    n = len(plan["shown"])
    ncols = _ncols(n)
    panels = []
    for k, where in enumerate(plan["shown"]):
        show_x, show_y = _grid_opts(k, n, backend)
        legend = backend == "bokeh" or k == ncols - 1 or n == 1   # matplotlib grid: one legend
        title = _where_label(where) if where else _figure_title(head, plan)
        p = _mu_panel(hv, _select(ds, where), plan["y"], backend, title, legend, show_x, show_y)
        p = p.opts(logy=logy, ylim=ylim, backend=backend)
        if backend == "bokeh":
            p = p.opts(width=1150 if n == 1 else 560, height=440 if n == 1 else 300, backend=backend)
        else:
            # a numeric aspect is a data aspect in holoviews-mpl, wrong on a log axis
            aspect = "auto" if logy else 2.4 if n == 1 else 1.5
            p = p.opts(aspect=aspect, backend=backend)
        panels.append(p)
    rows = -(-n // ncols)
    inches = (11, 4.6) if n == 1 else (9.6, 2.7 * rows + 0.8)
    return _layout(hv, panels, backend, ncols, _figure_title(head, plan), fig_inches=inches)


def stability_boundaries(ds, intervals=None):
    """Stability boundaries chosen for the multiplier figure: up to MAX_BOUNDARIES entries
    {where: other-axis values, i_stable / i_unstable: speed indices of the grid points on either
    side, kind: 'onset' or 'end' of the unstable run, type: the run's type from
    query.unstable_intervals}. Runs that touch the end of the speed grid have no boundary there.
    Selection is deterministic: the first onset of each instability type, then evenly spaced
    picks among the rest, returned in cube order."""
    if intervals is None:
        intervals = query.unstable_intervals(ds)
    others = [a for a in schema.AXES if a in ds.dims and a != "speed"]
    speed = ds["speed"].values
    cands = []
    for iv in intervals:
        where = {a: iv[a] for a in others}
        i0 = int(np.argmin(np.abs(speed - iv["start"])))
        i1 = int(np.argmin(np.abs(speed - iv["end"])))
        if i0 > 0:
            cands.append({"where": where, "i_stable": i0 - 1, "i_unstable": i0, "kind": "onset",
                          "type": iv["type"]})
        if i1 < speed.size - 1:
            cands.append({"where": where, "i_stable": i1 + 1, "i_unstable": i1, "kind": "end",
                          "type": iv["type"]})
    if len(cands) <= MAX_BOUNDARIES:
        return cands
    chosen, seen = [], set()
    for i, c in enumerate(cands):     # first onset of each type (real bifurcations first)
        if c["kind"] == "onset" and c["type"] not in seen and c["type"] != "no_orbit":
            seen.add(c["type"])
            chosen.append(i)
    rest = [i for i in range(len(cands)) if i not in chosen]
    need = MAX_BOUNDARIES - len(chosen)
    if need > 0 and rest:
        picks = np.linspace(0, len(rest) - 1, min(need, len(rest))).round().astype(int)
        chosen += [rest[j] for j in sorted(set(picks))]
    return [cands[i] for i in sorted(chosen[:MAX_BOUNDARIES])]


_TYPE_NAMES = {"fold": "fold", "period_doubling": "period doubling",
               "neimark_sacker": "Neimark-Sacker", "no_orbit": "no periodic orbit",
               "none": "unclassified"}


def _boundary_title(b, speed):
    a, c = sorted((b["i_stable"], b["i_unstable"]))
    where = _where_label(b["where"], short=True)
    verb = "loses stability" if b["kind"] == "onset" else "regains stability"
    return f"{where}\n{verb} {speed[a]:.4g}-{speed[c]:.4g} Hz ({_TYPE_NAMES.get(b['type'], b['type'])})"


def fig_multiplier_paths(ds, backend="bokeh", intervals=None):
    """Floquet multipliers in the complex plane for the grid speeds around each chosen stability
    boundary, coloured by speed, unit circle drawn; one panel per boundary."""
    hv = _hv()
    bounds = stability_boundaries(ds, intervals)
    speed_all = ds["speed"].values
    theta = np.linspace(0, 2 * np.pi, 361)
    panels = []
    for b in bounds:
        lo = max(0, min(b["i_stable"], b["i_unstable"]) - BOUNDARY_POINTS + 1)
        hi = min(speed_all.size, max(b["i_stable"], b["i_unstable"]) + BOUNDARY_POINTS)
        line = _select(ds, b["where"]).isel(speed=slice(lo, hi))
        re = line["multiplier_real"].transpose("speed", "multiplier").values
        im = line["multiplier_imag"].transpose("speed", "multiplier").values
        sp = np.broadcast_to(line["speed"].values[:, None], re.shape)
        ok = np.isfinite(re) & np.isfinite(im)
        pts = hv.Points((re[ok], im[ok], sp[ok]), ["Re", "Im"], ["speed"])
        r = max(1.15, float(np.nanmax(np.hypot(re[ok], im[ok]))) * 1.1 if ok.any() else 1.15)
        circle = hv.Curve((np.cos(theta), np.sin(theta)), "Re", "Im")
        title = _boundary_title(b, speed_all)
        clim = (float(line["speed"].min()), float(line["speed"].max()))
        if backend == "bokeh":
            pts = pts.opts(color="speed", cmap="viridis", clim=clim, size=7, colorbar=True,
                           colorbar_opts={"title": "speed [Hz]"}, tools=["hover"], backend=backend)
            circle = circle.opts(color="#555555", line_dash="dashed", backend=backend)
            panel = (circle * pts).opts(title=title, xlim=(-r, r), ylim=(-r, r), width=400,
                                        height=340, data_aspect=1, xlabel="Re λ", ylabel="Im λ",
                                        fontsize=_fonts(backend), backend=backend)
        else:
            pts = pts.opts(color="speed", cmap="viridis", clim=clim, s=28, colorbar=True,
                           clabel="speed [Hz]", backend=backend)
            circle = circle.opts(color="#555555", linestyle="--", linewidth=1, backend=backend)
            panel = (circle * pts).opts(title=title, xlim=(-r, r), ylim=(-r, r), aspect="equal",
                                        xlabel="Re λ", ylabel="Im λ",
                                        fontsize={**_fonts(backend), "title": 10}, backend=backend)
        panels.append(panel)
    head = "Floquet multipliers around stability boundaries (unit circle dashed)"
    if not panels:
        empty = hv.Text(0, 0, "no stability boundary inside the speed grid")
        circle = hv.Curve((np.cos(theta), np.sin(theta)), "Re", "Im")
        common = dict(title=head, xlim=(-1.2, 1.2), ylim=(-1.2, 1.2), xlabel="Re λ",
                      ylabel="Im λ", fontsize=_fonts(backend), backend=backend)
        if backend == "bokeh":
            circle = circle.opts(color="#555555", line_dash="dashed", backend=backend)
            return (circle * empty.opts(text_align="center", backend=backend)).opts(
                width=600, height=560, data_aspect=1, **common)
        circle = circle.opts(color="#555555", linestyle="--", linewidth=1, backend=backend)
        return (circle * empty.opts(fontsize=12, backend=backend)).opts(
            aspect="equal", fig_inches=(7, 7), **common)
    n = len(panels)
    ncols = min(3, n)
    rows = -(-n // ncols)
    lay = _layout(hv, panels, backend, ncols, head, fig_inches=(10.8, 4.0 * rows + 0.6))
    if backend == "matplotlib" and n > 1:
        lay = lay.opts(hspace=0.6, vspace=0.5, backend=backend)
    return lay


# ----------------------------------------------------------------------------- attractor figures

# Poincare points per panel of the bifurcation diagram: per speed the distinct values (at a
# resolution of 1/THIN_LEVELS of the panel's range), evenly thinned to at most budget / speeds.
# 2401 speeds x 128 samples per line (Bai's Fig. 13) would be 1.5 M points: slow to draw with
# matplotlib and tens of MB in the HTML.
BIF_POINTS = {"matplotlib": 200_000, "bokeh": 40_000}
THIN_LEVELS = 1500
SWEEP_COLOURS = ("#111111", "#D55E00")       # up (the plain variables), down (_down)
HYSTERESIS_COLOUR = "#009E73"
SHADE_ALPHA = 0.28


def _points(hv, x, y, kdims, label):
    """hv.Points that keeps its legend entry when empty (one NaN point, drawn nowhere): the
    matplotlib grids show one legend for all panels, on a panel that may lack the group."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if not x.size:
        x, y = np.array([np.nan]), np.array([np.nan])
    return hv.Points((x, y), kdims, label=label)


def has_attractor(ds):
    """Whether the cube holds the attractor diagnostics ([analysis] attractor = true)."""
    return all(v in ds.variables for v in ("attractor", "period", "lle", "poincare_x"))


def has_down(ds):
    return "poincare_x" + schema.DOWN_SUFFIX in ds.variables


def sweep_labels(ds):
    """Legend labels of the plain and the _down variables: the plain ones sweep speed up, unless
    the scene swept only down."""
    direction = _scene_toml(ds).get("analysis", {}).get("sweep_direction", "up")
    return ("sweep down" if direction == "down" else "sweep up"), "sweep down"


def _scene_toml(ds):
    try:
        import tomllib
    except ImportError:          # Python 3.10
        import tomli as tomllib
    try:
        return tomllib.loads(ds.attrs.get("config_toml", ""))
    except Exception:
        return {}


def thin_points(speed, values, cap, resolution):
    """(speed, value) pairs to draw from values[speed, sample]: per speed the distinct finite
    values at `resolution`, and where there are more than `cap` of them every k-th in sorted
    order (an even thinning that keeps the spread of a chaotic cloud)."""
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
    sp = np.broadcast_to(np.asarray(speed, float)[:, None], values.shape)
    return sp[keep], vs[keep]


def _unstable_spans(ds, where):
    """[(lo, hi, class)] of one line where the period-1 orbit is not stable (refined edges);
    none where the scene did not compute periodic orbits."""
    line = _select(ds, where)
    if (line["orbit_status"].values == schema.ORBIT_STATUS.index("not_applicable")).all():
        return []
    return [(lo, hi, c) for lo, hi, c in line_segments(ds, where)[0] if not c == 0]


def _bif_range(values):
    finite = values[np.isfinite(values)]
    if not finite.size:
        return -1.0, 1.0
    lo, hi = float(finite.min()), float(finite.max())
    pad = 0.06 * (hi - lo) if hi > lo else max(0.05 * abs(hi), 0.05)
    return lo - pad, hi + pad


def _bif_panel(hv, ds, where, backend, title, legend, show_x, show_y, span_keys):
    line = _select(ds, where)
    speed = line["speed"].values.astype(float)
    labels = sweep_labels(ds)
    sweeps = [line["poincare_x"].transpose("speed", ...).values * 1e6]
    if has_down(line):
        sweeps.append(line["poincare_x" + schema.DOWN_SUFFIX].transpose("speed", ...).values * 1e6)
    ylim = _bif_range(np.concatenate([v.ravel() for v in sweeps]))
    height = ylim[1] - ylim[0]
    cap = int(np.clip(BIF_POINTS[backend] // max(speed.size * len(sweeps), 1), 4, sweeps[0].shape[1]))
    elements = []
    spans = _unstable_spans(ds, where)
    x0 = float(speed[0])
    for c in span_keys:      # every panel names every shaded class (one legend for all panels)
        rows = [(lo, ylim[0], hi, ylim[1]) for lo, hi, cc in spans
                if cc == c or (np.isnan(c) and np.isnan(cc))] or [(x0, ylim[0], x0, ylim[0])]
        el = hv.Rectangles(rows, label=f"orbit unstable: {_class_name(c)}")
        if backend == "bokeh":
            el = el.opts(color=_class_colour(c), alpha=SHADE_ALPHA, line_width=0, backend=backend)
        else:
            el = el.opts(color=_class_colour(c), alpha=SHADE_ALPHA, linewidth=0, backend=backend)
        elements.append(el)
    dot = float(np.clip(300.0 / max(speed.size, 1), 1.0, 5.0))
    for k in reversed(range(len(sweeps))):       # down first: the up sweep is drawn on top
        sp, val = thin_points(speed, sweeps[k], cap, height / THIN_LEVELS)
        pts = _points(hv, sp, val, ["speed", "poincare_x"], labels[k])
        if backend == "bokeh":
            pts = pts.opts(color=SWEEP_COLOURS[k], size=dot + (1 if k else 0), line_width=0,
                           backend=backend)
        else:
            size = float(np.clip(28.0 / np.sqrt(max(speed.size, 1)), 0.55, 3.2)) * (1.3 if k else 1.0)
            pts = pts.opts(color=SWEEP_COLOURS[k], s=size ** 2, linewidth=0, backend=backend)
        elements.append(pts)
    if "hysteresis" in line:
        hs = speed[line["hysteresis"].values == 1]
        yy = np.full(hs.size, ylim[1] - 0.04 * height)
        mark = _points(hv, hs, yy, ["speed", "poincare_x"], "hysteresis (up and down differ)")
        elements.append(mark.opts(**_marker_style(backend, HYSTERESIS_COLOUR, 7, "v"), backend=backend))
    overlay = hv.Overlay(elements).opts(
        xlim=_speed_edges(speed), ylim=ylim, title=title, show_legend=legend,
        legend_position="right", xlabel=_axis_label("speed") if show_x else "",
        ylabel="Poincaré x [µm]" if show_y else "", fontsize=_fonts(backend), backend=backend)
    if backend == "matplotlib":
        overlay = overlay.opts(hooks=[_legend_markers], backend=backend)
    return overlay


def _line_figure(ds, backend, head, panel):
    """One panel per line (line_plan), stacked in one column (two beyond six lines)."""
    hv = _hv()
    plan = line_plan(ds)
    n = len(plan["shown"])
    ncols = 1 if n <= 6 else 2
    panels = []
    for k, where in enumerate(plan["shown"]):
        show_x = backend == "bokeh" or k + ncols >= n
        show_y = backend == "bokeh" or k % ncols == 0
        legend = backend == "bokeh" or k == ncols - 1
        title = _where_label(where) if where else _figure_title(head, plan)
        p = panel(hv, ds, where, backend, title, legend, show_x, show_y)
        if backend == "bokeh":
            p = p.opts(width=1150 if ncols == 1 else 620, height=440 if n == 1 else 300, backend=backend)
        else:
            p = p.opts(aspect=2.6 if n == 1 else 4.6 if ncols == 1 else 2.2, backend=backend)
        panels.append(p)
    rows = -(-n // ncols)
    inches = (11, 2.1 * rows + 0.8)
    if backend == "matplotlib" and n > 1:
        return hv.Layout(panels).cols(ncols).opts(
            title=_figure_title(head, plan), sublabel_format="", fig_inches=inches, hspace=0.15,
            vspace=0.45, fontsize={"title": 13}, backend=backend)
    return _layout(hv, panels, backend, ncols, _figure_title(head, plan),
                   fig_inches=(11, 4.6 if n == 1 else inches[1]))


def fig_bifurcation(ds, backend="bokeh"):
    """Bifurcation diagram: the Poincare section's x (once per forcing period) vs shaft speed,
    one panel per line; intervals where the period-1 orbit is unstable shaded behind the dots
    (refined edges), the down sweep in a second colour, hysteresis speeds marked."""
    keys = sorted({c for where in line_plan(ds)["shown"] for _, _, c in _unstable_spans(ds, where)},
                  key=lambda c: (np.isnan(c), c))
    head = "Bifurcation diagram (Poincaré section once per forcing period)"

    def panel(hv, ds, where, backend, title, legend, show_x, show_y):
        return _bif_panel(hv, ds, where, backend, title, legend, show_x, show_y, keys)
    return _line_figure(ds, backend, head, panel)


LLE_COLOURS = {"integrated": "#0072B2", "derived": "#999999", "chaotic": "#CC0000", "band": "#56B4E9"}


def _lle_panel(hv, ds, where, backend, title, legend, show_x, show_y):
    line = _select(ds, where)
    speed = line["speed"].values.astype(float)
    lle = line["lle"].values.astype(float)
    err = np.nan_to_num(line["lle_stderr"].values.astype(float), nan=0.0)
    method = line["lle_method"].values
    cls = line["attractor"].values
    ok = np.isfinite(lle)
    labels = sweep_labels(ds)
    elements = [
        hv.Spread((speed[ok], lle[ok], err[ok]), "speed", ["lle", "stderr"], label="± standard error")
        .opts(color=LLE_COLOURS["band"], alpha=0.35, backend=backend,
              **({"line_width": 0} if backend == "bokeh" else {"linewidth": 0})),
        hv.HLine(0.0).opts(color="#444444", **_line_style(backend, 1.0, dash=True), backend=backend),
        hv.Curve((speed, lle), "speed", "lle", label=labels[0])
        .opts(color="#555555", **_line_style(backend, 0.8), backend=backend),
    ]
    if has_down(line):
        down = line["lle" + schema.DOWN_SUFFIX].values.astype(float)
        elements.append(hv.Curve((speed, down), "speed", "lle", label=labels[1])
                        .opts(color=SWEEP_COLOURS[1], **_line_style(backend, 1.2, dash=True),
                              backend=backend))
    if backend == "bokeh":
        size = float(np.clip(260.0 / max(speed.size, 1), 3.0, 7.0))
    else:
        size = float(np.clip(40.0 / np.sqrt(max(speed.size, 1)), 1.6, 5.0))
    groups = (("integrated", method == 0, "o", False, "integrated (Benettin/QR)"),
              ("derived", method == 1, "^", False, "derived ln|λ|/(kT)"),
              ("chaotic", cls == 3, "o", True, "chaotic attractor"))
    for key, mask, marker, hollow, label in groups:
        m = mask & ok
        pts = _points(hv, speed[m], lle[m], ["speed", "lle"], label)
        style = _marker_style(backend, LLE_COLOURS[key], size * (1.9 if hollow else 1.0), marker, hollow)
        elements.append(pts.opts(**style, backend=backend))
    overlay = hv.Overlay(elements).opts(
        xlim=_speed_edges(speed), title=title, show_legend=legend, legend_position="right",
        show_grid=True, xlabel=_axis_label("speed") if show_x else "",
        ylabel="largest Lyapunov exp. [1/s]" if show_y else "", fontsize=_fonts(backend),
        backend=backend)
    if backend == "matplotlib":
        overlay = overlay.opts(hooks=[_legend_markers], backend=backend)
    return overlay


def fig_lle(ds, backend="bokeh"):
    """Largest Lyapunov exponent vs shaft speed, one panel per line: ± standard error band,
    zero line, integrated and derived estimates as different markers, chaotic points ringed."""
    return _line_figure(ds, backend, "Largest Lyapunov exponent vs shaft speed (shaded: ± standard error)",
                        _lle_panel)


# (PNG name, HTML caption) of each figure, in report order
FIGURES = (("stability_map.png", "Stability-region map"),
           ("max_multiplier.png", "Largest Floquet multiplier vs shaft speed"),
           ("multiplier_paths.png", "Floquet multipliers around stability boundaries"))
# and for cubes with the attractor diagnostics
ATTRACTOR_FIGURES = (("bifurcation.png", "Bifurcation diagram"),
                     ("lle.png", "Largest Lyapunov exponent vs shaft speed"))


def report_figures(ds):
    """(PNG name, HTML caption) of the figures of this cube's report, in order."""
    return FIGURES + (ATTRACTOR_FIGURES if has_attractor(ds) else ())


def build_figures(ds, backend, intervals=None):
    """The report's figures, in report_figures order, built for `backend` ('bokeh' or
    'matplotlib')."""
    figs = [fig_stability_map(ds, backend), fig_max_multiplier(ds, backend),
            fig_multiplier_paths(ds, backend, intervals)]
    if has_attractor(ds):
        figs += [fig_bifurcation(ds, backend), fig_lle(ds, backend)]
    return figs


# ----------------------------------------------------------------------------- one point in detail

POINT_PERIODS = 256        # forcing periods of the trajectory drawn at a --point
POINT_STEPS = 64           # samples per forcing period (the Poincare section is every 64th)
SPECTRUM_HARMONICS = 3.3   # spectrum drawn up to this multiple of the ball-passage frequency


def parse_point(items):
    """`AXIS=VALUE` strings (several per string allowed, separated by spaces or commas) ->
    {axis: float}, e.g. ["speed=36", "clearance=19e-6"] -> {"speed": 36.0, "clearance": 1.9e-05}."""
    import re

    items = [items] if isinstance(items, str) else list(items)
    point = {}
    for item in items:
        for token in (t for t in re.split(r"[\s,]+", str(item).strip()) if t):
            axis, sep, value = (part.strip() for part in token.partition("="))
            if not sep or not axis or not value:
                raise query.QueryError(f"bad point item {token!r}: expected AXIS=VALUE, e.g. speed=36")
            if axis not in schema.AXES:
                raise query.QueryError(f"unknown axis {axis!r} in point {token!r}; "
                                       f"the axes are {', '.join(schema.AXES)}")
            if axis in point:
                raise query.QueryError(f"{axis} is given twice in one point")
            try:
                point[axis] = float(value)
            except ValueError:
                raise query.QueryError(f"bad number {value!r} in point item {token!r}") from None
    return point


def _span(axis, grid):
    unit = schema.AXES[axis][0]
    if grid.size == 1:
        return f"{grid[0]:g} {unit}"
    return f"{grid.min():g} .. {grid.max():g} {unit} ({grid.size} values)"


def resolve_point(ds, spec):
    """The grid point nearest to `spec` ({axis: value}, SI units and degrees, or AXIS=VALUE
    strings): {"values": {axis: grid value}, "index": {axis: index}, "asked": spec}. Every swept
    axis with more than one value must be given; a value outside the grid is an error naming
    the valid range."""
    asked = spec if isinstance(spec, dict) else parse_point(spec)
    swept = [a for a in schema.AXES if a in ds.dims]
    for axis in asked:
        if axis not in swept:
            raise query.QueryError(f"point: {axis} is not swept in this cube; its axes are "
                                   f"{', '.join(f'{a} ({_span(a, ds[a].values)})' for a in swept)}")
    values, index = {}, {}
    for axis in swept:
        grid = ds[axis].values.astype(float)
        if axis not in asked:
            if grid.size == 1:
                values[axis], index[axis] = float(grid[0]), 0
                continue
            raise query.QueryError(f"point: give {axis}=VALUE too; the cube sweeps {axis} over "
                                   f"{_span(axis, grid)}")
        v = float(asked[axis])
        tol = 1e-9 * max(abs(grid.min()), abs(grid.max()), 1e-300)
        if not np.isfinite(v) or v < grid.min() - tol or v > grid.max() + tol:
            raise query.QueryError(f"point {axis}={v:g} is outside the cube's grid: {axis} spans "
                                   f"{_span(axis, grid)}")
        i = int(np.argmin(np.abs(grid - v)))
        values[axis], index[axis] = float(grid[i]), i
    return {"values": values, "index": index, "asked": dict(asked)}


def scene_data(ds):
    """The validated scene of a cube (config_toml), which --point needs to recompute a point."""
    from pipeline import config as config_mod

    text = ds.attrs.get("config_toml")
    if not text:
        raise query.QueryError("point: this cube stores no scene (config_toml attribute); "
                               "a point cannot be recomputed")
    try:
        return config_mod.parse_config(text, path="<cube config_toml>", allow_large=True).data
    except config_mod.ConfigError as exc:
        raise query.QueryError(f"point: the cube's scene (config_toml) is not a valid config, "
                               f"so the point cannot be recomputed: {exc}") from None


def point_filename(resolved):
    """point_<speed>Hz_<clearance>um[_<angle>deg][_<preload>N].png (the swept axes)."""
    parts = []
    for axis, value in resolved["values"].items():
        factor, unit, _ = DISPLAY[axis]
        parts.append(f"{value * factor:.6g}{'um' if axis == 'clearance' else unit}")
    return "point_" + "_".join(parts).replace("+", "") + ".png"


_POINT_CUBE_VARS = ("orbit_status", "stable", "bifurcation", "max_abs_multiplier", "multiplier_real",
                    "multiplier_imag", "forcing_period", "attractor", "period", "lle", "lle_stderr",
                    "lle_method", "poincare_x", "poincare_y", "attractor_multiplier_real",
                    "attractor_multiplier_imag", "attractor_state")


def compute_point(ds, data, resolved):
    """Recompute one grid point for the report (pipeline.compute.point_detail): a trajectory on
    the attractor the sweep found there (started from the cube's attractor_state; a second one
    from attractor_state_down where the down sweep ended elsewhere), plus the cube's values."""
    from pipeline import compute

    fixed = compute.fixed_values(data)
    values = resolved["values"]
    point = {"speed": values["speed"],
             **{k: values.get(k, fixed[k]) for k in ("clearance", "contact_angle", "preload")}}
    sub = ds.isel(resolved["index"])
    names = [n + sfx for n in _POINT_CUBE_VARS for sfx in ("", schema.DOWN_SUFFIX)
             if n + sfx in sub.variables] + (["hysteresis"] if "hysteresis" in sub.variables else [])
    cube_values = {n: np.asarray(sub[n].values) for n in names}
    runs = []
    sweeps = [("", sweep_labels(ds)[0])]
    if "attractor_state" + schema.DOWN_SUFFIX in cube_values and int(cube_values.get("hysteresis", 0)) == 1:
        sweeps.append((schema.DOWN_SUFFIX, sweep_labels(ds)[1]))
    for suffix, label in sweeps:
        state = cube_values.get("attractor_state" + suffix)
        start = state if state is not None and np.all(np.isfinite(state)) else None
        detail = compute.point_detail(data, point, start_state=start, periods=POINT_PERIODS,
                                      steps_per_period=POINT_STEPS)
        runs.append({"suffix": suffix, "label": label, "detail": detail, "from_cube": start is not None})
    return {"resolved": resolved, "point": point, "cube": cube_values, "runs": runs,
            "labels": sweep_labels(ds)}


def _mult_text(re, im):
    re, im = np.asarray(re, float), np.asarray(im, float)
    if not np.isfinite(re).any():
        return "-"
    out, skip = [], False
    pairs = [(a, b) for a, b in zip(re, im) if np.isfinite(a)]
    for j, (a, b) in enumerate(pairs):
        if skip:
            skip = False
            continue
        if abs(b) < 1e-12:
            out.append(f"{a:.4g}")
        elif j + 1 < len(pairs) and np.isclose(pairs[j + 1][0], a) and np.isclose(pairs[j + 1][1], -b):
            out.append(f"{a:.4g}±{abs(b):.4g}i")
            skip = True
        else:
            out.append(f"{a:.4g}{b:+.4g}i")
    return ", ".join(out) + f"  (max |λ| {np.nanmax(np.hypot(re, im)):.4g})"


def _attractor_text(values, suffix=""):
    """(class, period, lle) strings of a cube row or point_detail row."""
    code = int(values["attractor" + suffix])
    name = schema.ATTRACTOR[code].replace("_", "-") if 0 <= code < len(schema.ATTRACTOR) else "-"
    k = int(values["period" + suffix])
    period = f"{k} forcing period{'s' if k != 1 else ''}" if k > 0 else "none found (up to max_period)"
    lle, err = float(values["lle" + suffix]), float(values["lle_stderr" + suffix])
    m = int(values["lle_method" + suffix])
    method = schema.LLE_METHOD[m] if 0 <= m < len(schema.LLE_METHOD) else "-"
    lle_text = f"{lle:+.4g} ± {err:.2g} 1/s ({method})" if np.isfinite(lle) else "-"
    mult = _mult_text(values["attractor_multiplier_real" + suffix], values["attractor_multiplier_imag" + suffix])
    return name, period, lle_text, mult


def point_rows(pt):
    """The table of a --point: [(quantity, value)]."""
    cube, values = pt["cube"], pt["resolved"]["values"]
    row = pt["runs"][0]["detail"]["row"]
    asked = pt["resolved"]["asked"]
    where = ", ".join(f"{DISPLAY[a][2]} {_fmt(a, v)}" for a, v in values.items())
    moved = [a for a, v in asked.items() if not np.isclose(v, values[a], rtol=1e-9, atol=0)]
    if moved:
        where += " (nearest grid point to " + ", ".join(f"{a}={asked[a]:g}" for a in moved) + ")"
    period_T = float(row["forcing_period"])
    rows = [("grid point", where),
            ("forcing period T", f"{period_T * 1e3:.4g} ms: ball passage {1 / period_T:.5g} Hz, "
                                 f"shaft {values['speed']:.5g} Hz")]
    src = cube if "multiplier_real" in cube else row
    status = int(src["orbit_status"])
    if status == 0:
        verdict = "stable" if int(src["stable"]) == 1 else \
            f"unstable ({_TYPE_NAMES.get(schema.BIFURCATION[int(src['bifurcation'])], '-')})"
    elif status == schema.ORBIT_STATUS.index("not_applicable"):
        verdict = "not computed ([analysis] floquet = false)"
    else:
        verdict = f"not found ({schema.ORBIT_STATUS[status]})" if 0 <= status < 4 else "-"
    rows.append(("periodic orbit (period T)", verdict))
    rows.append(("  multipliers", _mult_text(src["multiplier_real"], src["multiplier_imag"])))
    if "attractor" in cube:
        sweeps = [("", pt["labels"][0])]
        if "attractor" + schema.DOWN_SUFFIX in cube:
            sweeps.append((schema.DOWN_SUFFIX, pt["labels"][1]))
        for suffix, label in sweeps:
            name, period, lle, mult = _attractor_text(cube, suffix)
            rows += [(f"attractor ({label}, cube)", name), ("  period", period),
                     ("  largest Lyapunov exp.", lle), ("  multipliers (kT orbit)", mult)]
        if "hysteresis" in cube:
            rows.append(("hysteresis", "yes: the sweeps end on different attractors"
                         if int(cube["hysteresis"]) == 1 else "no"))
    else:
        name, period, lle, mult = _attractor_text(row)
        rows += [("attractor (computed now)", name), ("  period", period),
                 ("  largest Lyapunov exp.", lle), ("  multipliers (kT orbit)", mult)]
    start = "the cube's attractor_state" if pt["runs"][0]["from_cube"] else "the periodic orbit (diagnosed now)"
    rows.append(("trajectory", f"{POINT_PERIODS} forcing periods from {start}"))
    return rows


def _point_title(pt):
    return "Point " + ", ".join(f"{DISPLAY[a][2]} {_fmt(a, v)}" for a, v in pt["resolved"]["values"].items())


def fig_point(pt, backend="bokeh", table=True):
    """Orbit (x vs y), Poincare section, power spectrum of x and (table=True) the point's table."""
    hv = _hv()
    colours = SWEEP_COLOURS
    orbit, poinc, spec = [], [], []
    speed = pt["resolved"]["values"]["speed"]
    row = pt["runs"][0]["detail"]["row"]
    f_bp = 1.0 / float(row["forcing_period"])
    pmax = 0.0
    for k, run in enumerate(pt["runs"]):
        d, colour, label = run["detail"], colours[k], run["label"]
        x, y = d["x"] * 1e6, d["y"] * 1e6
        orbit.append(hv.Curve((x, y), "x", "y", label=label)
                     .opts(color=colour, **_line_style(backend, 0.9 if backend == "bokeh" else 0.6, alpha=0.8),
                           backend=backend))
        cube_x = pt["cube"].get("poincare_x" + run["suffix"])
        if cube_x is not None and np.isfinite(cube_x).any():
            cy = pt["cube"]["poincare_y" + run["suffix"]]
            poinc.append(hv.Points((cube_x * 1e6, cy * 1e6), ["x", "y"], label=f"{label}: cube samples")
                         .opts(**_marker_style(backend, colour, 6 if backend == "bokeh" else 4.5), backend=backend))
        sx, sy = x[::POINT_STEPS], y[::POINT_STEPS]
        poinc.append(hv.Points((sx, sy), ["x", "y"], label=f"{label}: this trajectory")
                     .opts(**_marker_style(backend, colour, 9 if backend == "bokeh" else 6.5, "o", hollow=True,
                                           alpha=0.6), backend=backend))
        f, pw = np.asarray(d["frequency"]), np.asarray(d["power"]) * 1e12
        keep = (f > 0) & (f <= SPECTRUM_HARMONICS * f_bp)
        if keep.any():
            pmax = max(pmax, float(np.nanmax(pw[keep])))
            spec.append((f[keep], pw[keep], colour, label))
    floor = pmax * 1e-9 if pmax > 0 else 1e-12
    curves = [hv.Curve((f, np.maximum(p, floor)), "frequency", "power", label=lab)
              .opts(color=c, **_line_style(backend, 1.0), backend=backend) for f, p, c, lab in spec]
    marks = [(speed, "shaft", "#009E73", False), (f_bp, "ball passage 1/T", "#CC79A7", True)]
    k_att = int(pt["cube"].get("period", row["period"]))
    if k_att > 1:
        marks.append((f_bp / k_att, f"1/({k_att}T)", "#E69F00", True))
    top = max(pmax, floor) * 3e3        # room for the legend above the peaks
    for fm, name, c, dash in marks:
        curves.append(hv.Curve(([fm, fm], [floor, top]), "frequency", "power", label=f"{name} {fm:.4g} Hz")
                      .opts(color=c, **_line_style(backend, 1.3, dash=dash), backend=backend))
    fonts = _fonts(backend)
    o = hv.Overlay(orbit).opts(title="orbit", xlabel="x [µm]", ylabel="y [µm]", show_legend=len(orbit) > 1,
                               fontsize=fonts, backend=backend)
    q = hv.Overlay(poinc).opts(title="Poincaré section (once per forcing period)", xlabel="x [µm]",
                               ylabel="y [µm]", show_legend=True, legend_position="bottom_right" if backend == "bokeh" else "best",
                               fontsize=fonts, backend=backend)
    sp = hv.Overlay(curves).opts(title="power spectrum of x", xlabel="frequency [Hz]",
                                 ylabel="power [µm²]", logy=True, ylim=(floor, top),
                                 xlim=(0, SPECTRUM_HARMONICS * f_bp), show_legend=True,
                                 legend_position="top_right" if backend == "bokeh" else "best",
                                 fontsize=fonts, backend=backend)
    title = _point_title(pt)
    if backend == "bokeh":
        o = o.opts(width=380, height=360, backend=backend)
        q = q.opts(width=380, height=360, backend=backend)
        sp = sp.opts(width=560, height=360, backend=backend)
        return hv.Layout([o, q, sp]).cols(3).opts(title=title, shared_axes=False, backend=backend)
    # "auto": a numeric aspect is a data aspect in holoviews-mpl, wrong on the log axis
    o, q, sp = (p.opts(aspect="auto", backend=backend) for p in (o, q, sp))
    panels = [o, q, sp]
    if table:
        panels.append(_text_table(hv, point_rows(pt), backend))
    return hv.Layout(panels).cols(2).opts(title=title, sublabel_format="", fig_inches=(12, 10),
                                         hspace=0.3, vspace=0.35, fontsize={"title": 13},
                                         backend=backend)


def _text_table(hv, rows, backend):
    """A two-column table as text in a frameless panel (matplotlib; hv.Table's cells shrink
    their font to fit)."""
    n = len(rows)
    texts = []
    for i, (key, value) in enumerate(rows):
        yy = n - i - 0.5
        texts.append(hv.Text(-0.08, yy, key, halign="left", fontsize=8.5))
        texts.append(hv.Text(0.36, yy, value, halign="left", fontsize=8.5))
    return hv.Overlay(texts).opts(xlim=(0, 1), ylim=(0, n), xaxis=None, yaxis=None, aspect="auto",
                                  title="this point", show_frame=False, backend=backend)


# ----------------------------------------------------------------------------- tables, header

def interval_rows(ds, intervals, machine=False):
    """The unstable-interval table as (header, rows of strings) in display units. machine=True:
    ASCII header and the query's type codes (fold, period_doubling, neimark_sacker, no_orbit),
    for the CSV."""
    others = [a for a in schema.AXES if a in ds.dims and a != "speed"]
    header = [_axis_label(a) for a in others] + ["start [Hz]", "end [Hz]", "refined onset [Hz]",
                                                  "refined offset [Hz]", "points", "type",
                                                  "max |multiplier|"]
    rows = []
    for iv in intervals:
        rows.append([f"{iv[a] * DISPLAY[a][0]:.6g}" for a in others]
                    + [f"{iv['start']:.6g}", f"{iv['end']:.6g}", _refined(iv, "onset"),
                       _refined(iv, "offset"), str(iv["n_points"]),
                       iv["type"] if machine else _TYPE_NAMES.get(iv["type"], iv["type"]),
                       f"{iv['max_abs_multiplier']:.4g}"])
    if machine:
        header = [h.replace("µ", "u").replace("|multiplier|", "abs multiplier") for h in header]
    return header, rows


def _refined(iv, key):
    value = iv.get(key, float("nan"))
    return f"{value:.8g}" if np.isfinite(value) else "-"


def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def counts(ds):
    """({orbit_status name: n}, {stability class name: n}) over all points."""
    status = ds["orbit_status"].values.ravel()
    by_status = {}
    for code, name in enumerate(schema.ORBIT_STATUS):
        by_status[name] = int((status == code).sum())
    missing = int((~np.isin(status, range(len(schema.ORBIT_STATUS)))).sum())
    if missing:
        by_status["missing"] = missing
    cls = stability_class(ds).ravel()
    by_class = {name: int((cls == i).sum()) for i, name in enumerate(CLASSES)}
    if np.isnan(cls).any():
        by_class[UNCLASSIFIED] = int(np.isnan(cls).sum())
    return by_status, by_class


def attractor_counts(ds, suffix=""):
    """{label: n} of the attractor classes of one sweep direction: periodic by period k (and
    'period not resolved' for a periodic class without k), quasi-periodic, chaotic, diverged
    (always listed) and not computed (when any)."""
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
    missing = int((cls == schema.ATTRACTOR.index("not_computed")).sum()
                  + (~np.isin(cls, range(len(schema.ATTRACTOR)))).sum())
    if missing:
        out["not computed"] = missing
    return out


def _scene_name(ds):
    toml = ds.attrs.get("config_toml", "")
    try:
        import tomllib
        name = tomllib.loads(toml).get("scene", {}).get("name")
    except Exception:
        name = None
    return name or ds.attrs.get("scene") or ds.attrs.get("title") or "rotorsweep cube"


def _html_table(header, rows):
    if not rows:
        return "<p><b>no unstable intervals</b> (every converged orbit on the grid is stable)</p>"
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "\n".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in rows)
    return f'<table class="intervals"><thead><tr>{head}</tr></thead>\n<tbody>\n{body}\n</tbody></table>'


def _header_html(ds, title, plan):
    by_status, by_class = counts(ds)
    n = int(np.prod([ds.sizes[a] for a in schema.AXES if a in ds.dims]))
    grid = " x ".join(f"{ds.sizes[a]} {DISPLAY[a][2]}" for a in schema.AXES if a in ds.dims)
    li = lambda d: "".join(f"<li>{html.escape(k)}: {v}</li>" for k, v in d.items())  # noqa: E731
    parts = [
        f"<h1>{html.escape(title)}</h1>",
        f"<p>scene <b>{html.escape(_scene_name(ds))}</b> &middot; config hash "
        f"<code>{html.escape(str(ds.attrs.get('config_hash', 'n/a')))}</code> &middot; "
        f"{n} grid points ({html.escape(grid)})</p>",
    ]
    if plan["fixed"]:
        parts.append(f"<p>fixed: {html.escape(_fixed_note(plan))}</p>")
    boxes = [f"<div><b>orbit status</b><ul>{li(by_status)}</ul></div>",
             f"<div><b>stability class</b><ul>{li(by_class)}</ul></div>"]
    if has_attractor(ds):
        labels = sweep_labels(ds)
        boxes.append(f"<div><b>attractor ({labels[0]})</b><ul>{li(attractor_counts(ds))}</ul></div>")
        if "attractor" + schema.DOWN_SUFFIX in ds:
            down = attractor_counts(ds, schema.DOWN_SUFFIX)
            if "hysteresis" in ds:
                down["hysteresis (sweeps end on different attractors)"] = int((ds["hysteresis"].values == 1).sum())
            boxes.append(f"<div><b>attractor ({labels[1]})</b><ul>{li(down)}</ul></div>")
    parts.append('<div style="display:flex;gap:4em">' + "".join(boxes) + "</div>")
    if plan["omitted"]:
        om = "; ".join(_where_label(c) for c in plan["omitted"])
        parts.append(f"<p><b>Panels omitted</b> (at most {MAX_PANELS} shown): {html.escape(om)}</p>")
    return "\n".join(parts)


_CSS = """<style>
table.intervals {border-collapse: collapse; font-family: sans-serif; font-size: 10pt}
table.intervals th, table.intervals td {border: 1px solid #bbb; padding: 2px 8px; text-align: right}
table.intervals th {background: #eef2f6}
body {font-family: sans-serif; margin: 1.5em 2em; max-width: 1250px}
div.figure {margin: 1.5em 0}
pre.config {background: #f6f6f6; border: 1px solid #ddd; padding: 8px; font-size: 9pt}
table.point {border-collapse: collapse; font-family: sans-serif; font-size: 10pt}
table.point th, table.point td {border: 1px solid #ccc; padding: 2px 8px; text-align: left}
table.point th {background: #eef2f6; font-weight: normal}
</style>"""


# ----------------------------------------------------------------------------- entry point

# attractor variables the report's figures and header read (with their _down twins)
_ATTRACTOR_VARS = ("attractor", "period", "lle", "lle_stderr", "lle_method", "poincare_x")


def _load(ds):
    """The variables the figures, tables and header need, in memory (not the Poincare y or the
    Lyapunov spectrum: a Fig. 13 cube holds 1.5 M Poincare samples per variable)."""
    names = [v for v in _VARS if v in ds.variables]
    names += [v + sfx for v in _ATTRACTOR_VARS for sfx in ("", schema.DOWN_SUFFIX) if v + sfx in ds.variables]
    names += [v for v in ("hysteresis",) if v in ds.variables]
    names += [v for v in ds.data_vars if ds[v].dims == ("boundary",)]     # the boundary table
    return ds[names].load()


def make_report(ds, out_dir, title=None, points=None):
    """Write report.html, the figures as PNGs (report_figures: stability_map, max_multiplier,
    multiplier_paths, and for cubes with attractor diagnostics bifurcation and lle) and
    unstable_intervals.csv into out_dir. points: grid points to show in detail ({axis: value}
    dicts or AXIS=VALUE strings, nearest grid point, see resolve_point), one
    point_<speed>Hz_<clearance>um.png each. Returns {"html": Path, "png": [Path, ...] (figures,
    then points), "csv": Path, "points": [Path, ...]}."""
    resolved = []
    for spec in points or []:       # every point is checked before anything is drawn
        r = resolve_point(ds, spec)
        if all(r["values"] != other["values"] for other in resolved):
            resolved.append(r)
    scene = scene_data(ds) if resolved else None
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    data = _load(ds)
    title = title or f"Stability report: {_scene_name(ds)}"
    plan = axes_plan(data)
    intervals = query.unstable_intervals(data)
    header, rows = interval_rows(data, intervals)
    csv_path = out / "unstable_intervals.csv"
    write_csv(csv_path, *interval_rows(data, intervals, machine=True))
    details = [compute_point(ds, scene, r) for r in resolved]

    pngs, point_pngs = [], []
    with _backend("matplotlib") as hv:
        for (name, _), obj in zip(report_figures(data), build_figures(data, "matplotlib", intervals)):
            hv.save(obj, out / name, backend="matplotlib", dpi=DPI)
            pngs.append(out / name)
        for pt in details:
            path = out / point_filename(pt["resolved"])
            hv.save(fig_point(pt, "matplotlib"), path, backend="matplotlib", dpi=DPI)
            point_pngs.append(path)

    html_path = out / "report.html"
    with _backend("bokeh"):
        figs = list(zip([caption for _, caption in report_figures(data)],
                        build_figures(data, "bokeh", intervals)))
        point_sections = [(_point_title(pt), fig_point(pt, "bokeh"), _html_rows(point_rows(pt)))
                          for pt in details]
        _save_html(html_path, title, _header_html(data, title, plan), figs,
                   _html_table(header, rows), ds.attrs.get("config_toml", ""), point_sections)
    return {"html": html_path, "png": pngs + point_pngs, "csv": csv_path, "points": point_pngs}


def _html_rows(rows):
    body = "\n".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>" for k, v in rows)
    return f'<table class="point">\n{body}\n</table>'


def _save_html(path, title, header_html, figs, table_html, config_toml, points=()):
    """A plain HTML page: the header, tables and config as HTML, the figures ((caption, figure)
    pairs, then the points' (title, figure, table HTML)) as bokeh components, with bokeh's
    JavaScript inlined (no network). Panel's own save() would link its theme CSS from a CDN
    even with inline resources."""
    from bokeh.embed import components
    from bokeh.embed.bundle import bundle_for_objs_and_resources
    from bokeh.resources import INLINE

    hv = _hv()
    models = [hv.render(fig, backend="bokeh") for _, fig in figs]
    models += [hv.render(fig, backend="bokeh") for _, fig, _ in points]
    script, divs = components(models)
    # only the JavaScript these models need (bokeh's INLINE.render() would add every registered
    # extension, Panel's included, some of which load relative URLs)
    bundle = bundle_for_objs_and_resources(models, INLINE)
    resources = bundle.scripts() + "".join(f"<style>{css}</style>" for css in bundle.css_raw)
    body = [header_html]
    for (caption, _), div in zip(figs, divs):
        body.append(f'<h2>{html.escape(caption)}</h2>\n<div class="figure">{div}</div>')
    if points:
        body.append("<h2>Points in detail</h2>")
    for (name, _, rows_html), div in zip(points, divs[len(figs):]):
        body.append(f'<h3>{html.escape(name)}</h3>\n<div class="figure">{div}</div>\n{rows_html}')
    body.append("<h2>Unstable speed intervals</h2>" + table_html)
    body.append('<h2>Configuration</h2><pre class="config">'
                + html.escape(config_toml or "(no config_toml in the cube)") + "</pre>")
    page = ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{html.escape(title)}</title>\n{resources}\n{_CSS}\n</head>\n"
            "<body>\n" + "\n".join(body) + f"\n{script}\n</body>\n</html>\n")
    Path(path).write_text(page, encoding="utf-8")

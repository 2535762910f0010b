"""Stability-map report of a result cube: one self-contained HTML page plus PNGs and a CSV.

    make_report(ds, out_dir) -> {"html": Path, "png": [Path, ...], "csv": Path}

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
    if len(combos) > MAX_PANELS:
        keep = sorted(set(np.linspace(0, len(combos) - 1, MAX_PANELS).round().astype(int)))
        shown = [combos[i] for i in keep]
        omitted = [c for i, c in enumerate(combos) if i not in set(keep)]
    else:
        shown, omitted = combos, []
    return {"y": y, "facets": facets, "fixed": fixed, "shown": shown, "omitted": omitted}


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


def _map_panel(hv, ds, plan, where, backend, title, colorbar, show_x=True, show_y=True):
    """One stability-class QuadMesh: x = speed, y = one band per value of plan['y']."""
    sub = _select(ds, where)
    speed = sub["speed"].values
    y = plan["y"]
    if y is None:
        z = stability_class(sub.transpose("speed", ...))[None, :]
        ylabels = [(0, "")]
    else:
        z = stability_class(sub.transpose(y, "speed", ...))      # rows: y bands
        ylabels = [(i, f"{v * DISPLAY[y][0]:.4g}") for i, v in enumerate(sub[y].values)]
    band = np.arange(z.shape[0], dtype=float)
    mesh = hv.QuadMesh((speed, band, z), kdims=["speed", "band"], vdims=["class"])
    if speed.size == 1:
        mesh = mesh.redim.range(speed=(speed[0] - 1, speed[0] + 1))
    common = dict(
        cmap=list(PALETTE), clim=(-0.5, len(CLASSES) - 0.5), colorbar=colorbar,
        xlabel=_axis_label("speed") if show_x else "",
        ylabel=_axis_label(y) if (y and show_y) else "", yticks=ylabels,
        title=title, fontsize=_fonts(backend), backend=backend,
    )
    ticks = [(i, name) for i, name in enumerate(CLASSES)]
    if backend == "bokeh":
        mesh = mesh.opts(cticks=ticks, line_width=0, tools=["hover"],
                         colorbar_opts={"title": "stability class"}, **common)
    else:
        mesh = mesh.opts(cbar_ticks=ticks, clabel="stability class", **common)
    return mesh


def fig_stability_map(ds, backend="bokeh"):
    """Stability-class map over speed x (first other swept axis), one panel per combination of
    the remaining swept axes (at most MAX_PANELS)."""
    hv = _hv()
    plan = axes_plan(ds)
    head = "Stability-region map"
    n = len(plan["shown"])
    ncols = _ncols(n)
    strip = plan["y"] is None
    panels = []
    for k, where in enumerate(plan["shown"]):
        show_x, show_y = _grid_opts(k, n, backend)
        # matplotlib grid: one colorbar per row (last column) instead of one per panel
        cbar = backend == "bokeh" or k % ncols == ncols - 1 or k == n - 1
        title = _where_label(where) if where else _figure_title(head, plan)
        p = _map_panel(hv, ds, plan, where, backend, title, cbar, show_x, show_y)
        if backend == "bokeh":
            size = (1150, 200 if strip else 480) if n == 1 else (560 if cbar else 420, 300)
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


# (PNG name, HTML caption) of each figure, in report order
FIGURES = (("stability_map.png", "Stability-region map"),
           ("max_multiplier.png", "Largest Floquet multiplier vs shaft speed"),
           ("multiplier_paths.png", "Floquet multipliers around stability boundaries"))


def build_figures(ds, backend, intervals=None):
    """The report's figures, in FIGURES order, built for `backend` ('bokeh' or 'matplotlib')."""
    return [fig_stability_map(ds, backend), fig_max_multiplier(ds, backend),
            fig_multiplier_paths(ds, backend, intervals)]


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
    parts.append('<div style="display:flex;gap:4em">'
                 f"<div><b>orbit status</b><ul>{li(by_status)}</ul></div>"
                 f"<div><b>stability class</b><ul>{li(by_class)}</ul></div></div>")
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
</style>"""


# ----------------------------------------------------------------------------- entry point

def _load(ds):
    names = [v for v in _VARS if v in ds.variables]
    return ds[names].load()


def make_report(ds, out_dir, title=None):
    """Write report.html, stability_map.png, max_multiplier.png, multiplier_paths.png and
    unstable_intervals.csv into out_dir; returns {"html": Path, "png": [Path, ...], "csv": Path}."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    data = _load(ds)
    title = title or f"Stability report: {_scene_name(ds)}"
    plan = axes_plan(data)
    intervals = query.unstable_intervals(data)
    header, rows = interval_rows(data, intervals)
    csv_path = out / "unstable_intervals.csv"
    write_csv(csv_path, *interval_rows(data, intervals, machine=True))

    pngs = []
    with _backend("matplotlib") as hv:
        for (name, _), obj in zip(FIGURES, build_figures(data, "matplotlib", intervals)):
            hv.save(obj, out / name, backend="matplotlib", dpi=DPI)
            pngs.append(out / name)

    html_path = out / "report.html"
    with _backend("bokeh"):
        figs = build_figures(data, "bokeh", intervals)
        _save_html(html_path, title, _header_html(data, title, plan), figs,
                   _html_table(header, rows), ds.attrs.get("config_toml", ""))
    return {"html": html_path, "png": pngs, "csv": csv_path}


def _save_html(path, title, header_html, figs, table_html, config_toml):
    """A plain HTML page: the header, table and config as HTML, the figures as bokeh components,
    with bokeh's JavaScript inlined (no network). Panel's own save() would link its theme CSS
    from a CDN even with inline resources."""
    from bokeh.embed import components
    from bokeh.embed.bundle import bundle_for_objs_and_resources
    from bokeh.resources import INLINE

    hv = _hv()
    models = [hv.render(fig, backend="bokeh") for fig in figs]
    script, divs = components(models)
    # only the JavaScript these models need (bokeh's INLINE.render() would add every registered
    # extension, Panel's included, some of which load relative URLs)
    bundle = bundle_for_objs_and_resources(models, INLINE)
    resources = bundle.scripts() + "".join(f"<style>{css}</style>" for css in bundle.css_raw)
    body = [header_html]
    for (_, caption), div in zip(FIGURES, divs):
        body.append(f'<h2>{html.escape(caption)}</h2>\n<div class="figure">{div}</div>')
    body.append("<h2>Unstable speed intervals</h2>" + table_html)
    body.append('<h2>Configuration</h2><pre class="config">'
                + html.escape(config_toml or "(no config_toml in the cube)") + "</pre>")
    page = ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{html.escape(title)}</title>\n{resources}\n{_CSS}\n</head>\n"
            "<body>\n" + "\n".join(body) + f"\n{script}\n</body>\n</html>\n")
    Path(path).write_text(page, encoding="utf-8")

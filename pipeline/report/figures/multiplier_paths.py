"""Floquet multipliers in the complex plane at the grid points around chosen stability
boundaries, coloured by the continued axis, unit circle dashed; one panel per boundary.

Not hvplot: a few grid points picked around each boundary, in square frames beside the unit
circle; hv.Points takes the picked arrays directly."""
import numpy as np

from rotorsweep.pipeline import query
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.branches import hover
from rotorsweep.pipeline.report.cubeinfo import continued_axis, has_orbits, other_axes, select
from rotorsweep.pipeline.report.plan import TYPE_NAMES, axis_display, axis_label, where_label
from rotorsweep.pipeline.report.registry import Figure, register

MAX_BOUNDARIES = 6     # stability boundaries in the multiplier figure
BOUNDARY_POINTS = 5    # grid points drawn on each side of a boundary
HEAD = "Floquet multipliers around stability boundaries (unit circle dashed)"
FRAME = 260            # bokeh frame (plot area) side in pixels


def stability_boundaries(ds, intervals=None):
    """Stability boundaries chosen for the multiplier figure: up to MAX_BOUNDARIES entries
    {where: other-axis values, i_stable / i_unstable: indices along the continued axis of the
    grid points on either side, kind: 'onset' or 'end' of the unstable run, type: the run's type
    from query.unstable_intervals}. Runs that touch the end of the grid have no boundary there.
    Selection is deterministic: the first onset of each instability type, then evenly spaced
    picks among the rest, returned in cube order."""
    if intervals is None:
        intervals = query.unstable_intervals(ds)
    others = other_axes(ds)
    grid = ds[continued_axis(ds)].values
    cands = []
    for iv in (iv for iv in intervals if iv["type"] not in query.TORUS_UNSTABLE):    # tori have no multipliers
        common = {"where": {a: iv[a] for a in others}, "type": iv["type"]}
        i0 = int(np.argmin(np.abs(grid - iv["start"])))
        i1 = int(np.argmin(np.abs(grid - iv["end"])))
        if i0 > 0:
            cands.append({**common, "i_stable": i0 - 1, "i_unstable": i0, "kind": "onset"})
        if i1 < grid.size - 1:
            cands.append({**common, "i_stable": i1 + 1, "i_unstable": i1, "kind": "end"})
    return cands if len(cands) <= MAX_BOUNDARIES else [cands[i] for i in _choose(cands)]


def _choose(cands):
    """Indices of MAX_BOUNDARIES of the candidates, sorted: the first onset of each type (real
    bifurcations first), then evenly spaced picks among the rest."""
    chosen, seen = [], set()
    for i, c in enumerate(cands):
        if c["kind"] == "onset" and c["type"] not in seen and c["type"] != "no_orbit":
            seen.add(c["type"])
            chosen.append(i)
    rest = [i for i in range(len(cands)) if i not in chosen]
    need = MAX_BOUNDARIES - len(chosen)
    if need > 0 and rest:
        picks = np.linspace(0, len(rest) - 1, min(need, len(rest))).round().astype(int)
        chosen += [rest[j] for j in sorted(set(picks))]
    return sorted(chosen[:MAX_BOUNDARIES])


def _boundary_title(ds, b):
    a, c = sorted((b["i_stable"], b["i_unstable"]))
    grid = ds[continued_axis(ds)].values
    factor, unit, _ = axis_display(ds, continued_axis(ds))
    verb = "loses stability" if b["kind"] == "onset" else "regains stability"
    return (f"{where_label(ds, b['where'], short=True)}\n{verb} {grid[a] * factor:.4g}-"
            f"{grid[c] * factor:.4g} {unit} ({TYPE_NAMES.get(b['type'], b['type'])})")


def _unit_circle(hv, backend):
    theta = np.linspace(0, 2 * np.pi, 361)
    circle = hv.Curve((np.cos(theta), np.sin(theta)), "Re", "Im")
    if backend == "bokeh":
        return circle.opts(color="#555555", line_dash="dashed", backend=backend)
    return circle.opts(color="#555555", linestyle="--", linewidth=1, backend=backend)


def _boundary_panel(hv, ds, b, backend):
    """The multipliers of BOUNDARY_POINTS grid points on each side of boundary b."""
    x = continued_axis(ds)
    size = ds.sizes[x]
    lo = max(0, min(b["i_stable"], b["i_unstable"]) - BOUNDARY_POINTS + 1)
    hi = min(size, max(b["i_stable"], b["i_unstable"]) + BOUNDARY_POINTS)
    line = select(ds, b["where"]).isel({x: slice(lo, hi)})
    re = line["multiplier_real"].transpose(x, "multiplier").values
    im = line["multiplier_imag"].transpose(x, "multiplier").values
    at = np.broadcast_to(line[x].values[:, None], re.shape)
    ok = np.isfinite(re) & np.isfinite(im)
    pts = hv.Points((re[ok], im[ok], at[ok]), ["Re", "Im"], [x])
    r = max(1.15, float(np.nanmax(np.hypot(re[ok], im[ok]))) * 1.1 if ok.any() else 1.15)
    colour = {"color": x, "cmap": "viridis", "clim": (float(line[x].min()), float(line[x].max())),
              "colorbar": True}
    clabel = axis_label(ds, x)
    common = {"title": _boundary_title(ds, b), "xlim": (-r, r), "ylim": (-r, r), "xlabel": "Re λ",
              "ylabel": "Im λ"}
    if backend == "bokeh":
        tips = hover(("Re", "Im", x), ("Re λ", "Im λ", clabel))
        pts = pts.opts(**colour, size=7, clabel=clabel, tools=["hover"], hover_tooltips=tips, backend=backend)
        # a round unit circle: data_aspect=1 holds only with a square frame, not width/height
        return (_unit_circle(hv, backend) * pts).opts(frame_width=FRAME, frame_height=FRAME, data_aspect=1,
                                                      fontsize=style.fonts(backend), **common, backend=backend)
    pts = pts.opts(**colour, s=28, clabel=clabel, backend=backend)
    return (_unit_circle(hv, backend) * pts).opts(aspect="equal", fontsize={**style.fonts(backend), "title": 10},
                                                  **common, backend=backend)


def _no_boundary(hv, ds, backend):
    """The unit circle and a note, for a cube without a stability boundary inside its grid."""
    empty = hv.Text(0, 0, f"no stability boundary inside the {continued_axis(ds)} grid")
    common = dict(title=HEAD, xlim=(-1.2, 1.2), ylim=(-1.2, 1.2), xlabel="Re λ",
                  ylabel="Im λ", fontsize=style.fonts(backend), backend=backend)
    if backend == "bokeh":
        return (_unit_circle(hv, backend) * empty.opts(text_align="center", backend=backend)).opts(
            frame_width=2 * FRAME, frame_height=2 * FRAME, data_aspect=1, **common)
    return (_unit_circle(hv, backend) * empty.opts(fontsize=12, backend=backend)).opts(
        aspect="equal", fig_inches=(7, 7), **common)


def fig_multiplier_paths(ds, backend="bokeh", intervals=None):
    """Floquet multipliers in the complex plane for the grid points around each chosen stability
    boundary, coloured by the continued axis, unit circle drawn; one panel per boundary."""
    hv = style.holoviews()
    panels = [_boundary_panel(hv, ds, b, backend) for b in stability_boundaries(ds, intervals)]
    if not panels:
        return _no_boundary(hv, ds, backend)
    n = len(panels)
    columns = min(3, n)
    lay = style.layout(hv, panels, backend, columns, HEAD, fig_inches=(10.8, 4.0 * -(-n // columns) + 0.6))
    if backend == "matplotlib" and n > 1:
        lay = lay.opts(hspace=0.6, vspace=0.5, backend=backend)
    return lay


register(Figure(name="multiplier_paths", filename="multiplier_paths.png",
                title="Floquet multipliers around stability boundaries", applies=has_orbits, build=fig_multiplier_paths))

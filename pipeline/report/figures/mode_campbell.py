"""Campbell diagram of the linear modes (rotorsweep.pipeline.modes.campbell): damped natural frequency
against shaft speed, forward whirl solid, backward dashed, axial and non-whirling modes dotted,
the damping ratio as the colour of the points; the 1x line and, where the scene has one, the
support-frequency line; the critical speeds (rotorsweep.pipeline.modes.critical_speeds: crossings of a mode
with those lines, located by a root solve) marked and labelled (in the HTML also listed in a table below); the scene's shaft
speeds marked. For the models with a linearization and a shaft speed (their spec's
`has_linearization`, `speed`); the sweep and the continuation reports both draw it from the
scene stored in the result."""
import json

import numpy as np

from rotorsweep.pipeline import modes
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.registry import Figure, register
from rotorsweep.kernels import models

CAMPBELL_SPEEDS = 41            # speeds of the drawn table, 0 to the top speed
WHIRL_DASH = {"forward": False, "backward": True}       # others (axial, no whirl): dotted
WHIRL_NAMES = {"forward": "forward whirl (solid)", "backward": "backward whirl (dashed)"}
OTHER_NAME = "axial / no whirl (dotted)"
CURVE_COLOUR = "#666666"
CRITICAL_COLOUR = "#C00000"
LINE_COLOURS = {"1x": "#000000"}        # the support lines: SUPPORT_COLOUR
SUPPORT_COLOUR = "#CC79A7"
SPEED_LABEL, FREQUENCY_LABEL = "shaft speed [Hz]", "damped natural frequency [Hz]"
CRITICAL_COLUMNS = ("shaft speed [Hz]", "frequency [Hz]", "line", "mode", "whirl", "label", "damping ratio [1]")


def campbell_speeds(scene, top=None):
    """Shaft speeds [Hz] above 0 (where the whirl directions are not defined) to the top:
    `top`, else 1.25 x the scene's highest grid speed."""
    if top is None:
        name = scene.model.speed
        first = {axis: float(v[0]) for axis, v in scene.axes.items()}
        top = 1.25 * max(float(s) for s in scene.axes.get(name, [modes.scene_values(scene, first)[name]]))
    top = float(top)
    return np.linspace(0.0, top, CAMPBELL_SPEEDS + 1)[1:]


def mode_series(rows):
    """{(mode index, whirl, label): (speeds, frequencies, damping ratios)} from modes.campbell rows."""
    out = {}
    for speed, k, freq, zeta, whirl, label in rows:
        series = out.setdefault((k, whirl, label), ([], [], []))
        for values, v in zip(series, (speed, freq, zeta)):
            values.append(v)
    return out


def _dims(hv):
    return hv.Dimension("speed", label=SPEED_LABEL), hv.Dimension("frequency", label=FREQUENCY_LABEL)


def _hover(backend, tips=None):
    if backend != "bokeh":
        return {}
    return {"tools": ["hover"], **({"hover_tooltips": tips} if tips else {})}


def _mode_elements(hv, rows, backend):
    """One curve per mode series (styled by whirl, one legend entry per style) and the points
    coloured by damping ratio."""
    dims = _dims(hv)
    elements, named = [], set()
    for (k, whirl, label), (x, y, _) in sorted(mode_series(rows).items()):
        name = WHIRL_NAMES.get(whirl, OTHER_NAME)
        look = style.line_style(backend, 1.6, dash=WHIRL_DASH.get(whirl, "dotted"))
        curve = hv.Curve((x, y), *dims, label="" if name in named else name)
        elements.append(curve.opts(color=CURVE_COLOUR, **look, **_hover(backend), backend=backend))
        named.add(name)
    table = {"speed": [r[0] for r in rows], "frequency": [r[2] for r in rows], "zeta": [r[3] for r in rows],
             "mode": [f"{r[5]}, {r[4]}" for r in rows]}
    zeta = hv.Dimension("zeta", label="damping ratio ζ [1]")
    pts = hv.Points(table, list(dims), [zeta, hv.Dimension("mode")], label="damping ratio ζ (colour)")
    look = {"size": 6} if backend == "bokeh" else {"s": 16}
    elements.append(pts.opts(color="zeta", cmap="viridis", colorbar=True, **look, **_hover(backend),
                             backend=backend))
    return elements


def _line_elements(hv, lines, speeds, backend):
    elements = []
    for line in lines:
        colour = LINE_COLOURS.get(line.name, SUPPORT_COLOUR)
        name = "1x (shaft speed)" if line.name == "1x" else line.name
        curve = hv.Curve((speeds, line.at(np.asarray(speeds))), *_dims(hv), label=name)
        elements.append(curve.opts(color=colour, **style.line_style(backend, 1.2, dash=line.name != "1x"),
                                   **_hover(backend), backend=backend))
    return elements


def _critical_elements(hv, found, backend):
    table = {"speed": [c.speed_hz for c in found], "frequency": [c.frequency_hz for c in found],
             "line": [c.line for c in found], "mode": [f"{c.mode}: {c.label}, {c.whirl}" for c in found]}
    pts = hv.Points(table, list(_dims(hv)), ["line", "mode"], label="critical speed")
    marker = style.marker_style(backend, CRITICAL_COLOUR, 11 if backend == "bokeh" else 7, marker="D", hollow=True)
    text = hv.Labels({"speed": table["speed"], "frequency": table["frequency"],
                      "text": [f"{s:.4g} Hz" for s in table["speed"]]}, list(_dims(hv)), "text")
    look = ({"text_font_size": "9pt", "yoffset": 0, "text_align": "left", "xoffset": 0} if backend == "bokeh"
            else {"size": 8, "horizontalalignment": "left", "verticalalignment": "top"})
    return [pts.opts(**marker, **_hover(backend), backend=backend),
            text.opts(text_color=CRITICAL_COLOUR, **look, backend=backend) if backend == "bokeh"
            else text.opts(color=CRITICAL_COLOUR, **look, backend=backend)]


def critical_table(hv, found):
    """The critical speeds as an hv.Table (CRITICAL_COLUMNS), for bokeh."""
    rows = [(round(c.speed_hz, 6), round(c.frequency_hz, 6), c.line, c.mode, c.whirl, c.label,
             round(c.damping_ratio, 6)) for c in found]
    table = hv.Table(rows, list(CRITICAL_COLUMNS[:2]), list(CRITICAL_COLUMNS[2:]))
    return table.opts(width=1100, height=30 + 26 * len(rows), backend="bokeh")


def fig_mode_campbell(scene, backend="bokeh", speeds=None, marks=()):
    """The Campbell diagram of a scene (rotorsweep.pipeline.scene.Scene) over `speeds` [Hz]
    (default campbell_speeds), its excitation lines and critical speeds (table below when
    there are any), and vertical lines at `marks`."""
    hv = style.holoviews()
    speeds = campbell_speeds(scene) if speeds is None else np.asarray(speeds, float)
    spec = scene.model
    first = {name: float(v[0]) for name, v in scene.axes.items()}
    values = modes.scene_values(scene, first)
    rows = modes.campbell(spec, values, speeds)
    fine = np.linspace(0.0, speeds[-1], modes.CRITICAL_GRID + 1)[1:]
    found = modes.scene_critical_speeds(spec, values, fine)
    top = 1.05 * max(r[2] for r in rows)
    elements = _mode_elements(hv, rows, backend) + _line_elements(hv, modes.excitation_lines(spec, values), speeds, backend)
    for s in marks:
        elements.append(hv.Curve(([s, s], [0.0, top]), *_dims(hv)).opts(
            color="#888888", **style.line_style(backend, 1.0, dash=True), backend=backend))
    elements += _critical_elements(hv, found, backend)
    size = ({"width": 1100, "height": 460, "legend_position": "right"} if backend == "bokeh"
            # the legend right of the colour bar ("inner": holoviews' "right" would override the anchor)
            else {"aspect": 1.9, "legend_position": "inner",
                  "legend_opts": {"bbox_to_anchor": (1.15, 1.0), "loc": "upper left"}})
    diagram = hv.Overlay(elements).opts(show_grid=True, ylim=(0, top), xlim=(0, float(speeds[-1])), **size,
                                        backend=backend)
    # matplotlib: the critical speeds labelled, no table; a lone overlay with a (width, height)
    # fig_inches gets its colour bar drawn inside the axes, one in a layout does not
    opts = {"shared_axes": False} if backend == "bokeh" else {"sublabel_format": "", "fig_inches": (14, 4.8)}
    panels = [diagram] + ([critical_table(hv, found)] if found and backend == "bokeh" else [])
    return hv.Layout([]).opts(backend=backend, **opts).clone(panels).cols(1)


def result_figure(ds, backend):
    """The Campbell diagram of a cube's or a continuation result's scene: to 1.25 x the top
    speed of the grid (or of the continued range), the grid's or the lines' speeds marked."""
    from rotorsweep.pipeline.report.points import scene_of

    scene = scene_of(ds)
    speed = scene.model.speed
    if ds.attrs.get("parameter") == speed:
        top = 1.25 * max(json.loads(ds.attrs["range"]))
        return fig_mode_campbell(scene, backend, campbell_speeds(scene, top))
    return fig_mode_campbell(scene, backend, marks=sorted({float(s) for s in np.atleast_1d(ds[speed].values)}))


def has_linear_analysis(ds):
    """The result's model has a linearization and a shaft speed, and the result stores its scene."""
    spec = models.REGISTRY.get(ds.attrs.get("model"))
    return spec is not None and spec.has_linearization and bool(spec.speed) and bool(ds.attrs.get("config_toml"))


CAPTION = ("Campbell diagram: damped natural frequencies vs shaft speed (forward solid, backward dashed, "
           "axial dotted; damping ratio as colour), critical speeds marked and listed")

register(Figure(name="mode_campbell", filename="mode_campbell.png", title=CAPTION,
                applies=has_linear_analysis, build=lambda ds, backend, intervals: result_figure(ds, backend)))

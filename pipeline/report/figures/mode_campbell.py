"""Campbell diagram of the linear modes (pipeline.modes.campbell): natural frequency against
shaft speed, forward whirl solid, backward and axial (no whirl) dashed, with the 1x line (unbalance resonances where a forward mode crosses it) and the
scene's shaft speeds marked. For the models with a linearization and a shaft speed (their spec's
`has_linearization`, `speed`); the sweep and the continuation reports both draw it from the scene
stored in the result."""
import json

import numpy as np

from pipeline import compute, modes
from pipeline.report import style
from pipeline.report.registry import Figure, register
from rotorkernels import models

CAMPBELL_SPEEDS = 41            # speeds of the drawn table, 0 to the top speed
WHIRL_DASH = {"forward": False, "backward": True}


def campbell_speeds(data, top=None):
    """Shaft speeds [Hz] above 0 (where the whirl directions are not defined) to the top:
    `top`, else 1.25 x the scene's highest grid speed."""
    if top is None:
        name = compute.model_of(data).speed
        first = {axis: float(v[0]) for axis, v in data["sweep"].items()}
        top = 1.25 * max(float(s) for s in data["sweep"].get(name, [modes.scene_values(data, first)[name]]))
    top = float(top)
    return np.linspace(0.0, top, CAMPBELL_SPEEDS + 1)[1:]


def mode_series(rows):
    """{(mode index, whirl, label): (speeds, frequencies)} from modes.campbell rows."""
    out = {}
    for speed, k, freq, _, whirl, label in rows:
        out.setdefault((k, whirl, label), ([], []))
        out[(k, whirl, label)][0].append(speed)
        out[(k, whirl, label)][1].append(freq)
    return out


def fig_mode_campbell(data, backend="bokeh", speeds=None, marks=()):
    """The Campbell diagram of a scene (data: a validated config's data) over `speeds` [Hz]
    (default campbell_speeds), the 1x line, and vertical lines at `marks`."""
    hv = style.holoviews()
    speeds = campbell_speeds(data) if speeds is None else speeds
    first = {name: float(v[0]) for name, v in data["sweep"].items()}
    rows = modes.campbell(compute.model_of(data), modes.scene_values(data, first), speeds)
    dims = (hv.Dimension("speed", label="shaft speed [Hz]"), hv.Dimension("frequency", label="natural frequency [Hz]"))
    elements, named = [], set()
    for (k, whirl, label), (x, y) in sorted(mode_series(rows).items()):
        name = f"{label}, {whirl} whirl" if whirl != "none" else f"{label}"
        colour = style.LINE_COLOURS[k % len(style.LINE_COLOURS)]
        look = style.line_style(backend, 1.8, dash=WHIRL_DASH.get(whirl, True))
        elements.append(hv.Curve((x, y), *dims, label="" if name in named else name).opts(color=colour, **look,
                                                                                         backend=backend))
        named.add(name)
    one = hv.Curve((speeds, speeds), *dims, label="1x (shaft speed)")
    elements.append(one.opts(color="#000000", **style.line_style(backend, 1.2), backend=backend))
    top = max(r[2] for r in rows)
    for s in marks:
        elements.append(hv.Curve(([s, s], [0.0, top]), *dims).opts(color="#888888", **style.line_style(backend, 1.0, dash=True),
                                                                  backend=backend))
    size = {"width": 1100, "height": 460} if backend == "bokeh" else {"fig_inches": (12, 4.8), "aspect": 1.9}
    return hv.Overlay(elements).opts(show_grid=True, legend_position="right", ylim=(0, 1.05 * top), **size,
                                     backend=backend)


def result_figure(ds, backend):
    """The Campbell diagram of a cube's or a continuation result's scene: to 1.25 x the top
    speed of the grid (or of the continued range), the grid's or the lines' speeds marked."""
    from pipeline.report.points import scene_data

    data = scene_data(ds)
    speed = compute.model_of(data).speed
    if ds.attrs.get("parameter") == speed:
        top = 1.25 * max(json.loads(ds.attrs["range"]))
        return fig_mode_campbell(data, backend, campbell_speeds(data, top))
    return fig_mode_campbell(data, backend, marks=sorted({float(s) for s in np.atleast_1d(ds[speed].values)}))


def has_linear_analysis(ds):
    """The result's model has a linearization and a shaft speed, and the result stores its scene."""
    spec = models.REGISTRY.get(ds.attrs.get("model"))
    return spec is not None and spec.has_linearization and bool(spec.speed) and bool(ds.attrs.get("config_toml"))


register(Figure(name="mode_campbell", filename="mode_campbell.png",
                title="Campbell diagram: natural frequencies vs shaft speed (forward solid, backward dashed)",
                applies=has_linear_analysis, build=lambda ds, backend, intervals: result_figure(ds, backend)))

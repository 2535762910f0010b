"""Mode shapes of a rotor at the scene's first grid point: per mode, the orbit of each station
(a bearing or journal centre, and the disc of a rigid rotor: rotorsweep.pipeline.modes.station_shapes) over
one period of the mode,
x = Re(X e^{i theta}), y = Re(Y e^{i theta}), normalized so that the largest coordinate
amplitude is 1, a dot where theta = 0 (the whirl direction runs from it). For the models with a
linearization whose coordinates name stations ("x1", "y1", ...); drawn beside the Campbell diagram."""
import numpy as np

from rotorsweep.pipeline import modes
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.registry import Figure, register
from rotorsweep.pipeline.report.figures.mode_campbell import has_linear_analysis

THETA = np.linspace(0.0, 2.0 * np.pi, 73)


def scene_modes(scene):
    """(modes at the scene's first grid point, the model's coordinate names, its disc (xi_D, l)
    or None)."""
    spec = scene.model
    first = {name: float(v[0]) for name, v in scene.axes.items()}
    values = modes.scene_values(scene, first)
    _, system = spec.linear_system(values)
    return modes.modes(spec, values), system.coordinates, modes.disk_of(spec, values)


def _mode_panel(hv, mode, coordinates, disk, k, backend):
    dims = (hv.Dimension("x", label="x [1]"), hv.Dimension("y", label="y [1]"))
    elements = []
    for i, (station, (X, Y)) in enumerate(modes.station_shapes(mode, coordinates, disk).items()):
        colour = style.LINE_COLOURS[i % len(style.LINE_COLOURS)]
        x, y = np.real(X * np.exp(1j * THETA)), np.real(Y * np.exp(1j * THETA))
        elements.append(hv.Curve((x, y), *dims, label=_station_label(station)).opts(
            color=colour, **style.line_style(backend, 1.8), **({"tools": ["hover"]} if backend == "bokeh" else {}),
            backend=backend))
        elements.append(hv.Points(([x[0]], [y[0]]), list(dims)).opts(**style.marker_style(backend, colour, 7),
                                                                      backend=backend))
    title = f"mode {k}: {mode.frequency:.4g} Hz, {mode.label}, whirl {mode.whirl}"
    size = ({"frame_width": 220, "frame_height": 220, "data_aspect": 1, "legend_position": "bottom_right"}
            if backend == "bokeh" else {"aspect": "equal", "legend_position": "best"})
    return hv.Overlay(elements).opts(title=title, xlim=(-1.15, 1.15), ylim=(-1.15, 1.15), show_grid=True,
                                     fontsize={"title": "9pt" if backend == "bokeh" else 9}, **size, backend=backend)


def _station_label(station):
    return "disc" if station == modes.DISK_STATION else f"station {station}"


def fig_mode_shapes(scene, backend="bokeh"):
    """One square panel per mode with the stations' orbits, three a row."""
    hv = style.holoviews()
    found, coordinates, disk = scene_modes(scene)
    panels = [_mode_panel(hv, m, coordinates, disk, k, backend) for k, m in enumerate(found)]
    rows = -(-len(panels) // 3)
    return style.layout(hv, panels, backend, min(3, len(panels)), "Mode shapes: the stations' orbits",
                        fig_inches=(12, 4.0 * rows))


def has_stations(ds):
    """has_linear_analysis and the model's coordinates name at least one station."""
    if not has_linear_analysis(ds):
        return False
    from rotorsweep.pipeline.report.points import scene_of

    found, coordinates, _ = scene_modes(scene_of(ds))
    return bool(found) and bool(modes.station_shapes(found[0], coordinates))


def result_figure(ds, backend):
    from rotorsweep.pipeline.report.points import scene_of

    return fig_mode_shapes(scene_of(ds), backend)


CAPTION = "Mode shapes at the scene's first grid point: each bearing station's and the disc's orbit (a dot at phase 0)"

register(Figure(name="mode_shapes", filename="mode_shapes.png", title=CAPTION, applies=has_stations,
                build=lambda ds, backend, intervals: result_figure(ds, backend)))

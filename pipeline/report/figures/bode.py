"""Bode and polar plots: the first harmonic (rotorsweep.pipeline.report.harmonics) of one observable of the
periodic orbits against the swept or continued parameter -- amplitude |X| and phase arg X
(o ~ |X| cos(2 pi t / T + arg X), unwrapped along each line), and X in the complex plane --
stable solid, unstable dashed, one colour per line (a value of the first other swept axis, or a
continuation branch). The sweep report registers it; the continuation report calls fig_bode."""
import numpy as np

from rotorsweep.pipeline import query
from rotorsweep.pipeline.report import harmonics, style
from rotorsweep.pipeline.report.branches import branch_elements
from rotorsweep.pipeline.report.points import scene_of
from rotorsweep.pipeline.report.registry import Figure, register


def display_unit(unit):
    """(factor, unit) the plots use: lengths in µm."""
    return (1e6, "µm") if unit == "m" else (1.0, unit)


def unwrapped_phase(harmonic):
    """arg X [deg] along a line, unwrapped over its finite points (NaN kept)."""
    phase = np.full(len(harmonic), np.nan)
    ok = np.isfinite(harmonic)
    phase[ok] = np.degrees(np.unwrap(np.angle(harmonic[ok])))
    return phase


def _panel(hv, lines, xs, ys, dims, labels, backend, size):
    """One panel: (xs[i], ys[i]) of each line, stable solid, unstable dashed."""
    elements = []
    for i, (x, y, stable, name) in enumerate(zip(xs, ys, lines.stable, lines.names)):
        elements += branch_elements(x, y, stable, (), backend, dims, labels, style.LINE_COLOURS[i % len(style.LINE_COLOURS)],
                                    name, legend_unstable=len(lines.names) == 1)
    return hv.Overlay(elements).opts(show_grid=True, **size, backend=backend)


def fig_bode(lines, observable, unit, xlabel, backend="bokeh"):
    """Amplitude and phase of the first harmonic against the parameter, and the polar plot;
    lines: harmonics.Lines, unit: the observable's SI unit, xlabel: the parameter's axis label."""
    hv = style.holoviews()
    factor, shown = display_unit(unit)
    par = lines.parameter
    amp_label, phase_label = f"|X| of {observable} [{shown}]", f"phase of {observable} [deg]"
    re_label, im_label = f"Re X of {observable} [{shown}]", f"Im X of {observable} [{shown}]"
    wide = {"width": 620, "height": 320} if backend == "bokeh" else {"aspect": 1.8}
    # holoviews hides a bokeh legend of more than 25 renderers (legend_limit)
    legend = {"legend_position": "top_right", "legend_limit": 200} if backend == "bokeh" else {"legend_position": "best"}
    amp = _panel(hv, lines, lines.x, [np.abs(h) * factor for h in lines.harmonic], (par, "amplitude"), (xlabel, amp_label),
                 backend, {**wide, **legend, "xlabel": xlabel, "ylabel": amp_label, "title": "Bode: amplitude"})
    phase = _panel(hv, lines, lines.x, [unwrapped_phase(h) for h in lines.harmonic], (par, "phase"), (xlabel, phase_label),
                   backend, {**wide, **legend, "xlabel": xlabel, "ylabel": phase_label, "title": "Bode: phase"})
    square = ({"frame_width": 420, "frame_height": 420, "data_aspect": 1} if backend == "bokeh"
              else {"aspect": "equal"})
    polar = _panel(hv, lines, [h.real * factor for h in lines.harmonic], [h.imag * factor for h in lines.harmonic], ("re", "im"), (re_label, im_label),
                   backend, {**square, **legend, "xlabel": re_label, "ylabel": im_label,
                             "title": f"Polar: X along {par}"})
    opts = {"shared_axes": False} if backend == "bokeh" else {"sublabel_format": "", "fig_inches": (13, 9.5),
                                                              "hspace": 0.3, "vspace": 0.35}
    return hv.Layout([]).opts(backend=backend, **opts).clone([amp, phase, polar]).cols(2)


def report_observable(scene):
    """The scene's [report] observable, else the model's first."""
    return scene.report.observable or scene.model.observables[0].name


def _sweep_figure(ds, backend):
    from rotorsweep.pipeline.report.plan import axis_label

    scene = scene_of(ds)
    spec = scene.model
    observable = report_observable(scene)
    lines = harmonics.sweep_lines(ds, scene, observable)
    unit = next(o.unit for o in spec.observables if o.name == observable)
    return fig_bode(lines, observable, unit, axis_label(ds, lines.parameter), backend)


def has_orbits_and_scene(ds):
    """The cube has converged orbits and stores a valid scene of a forced model (to integrate them)."""
    if "orbit_state" not in ds or not (ds["orbit_status"].values == harmonics.CONVERGED).any():
        return False
    try:
        return scene_of(ds).model.forced
    except query.QueryError:
        return False


register(Figure(name="bode", filename="bode.png",
                title="Bode and polar plots: first harmonic of the orbit vs {axis} (stable solid, unstable dashed)",
                applies=has_orbits_and_scene, build=lambda ds, backend, intervals: _sweep_figure(ds, backend)))

"""The report of `rotorsweep modes --report DIR`: one offline page with the linear modes at one
point (rotorsweep.pipeline.modes.records: damped and undamped frequencies, damping ratio, log decrement,
whirl), the Campbell diagram with its critical speeds marked and listed (figures/mode_campbell.py,
for the models with a shaft speed) and the mode shapes (figures/mode_shapes.py, for the models
whose coordinates name stations), as the other reports: report.html, one PNG per figure, and the
modes table as modes.csv."""
import dataclasses
import html

import numpy as np

from rotorsweep.pipeline import fileio, modes, query
from rotorsweep.pipeline.report import page
from rotorsweep.pipeline.report.figures import mode_campbell, mode_shapes

MODE_COLUMNS = ("mode [index]", "damped frequency [Hz]", "undamped frequency [Hz]", "damping ratio [1]",
                "log decrement [1]", "whirl", "label")


def scene_at(scene, point):
    """The scene with its grid reduced to `point` {axis: value} (an axis the scene fixes becomes
    a fixed value): the figure builders draw at a scene's first grid point."""
    axes = {name: np.array([float(point[name])]) for name in scene.axes}
    fixed = {**scene.fixed, **{name: v for name, v in point.items() if name not in scene.axes}}
    return dataclasses.replace(scene, axes=axes, fixed=fixed)


def mode_columns(rec):
    """{header: values} of the modes in a records() dict (MODE_COLUMNS)."""
    zeta = [m["damping_ratio"] for m in rec["modes"]]
    values = (list(range(len(rec["modes"]))), [m["damped_frequency_hz"] for m in rec["modes"]],
              [m["undamped_frequency_hz"] for m in rec["modes"]], zeta,
              [float(modes.log_decrement(z)) for z in zeta], [m["whirl"] for m in rec["modes"]],
              [m["label"] for m in rec["modes"]])
    return dict(zip(MODE_COLUMNS, values))


def campbell_speeds(spec, values, speeds=None):
    """The Campbell diagram's speeds [Hz]: `speeds` (--campbell) or the critical-speed search
    range of `modes` (to CRITICAL_RANGE x the highest frequency at rest), so the page lists the
    critical speeds the text and --json give."""
    return modes.critical_speed_range(spec, values) if speeds is None else np.asarray(speeds, float)


def figures(scene, grid_speeds, speeds, backend):
    """(caption, filename, figure) of the Campbell diagram (a model with a shaft speed; the
    scene's grid speeds marked) and the mode shapes (a model whose coordinates name stations)."""
    spec = scene.model
    out = []
    if spec.speed:
        out.append((mode_campbell.CAPTION, "mode_campbell.png",
                    mode_campbell.fig_mode_campbell(scene, backend, speeds, marks=grid_speeds)))
    found, coordinates, disk = mode_shapes.scene_modes(scene)
    if found and modes.station_shapes(found[0], coordinates):
        out.append((mode_shapes.CAPTION.replace("the scene's first grid point", "this point"), "mode_shapes.png",
                    mode_shapes.fig_mode_shapes(scene, backend)))
    return out


def header_html(scene, rec, point, title):
    """Title, scene and model, the point, the static equilibrium and the conventions."""
    eq = rec["equilibrium"]
    where = ", ".join(f"{name} = {value:g}" for name, value in point.items())
    state = ", ".join(f"{c} = {q:.4g}" for c, q in zip(eq["coordinates"], eq["position"]))
    note = f"<br>{html.escape(eq['note'])}" if eq["note"] else ""
    return (f"<h1>{html.escape(title)}</h1><p>scene <b>{html.escape(scene.name)}</b> &middot; model "
            f"<b>{html.escape(rec['model'])}</b> &middot; at {html.escape(where or 'its parameters')} (SI)</p>"
            f"<p>static equilibrium (SI): {html.escape(state)}; relative residual {eq['residual']:.1e} "
            f"({eq['iterations']} Newton iterations){note}</p>"
            "<p>Linearized about it: eigenvalues s = -&zeta; &omega;<sub>n</sub> &plusmn; i &omega;<sub>d</sub>; "
            "damped frequency Im(s) / 2&pi;, undamped |s| / 2&pi;, damping ratio &zeta; = -Re(s) / |s|, "
            "log decrement 2&pi;&zeta; / &radic;(1 - &zeta;&sup2;).</p>")


def make_report(cfg, point, out_dir, campbell_speeds_hz=None, title=None):
    """report.html, a PNG per figure and modes.csv into out_dir for the scene `cfg` at `point`
    {axis: value} (rotorsweep.pipeline.modes.at_point); returns the paths as rotorsweep.pipeline.report.make_report
    does. campbell_speeds_hz: the Campbell diagram's speeds (default campbell_speeds). The page is
    built next to out_dir and replaces an earlier report there whole, once complete (a directory
    that holds no report is refused: fileio.check_report_dir)."""
    fileio.check_report_dir(out_dir, None, overwrite=True)
    spec = cfg.model
    scene = scene_at(cfg.scene, point)
    values = modes.scene_values(cfg.scene, point)
    rec = modes.records(spec, values)
    speeds = campbell_speeds(spec, values, campbell_speeds_hz) if spec.speed else None
    grid = sorted(float(s) for s in cfg.axes.get(spec.speed, ())) if spec.speed else []
    title = title or f"Linear modes: {cfg.scene.name}"
    cols = mode_columns(rec)
    # the modes table first, then the figures (the tables of write_result_report go below them)
    return fileio.report_into(out_dir, lambda tmp: page.write_result_report(
        tmp, title, header_html(cfg.scene, rec, point, title) + page.columns_html("Modes", cols, 6),
        lambda backend: figures(scene, grid, speeds, backend), "", cfg.source, "modes.csv", query.render(cols, "csv")))

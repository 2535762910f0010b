"""make_report: the report of one cube, every figure the registry says applies to it."""
import time
from pathlib import Path

from rotorsweep.pipeline import query, schema
from rotorsweep.pipeline.report import figures  # noqa: F401  (registers the figures)
from rotorsweep.pipeline.report import page, pngs, style
from rotorsweep.pipeline.report.cubeinfo import scene_name
from rotorsweep.pipeline.report.figures.point import fig_point
from rotorsweep.pipeline.report.plan import axes_plan
from rotorsweep.pipeline.report.points import (compute_point, point_filename, point_rows, point_title,
                                    resolve_point, scene_of)
from rotorsweep.pipeline.report.registry import figures_for
from rotorsweep.pipeline.report.tables import bistable_rows, interval_rows, write_csv

_VARS = ("orbit_status", "stable", "bifurcation", "max_abs_multiplier", "multiplier_real",
         "multiplier_imag", "forcing_period", "orbit_state")
# attractor variables the report's figures and header read (with their _down twins)
_ATTRACTOR_VARS = ("attractor", "period", "lle", "lle_stderr", "lle_method", "poincare_x")


def _load(ds):
    """The variables the figures, tables and header need, in memory (not the Poincare y or the
    Lyapunov spectrum: a Fig. 13 cube holds 1.5 M Poincare samples per variable)."""
    names = [v for v in _VARS if v in ds.variables]
    names += [v for v in schema.observable_variables(schema.model_of(ds)) if v in ds.variables]
    names += [v + sfx for v in _ATTRACTOR_VARS for sfx in ("", schema.DOWN_SUFFIX) if v + sfx in ds.variables]
    names += [v for v in ("hysteresis", "torus_status", "torus_stability", "torus_exponent") if v in ds.variables]
    names += [v for v in ds.data_vars if ds[v].dims == ("boundary",)]     # the boundary table
    return ds[names].load()


def _resolve_all(ds, points):
    """Every requested point resolved (and so checked) before anything is drawn, duplicates
    dropped."""
    resolved = []
    for spec in points or []:
        r = resolve_point(ds, spec)
        if all(r["values"] != other["values"] for other in resolved):
            resolved.append(r)
    return resolved


def make_report(ds, out_dir, title=None, points=None, parallel=None, say=None):
    """Write report.html, the figures as PNGs (those of the figure registry that apply to the
    cube, e.g. stability_map.png, max_multiplier.png, multiplier_paths.png, and for cubes with
    attractor diagnostics bifurcation.png and lle.png) and unstable_intervals.csv into out_dir.
    points: grid points to show in detail ({axis: value} dicts or AXIS=VALUE strings, nearest
    grid point, see resolve_point), one point_<speed>Hz_<clearance>um.png each. parallel
    (default: with 2 or more usable CPUs): the PNGs are drawn by a second process while this one
    draws the HTML, then helps with those left (rotorsweep.pipeline.report.pngs). say(text): where phase
    lines go (None: nowhere). Returns {"html": Path, "png": [Path, ...] (figures, then points),
    "csv": Path, "points": [Path, ...]}."""
    say = say or (lambda text: None)
    start = time.perf_counter()
    resolved = _resolve_all(ds, points)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with pngs.drawer(parallel) as draw_pngs:
        scene = scene_of(ds) if resolved else None
        data = _load(ds)
        title = title or f"Stability report: {scene_name(ds)}"
        intervals = query.unstable_intervals(data)
        csv_path = out / "unstable_intervals.csv"
        write_csv(csv_path, *interval_rows(data, intervals, machine=True))
        details = [compute_point(ds, scene, r) for r in resolved]
        point_pngs = [out / point_filename(ds, r) for r in resolved]
        chosen = figures_for(data)
        here = draw_pngs is pngs.write_pngs
        say(f"drawing the figures ({len(chosen)})" + (f" and the points in detail ({len(details)})" if details else "")
            + (": the PNGs, then the HTML page" if here else ": the PNGs in a second process, the HTML page here"))
        draw_pngs(pngs.CubePngs(data, intervals, [fig.name for fig in chosen],
                                [(pt, path.name) for pt, path in zip(details, point_pngs)]), out)
        if here:
            say(f"PNGs written ({time.perf_counter() - start:.1f} s)")

        html_path = out / "report.html"
        with style.backend("bokeh"):
            figs = [(fig.caption(data), fig.build(data, "bokeh", intervals)) for fig in chosen]
            point_sections = [(point_title(pt), fig_point(pt, "bokeh"), page.point_table_html(point_rows(pt)))
                              for pt in details]
            page.save_html(html_path, title, page.header_html(data, title, axes_plan(data)), figs,
                           page.intervals_html(data, *interval_rows(data, intervals))
                           + page.bistable_html(data, *bistable_rows(data, query.bistable_intervals(data))),
                           ds.attrs.get("config_toml", ""), point_sections)
        say(f"HTML page written ({time.perf_counter() - start:.1f} s)" + ("" if here else "; the PNGs left are drawn here"))
    if not here:
        say(f"PNGs written ({time.perf_counter() - start:.1f} s)")
    return {"html": html_path, "png": [out / fig.filename for fig in chosen] + point_pngs, "csv": csv_path,
            "points": point_pngs}

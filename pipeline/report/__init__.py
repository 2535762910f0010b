"""Stability-map report of a result cube: one self-contained HTML page plus PNGs and a CSV.

    make_report(ds, out_dir, points=None) -> {"html": Path, "png": [Path, ...], "csv": Path,
                                              "points": [Path, ...]}

Figures come from a registry (registry.py): each module of figures/ registers one Figure with
the condition under which it applies to a cube, and make_report draws those that apply, in
registration order. Today: the stability-region map (runs of one stability class as rectangles
whose edges are the refined boundaries of the cube's boundary table), the periodic orbit's branch
diagram (stable solid, unstable dashed, LP / PD / NS at the refined boundaries; branches.py draws
any branch from plain arrays), max |multiplier| in the same style, response curves, a
frequency of the critical multiplier and the multipliers around stability
boundaries; for cubes with attractor diagnostics also the bifurcation diagram (Poincare x) and
the largest Lyapunov exponent. Every figure runs along the
cube's continued axis (cubeinfo.continued_axis). Per requested point (`points`, `rotorsweep
report --point`) the report adds its orbit, Poincare section, spectrum and a table.

Every figure is built by one function `fig_*(ds, backend)` that returns a HoloViews object styled
for that backend. The HTML page (bokeh, JavaScript inlined so it opens offline) and the PNGs
(matplotlib, no browser) call the same functions, building each figure anew per backend: a
bokeh-styled object saved with matplotlib silently loses its colormap, limits and colorbar.
With 2 or more usable CPUs the PNGs are drawn by a second Python process while this one draws the
HTML, and this one then helps with the PNGs left (pngs.py; make_report(parallel=False) draws all
here). The continuation and backbone results' reports draw theirs here: their figures take a
third of the time, and a second process gained nothing measurable (fold report 8.3-9.2 s against
8.5-8.7 s).

Modules import only downward: driver -> pngs -> figures -> registry, page, points, tables, branches ->
plan, stability -> cubeinfo, style.
"""
import importlib

# name -> the submodule defining it, imported on first use (PEP 562): importing any
# rotorsweep.pipeline.report.<module> (the accessor's cubeinfo, style) loads this package, which must not load
# the report driver and every figure with it (issue 35)
_NAMES = {
    "branches": "SPECIAL_LABELS Special branch_elements stability_runs",
    "cubeinfo": "attractor_counts axis_edges branch_observables continued_axis has_attractor has_down sweep_labels",
    "driver": "make_report",
    "figures.bifurcation": "fig_bifurcation",
    "figures.branch_diagram": "fig_branches",
    "figures.multiplier_frequency": "critical_frequency fig_multiplier_frequency",
    "figures.lle": "fig_lle",
    "figures.max_multiplier": "fig_max_multiplier",
    "figures.multiplier_paths": "MAX_BOUNDARIES fig_multiplier_paths stability_boundaries",
    "figures.point": "fig_point",
    "figures.response": "fig_response",
    "figures.stability_map": "RECT_HALF fig_stability_map map_rectangles",
    "page": "header_html",
    "plan": "MAX_PANELS axes_plan axis_display figure_title line_plan where_label",
    "poincare": "BIF_POINTS thin_points",
    "points": "parse_point point_filename resolve_point",
    "registry": "Figure figures_for register",
    "stability": "CLASSES PALETTE counts line_segments refined_edges stability_class",
    "style": "SWEEP_COLOURS holoviews",
}
_WHERE = {name: module for module, names in _NAMES.items() for name in names.split()}

__all__ = [
    "BIF_POINTS", "CLASSES", "Figure", "MAX_BOUNDARIES", "MAX_PANELS", "PALETTE", "RECT_HALF",
    "SPECIAL_LABELS", "SWEEP_COLOURS", "Special", "attractor_counts", "axes_plan", "axis_display",
    "axis_edges", "branch_elements", "branch_observables", "continued_axis", "counts",
    "critical_frequency", "fig_bifurcation", "fig_branches", "fig_multiplier_frequency", "fig_lle",
    "fig_max_multiplier", "fig_multiplier_paths", "fig_point", "fig_response", "fig_stability_map",
    "figure_title", "figures_for", "has_attractor", "has_down", "header_html", "holoviews", "line_plan", "line_segments",
    "make_report", "map_rectangles", "parse_point", "point_filename", "refined_edges", "register",
    "resolve_point", "stability_boundaries", "stability_class", "stability_runs", "sweep_labels",
    "thin_points", "where_label",
]


def __getattr__(name):
    if name not in _WHERE:
        raise AttributeError(f"module 'rotorsweep.pipeline.report' has no attribute {name!r}")
    if _WHERE[name] == "registry":
        importlib.import_module("rotorsweep.pipeline.report.figures")     # registers them: figures_for sees every one
    value = getattr(importlib.import_module(f"rotorsweep.pipeline.report.{_WHERE[name]}"), name)
    globals()[name] = value
    return value

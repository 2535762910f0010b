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
from pipeline.report.branches import SPECIAL_LABELS, Special, branch_elements, stability_runs
from pipeline.report.cubeinfo import (attractor_counts, axis_edges, branch_observables,
                                      continued_axis, has_attractor, has_down, sweep_labels)
from pipeline.report.driver import make_report
from pipeline.report.figures.bifurcation import fig_bifurcation
from pipeline.report.figures.branch_diagram import fig_branches
from pipeline.report.figures.multiplier_frequency import critical_frequency, fig_multiplier_frequency
from pipeline.report.figures.lle import fig_lle
from pipeline.report.figures.max_multiplier import fig_max_multiplier
from pipeline.report.figures.multiplier_paths import (MAX_BOUNDARIES, fig_multiplier_paths,
                                                      stability_boundaries)
from pipeline.report.figures.point import fig_point
from pipeline.report.figures.response import fig_response
from pipeline.report.figures.stability_map import RECT_HALF, fig_stability_map, map_rectangles
from pipeline.report.page import header_html
from pipeline.report.plan import (MAX_PANELS, axes_plan, axis_display, figure_title, line_plan,
                                  where_label)
from pipeline.report.poincare import BIF_POINTS, thin_points
from pipeline.report.points import parse_point, point_filename, resolve_point
from pipeline.report.registry import Figure, figures_for, register
from pipeline.report.stability import (CLASSES, PALETTE, counts, line_segments, refined_edges,
                                       stability_class)
from pipeline.report.style import SWEEP_COLOURS, holoviews

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

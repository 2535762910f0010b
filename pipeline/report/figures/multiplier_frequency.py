"""Frequency of the critical (largest) Floquet multiplier, arg(lambda) / 2 pi times the forcing
frequency 1/T, against shaft speed, one series per value of the first other swept axis, with the
1x (shaft speed) and ball-passage (1/T) lines. A multiplier's frequency is defined modulo 1/T;
arg in [0, pi] folds it into [0, 1/(2T)], so the points zig-zag where the frequency passes a
multiple of 1/(2T): this is not a Campbell diagram (natural frequencies of the linear modes
against speed, figures/mode_campbell.py, for the models with a linearization)."""
import numpy as np
import xarray as xr

from rotorsweep.pipeline import schema
from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.branches import hover
from rotorsweep.pipeline.report.cubeinfo import continued_axis, select
from rotorsweep.pipeline.report.figures.panels import Sizes, facet_figure, panel_opts
from rotorsweep.pipeline.report.plan import axes_plan, axis_label, where_label
from rotorsweep.pipeline.report.registry import Figure, register

FREQUENCY_LABEL = "frequency [Hz]"


def critical_frequency(ds):
    """|arg(lambda_0)| / 2 pi / T [Hz] of the leading multiplier at every point of a cube (NaN:
    no orbit), as a DataArray named `frequency`."""
    lead = ds.isel(multiplier=0, drop=True)        # no scalar `multiplier` coordinate in titles
    angle = np.abs(np.arctan2(lead["multiplier_imag"], lead["multiplier_real"]))
    return (angle / (2 * np.pi) / ds["forcing_period"]).rename("frequency").assign_attrs(
        units="Hz", long_name="frequency of the critical Floquet multiplier")


def multiplier_frequency_points(ds, by=None):
    """hvplot scatter of critical_frequency along the continued axis, one series per value of
    `by` (hover: the value of max |multiplier| too)."""
    import hvplot.xarray  # noqa: F401  (registers .hvplot)

    data = xr.merge([critical_frequency(ds), ds["max_abs_multiplier"]])
    return data.hvplot.scatter(x=continued_axis(ds), y="frequency", by=by, hover_cols=["max_abs_multiplier"])


def _frequency_panel(hv, ds, where, backend, slot, y):
    sub = select(ds, where)
    x = continued_axis(ds)
    grid = sub[x].values.astype(float)
    tips = hover((x, "frequency", "max_abs_multiplier"), (axis_label(ds, x), FREQUENCY_LABEL, "max |multiplier|"))
    series = multiplier_frequency_points(sub, y)
    groups = list(series.items()) if y else [(None, series)]
    elements = []
    for i, (v, pts) in enumerate(groups):
        look = style.marker_style(backend, style.LINE_COLOURS[i % len(style.LINE_COLOURS)], 5 if backend == "bokeh" else 3)
        # hvplot's own sizes (fig_size, aspect) would override the panel's layout
        pts = pts.relabel(where_label(ds, {y: v}) if y else "critical multiplier").opts.clear()
        elements.append(pts.opts(**look, **({"tools": ["hover"], "hover_tooltips": tips} if backend == "bokeh" else {}),
                                 backend=backend))
    ball_pass = 1.0 / sub["forcing_period"].transpose(x, ...).values.reshape(grid.size, -1)[:, 0]
    for f, name, colour in ((grid, "1x (shaft speed)", "#009E73"), (ball_pass, "ball passage 1/T", "#CC79A7")):
        elements.append(hv.Curve((grid, f), x, "frequency", label=name)
                        .opts(color=colour, **style.line_style(backend, 1.3, dash=True), backend=backend))
    top = 1.05 * float(np.nanmax(ball_pass))
    return hv.Overlay(elements).opts(show_grid=True, ylim=(0, top), **panel_opts(ds, slot, backend, FREQUENCY_LABEL))


def fig_multiplier_frequency(ds, backend="bokeh"):
    """Frequency of the critical multiplier vs shaft speed with the 1x and ball-passage lines."""
    y = axes_plan(ds)["y"]

    def panel(hv, ds, where, backend, slot):
        return _frequency_panel(hv, ds, where, backend, slot, y)
    sizes = Sizes(bokeh_one=(1150, 440), bokeh_grid=(560, 300), aspect_one=2.4, aspect_grid=1.5,
                  inches_one=(11, 4.6), grid_width=9.6)
    return facet_figure(ds, backend, "Frequency of the critical Floquet multiplier "
                        "arg(λ)/2π · 1/T (folded into [0, 1/2T])", panel, sizes)


def along_shaft_speed(ds):
    """The cube is continued along its model's shaft speed (ModelSpec.speed) and has orbits."""
    return continued_axis(ds) == schema.model_of(ds).speed and bool((ds["orbit_status"].values == 0).any())


register(Figure(name="multiplier_frequency", filename="multiplier_frequency.png",
                title="Frequency of the critical Floquet multiplier vs {axis} (not a Campbell diagram)",
                applies=along_shaft_speed,
                build=lambda ds, backend, intervals: fig_multiplier_frequency(ds, backend)))

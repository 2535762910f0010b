"""A cube explored the hvplot way, in a notebook: one function per figure kind of the report,
each returning an hvplot (HoloViews) object, also reachable as methods of the `rotorsweep`
accessor that importing this module (or `rotorsweep`) registers on xarray Datasets:

    import rotorsweep
    ds = rotorsweep.open_cube("out/demo.nc")
    ds.max_abs_multiplier.hvplot(x="speed", by="clearance")   # plain hvplot works on a cube
    ds.rotorsweep.max_multiplier()                            # the same with the |lambda| = 1 line
    ds.rotorsweep.branches("amplitude_y")                     # stable solid, unstable dashed
    ds, _ = rotorsweep.open_result("out/fold.nc")             # a continuation result
    ds.rotorsweep.branch_diagram()                            # its branches (a backbone result: backbones())

Swept axes beyond x and `by` become hvplot's widgets. The report draws with HoloViews elements
where hvplot has no such kind (see pipeline/report/figures/*); its critical-multiplier frequency
figure is built on multiplier_frequency() here.

Plotting (hvplot, HoloViews, bokeh) is imported when a figure is first drawn, not when the
accessor registers: `import rotorsweep` stays light (issue 35).
"""
import functools

import numpy as np
import pandas as pd
import xarray as xr

from pipeline import result_kinds, schema
from pipeline.report.cubeinfo import (branch_observables, branch_values, continued_axis,
                                      default_observable, has_attractor, other_axes)
from pipeline.report.stability import CLASSES, PALETTE, stability_class
from pipeline.report.style import holoviews


def plotting(figure):
    """A figure function that imports hvplot (registering .hvplot on pandas and xarray objects)
    before it draws."""
    @functools.wraps(figure)
    def draw(*args, **kwargs):
        import hvplot.pandas  # noqa: F401
        import hvplot.xarray  # noqa: F401
        return figure(*args, **kwargs)
    return draw


def _by(ds):
    """The first other swept axis with several values (one line per value), else None."""
    return next((a for a in other_axes(ds) if ds.sizes[a] > 1), None)


def _point_array(ds, values, name, attrs):
    dims = schema.point_axes(ds)
    return xr.DataArray(values, coords={d: ds[d] for d in dims}, dims=dims, name=name, attrs=attrs)


def _limit(y, **style):
    return holoviews().HLine(y).opts(color="#C00000", line_dash="dashed", **style)


@plotting
def max_multiplier(ds, **kwargs):
    """max |multiplier| along the continued axis, one line per value of the first other axis,
    and the |lambda| = 1 line."""
    return ds["max_abs_multiplier"].hvplot.line(x=continued_axis(ds), by=_by(ds), **kwargs) * _limit(1.0)


@plotting
def stability_map(ds, **kwargs):
    """The stability class of every grid point (colours of the report's map) over the continued
    axis and the first other axis (grid cells, not the refined edges of the report's map)."""
    cls = _point_array(ds, stability_class(ds), "stability_class",
                       {"long_name": "stability class: " + ", ".join(f"{i} {c}" for i, c in enumerate(CLASSES))})
    x, y = continued_axis(ds), _by(ds)
    if y is None:
        return cls.hvplot.scatter(x=x, color="stability_class", cmap=list(PALETTE), **kwargs)
    return cls.hvplot.quadmesh(x=x, y=y, cmap=list(PALETTE), clim=(-0.5, len(CLASSES) - 0.5), **kwargs)


@plotting
def branches(ds, observable=None, **kwargs):
    """The periodic orbit's `observable` (see report.branch_observables; default: Poincare
    coordinate with attractors, else amplitude) along the continued axis, stable solid and
    unstable dashed, one colour per value of the first other axis."""
    observable = observable or default_observable(ds)
    label, units = branch_observables(ds)[observable]
    da = _point_array(ds, branch_values(ds, observable), observable, {"long_name": label, "units": units})
    stable = ds["stable"] == 1
    x, by = continued_axis(ds), _by(ds)
    return (da.where(stable).hvplot.line(x=x, by=by, **kwargs)
            * da.where(~stable).hvplot.line(x=x, by=by, line_dash="dashed", **kwargs))


@plotting
def response(ds, observable=None, **kwargs):
    """Half peak-to-peak amplitude of an observable (default: the first) along the continued
    axis, one line per value of the first other axis."""
    observable = observable or schema.model_of(ds).observables[0].name
    return ds[f"amplitude_{observable}"].hvplot.line(x=continued_axis(ds), by=_by(ds), **kwargs)


@plotting
def multiplier_frequency(ds, **kwargs):
    """Frequency of the critical multiplier (arg(lambda) / 2 pi / T) vs shaft speed, one series
    per value of the first other axis, with the 1x line (not a Campbell diagram: campbell())."""
    from pipeline.report.figures.multiplier_frequency import multiplier_frequency_points

    speed = ds[continued_axis(ds)].values
    one_x = holoviews().Curve((speed, speed), continued_axis(ds), "frequency", label="1x").opts(line_dash="dashed")
    return multiplier_frequency_points(ds, _by(ds)).opts(**kwargs) * one_x


@plotting
def bode(ds, observable=None, **kwargs):
    """Bode (amplitude, phase) and polar plots of the first harmonic of `observable` (default:
    the scene's report observable) of the orbits along the swept or continued parameter, stable
    solid, unstable dashed (pipeline.report.figures.bode; the orbits are integrated again)."""
    from pipeline.report import harmonics
    from pipeline.report.figures import bode as figure
    from pipeline.report.points import scene_data

    data = scene_data(ds)
    observable = observable or figure.report_observable(data)
    if result_kinds.kind_of(ds).name == result_kinds.CONTINUATION:
        lines = harmonics.continuation_lines(ds, data, observable, [f"branch {b}" for b in range(ds.sizes["branch"])])
        xlabel = f"{ds.attrs['parameter']} [{ds['parameter'].attrs.get('units', '')}]"
    else:
        lines = harmonics.sweep_lines(ds, data, observable)
        xlabel = f"{lines.parameter} [{ds[lines.parameter].attrs.get('units', '')}]"
    unit = next(o.unit for o in schema.model_of(ds).observables if o.name == observable)
    return figure.fig_bode(lines, observable, unit, xlabel).opts(**kwargs)


@plotting
def campbell(ds, **kwargs):
    """The Campbell diagram of the result's scene (models with a linearization and a shaft
    speed): damped natural frequencies vs shaft speed, critical speeds marked and listed."""
    from pipeline.report.figures import mode_campbell

    if not mode_campbell.has_linear_analysis(ds):
        raise ValueError(f"model {ds.attrs.get('model')}: no Campbell diagram (it needs a linearization, a shaft "
                         "speed and the scene stored in the result)")
    return mode_campbell.result_figure(ds, "bokeh").opts(**kwargs)


@plotting
def mode_shapes(ds, **kwargs):
    """The mode shapes at the scene's first grid point: each station's orbit, one panel per mode
    (models with a linearization whose coordinates name stations)."""
    from pipeline.report.figures import mode_shapes as figure

    if not figure.has_stations(ds):
        raise ValueError(f"model {ds.attrs.get('model')}: no mode shapes (they need a linearization, a shaft "
                         "speed, coordinates that name stations and the scene stored in the result)")
    return figure.result_figure(ds, "bokeh").opts(**kwargs)


@plotting
def bifurcation(ds, variable="poincare_x", **kwargs):
    """The attractors' Poincare samples along the continued axis (all samples of a point in one
    column; pass rasterize=True for large cubes, which needs datashader: not installed with rotorsweep)."""
    if not has_attractor(ds):
        raise ValueError("the cube has no attractor diagnostics ([analysis] attractor = true)")
    return ds[variable].hvplot.scatter(x=continued_axis(ds), y=variable, by=_by(ds), groupby=[], size=2, **kwargs)


@plotting
def lle(ds, **kwargs):
    """Largest Lyapunov exponent along the continued axis, one line per value of the first
    other axis, and the zero line."""
    return ds["lle"].hvplot.line(x=continued_axis(ds), by=_by(ds), **kwargs) * _limit(0.0)


@plotting
def multipliers(ds, where=None, **kwargs):
    """The Floquet multipliers in the complex plane along a line (`where`: the other axes'
    values), coloured by the continued axis, in a square frame with the unit circle."""
    line = ds.sel(where) if where else ds
    t = np.linspace(0, 2 * np.pi, 361)
    circle = holoviews().Curve((np.cos(t), np.sin(t)), "multiplier_real", "multiplier_imag").opts(
        color="#555555", line_dash="dashed")
    table = line[["multiplier_real", "multiplier_imag"]].to_dataframe().reset_index()
    pts = table.hvplot.scatter(x="multiplier_real", y="multiplier_imag", c=continued_axis(ds), cmap="viridis",
                               hover_cols=[continued_axis(ds)], frame_width=320, frame_height=320,
                               data_aspect=1, **kwargs)
    return circle * pts


@plotting
def branch_diagram(ds, observable=None, **kwargs):
    """A continuation result's branches: half peak-to-peak of `observable` (default: the
    result's report observable) over the continued parameter, one colour per branch, stable
    solid and unstable dashed (a NaN ends a line: the other stability's points are gaps)."""
    observable = observable or ds.attrs.get("report_observable") or str(ds["observable"].values[0])
    table = pd.DataFrame({"branch": np.repeat(np.arange(ds.sizes["branch"]), ds.sizes["point"]),
                          ds.attrs["parameter"]: ds["parameter"].values.ravel(),
                          observable: ds["amplitude_half_pp"].sel(observable=observable).values.ravel(),
                          "stable": ds["stable"].values.ravel()})
    style = {"x": ds.attrs["parameter"], "y": observable, "by": "branch", **kwargs}
    stable = table.assign(**{observable: table[observable].where(table["stable"] == 1)})
    unstable = table.assign(**{observable: table[observable].where(table["stable"] == 0)})
    return stable.hvplot.line(**style) * unstable.hvplot.line(line_dash="dashed", **style)


@plotting
def backbones(ds, where=None, **kwargs):
    """A backbone result's backbones at one line (`where`: the swept axes' values; default the
    first): frequency over the master's amplitude, continuation solid and manifold dashed, one
    colour per mode."""
    line = ds.sel(where) if where else ds.isel({a: 0 for a in ds["axial_approach"].dims})
    modes = line["mode"].values
    table = pd.DataFrame({"mode": np.repeat(modes, line.sizes["amplitude"]),
                          "amplitude": np.tile(line["amplitude_grid"].values, len(modes)),
                          "continuation": line["frequency_continuation"].values.ravel(),
                          "manifold": line["frequency_manifold"].values.ravel()})
    style = {"x": "amplitude", "by": "mode", "logx": True, "ylabel": "frequency [Hz]", **kwargs}
    return table.hvplot.line(y="continuation", **style) * table.hvplot.line(y="manifold", line_dash="dashed", **style)


# the accessor's figures of each result kind (pipeline.result_kinds)
FIGURES = {kind: {f.__name__: f for f in figures} for kind, figures in (
    (result_kinds.SWEEP, (max_multiplier, stability_map, branches, response, multiplier_frequency, bifurcation, lle,
                          multipliers, bode, campbell, mode_shapes)),
    (result_kinds.CONTINUATION, (branch_diagram, bode, campbell, mode_shapes)),
    (result_kinds.BACKBONE, (backbones,)))}


@xr.register_dataset_accessor("rotorsweep")
class CubeAccessor:
    """ds.rotorsweep.<figure>(...): the functions of pipeline.explore on this result, where its
    kind has them (pipeline.result_kinds: a sweep cube has every one; a figure that does not
    apply says so); ds.rotorsweep.kind and describe() work on every kind."""

    def __init__(self, ds):
        self._ds = ds

    @property
    def kind(self):
        """The result's kind: "sweep", "continuation", "backbone"."""
        return result_kinds.kind_of(self._ds).name

    def describe(self):
        """What the result holds, as `rotorsweep info` prints it."""
        return result_kinds.kind_of(self._ds).describe(self._ds)

    def _draw(self, figure, *args, **kwargs):
        kind = result_kinds.kind_of(self._ds)
        if figure not in FIGURES.get(kind.name, {}):
            applies = " or ".join(result_kinds.KINDS[k].label() for k, figs in FIGURES.items() if figure in figs)
            raise ValueError(f"ds.rotorsweep.{figure}() draws {applies}, not {kind.label()}; `rotorsweep report` "
                             "draws its figures, ds.rotorsweep.describe() says what it holds")
        return FIGURES[kind.name][figure](self._ds, *args, **kwargs)

    def max_multiplier(self, **kwargs):
        return self._draw("max_multiplier", **kwargs)

    def stability_map(self, **kwargs):
        return self._draw("stability_map", **kwargs)

    def branches(self, observable=None, **kwargs):
        return self._draw("branches", observable, **kwargs)

    def response(self, observable=None, **kwargs):
        return self._draw("response", observable, **kwargs)

    def multiplier_frequency(self, **kwargs):
        return self._draw("multiplier_frequency", **kwargs)

    def bode(self, observable=None, **kwargs):
        return self._draw("bode", observable, **kwargs)

    def campbell(self, **kwargs):
        return self._draw("campbell", **kwargs)

    def mode_shapes(self, **kwargs):
        return self._draw("mode_shapes", **kwargs)

    def bifurcation(self, variable="poincare_x", **kwargs):
        return self._draw("bifurcation", variable, **kwargs)

    def lle(self, **kwargs):
        return self._draw("lle", **kwargs)

    def multipliers(self, where=None, **kwargs):
        return self._draw("multipliers", where, **kwargs)

    def branch_diagram(self, observable=None, **kwargs):
        return self._draw("branch_diagram", observable, **kwargs)

    def backbones(self, where=None, **kwargs):
        return self._draw("backbones", where, **kwargs)

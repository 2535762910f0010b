"""A cube explored the hvplot way, in a notebook: one function per figure kind of the report,
each returning an hvplot (HoloViews) object, also reachable as methods of the `rotorsweep`
accessor that importing this module (or `rotorsweep`: rotorsweep.pipeline.register_accessor) registers on
xarray Datasets:

    import rotorsweep
    ds = rotorsweep.open_cube("out/demo.nc")
    ds.max_abs_multiplier.hvplot(x="speed", by="clearance")   # plain hvplot works on a cube
    ds.rotorsweep.max_multiplier()                            # the same with the |lambda| = 1 line
    ds.rotorsweep.branches("amplitude_y")                     # stable solid, unstable dashed
    ds, _ = rotorsweep.open_result("out/fold.nc")             # a continuation result
    ds.rotorsweep.branch_diagram()                            # its branches (a backbone result: backbones())
    ds.rotorsweep.to_frame(["max_abs_multiplier"]).hvplot.scatter(x="speed_Hz", y="max_abs_multiplier")

Plain `ds.hvplot()` flattens every variable over every dimension (seconds and gigabytes on a
small cube): select a variable first, or take the tidy table of to_frame(). Figures and the
table show lengths in um (cube: metres) and leave out the dataset's scalar coordinates (which
hvplot would put in every title).

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

from rotorsweep.pipeline import register_accessor, result_kinds, schema
from rotorsweep.pipeline.report.cubeinfo import (branch_observables, branch_values, continued_axis,
                                      default_observable, has_attractor, other_axes)
from rotorsweep.pipeline.report.stability import CLASSES, PALETTE, stability_class
from rotorsweep.pipeline.report.style import LINE_COLOURS, holoviews


def plotting(figure):
    """A figure function that imports hvplot (registering .hvplot on pandas and xarray objects)
    before it draws.

    >>> @rotorsweep.explore.plotting
    ... def speeds(ds):
    ...     return ds["max_abs_multiplier"].isel(clearance=0).hvplot.line(x="speed")   # .hvplot: registered by then
    >>> type(speeds(rotorsweep.open_cube(cube_path))).__name__
    'Curve'
    """
    @functools.wraps(figure)
    def draw(*args, **kwargs):
        import hvplot.pandas  # noqa: F401
        import hvplot.xarray  # noqa: F401
        return figure(*args, **kwargs)
    return draw


# display units of the accessor (the cubes store SI): unit -> (factor, shown unit, column suffix)
_DISPLAY = {"m": (1e6, "µm", "um"), "Hz": (1.0, "Hz", "Hz")}


def _shown(obj):
    """A Dataset or DataArray as the accessor shows it: lengths in µm (values and units
    attribute), scalar coordinates dropped (hvplot would write them into every title)."""
    obj = obj.drop_vars([c for c in obj.coords if obj[c].ndim == 0])
    obj = obj.assign_coords({n: (obj[n].dims, *_scaled(obj[n])) for n in obj.coords if _scales(obj[n])})
    if isinstance(obj, xr.Dataset):
        return obj.assign({n: (obj[n].dims, *_scaled(obj[n])) for n in obj.data_vars if _scales(obj[n])})
    return obj.copy(data=_scaled(obj)[0]).assign_attrs(_scaled(obj)[1]) if _scales(obj) else obj


def _scales(da):
    return da.attrs.get("units") in _DISPLAY


def _scaled(da):
    """(values, attrs) of a variable in display units."""
    factor, unit, _ = _DISPLAY[da.attrs["units"]]
    return da.values * factor, {**da.attrs, "units": unit}


def row_dims(ds):
    """The dimensions of one row of to_frame(): the grid points of a sweep cube, the points of
    a continuation's branches, the amplitudes of a backbone result's lines.

    >>> rotorsweep.explore.row_dims(rotorsweep.open_cube(cube_path))
    ['speed', 'clearance']
    >>> rotorsweep.explore.row_dims(rotorsweep.open_result(continuation_path)[0])
    ['branch', 'point']
    """
    kind = result_kinds.kind_of(ds).name
    if kind == result_kinds.CONTINUATION:
        return list(ds["parameter"].dims)
    if kind == result_kinds.BACKBONE:
        return list(ds["frequency_continuation"].dims)
    return schema.point_axes(ds)


def to_frame(ds, variables=None):
    """A tidy pandas DataFrame: one row per grid point (sweep cube), branch point (continuation)
    or backbone point, the row's coordinates and the `variables` (default: every variable with
    one value per row) as columns; lengths in um and frequencies in Hz with the unit in the
    column name (`clearance_um`, `speed_Hz`). Cheap to plot with hvplot, unlike the whole cube.

    >>> table = rotorsweep.explore.to_frame(rotorsweep.open_cube(cube_path), ["max_abs_multiplier"])
    >>> table.columns.tolist(), table["clearance_um"].tolist()
    (['speed_Hz', 'clearance_um', 'max_abs_multiplier'], [7.6, 7.6])
    """
    dims = row_dims(ds)
    if variables is None:
        variables = [v for v in ds.data_vars if set(ds[v].dims) == set(dims)]
    wrong = [v for v in variables if v not in ds.data_vars or set(ds[v].dims) != set(dims)]
    if wrong:
        raise ValueError(f"to_frame: {', '.join(map(str, wrong))} not a variable with one value per row "
                         f"({', '.join(dims)}); select them from the dataset instead")
    sub = _shown(ds[list(variables)].transpose(*dims))
    table = sub.to_dataframe().reset_index()
    return table.rename(columns={n: f"{n}_{_suffix(sub[n])}" for n in table.columns
                                 if n in sub.variables and _suffix(sub[n])})


def _suffix(da):
    units = da.attrs.get("units")
    return next((suffix for _, unit, suffix in _DISPLAY.values() if unit == units), None)


def _by(ds):
    """The first other swept axis with several values (one line per value), else None."""
    return next((a for a in other_axes(ds) if ds.sizes[a] > 1), None)


def _point_array(ds, values, name, attrs):
    dims = schema.point_axes(ds)
    return xr.DataArray(values, coords={d: ds[d] for d in dims}, dims=dims, name=name, attrs=attrs)


def _solid_dashed(solid, dashed):
    """Stable (solid) lines overlaid by unstable (dashed) ones, the dashed line of each key in
    the colour of its solid line (hvplot's colour cycle would go on over the dashed lines)."""
    return _coloured(solid) * _coloured(dashed)


def _coloured(lines):
    hv = holoviews()
    if not isinstance(lines, hv.NdOverlay):
        return lines.opts(color=LINE_COLOURS[0])
    for i, line in enumerate(lines):
        line.opts(color=LINE_COLOURS[i % len(LINE_COLOURS)])
    return lines


def _limit(y, **style):
    return holoviews().HLine(y).opts(color="#C00000", line_dash="dashed", **style)


@plotting
def max_multiplier(ds, **kwargs):
    """The largest Floquet multiplier modulus along the continued axis, one line per value of the
    first other axis, and the line where it is 1.

    >>> ds = rotorsweep.open_cube(cube_path)
    >>> fig = rotorsweep.explore.max_multiplier(ds)      # or ds.rotorsweep.max_multiplier()
    >>> type(fig).__name__, [d.name for d in fig.kdims]  # a widget per further axis
    ('DynamicMap', ['clearance'])
    """
    return _shown(ds["max_abs_multiplier"]).hvplot.line(x=continued_axis(ds), by=_by(ds), **kwargs) * _limit(1.0)


@plotting
def stability_map(ds, **kwargs):
    """The stability class of every grid point (colours of the report's map) over the continued
    axis and the first other axis (grid cells, not the refined edges of the report's map).

    >>> fig = rotorsweep.explore.stability_map(rotorsweep.open_cube(cube_path))
    >>> type(fig).__name__
    'DynamicMap'
    """
    cls = _point_array(ds, stability_class(ds), "stability_class",
                       {"long_name": "stability class: " + ", ".join(f"{i} {c}" for i, c in enumerate(CLASSES))})
    x, y = continued_axis(ds), _by(ds)
    if y is None:
        return _shown(cls).hvplot.scatter(x=x, color="stability_class", cmap=list(PALETTE), **kwargs)
    return _shown(cls).hvplot.quadmesh(x=x, y=y, cmap=list(PALETTE), clim=(-0.5, len(CLASSES) - 0.5), **kwargs)


@plotting
def branches(ds, observable=None, **kwargs):
    """The periodic orbit's `observable` (see report.branch_observables; default: Poincare
    coordinate with attractors, else amplitude) along the continued axis, stable solid and
    unstable dashed, one colour per value of the first other axis.

    >>> fig = rotorsweep.explore.branches(rotorsweep.open_cube(cube_path), "amplitude_x")
    >>> type(fig).__name__
    'DynamicMap'
    """
    observable = observable or default_observable(ds)
    label, units = branch_observables(ds)[observable]
    da = _point_array(ds, branch_values(ds, observable), observable, {"long_name": label, "units": units})
    stable = ds["stable"] == 1
    x, by = continued_axis(ds), _by(ds)
    return _solid_dashed(_shown(da.where(stable)).hvplot.line(x=x, by=by, **kwargs),
                         _shown(da.where(~stable)).hvplot.line(x=x, by=by, line_dash="dashed", **kwargs))


@plotting
def response(ds, observable=None, **kwargs):
    """Half peak-to-peak amplitude of an observable (default: the first) along the continued
    axis, one line per value of the first other axis.

    >>> fig = rotorsweep.explore.response(rotorsweep.open_cube(cube_path))
    >>> type(fig).__name__
    'DynamicMap'
    """
    observable = observable or schema.model_of(ds).observables[0].name
    return _shown(ds[f"amplitude_{observable}"]).hvplot.line(x=continued_axis(ds), by=_by(ds), **kwargs)


@plotting
def multiplier_frequency(ds, **kwargs):
    """Frequency of the critical multiplier (arg(lambda) / 2 pi / T) vs shaft speed, one series
    per value of the first other axis, with the 1x line (not a Campbell diagram: campbell()).

    >>> fig = rotorsweep.explore.multiplier_frequency(rotorsweep.open_cube(cube_path))
    >>> type(fig).__name__
    'DynamicMap'
    """
    from rotorsweep.pipeline.report.figures.multiplier_frequency import multiplier_frequency_points

    speed = ds[continued_axis(ds)].values
    one_x = holoviews().Curve((speed, speed), continued_axis(ds), "frequency", label="1x").opts(line_dash="dashed")
    return multiplier_frequency_points(_shown(ds), _by(ds)).opts(**kwargs) * one_x


@plotting
def bode(ds, observable=None, **kwargs):
    """Bode (amplitude, phase) and polar plots of the first harmonic of `observable` (default:
    the scene's report observable) of the orbits along the swept or continued parameter, stable
    solid, unstable dashed (rotorsweep.pipeline.report.figures.bode; the orbits are integrated again).

    >>> fig = rotorsweep.explore.bode(rotorsweep.open_result(continuation_path)[0])
    >>> type(fig).__name__, len(fig)                 # amplitude, phase and polar panels
    ('Layout', 3)
    """
    from rotorsweep.pipeline.report import harmonics
    from rotorsweep.pipeline.report.figures import bode as figure
    from rotorsweep.pipeline.report.points import scene_of
    from rotorsweep.pipeline.report.plan import axis_label

    scene = scene_of(ds)
    observable = observable or figure.report_observable(scene)
    if result_kinds.kind_of(ds).name == result_kinds.CONTINUATION:
        lines = harmonics.continuation_lines(ds, scene, observable, [f"branch {b}" for b in range(ds.sizes["branch"])])
        xlabel = f"{ds.attrs['parameter']} [{ds['parameter'].attrs.get('units', '')}]"
    else:
        lines = harmonics.sweep_lines(ds, scene, observable)
        xlabel = axis_label(ds, lines.parameter)       # as the report labels it
    unit = next(o.unit for o in schema.model_of(ds).observables if o.name == observable)
    return figure.fig_bode(lines, observable, unit, xlabel).opts(**kwargs)


@plotting
def campbell(ds, **kwargs):
    """The Campbell diagram of the result's scene (models with a linearization and a shaft
    speed): damped natural frequencies vs shaft speed, critical speeds marked and listed.

    >>> ds, _ = rotorsweep.open_result(backbone_path)      # asymmetric5: a linearization and a speed
    >>> fig = rotorsweep.explore.campbell(ds)
    >>> type(fig).__name__
    'Layout'
    """
    from rotorsweep.pipeline.report.figures import mode_campbell

    return _linear_figure(ds, mode_campbell, mode_campbell.has_linear_analysis(ds), "Campbell diagram",
                          "a linearization, a shaft speed", kwargs)


@plotting
def mode_shapes(ds, **kwargs):
    """The mode shapes at the scene's first grid point: each station's orbit, one panel per mode
    (models with a linearization whose coordinates name stations).

    >>> ds, _ = rotorsweep.open_result(backbone_path)
    >>> fig = rotorsweep.explore.mode_shapes(ds)
    >>> type(fig).__name__
    'Layout'
    """
    from rotorsweep.pipeline.report.figures import mode_shapes as figure

    return _linear_figure(ds, figure, figure.has_stations(ds), "mode shapes",
                          "a linearization, a shaft speed, coordinates that name stations", kwargs)


def _linear_figure(ds, figure, available, what, needs, kwargs):
    """A figure of the scene's linearization (figure.result_figure), or a ValueError saying what it needs."""
    if not available:
        raise ValueError(f"model {ds.attrs.get('model')}: no {what} (it needs {needs} and the scene stored in "
                         "the result)")
    return figure.result_figure(ds, "bokeh").opts(**kwargs)


@plotting
def bifurcation(ds, variable="poincare_x", **kwargs):
    """The attractors' Poincare samples along the continued axis (all samples of a point in one
    column; pass rasterize=True for large cubes, which needs datashader: not installed with rotorsweep).

    >>> fig = rotorsweep.explore.bifurcation(rotorsweep.open_cube(cube_path))
    >>> type(fig).__name__, fig.kdims[0].name
    ('Scatter', 'speed')
    """
    if not has_attractor(ds):
        raise ValueError("the cube has no attractor diagnostics ([analysis] attractor = true)")
    single = [a for a in other_axes(ds) if ds.sizes[a] == 1]      # flattened: its value would be the title
    return _shown(ds[variable].squeeze(single, drop=True)).hvplot.scatter(x=continued_axis(ds), y=variable, by=_by(ds), groupby=[], size=2, **kwargs)


@plotting
def lle(ds, **kwargs):
    """Largest Lyapunov exponent along the continued axis, one line per value of the first
    other axis, and the zero line.

    >>> fig = rotorsweep.explore.lle(rotorsweep.open_cube(cube_path))
    >>> type(fig).__name__
    'DynamicMap'
    """
    return _shown(ds["lle"]).hvplot.line(x=continued_axis(ds), by=_by(ds), **kwargs) * _limit(0.0)


@plotting
def multipliers(ds, where=None, **kwargs):
    """The Floquet multipliers in the complex plane along a line (`where`: the other axes'
    values), coloured by the continued axis, in a square frame with the unit circle.

    >>> fig = rotorsweep.explore.multipliers(rotorsweep.open_cube(cube_path), where={"clearance": 7.6e-6})
    >>> [type(layer).__name__ for layer in fig]       # the unit circle, the multipliers
    ['Curve', 'Scatter']
    """
    line = ds.sel(where) if where else ds
    t = np.linspace(0, 2 * np.pi, 361)
    circle = holoviews().Curve((np.cos(t), np.sin(t)), "multiplier_real", "multiplier_imag").opts(
        color="#555555", line_dash="dashed")
    table = _shown(line[["multiplier_real", "multiplier_imag"]]).to_dataframe().reset_index()
    pts = table.hvplot.scatter(x="multiplier_real", y="multiplier_imag", c=continued_axis(ds), cmap="viridis",
                               hover_cols=[continued_axis(ds)], frame_width=320, frame_height=320,
                               data_aspect=1, **kwargs)
    return circle * pts


@plotting
def branch_diagram(ds, observable=None, **kwargs):
    """A continuation result's branches: half peak-to-peak of `observable` (default: the
    result's report observable) over the continued parameter, one colour per branch, stable
    solid and unstable dashed (a NaN ends a line: the other stability's points are gaps).

    >>> ds, _ = rotorsweep.open_result(continuation_path)
    >>> fig = rotorsweep.explore.branch_diagram(ds)  # or ds.rotorsweep.branch_diagram()
    >>> type(fig).__name__, fig.get_dimension("omega").name
    ('Overlay', 'omega')
    """
    observable = observable or ds.attrs.get("report_observable") or str(ds["observable"].values[0])
    shown = _shown(ds[["parameter", "amplitude_half_pp"]].sel(observable=observable))
    table = pd.DataFrame({"branch": np.repeat(np.arange(ds.sizes["branch"]), ds.sizes["point"]),
                          ds.attrs["parameter"]: shown["parameter"].values.ravel(),
                          observable: shown["amplitude_half_pp"].values.ravel(),
                          "stable": ds["stable"].values.ravel()})
    style = {"x": ds.attrs["parameter"], "y": observable, "by": "branch",
             "xlabel": _label(ds.attrs["parameter"], shown["parameter"]),
             "ylabel": _label(f"half peak-to-peak {observable}", shown["amplitude_half_pp"]), **kwargs}
    stable = table.assign(**{observable: table[observable].where(table["stable"] == 1)})
    unstable = table.assign(**{observable: table[observable].where(table["stable"] == 0)})
    return _solid_dashed(stable.hvplot.line(**style), unstable.hvplot.line(line_dash="dashed", **style))


def _label(name, da):
    units = da.attrs.get("units", "")
    return f"{name} [{units}]" if units not in ("", "1", "various") else name


@plotting
def backbones(ds, where=None, **kwargs):
    """A backbone result's backbones at one line (`where`: the swept axes' values; default the
    first): frequency over the master's amplitude, continuation solid and manifold dashed, one
    colour per mode.

    >>> ds, _ = rotorsweep.open_result(backbone_path)
    >>> fig = rotorsweep.explore.backbones(ds)       # or ds.rotorsweep.backbones()
    >>> type(fig).__name__
    'Overlay'
    """
    line = ds.sel(where) if where else ds.isel({a: 0 for a in ds["axial_approach"].dims})
    modes = line["mode"].values
    table = pd.DataFrame({"mode": np.repeat(modes, line.sizes["amplitude"]),
                          "amplitude": np.tile(_shown(line["amplitude_grid"]).values, len(modes)),
                          "continuation": line["frequency_continuation"].values.ravel(),
                          "manifold": line["frequency_manifold"].values.ravel()})
    style = {"x": "amplitude", "by": "mode", "logx": True, "ylabel": "frequency [Hz]",
             "xlabel": _label("master amplitude", _shown(line["amplitude_grid"])), **kwargs}
    return _solid_dashed(table.hvplot.line(y="continuation", **style),
                         table.hvplot.line(y="manifold", line_dash="dashed", **style))


# the accessor's figures of each result kind (rotorsweep.pipeline.result_kinds)
FIGURES = {kind: {f.__name__: f for f in figures} for kind, figures in (
    (result_kinds.SWEEP, (max_multiplier, stability_map, branches, response, multiplier_frequency, bifurcation, lle,
                          multipliers, bode, campbell, mode_shapes)),
    (result_kinds.CONTINUATION, (branch_diagram, bode, campbell, mode_shapes)),
    (result_kinds.BACKBONE, (backbones,)))}


class CubeAccessor:
    """ds.rotorsweep.<figure>(...): the functions of rotorsweep.pipeline.explore on this result, where its
    kind has them (rotorsweep.pipeline.result_kinds: a sweep cube has every one; a figure that does not
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

    def to_frame(self, variables=None):
        """The tidy table of rotorsweep.pipeline.explore.to_frame (every result kind)."""
        return to_frame(self._ds, variables)

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


register_accessor()         # ds.rotorsweep: this module's CubeAccessor (rotorsweep.pipeline.register_accessor)

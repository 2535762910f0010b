"""The report of a continuation result (`rotorsweep continue`): branch diagrams as users of AUTO
or BifurcationKit read them (an orbit amplitude against the continued parameter, stable branches
solid, unstable dashed, located folds LP, period doublings PD and Neimark-Sacker points NS
marked and labelled), max |multiplier| along the branches, and the table of located points.

A branch that turns back at a fold is not a function of the parameter: it is drawn in its own
order (runs of one stability along the branch, rotorsweep.pipeline.report.branches), never sorted by the
parameter."""
import html

import numpy as np

from rotorsweep.pipeline import coexistence, continuation_result, query, schema
from rotorsweep.pipeline.report import branches, harmonics, page, style
from rotorsweep.pipeline.report.figures import bode, locked_marks, mode_campbell, mode_shapes, torus_detail
from rotorsweep.kernels.continuation import arclength as al

def _shown(value, units):
    """(value, units) as the report shows them: lengths in um (clearances, amplitudes)."""
    return (value * 1e6, "µm") if units == "m" else (value, units)


def _branch_label(ds, b):
    where = ", ".join("{} = {:.4g} {}".format(c, *_shown(float(ds[c].values[b]), ds[c].attrs.get("units", "")))
                      for c in ds.coords if ds[c].dims == ("branch",))
    k = int(ds["branch_periods"].values[b])
    torus = "branch_kind" in ds and ds["branch_kind"].values[b] == 1
    return ("torus" if torus else f"period-{k}") + (f" ({where})" if where else "")


def parameter_axis(ds):
    """(branch x point values, event values, axis label) of the continued parameter as the
    report draws it: in its units, or over omega_l where the result has that coordinate
    ([report] frequency_unit = "omega_l")."""
    par = ds.attrs["parameter"]
    if "parameter_over_omega_l" in ds:
        wl = ds["parameter_over_omega_l"].attrs["omega_l"]
        return (ds["parameter_over_omega_l"].values, ds["event_parameter_over_omega_l"].values,
                f"{par} / ω_l (ω_l = {wl:.4g} Hz)")
    return ds["parameter"].values, ds["event_parameter"].values, f"{par} [{ds['parameter'].attrs.get('units', '')}]"


NOT_AMPLITUDES = ("max_abs_multiplier", "torus_exponent")     # the panels' quantities that are not an observable's


def _panel(hv, ds, yname, ylabel, backend, ref_one=False, kind="amplitude_max"):
    """All distinct branches (a copy of another, coexistence.branch_copy_of, drawn once): y (an
    observable's `kind` of amplitude, or max |multiplier|) against the parameter, solid where
    stable, dashed where not, each with its located events (branches.branch_elements, shared
    with the sweep report's branch diagrams)."""
    par = ds.attrs["parameter"]
    xs, event_xs, xlabel = parameter_axis(ds)
    dims = (hv.Dimension(par, label=xlabel), hv.Dimension(yname, label=ylabel))
    ys, orbit_ys = _values(ds, yname, kind), _event_values(ds, yname, kind)
    # a locked ratio's row holds one orbit of the torus's family: its marker sits on the torus curve
    amplitude = yname not in NOT_AMPLITUDES
    event_ys = locked_marks.on_curve(ds, xs, ys, event_xs, orbit_ys) if amplitude else orbit_ys
    elements = []
    for b in coexistence.distinct_branches(ds):
        mine = ds["event_branch"].values == b
        special = [(x, y, al.EVENT_LABELS[int(k)]) for x, y, k in
                   zip(event_xs[mine], event_ys[mine], ds["event_type"].values[mine])]
        elements += branches.branch_elements(xs[b], ys[b], ds["stable"].values[b] == 1, special,
                                             backend, dims, (xlabel, ylabel), style.LINE_COLOURS[b % len(style.LINE_COLOURS)],
                                             _branch_label(ds, b), legend_unstable=False)
        if amplitude:
            elements += locked_marks.hover_marks(hv, ds, mine, event_xs, event_ys, orbit_ys, dims, (xlabel, ylabel),
                                                 backend)
    if ref_one:
        ref = hv.Curve(([np.nanmin(xs), np.nanmax(xs)], [1.0, 1.0]), *dims, label="|λ| = 1")
        elements.append(ref.opts(color="#C00000", **style.line_style(backend, 1.2, dash=True), backend=backend))
    # bokeh: holoviews hides a legend of more than 25 renderers (legend_limit), six branches have more
    size = ({"width": 1100, "height": 460, "legend_limit": 200} if backend == "bokeh"
            else {"fig_inches": (12, 4.8), "aspect": 1.9})
    return hv.Overlay(elements).opts(show_grid=True, legend_position="right", **size, backend=backend)


def _values(ds, yname, kind):
    """(branch, point) values of a plotted quantity: max |multiplier| or an observable's
    amplitude (kind: amplitude_max, max |o| over the orbit, or amplitude_half_pp), in the units
    the report shows."""
    if yname in NOT_AMPLITUDES:
        return ds[yname].values
    j = list(ds["observable"].values).index(yname)
    return _shown(ds[kind].values[:, :, j], ds[kind].attrs.get("units"))[0]


def _event_values(ds, yname, kind):
    """The events' values of the plotted quantity (NaN: not in the result, one written before
    event_amplitude_half_pp existed)."""
    n = ds.sizes.get("event", 0)
    if yname in NOT_AMPLITUDES:
        return np.ones(n) if yname == "max_abs_multiplier" else np.full(n, np.nan)
    name = "event_" + kind
    if name not in ds:
        return np.full(n, np.nan)
    j = list(ds["observable"].values).index(yname)
    return _shown(ds[name].values[:, j], ds[kind].attrs.get("units"))[0]


def _parameter_scale(ds):
    """Factor from the parameter's units to the drawn axis (1 / omega_l, or 1)."""
    return 1.0 / ds["parameter_over_omega_l"].attrs["omega_l"] if "parameter_over_omega_l" in ds else 1.0


CLASS_COLOURS = {0: ("no stable orbit on the branches", "#D55E00"), 1: ("stable", "#56B4E9"),
                 2: ("bistable (two stable orbits)", "#7B3294")}


def _stability_map(hv, ds, backend):
    """One band per line: the parameter range split where the number of stable orbits on the
    line's branches changes (none / one / two or more: bistable)."""
    keys, lines = coexistence.stability_classes(ds)
    par = ds.attrs["parameter"]
    x, _, xlabel = parameter_axis(ds)
    scale = _parameter_scale(ds)
    xdim = hv.Dimension(par, label=xlabel)
    rects = {c: [] for c in CLASS_COLOURS}
    ticks = []
    for i, (where, pieces) in enumerate(lines.items()):
        units = [ds[k].attrs.get("units", "") for k in keys]
        ticks.append((i, ", ".join("{:.4g} {}".format(*_shown(v, u)) for v, u in zip(where, units)) or "line"))
        for lo, hi, n in pieces:
            rects[min(n, 2)].append((lo * scale, i - 0.42, hi * scale, i + 0.42))
    elements = []
    for c, (name, colour) in CLASS_COLOURS.items():
        data = rects[c] or [(0, 0, 0, 0)]
        hover = {"tools": ["hover"]} if backend == "bokeh" else {}
        el = hv.Rectangles(data, kdims=[xdim, "y", "x1", "y1"], label=name)
        elements.append(el.opts(**style.fill_style(backend, colour), **hover, backend=backend))
    size = {"width": 1100, "height": 140 + 40 * len(lines)} if backend == "bokeh" else {"fig_inches": (12, 1.6 + 0.5 * len(lines)), "aspect": "auto"}
    return hv.Overlay(elements).opts(yticks=ticks, ylim=(-0.5, len(lines) - 0.5), xlim=(np.nanmin(x), np.nanmax(x)),
                                     ylabel=", ".join(keys) or "", legend_position="right", **size, backend=backend)


CURVE_COLOURS = {"fold": "#C00000", "period_doubling": "#0060C0", "neimark_sacker": "#008040"}


def _curves_map(hv, ds, backend):
    """Boundary curves in (parameter, second axis) over the lines' stability bands (none /
    stable / bistable) drawn at their values of the second axis: a Fig. 13-type map whose
    boundaries are curves."""
    par, second = ds.attrs["parameter"], ds.attrs["curves_in"]
    factor, unit = _shown(1.0, ds["curve_second"].attrs.get("units", ""))
    xdim = hv.Dimension(par, label=f"{par} [{ds['parameter'].attrs.get('units', '')}]")
    ydim = hv.Dimension(second, label=f"{second} [{unit}]")
    keys, lines = coexistence.stability_classes(ds)
    elements = []
    if keys == [second]:
        values = np.array(sorted(w[0] for w in lines)) * factor
        half = 0.3 * (np.diff(values).min() if values.size > 1 else 1.0)
        rects = {c: [] for c in CLASS_COLOURS}
        for (v,), pieces in lines.items():
            for lo, hi, n in pieces:
                rects[min(n, 2)].append((lo, v * factor - half, hi, v * factor + half))
        for c, (name, colour) in CLASS_COLOURS.items():
            empty = [(lines and min(p[0] for ps in lines.values() for p in ps), values[0]) * 2]
            el = hv.Rectangles(rects[c] or empty, kdims=[xdim, ydim, "x1", "y1"], label=name)
            elements.append(el.opts(**style.fill_style(backend, colour, alpha=0.45), backend=backend))
    kinds = [al.EVENT_TYPES[int(k)] for k in ds["curve_type"].values]
    for i, kind in enumerate(kinds):
        label = f"{branches.SPECIAL_LABELS[kind]} curve" if kind not in kinds[:i] else ""
        curve = hv.Curve((ds["curve_parameter"].values[i], ds["curve_second"].values[i] * factor), xdim, ydim, label=label)
        hover = {"tools": ["hover"]} if backend == "bokeh" else {}
        elements.append(curve.opts(color=CURVE_COLOURS[kind], **style.line_style(backend, 2.2), **hover, backend=backend))
    size = {"width": 1100, "height": 460} if backend == "bokeh" else {"fig_inches": (12, 4.8), "aspect": 1.9}
    return hv.Overlay(elements).opts(show_grid=True, legend_position="right", **size, backend=backend)


def branch_observables(ds):
    """The observables of the max |o| branch diagrams: the report's (the response panel's) first,
    then the model's first other one."""
    obs = list(ds["observable"].values)
    main = ds.attrs.get("report_observable") or obs[0]
    return [main] + [o for o in obs if o != main][:1]


def figures(ds, backend):
    """(caption, filename, figure) of each figure."""
    hv = style.holoviews()
    units = _shown(1.0, ds["amplitude_max"].attrs.get("units", ""))[1]
    shown = branch_observables(ds)
    main = shown[0]
    out = [(f"Response: half peak-to-peak of {main} over the orbit", f"response_{main}.png",
            _panel(hv, ds, main, f"half peak-to-peak {main} [{units}]", backend, kind="amplitude_half_pp"))]
    out += [(f"Branch diagram: max |{o}| over the orbit", f"branch_{o}.png",
             _panel(hv, ds, o, f"max |{o}| [{units}]", backend)) for o in shown]
    out.insert(1, ("Stability along the parameter: stable, none stable, bistable", "branch_stability_map.png",
                   _stability_map(hv, ds, backend)))
    if "curve" in ds.dims and ds.sizes["curve"]:
        out.insert(2, (f"Stability boundary curves in ({ds.attrs['parameter']}, {ds.attrs['curves_in']})",
                       "boundary_curves.png", _curves_map(hv, ds, backend)))
    tori = ds["branch_kind"].values == 1 if "branch_kind" in ds else np.zeros(ds.sizes["branch"], bool)
    if not tori.all():      # a torus has no first harmonic nor Floquet multipliers
        out.insert(2, (f"Bode and polar plots: first harmonic of {main} along the branches (stable solid, unstable "
                       "dashed)", "bode.png", _bode(ds, main, backend)))
        out.append(("Largest Floquet multiplier modulus along the branches", "branch_max_multiplier.png",
                    _panel(hv, ds, "max_abs_multiplier", "max |multiplier|", backend, ref_one=True)))
    if tori.any():
        out.append(("Tori: largest normal Lyapunov exponent (< 0: stable)", "torus_exponent.png",
                    _panel(hv, ds, "torus_exponent", "largest normal exponent [1/s]", backend)))
        if torus_detail.has_torus_detail(ds):
            out.append((torus_detail.CAPTION, "torus_detail.png", torus_detail.result_figure(ds, backend)))
    if mode_campbell.has_linear_analysis(ds):
        out.append((mode_campbell.CAPTION, "mode_campbell.png", mode_campbell.result_figure(ds, backend)))
    if mode_shapes.has_stations(ds):
        out.append((mode_shapes.CAPTION, "mode_shapes.png", mode_shapes.result_figure(ds, backend)))
    return out


def _bode(ds, observable, backend):
    """The Bode and polar plots of the branches, along the parameter as the other panels draw it."""
    from rotorsweep.pipeline.report.points import scene_of

    scene = scene_of(ds)
    names = [_branch_label(ds, b) for b in range(ds.sizes["branch"])]
    lines = harmonics.continuation_lines(ds, scene, observable, names)
    xs, _, xlabel = parameter_axis(ds)
    lines = lines._replace(x=[row[:len(x)] for row, x in zip(xs, lines.x)])
    unit = next(o.unit for o in scene.model.observables if o.name == observable)
    return bode.fig_bode(lines, observable, unit, xlabel, backend)


def column_units(ds):
    """{column of the events and bistable tables: its unit}: the parameter's (and its error's), the
    line axes', the observables' (model spec), 1 for multipliers and period counts."""
    par, par_unit = ds.attrs["parameter"], ds["parameter"].attrs.get("units", "")
    units = {par: par_unit, f"{par}_error": par_unit, "lo": par_unit, "hi": par_unit, "periods": "1",
             "multiplier_real": "1", "multiplier_imag": "1"}
    units.update({c: ds[c].attrs.get("units", "") for c in ds.coords if ds[c].dims == ("branch",)})
    units.update({f"{kind}_{o.name}": o.unit for o in schema.model_of(ds).observables
                  for kind in ("amplitude_max", "amplitude_half_pp")})
    return units


def with_units(ds, cols):
    """The columns {name: values} renamed "name [unit]" where the name has a unit."""
    units = column_units(ds)
    return {f"{k} [{units[k]}]" if units.get(k) else k: v for k, v in cols.items()}


def _bistable_html(ds):
    rows = coexistence.bistable_intervals(ds)
    if not rows:
        return "<h2>Coexisting stable orbits</h2><p>none on the computed branches</p>"
    return page.columns_html("Coexisting stable orbits", with_units(ds, {k: [r[k] for r in rows] for k in rows[0]}))


def _events_html(ds):
    cols = with_units(ds, continuation_result.events_table(ds))
    if not cols["type"]:
        return "<h2>Located points</h2><p>no fold, period doubling, Neimark-Sacker point or peak on the branches</p>"
    return page.columns_html("Located points", cols)


def _header_html(ds, title):
    lines = continuation_result.describe(ds).splitlines()
    items = "".join(f"<li>{html.escape(s.strip())}</li>" for s in lines[2:])
    return (f"<h1>{html.escape(title)}</h1><p>{html.escape(lines[0])}<br>{html.escape(lines[1])}</p><ul>{items}</ul>"
            "<p>Stable branches solid, unstable dashed; LP: fold (limit point), PD: period doubling, "
            "NS: Neimark-Sacker, BP: branch point; on torus branches TS: the normal stability changes, TF: a fold "
            "of tori, locked: a ratio p/q of the forcings with its periodic orbit (the table's note).</p>")


def make_report(ds, out_dir, title=None):
    """report.html, one PNG per figure and events.csv into out_dir; returns the paths as
    rotorsweep.pipeline.report.make_report does."""
    title = title or f"Continuation report: {ds.attrs.get('scene', '')}"
    return page.write_result_report(out_dir, title, _header_html(ds, title), lambda backend: figures(ds, backend),
                                    _events_html(ds) + _bistable_html(ds), ds.attrs.get("config_toml", ""),
                                    "events.csv", query.render(with_units(ds, continuation_result.events_table(ds)), "csv"))

"""The figure of one `--point`: orbit, Poincare section, power spectrum and the point's table.
Drawn per requested point, not per cube, so it is not in the figure registry."""
import numpy as np

from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.points import POINT_STEPS, point_rows, point_title

SPECTRUM_HARMONICS = 3.3   # spectrum drawn up to this multiple of the ball-passage frequency


def _run_elements(hv, run, colour, cube, backend, pair):
    """The orbit curve and Poincare points of one trajectory (and the cube's samples) in the
    observables `pair` (points.orbit_pair)."""
    d, label = run["detail"], run["label"]
    a, b = pair
    x, y = d[a] * 1e6, d[b] * 1e6
    orbit = (hv.Curve((x, y), "x", "y", label=label)
             .opts(color=colour, **style.line_style(backend, 0.9 if backend == "bokeh" else 0.6, alpha=0.8),
                   backend=backend))
    poinc = []
    cube_x = cube.get(f"poincare_{a}" + run["suffix"])
    if cube_x is not None and np.isfinite(cube_x).any():
        cy = cube[f"poincare_{b}" + run["suffix"]]
        poinc.append(hv.Points((cube_x * 1e6, cy * 1e6), ["x", "y"], label=f"{label}: cube samples")
                     .opts(**style.marker_style(backend, colour, 6 if backend == "bokeh" else 4.5), backend=backend))
    poinc.append(hv.Points((x[::POINT_STEPS], y[::POINT_STEPS]), ["x", "y"], label=f"{label}: this trajectory")
                 .opts(**style.marker_style(backend, colour, 9 if backend == "bokeh" else 6.5, "o", hollow=True,
                                            alpha=0.6), backend=backend))
    return orbit, poinc


def _history(hv, pt, backend):
    """The time history of the drawn pair's second observable over the trajectory (the paper's
    Figs. 5a / 6a: beats show as a varying envelope)."""
    name = pt["pair"][1]
    curves = [hv.Curve((run["detail"]["time"] * 1e3, run["detail"][name] * 1e6), "time", name, label=run["label"])
              .opts(color=colour, **style.line_style(backend, 0.8), backend=backend)
              for run, colour in zip(pt["runs"], style.SWEEP_COLOURS)]
    return hv.Overlay(curves).opts(title=f"time history of {name} (on the attractor)", xlabel="time [ms]",
                                   ylabel=f"{name} [µm]", show_legend=len(curves) > 1,
                                   fontsize=style.fonts(backend), backend=backend)


def _spectrum(hv, pt, backend):
    """The power spectra of x up to SPECTRUM_HARMONICS ball-passage frequencies, with the shaft,
    ball-passage and attractor-period frequencies marked."""
    row = pt["runs"][0]["detail"]["row"]
    f_bp = 1.0 / float(row["forcing_period"])
    spec, pmax = [], 0.0
    for run, colour in zip(pt["runs"], style.SWEEP_COLOURS):
        f, pw = np.asarray(run["detail"]["frequency"]), np.asarray(run["detail"]["power"]) * 1e12
        keep = (f > 0) & (f <= SPECTRUM_HARMONICS * f_bp)
        if keep.any():
            pmax = max(pmax, float(np.nanmax(pw[keep])))
            spec.append((f[keep], pw[keep], colour, run["label"]))
    floor = pmax * 1e-9 if pmax > 0 else 1e-12
    curves = [hv.Curve((f, np.maximum(p, floor)), "frequency", "power", label=lab)
              .opts(color=c, **style.line_style(backend, 1.0), backend=backend) for f, p, c, lab in spec]
    # the shaft frequency is the point's speed (a physical parameter, swept in every cube)
    marks = [(pt["resolved"]["values"]["speed"], "shaft", "#009E73", False),
             (f_bp, "ball passage 1/T", "#CC79A7", True)]
    k_att = int(pt["cube"].get("period", row["period"]))
    if k_att > 1:
        marks.append((f_bp / k_att, f"1/({k_att}T)", "#E69F00", True))
    top = max(pmax, floor) * 3e3        # room for the legend above the peaks
    for fm, name, c, dash in marks:
        curves.append(hv.Curve(([fm, fm], [floor, top]), "frequency", "power", label=f"{name} {fm:.4g} Hz")
                      .opts(color=c, **style.line_style(backend, 1.3, dash=dash), backend=backend))
    return hv.Overlay(curves).opts(title=f"power spectrum of {pt['runs'][0]['detail']['spectrum_of']}", xlabel="frequency [Hz]",
                                   ylabel="power [µm²]", logy=True, ylim=(floor, top),
                                   xlim=(0, SPECTRUM_HARMONICS * f_bp), show_legend=True,
                                   legend_position="top_right" if backend == "bokeh" else "best",
                                   fontsize=style.fonts(backend), backend=backend)


def _text_table(hv, rows, backend):
    """A two-column table as text in a frameless panel (matplotlib; hv.Table's cells shrink
    their font to fit)."""
    n = len(rows)
    texts = []
    for i, (key, value) in enumerate(rows):
        yy = n - i - 0.5
        texts.append(hv.Text(-0.08, yy, key, halign="left", fontsize=8.5))
        texts.append(hv.Text(0.36, yy, value, halign="left", fontsize=8.5))
    return hv.Overlay(texts).opts(xlim=(0, 1), ylim=(0, n), xaxis=None, yaxis=None, aspect="auto",
                                  title="this point", show_frame=False, backend=backend)


def fig_point(pt, backend="bokeh", table=True):
    """Orbit and Poincare section in the pair of observables (points.orbit_pair), power spectrum of
    the first observable, the time history of the pair's second and (table=True) the point's
    table."""
    hv = style.holoviews()
    orbit, poinc = [], []
    for run, colour in zip(pt["runs"], style.SWEEP_COLOURS):
        o, p = _run_elements(hv, run, colour, pt["cube"], backend, pt["pair"])
        orbit.append(o)
        poinc += p
    fonts = style.fonts(backend)
    xl, yl = (f"{o} [µm]" for o in pt["pair"])
    o = hv.Overlay(orbit).opts(title="orbit", xlabel=xl, ylabel=yl, show_legend=len(orbit) > 1,
                               fontsize=fonts, backend=backend)
    q = hv.Overlay(poinc).opts(title="Poincaré section (once per forcing period)", xlabel=xl,
                               ylabel=yl, show_legend=True,
                               legend_position="bottom_right" if backend == "bokeh" else "best",
                               fontsize=fonts, backend=backend)
    sp = _spectrum(hv, pt, backend)
    th = _history(hv, pt, backend)
    if backend == "bokeh":
        # two 600 px panels a row: the page fits a 1400 px window (legends outside add to a row)
        o = o.opts(width=600, height=360, backend=backend)
        q = q.opts(width=600, height=360, backend=backend)
        sp = sp.opts(width=600, height=360, backend=backend)
        th = th.opts(width=600, height=360, backend=backend)
        return hv.Layout([o, q, sp, th]).cols(2).opts(title=point_title(pt), shared_axes=False, backend=backend)
    # "auto": a numeric aspect is a data aspect in holoviews-mpl, wrong on the log axis
    panels = [p.opts(aspect="auto", backend=backend) for p in (o, q, sp, th)]
    if table:
        panels.append(_text_table(hv, point_rows(pt), backend))
    return hv.Layout(panels).cols(2).opts(title=point_title(pt), sublabel_format="", fig_inches=(12, 14),
                                         hspace=0.3, vspace=0.35, fontsize={"title": 13},
                                         backend=backend)

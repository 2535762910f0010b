"""One torus of a continuation result in detail, as Filipkovsky 2016 draws Figs. 5-6: (a) a
trajectory on the torus in the plane of two observables (the report observable against the next
one, e.g. y_B against z), its stroboscopic points (once per shaft turn) and the invariant circle
through which they pass; (b) the report observable's time history along that trajectory; (c) the
decay of the circle's Fourier coefficients (the breakdown criterion of the branch).

The torus: the point of the largest half-swing of the report observable over the torus branches,
or the point nearest `[report] torus_detail` (a value of the continued parameter). Its circle is
the trigonometric interpolant of the result's `torus_nodes`; the trajectory is integrated from
the circle at phase 0 with the scene's kernel (the scene stored in the result), so its
stroboscopic points fall on the circle to the torus's error (tests/test_torus_detail.py).
"""
from typing import NamedTuple

import numpy as np

from rotorsweep.pipeline.report import style
from rotorsweep.kernels import shooting, torus as tr

CIRCLE_PHASES = 256
TURNS = 40              # shaft turns of the trajectory drawn
SAMPLES_PER_TURN = 48
CAPTION = ("A torus in detail (Filipkovsky 2016, Figs. 5-6): a trajectory on it with its once-per-turn points on "
           "the invariant circle, its time history, and the circle's Fourier decay")


class Detail(NamedTuple):
    branch: int
    point: int
    parameter: float
    names: tuple            # (x, y) observables of the section plane
    circle: np.ndarray      # (CIRCLE_PHASES, 2) the circle in the plane, SI
    trajectory: np.ndarray  # (TURNS * SAMPLES_PER_TURN, 2) SI
    time: np.ndarray        # its times [s]
    spectrum: np.ndarray    # |c_m| / max(1, max |U|), m = 0 .. K, largest over the state
    torus: tr.Torus         # the circle (scaled state)
    states: np.ndarray      # the trajectory (scaled state)


def has_torus_detail(ds):
    return "torus_nodes" in ds and bool(ds.attrs.get("config_toml")) and bool(
        (ds["torus_status"].values >= 0).any())


def chosen_point(ds, value=None):
    """(branch, point) of the torus drawn: nearest `value` of the parameter, else the largest
    half-swing of the report observable."""
    obs = list(ds["observable"].values)
    j = obs.index(ds.attrs["report_observable"]) if ds.attrs.get("report_observable") in obs else 0
    torus = ds["torus_status"].values >= 0
    if value is not None:
        score = np.where(torus, -np.abs(ds["parameter"].values - value), -np.inf)
    else:
        score = np.where(torus, np.nan_to_num(ds["amplitude_half_pp"].values[..., j], nan=-np.inf), -np.inf)
    b, k = np.unravel_index(np.argmax(score), score.shape)
    return int(b), int(k)


def torus_detail(ds, scene):
    """The Detail of the chosen torus (module docstring), from the result and its scene."""
    from rotorsweep.pipeline import continuation, torus_branches

    b, k = chosen_point(ds, scene.report.torus_detail)
    nodes = ds["torus_nodes"].values[b, k]
    nodes = nodes[~np.isnan(nodes).any(axis=1)]
    lam = float(ds["parameter"].values[b, k])
    where = {c: float(ds[c].values[b]) for c in ds.coords if ds[c].dims == ("branch",)}
    family, built = torus_branches.torus_family(scene, continuation.plan(scene), where, nodes.shape[0])
    circle = tr.Torus(nodes, float(family.rotation(lam)), family.period, tr.CONVERGED, 0, np.nan,
                      tr.fourier_tail(nodes), np.nan, np.empty(0), 0)
    spec = scene.model
    p = np.array(family.params(lam), float)
    p[family.phase_index] = 0.0
    states = shooting.sample_orbit(spec.kernel, circle.at(0.0)[0], p, TURNS * family.period, TURNS * SAMPLES_PER_TURN,
                                   family.opts)
    obs = list(ds["observable"].values)
    j = obs.index(ds.attrs["report_observable"]) if ds.attrs.get("report_observable") in obs else 0
    pair = [(j + 1) % len(obs), j]
    period = built(lam).period
    coef = np.abs(np.fft.rfft(nodes, axis=0)).max(axis=1) / nodes.shape[0] / max(1.0, np.abs(nodes).max())
    return Detail(b, k, lam, tuple(obs[i] for i in pair),
                  spec.observe(circle.at(tr.node_phases(CIRCLE_PHASES)), period)[:, pair],
                  spec.observe(states, period)[:, pair], np.arange(len(states)) * period / SAMPLES_PER_TURN,
                  coef, circle, states)


def _hover(backend, *tooltips):
    return {"tools": ["hover"], "hover_tooltips": list(tooltips)} if backend == "bokeh" else {}


def _section(hv, d, backend):
    (xn, yn), um = d.names, 1e6
    dims = [hv.Dimension(xn, label=f"{xn} [µm]"), hv.Dimension(yn, label=f"{yn} [µm]")]
    strobe = d.trajectory[::SAMPLES_PER_TURN] * um
    return hv.Overlay([
        hv.Curve((d.trajectory[:, 0] * um, d.trajectory[:, 1] * um), *dims, label=f"trajectory, {TURNS} turns").opts(
            color="#999999", **style.line_style(backend, 0.8, alpha=0.7), backend=backend),
        hv.Curve((d.circle[:, 0] * um, d.circle[:, 1] * um), *dims, label="invariant circle (phase 0 section)").opts(
            color=style.LINE_COLOURS[0], **style.line_style(backend, 2.2), **_hover(backend, (xn, f"@{{{xn}}} µm"),
                                                                                 (yn, f"@{{{yn}}} µm")), backend=backend),
        style.legend_points(hv, strobe[:, 0], strobe[:, 1], dims, "trajectory once per turn").opts(
            **style.marker_style(backend, style.LINE_COLOURS[4], 7, "o", hollow=True), backend=backend),
    ]).opts(title="(a) trajectory on the torus and its section", show_grid=True, legend_position="bottom_right",
            backend=backend)


def _history(hv, d, backend):
    yn = d.names[1]
    dims = [hv.Dimension("t", label="t [ms]"), hv.Dimension(yn, label=f"{yn} [µm]")]
    curve = hv.Curve((d.time * 1e3, d.trajectory[:, 1] * 1e6), *dims, label=f"{yn} on the torus").opts(
        color=style.LINE_COLOURS[0], **style.line_style(backend, 1.0), **_hover(backend, ("t", "@t ms"), (yn, f"@{{{yn}}} µm")),
        backend=backend)
    return hv.Overlay([curve]).opts(title="(b) time history", show_grid=True, legend_position="top_right", backend=backend)


def _spectrum(hv, d, backend):
    from rotorsweep.pipeline import torus_branches

    dims = [hv.Dimension("m", label="Fourier mode m in the forcing phase"),
            hv.Dimension("c", label="max |c_m| over the state (relative)")]
    m = np.arange(d.spectrum.size)
    c = np.maximum(d.spectrum, 1e-18)     # round-off zeros drawn at the floor of a log axis
    return hv.Overlay([
        hv.Curve((m, c), *dims, label=f"circle, {d.torus.nodes.shape[0]} nodes").opts(
            color=style.LINE_COLOURS[0], **style.line_style(backend, 1.6), backend=backend),
        style.legend_points(hv, m, c, dims, "coefficients").opts(
            **style.marker_style(backend, style.LINE_COLOURS[0], 6), **_hover(backend, ("m", "@m"), ("|c_m|", "@c")),
            backend=backend),
        hv.HLine(torus_branches.BREAKDOWN_TOL, label="breakdown tolerance").opts(
            color="#CC0000", **style.line_style(backend, 1.2, dash=True), backend=backend),
    ]).opts(title="(c) Fourier decay of the circle", logy=True, show_grid=True, legend_position="top_right",
            backend=backend)


def result_figure(ds, backend):
    from rotorsweep.pipeline.report.points import scene_of

    hv = style.holoviews()
    d = torus_detail(ds, scene_of(ds))
    size = {"width": 440, "height": 400} if backend == "bokeh" else {"aspect": 1.1}
    panels = [f(hv, d, backend).opts(**size, backend=backend) for f in (_section, _history, _spectrum)]
    title = (f"Torus at {ds.attrs['parameter']} = {d.parameter:.6g} {ds['parameter'].attrs.get('units', '')} "
             f"(branch {d.branch}, point {d.point})")
    return style.layout(hv, panels, backend, 3, title, fig_inches=(14, 4.6))

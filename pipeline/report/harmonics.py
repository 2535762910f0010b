"""First harmonic of a result's periodic orbits (Bode and polar plots): the complex amplitude X
of an observable at the forcing frequency 1/T, o(t) ~ Re(X exp(2 pi i t / T)) = |X| cos(2 pi t / T
+ arg X), the phase measured from the forcing's own phase at t = 0 (tau = 0 of the kernels: the
unbalance and the Duffing force peak there).

The results store each orbit's state at t = 0, not its time history: the orbit is integrated
again over its period (k forcing periods for a period-k orbit) at the scene's integrator
settings, sampled at HARMONIC_SAMPLES per forcing period, and X is the DFT coefficient of the
forcing frequency (index k). Why that is exact for the orbit: the DFT of N equally spaced samples
of a periodic signal returns its Fourier coefficient c_k plus the aliases c_{k +- mN}; a smooth
(analytic) orbit's coefficients decay geometrically, so with N = 64 k samples the error is of
the order of its 63rd harmonic, far below the integrator's tolerance for the orbits of these
models (a linear orbit is a pure sinusoid: exact to rounding for any N >= 3)."""
from typing import NamedTuple

import numpy as np

from rotorsweep.pipeline import compute, schema
from rotorsweep.pipeline.report.cubeinfo import continued_axis, other_axes
from rotorsweep.kernels.orbits import ForcedOrbitProblem

HARMONIC_SAMPLES = 64
CONVERGED = schema.ORBIT_STATUS.index("converged")


def first_harmonic(values, periods=1):
    """Complex amplitude X (per column) of the forcing frequency from samples at t_j = j k T / N,
    j = 0..N-1, over k = `periods` forcing periods: X = (2 / N) sum_j o_j exp(-2 pi i k j / N)."""
    values = np.asarray(values, float)
    n = len(values)
    basis = np.exp(-2j * np.pi * periods * np.arange(n) / n)
    return 2.0 / n * (basis @ values)


def orbit_harmonic(spec, built, opts, state, periods=1):
    """First harmonic of every observable (SI) of the orbit through the scaled `state` at the
    point `built` (compute.builder's Built); NaN where there is no orbit or the flow fails."""
    state = np.asarray(state, float)
    if not np.all(np.isfinite(state)):
        return np.full(len(spec.observables), np.nan + 0j)
    problem = ForcedOrbitProblem(spec, built.p, opts, float(periods))
    samples = problem.samples(state, HARMONIC_SAMPLES)
    return first_harmonic(spec.observe(samples, built.period), periods)


class Lines(NamedTuple):
    """What a Bode or polar plot draws: per line, the parameter values, the first harmonic of one
    observable [SI] and the stability, in branch order; the line's legend name."""
    x: list
    harmonic: list
    stable: list
    names: list
    parameter: str          # the swept or continued parameter's name


def _observable_index(spec, observable):
    names = [o.name for o in spec.observables]
    if observable not in names:
        raise ValueError(f"no observable {observable!r}; the model's are {', '.join(names)}")
    return names.index(observable)


def sweep_lines(ds, scene, observable):
    """Lines of a sweep cube along its continued axis, one per value of the first other axis
    with several values (the other axes at their first value): the grid's converged orbits
    (scene: the cube's rotorsweep.pipeline.scene.Scene)."""
    spec = scene.model
    j = _observable_index(spec, observable)
    build, fixed, opts = compute.builder(scene), scene.fixed, scene.integrator
    x = continued_axis(ds)
    by = next((a for a in other_axes(ds) if ds.sizes[a] > 1), None)
    rest = {a: 0 for a in other_axes(ds) if a != by}
    groups = range(ds.sizes[by]) if by else [None]
    out = Lines([], [], [], [], x)
    for g in groups:
        line = ds.isel({**rest, **({by: g} if by else {})}).transpose(x, ...)
        where = {a: float(line[a].values) for a in schema.point_axes(ds) if a != x}
        grid = line[x].values.astype(float)
        harmonic = np.array([orbit_harmonic(spec, build({**fixed, **where, x: float(v)}), opts,
                                            line["orbit_state"].values[i])[j]
                             if int(line["orbit_status"].values[i]) == CONVERGED else np.nan + 0j
                             for i, v in enumerate(grid)])
        out.x.append(grid)
        out.harmonic.append(harmonic)
        out.stable.append(line["stable"].values == 1)
        out.names.append(f"{by} = {float(line[by].values):.4g}" if by else "periodic orbit")
    return out


def continuation_lines(ds, scene, observable, names):
    """Lines of a continuation result, one per branch (names: the branches' legend names)."""
    spec = scene.model
    j = _observable_index(spec, observable)
    build, fixed, opts = compute.builder(scene), scene.fixed, scene.integrator
    par = ds.attrs["parameter"]
    out = Lines([], [], [], [], par)
    for b in range(ds.sizes["branch"]):
        n = int(ds["branch_points"].values[b])
        where = {c: float(ds[c].values[b]) for c in ds.coords if ds[c].dims == ("branch",)}
        lams = ds["parameter"].values[b, :n]
        periods = int(ds["branch_periods"].values[b])
        states = ds["orbit_state"].values[b, :n]
        out.x.append(lams)
        out.harmonic.append(np.array([orbit_harmonic(spec, build({**fixed, **where, par: float(lam)}), opts,
                                                     state, periods)[j] for lam, state in zip(lams, states)]))
        out.stable.append(ds["stable"].values[b, :n] == 1)
        out.names.append(names[b])
    return out

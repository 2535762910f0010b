"""Reading a continuation result (`rotorsweep info`, `query`, the report's tables): what
rotorsweep.pipeline.continuation wrote, read without its kernels, so that info and query on a
continuation result import no Numba (issue 35; tests/test_latency.py)."""
import json

import numpy as np

from rotorsweep.pipeline import query, result_kinds
from rotorsweep.pipeline.coexistence import bistable_intervals, branch_copy_of, distinct_branches, distinct_events
from rotorsweep.kernels import continuation_codes as codes

_STATUS = result_kinds.CONTINUATION_VARIABLES["torus_status"][1]
# a torus point's normal stability: its name -> its torus_status code (no_torus, -1, left out)
TORUS_STATUS = {name: int(code) for name, code in zip(_STATUS["flag_meanings"].split(), _STATUS["flag_values"])
                if code >= 0}
# Whose amplitudes an event row's event_amplitude_* are, by event code (the events table's
# `amplitudes_of`): a locked row's are ONE orbit of the torus's family of locked orbits, so they lie
# at or below the torus's own (taken over all phases theta of its circle); other rows' are the branch's.
AMPLITUDES_OF = {codes.LOCKED: "linked orbit at theta = 0", codes.TORUS_STABILITY: "torus", codes.TORUS_FOLD: "torus"}


def open_result(path):
    """Open a continuation result into memory; CubeError if the file is not one."""
    return result_kinds.open_kind(path, result_kinds.CONTINUATION)


def describe(ds):
    """`rotorsweep info` of a continuation result."""
    par = ds.attrs["parameter"]
    unit = ds["parameter"].attrs.get("units", "")
    lines = [f"continuation result: scene {ds.attrs.get('scene', '?')}, model {ds.attrs.get('model', '?')}",
             f"parameter {par} [{unit}] over {json.loads(ds.attrs['range'])}",
             f"{ds.sizes['branch']} branch(es) ({len(distinct_branches(ds))} distinct, copies of one family of orbits "
             f"counted once), {len(distinct_events(ds))} distinct located event(s)"
             f" ({ds.sizes.get('event', 0)} met, copies of one orbit counted once)"]
    for b in distinct_branches(ds):
        where = ", ".join(f"{c}={float(ds[c].values[b]):g}" for c in ds.coords if ds[c].dims == ("branch",))
        what = "torus" if "branch_kind" in ds and ds["branch_kind"].values[b] == 1 else \
            f"period-{int(ds['branch_periods'].values[b])}"
        lines.append(f"  branch {b}: {what}"
                     f"{f' from branch {int(ds.branch_parent.values[b])}' if ds.branch_parent.values[b] >= 0 else ''}"
                     f"{f' ({where})' if where else ''}, {int(ds['branch_points'].values[b])} points, "
                     f"ended {codes.END_REASONS[int(ds['branch_end'].values[b])]}: {ds['branch_detail'].values[b]}"
                     + "".join(f"; branch {c} is the same" for c in np.flatnonzero(branch_copy_of(ds) == b) if c != b))
    lines += _peak_lines(ds, par, unit) + torus_lines(ds, par, unit)
    for iv in bistable_intervals(ds):
        where = ", ".join(f"{k}={v:g}" for k, v in iv.items() if k not in ("lo", "hi", "branches"))
        lines.append(f"  two stable orbits coexist: {par} {iv['lo']:.10g} to {iv['hi']:.10g} {unit}"
                     f"{f' ({where})' if where else ''}, branches {iv['branches']}")
    return "\n".join(lines)


def _peak_lines(ds, par, unit):
    """`info`'s lines of the located peaks: where, the plotted observable's half peak-to-peak
    there, stability."""
    obs = list(ds["observable"].values)
    j = obs.index(ds.attrs["report_observable"]) if ds.attrs.get("report_observable") in obs else 0
    units = ds["event_amplitude_half_pp"].attrs.get("units", "")
    mult = ds["event_multiplier_real"].values + 1j * ds["event_multiplier_imag"].values
    return [f"  peak on branch {int(ds['event_branch'].values[k])}: {par} {ds['event_parameter'].values[k]:.10g}"
            f"{error_text(ds, k)} {unit}, "
            f"half peak-to-peak {obs[j]} {ds['event_amplitude_half_pp'].values[k, j]:.10g} {units}, "
            f"{'stable' if np.abs(mult[k]).max() < 1.0 else 'unstable'}"
            for k in np.flatnonzero(ds["event_type"].values == codes.PEAK)]


def parameter_errors(ds):
    """Each event's parameter error estimate (NaN: not estimated, or a result written before it was)."""
    if "event_parameter_error" in ds:
        return ds["event_parameter_error"].values
    return np.full(ds.sizes.get("event", 0), np.nan)


def error_text(ds, k):
    """" +- 2e-05" of event k's parameter error estimate ("" where it has none)."""
    error = parameter_errors(ds)[k]
    return f" +- {error:.2g}" if np.isfinite(error) else ""


def _event_periods(ds):
    """Forcing periods of each event's orbit: event_periods where written (a torus branch's locked
    p/q row: q), else its branch's."""
    return ds["event_periods"].values if "event_periods" in ds else ds["branch_periods"].values[ds["event_branch"].values]


def events_table(ds):
    """The located events as columns (for query's renderer), each orbit once (its first record):
    type, branch, parameter and its error estimate (NaN: none), period, the critical multiplier,
    max |observable|."""
    par = ds.attrs["parameter"]
    ds = ds.isel(event=distinct_events(ds))
    mult = ds["event_multiplier_real"].values + 1j * ds["event_multiplier_imag"].values
    kinds = ds["event_type"].values
    targets = np.array([{0: 1.0, 1: -1.0}.get(int(k), np.nan) for k in kinds])
    critical = [m[np.argmin(np.abs(m - t))] if np.isfinite(t) else m[np.argmin(np.abs(np.abs(m) - 1.0))]
                for m, t in zip(mult, targets)] if len(kinds) else []
    branch = ds["event_branch"].values
    cols = {"type": [codes.EVENT_LABELS[int(k)] for k in kinds], "branch": branch.tolist(),
            "periods": _event_periods(ds).tolist(),
            par: ds["event_parameter"].values.tolist(), f"{par}_error": parameter_errors(ds).tolist(),
            "multiplier_real": [float(c.real) for c in critical], "multiplier_imag": [float(c.imag) for c in critical]}
    for c in ds.coords:
        if ds[c].dims == ("branch",):
            cols[c] = ds[c].values[branch].tolist() if len(branch) else []
    cols["stable"] = [-1 if np.isnan(m).all() else int(np.abs(m).max() < 1.0) for m in mult]   # -1: a torus flag
    if "event_note" in ds:      # torus branches' events (rotorsweep.pipeline.torus_events) in words
        cols["note"] = [str(v) for v in ds["event_note"].values]
        cols["amplitudes_of"] = [AMPLITUDES_OF.get(int(k), "orbit") for k in kinds]
    for j, name in enumerate(ds["observable"].values):
        cols[f"amplitude_max_{name}"] = ds["event_amplitude_max"].values[:, j].tolist()
        cols[f"amplitude_half_pp_{name}"] = ds["event_amplitude_half_pp"].values[:, j].tolist()
    return cols


def torus_lines(ds, par, unit):
    """`info`'s lines of a continuation result's torus branches: where each is stable, its
    largest half-swing of the report observable, its largest error estimate."""
    if "branch_kind" not in ds:
        return []
    obs = list(ds["observable"].values)
    j = obs.index(ds.attrs["report_observable"]) if ds.attrs.get("report_observable") in obs else 0
    out, stretches = [], query.branch_unstable_stretches(ds)
    for b in np.flatnonzero(ds["branch_kind"].values == 1):
        n = int(ds["branch_points"].values[b])
        if not n:
            continue
        lam, status = ds["parameter"].values[b, :n], ds["torus_status"].values[b, :n]
        counts = ", ".join(f"{(status == code).sum()} {name}" for name, code in TORUS_STATUS.items())
        out.append(f"  torus branch {b}: {par} {lam.min():.10g} to {lam.max():.10g} {unit}, points {counts}; "
                   f"half-swing {obs[j]} up to {np.nanmax(ds['amplitude_half_pp'].values[b, :n, j]):.6g} "
                   f"{ds['amplitude_half_pp'].attrs.get('units', '')}, error estimate up to "
                   f"{np.nanmax(ds['torus_error'].values[b, :n]):.2g}{modes_text(ds, b, n)}")
        out += [f"    stability changes between {par} {lam[i]:.10g} and {lam[i + 1]:.10g} {unit}"
                for i in np.flatnonzero((status[:-1] != status[1:]) & (status[:-1] < 2) & (status[1:] < 2))]
        out += [event_line(ds, k, par, unit) for k in np.flatnonzero(ds["event_branch"].values == b)] \
            if "event_note" in ds else []
        out += [stretch_line(st, par, unit) for st in stretches if st["branch"] == b]
    return out


def stretch_line(st, par, unit):
    """`info`'s line of an unstable torus stretch (query.branch_unstable_stretches): its points and
    where its stability is lost and regained (the located TS / TF events)."""
    def at(value):
        return f"{value:.10g} {unit}" if np.isfinite(value) else "not located"
    return (f"    unstable from {par} {st['start']:.10g} to {st['end']:.10g} {unit} ({st['n_points']} points): "
            f"onset {at(st['onset'])}, offset {at(st['offset'])}")


def event_line(ds, k, par, unit):
    """`info`'s line of a torus branch's event k: where it was located (a flag kept as a bracket,
    NaN parameter, says so; its note gives the bracket)."""
    value = ds["event_parameter"].values[k]
    where = f"at {par} {value:.10g} {unit}" if np.isfinite(value) else "(not located)"
    return f"    {codes.EVENT_LABELS[int(ds['event_type'].values[k])]} {where}: {ds['event_note'].values[k]}"


def modes_text(ds, b, n):
    """", Fourier modes K (2K + 1 nodes) from a to b, c changes" of branch b's first n points ("" in
    a result written before torus_modes was)."""
    if "torus_modes" not in ds:
        return ""
    modes = ds["torus_modes"].values[b, :n]
    changes = int(np.count_nonzero(np.diff(modes)))
    span = f"{modes.min()}" if modes.min() == modes.max() else f"{modes.min()} to {modes.max()}"
    return f", Fourier modes {span} ({changes} change{'s' * (changes != 1)} along the branch)"

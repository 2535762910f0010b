"""Reading a backbone result (`rotorsweep info`, `query`, the report's tables): what
rotorsweep.pipeline.backbone wrote, read without its kernels and scipy, so that info and query on
a backbone result import no Numba (issue 35; tests/test_latency.py)."""
import numpy as np

from rotorsweep.pipeline import result_kinds


def open_result(path):
    """Open a backbone result into memory; CubeError if the file is not one."""
    return result_kinds.open_kind(path, result_kinds.BACKBONE)


def table(ds):
    """One row per (line, mode): the columns `query` prints."""
    cols = {a: [] for a in ds["axial_approach"].dims}
    cols.update({k: [] for k in ("mode", "label", "whirl", "linear_frequency_hz", "kappa", "parting_amplitude_m",
                                 "invariance_distance_m", "continuation_end")})
    for idx in np.ndindex(ds["axial_approach"].shape):
        sel = dict(zip(ds["axial_approach"].dims, idx))
        line = ds.isel(sel)
        for a, i in sel.items():
            cols[a] += [float(ds[a].values[i])] * ds.sizes["mode"]
        cols["mode"] += [int(m) for m in ds["mode"].values]
        cols["label"] += [str(x) for x in line["mode_label"].values]
        cols["whirl"] += [str(x) for x in line["mode_whirl"].values]
        cols["linear_frequency_hz"] += line["linear_frequency"].values.tolist()
        cols["kappa"] += line["kappa"].values.tolist()
        cols["parting_amplitude_m"] += line["parting_amplitude"].values.tolist()
        cols["invariance_distance_m"] += line["invariance_distance"].values.tolist()
        cols["continuation_end"] += [str(x) for x in line["continuation_end"].values]
    return cols


def describe(ds):
    """`rotorsweep info` of a backbone result."""
    lines = [f"backbone result: scene {ds.attrs.get('scene', '?')}, model {ds.attrs.get('model', '?')}",
             f"{ds.sizes['mode']} mode(s) x {ds.sizes['amplitude']} amplitudes"
             + "".join(f" x {ds.sizes[a]} {a}" for a in ds["axial_approach"].dims)]
    cols = table(ds)
    for i in range(len(cols["mode"])):
        where = ", ".join(f"{a}={cols[a][i]:g}" for a in ds["axial_approach"].dims)
        part = cols["parting_amplitude_m"][i]
        lines.append(f"  mode {cols['mode'][i]}{f' ({where})' if where else ''}: {cols['label'][i]} {cols['whirl'][i]}, "
                     f"{cols['linear_frequency_hz'][i]:.6g} Hz, manifold and continuation part by 1 % at "
                     f"{f'{part * 1e6:.3g} um' if np.isfinite(part) else 'no amplitude of the grid'}; "
                     f"continuation {cols['continuation_end'][i]}")
    return "\n".join(lines)

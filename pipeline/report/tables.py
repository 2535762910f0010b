"""The unstable-interval table of a cube, for the HTML page and the CSV, and the bistable
intervals with the two stable orbits that coexist in each."""
import csv

import numpy as np

from rotorsweep.pipeline.report.cubeinfo import continued_axis, other_axes
from rotorsweep.pipeline.report.plan import TYPE_NAMES, axis_display, axis_label, unit_display


def interval_rows(ds, intervals, machine=False):
    """The unstable-interval table as (header, rows of strings) in display units. machine=True:
    ASCII header and the query's type codes (fold, period_doubling, neimark_sacker, no_orbit,
    quasi_periodic_unstable, torus_failed), for the CSV. A cube with tori adds the runs' largest
    normal exponent of the torus and a failed torus run's reason."""
    others = other_axes(ds)
    unit = axis_display(ds, continued_axis(ds))[1]
    tori = "torus_status" in ds
    header = ([axis_label(ds, a) for a in others]
              + [f"start [{unit}]", f"end [{unit}]", f"refined onset [{unit}]", f"refined offset [{unit}]",
                 "points", "type", "max |multiplier|"] + (["max torus exponent [1/s]", "torus failed: status"] if tori else []))
    factors = [axis_display(ds, a)[0] for a in others]
    rows = []
    for iv in intervals:
        rows.append([f"{iv[a] * f:.6g}" for a, f in zip(others, factors)]
                    + [f"{iv['start']:.6g}", f"{iv['end']:.6g}", _refined(iv, "onset"),
                       _refined(iv, "offset"), str(iv["n_points"]),
                       iv["type"] if machine else TYPE_NAMES.get(iv["type"], iv["type"]),
                       f"{iv['max_abs_multiplier']:.4g}"]
                    + ([_number(iv["max_torus_exponent"]), iv["reason"] or "-"] if tori else []))
    if machine:
        header = [h.replace("µ", "u").replace("|multiplier|", "abs multiplier") for h in header]
    return header, rows


def bistable_rows(ds, intervals):
    """The bistable-interval table (query.bistable_intervals) as (header, rows of strings) in
    display units: the line, the fold pair, and each of the two coexisting stable orbits (computed
    by coexistence.distinct_stable_orbits where the sweep met the jump) with its half
    peak-to-peak amplitudes, period and largest |multiplier| ("-" where not recorded)."""
    others = other_axes(ds)
    unit = axis_display(ds, continued_axis(ds))[1]
    names = sorted({k[len("orbit1_amplitude_"):] for iv in intervals for k in iv if k.startswith("orbit1_amplitude_")})
    orbit_cols = [f"amplitude_{n}" for n in names] + ["periods", "max_abs_multiplier"]
    header = ([axis_label(ds, a) for a in others] + [f"lower fold [{unit}]", f"upper fold [{unit}]", f"orbits at [{unit}]"]
              + [f"orbit {j}: " + (f"half p-p {c[len('amplitude_'):]} [{_display(ds, c)[1]}]" if c.startswith("amplitude_")
                                   else "period [forcing periods]" if c == "periods" else "max |multiplier|")
                 for j in (1, 2) for c in orbit_cols])
    factors = [axis_display(ds, a)[0] for a in others]
    rows = []
    for iv in intervals:
        cells = [_orbit_cell(ds, c, iv.get(f"orbit{j}_{c}")) for j in (1, 2) for c in orbit_cols]
        rows.append([f"{iv[a] * f:.6g}" for a, f in zip(others, factors)]
                    + [_refined(iv, "start"), _refined(iv, "end"), _refined(iv, "orbits_at")] + cells)
    return header, rows


def _display(ds, column):
    """(factor, display unit) of an amplitude column: its cube variable's units (SI)."""
    return unit_display(ds[column].attrs.get("units", "1") if column in ds else "1")


def _orbit_cell(ds, column, value):
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "-"
    if column.startswith("amplitude_"):
        return f"{value * _display(ds, column)[0]:.6g}"
    return str(value) if column == "periods" else f"{value:.4g}"


def _number(value):
    return f"{value:.4g}" if np.isfinite(value) else "-"


def _refined(iv, key):
    value = iv.get(key, float("nan"))
    return f"{value:.8g}" if np.isfinite(value) else "-"


def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)

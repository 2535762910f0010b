"""The unstable-interval table of a cube, for the HTML page and the CSV."""
import csv

import numpy as np

from pipeline.report.cubeinfo import continued_axis, other_axes
from pipeline.report.plan import TYPE_NAMES, axis_display, axis_label


def interval_rows(ds, intervals, machine=False):
    """The unstable-interval table as (header, rows of strings) in display units. machine=True:
    ASCII header and the query's type codes (fold, period_doubling, neimark_sacker, no_orbit),
    for the CSV."""
    others = other_axes(ds)
    unit = axis_display(ds, continued_axis(ds))[1]
    header = ([axis_label(ds, a) for a in others]
              + [f"start [{unit}]", f"end [{unit}]", f"refined onset [{unit}]", f"refined offset [{unit}]",
                 "points", "type", "max |multiplier|"])
    factors = [axis_display(ds, a)[0] for a in others]
    rows = []
    for iv in intervals:
        rows.append([f"{iv[a] * f:.6g}" for a, f in zip(others, factors)]
                    + [f"{iv['start']:.6g}", f"{iv['end']:.6g}", _refined(iv, "onset"),
                       _refined(iv, "offset"), str(iv["n_points"]),
                       iv["type"] if machine else TYPE_NAMES.get(iv["type"], iv["type"]),
                       f"{iv['max_abs_multiplier']:.4g}"])
    if machine:
        header = [h.replace("µ", "u").replace("|multiplier|", "abs multiplier") for h in header]
    return header, rows


def _refined(iv, key):
    value = iv.get(key, float("nan"))
    return f"{value:.8g}" if np.isfinite(value) else "-"


def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)

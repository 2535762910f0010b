"""Backbone curves two ways (issue 14's benchmark): the cost of the Shaw-Pierre manifold's
backbone against continuation of the full model, and their agreement, per mode of the 2010
papers' rotors, in one run.

    python -m workflows.bench.backbone [--repeats 5]      # -> docs/benchmarks/backbone.{json,md}
"""
import argparse
import json
import time
from pathlib import Path

import numpy as np

from rotorsweep.pipeline import backbone as pb, config, scene as scenes
from rotorsweep.kernels import nnm
from workflows.bench import render
from workflows.bench.common import DOCS, best_time, loadavg, log, provenance

SCENES = ("configs/filipkovsky2010_axial.toml", "configs/filipkovsky2010_symmetric.toml")


def slope(grid, rel):
    """Log-log slope of |rel| over the grid's lowest decade (NaN when it holds no finite value)."""
    low = (grid <= grid[0] * 10 * (1 + 1e-9)) & np.isfinite(rel) & (rel != 0)
    return float(np.polyfit(np.log(grid[low]), np.log(np.abs(rel[low])), 1)[0]) if low.sum() > 2 else np.nan


def mode_rows(path, repeats, grid_points=None):
    """One row per mode of the scene at `path`: times, agreement, continuation's work."""
    data = config.load_config(path).data
    if grid_points:
        data["backbone"]["amplitude_points"] = grid_points
    scene = scenes.from_data(data)
    pl = pb.plan(scene)
    spec = scene.model
    values = pb.line_values(scene, pl.lines[0])
    system = spec.polynomial(values)
    grid = pb.amplitudes(pl, spec.build(values).derived["axial_approach"])
    modes = nnm.linear_modes(system)
    opts = scene.integrator
    pb.continued_backbone(spec, values, modes, 0, grid, pl, opts)      # compiles (or loads) the kernels
    rows = []
    for k in range(len(modes)):
        start = time.perf_counter()
        bb = pb.continued_backbone(spec, values, modes, k, grid, pl, opts)
        cont_s = time.perf_counter() - start
        man_s, f_man = best_time(lambda: nnm.backbone(nnm.manifold(system, k, master=bb.coordinate), grid), repeats)
        f_cont = pb.frequency_on_grid(bb, grid)
        rel = (f_cont - f_man) / f_cont
        rows.append({"scene": spec.name, "mode": k + 1, "label": f"{modes[k].label} {modes[k].whirl}",
                     "linear_frequency_hz": modes[k].frequency, "manifold_s": man_s, "continuation_s": cont_s,
                     "continuation_points": int(bb.frequency.size), "continuation_rhs": int(bb.n_rhs),
                     "continuation_end": bb.status, "max_rel_difference": float(np.nanmax(np.abs(rel))),
                     "slope": slope(grid, rel), "parting_amplitude_m": pb.parting_amplitude(grid, rel),
                     "amplitude_max_m": float(grid[-1])})
        log(f"{spec.name} mode {k + 1}: manifold {man_s * 1e3:.2f} ms, continuation {cont_s:.2f} s")
    return rows


def _cells(r):
    part = r["parting_amplitude_m"]
    return [r["scene"], r["mode"], r["label"], f"{r['linear_frequency_hz']:.2f}", f"{r['manifold_s'] * 1e3:.2f}",
            f"{r['continuation_s']:.2f}", f"{r['continuation_s'] / r['manifold_s']:.0f}x",
            f"{r['continuation_points']} / {r['continuation_rhs']:,}", f"{r['max_rel_difference']:.1e}",
            f"{r['slope']:.2f}", "-" if not np.isfinite(part) else f"{part * 1e6:.2f}", f"{r['amplitude_max_m'] * 1e6:.2f}"]


def markdown(result):
    table = render.table(["model", "mode", "shape", "linear [Hz]", "manifold [ms]", "continuation [s]",
                          "manifold faster", "continuation points / rhs", "max rel. difference",
                          "slope (lowest decade)", "1 % parting [um]", "amplitude_max [um]"],
                         [_cells(r) for r in result["rows"]])
    return render.fill("backbone", date=result["date"], command=result["command"], machine=json.dumps(result["machine"]),
                       load=result["load"], repeats=result["repeats"], rtol=result["rtol"],
                       scenes=", ".join(f"`{s}`" for s in result["scenes"]), table=table)


def write(result, out):
    out.mkdir(parents=True, exist_ok=True)
    (out / "backbone.md").write_text(markdown(result))
    (out / "backbone.json").write_text(json.dumps(result, indent=1) + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=5, help="timed manifold computations per mode (best taken)")
    ap.add_argument("--scenes", nargs="+", default=list(SCENES))
    ap.add_argument("--grid-points", type=int, help="amplitudes of the grid (default: the scene's)")
    ap.add_argument("--out", type=Path, default=DOCS)
    args = ap.parse_args(argv)
    load = loadavg()
    rows = [r for path in args.scenes for r in mode_rows(path, args.repeats, args.grid_points)]
    rtol = config.load_config(args.scenes[0]).data["numerics"]["rtol"]
    result = {"scenes": args.scenes, "rows": rows, "repeats": args.repeats, "rtol": rtol,
              **provenance(load, "workflows.bench.backbone", argv)}
    write(result, args.out)
    log(f"wrote {args.out / 'backbone.md'}")
    return result


if __name__ == "__main__":
    main()

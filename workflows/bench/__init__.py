"""Benchmarks of the kernels and of a distributed sweep -> docs/benchmarks/.

Entry points: `python -m workflows.bench.kernels` and `python -m workflows.bench.scaling`
(`--quick`, `--render-only`, see their docstrings). Layout:

- measurement, writing the JSON: `references`, `work_precision`, `peer_baseline`, `cfloor`
  (kernel benchmarks, on the scene of `scene`); `scaling_scene`, `scaling_runs`,
  `scaling_analysis` (scaling benchmark);
- `jeffcott`: the only module that imports `rotorsweep.kernels`: the kernels as the benchmarks call them;
- `peers/`: the same model outside our kernels, scipy (`jeffcott_scipy`) and C (`jeffcott_c`,
  with `jeffcott_rhs.c`);
- rendering from the JSON: `render` (templates), `kernels_md` and `scaling_md` filling
  `templates/*.md`; plots in `kernels_plots` and `scaling_plots`;
- `common`: timing, machine description, paths.
"""

"""Workflows built on rotorsweep: scripts run as modules (`python -m workflows.<name>`) that produce
documents rather than result cubes, e.g. `workflows.bench.kernels` (docs/benchmarks/)."""

"""rotorsweep: stability maps of rotors on ball bearings (shooting, Floquet, Lyapunov) into
netCDF result cubes. The public API in one place; the work is done by `rotorsweep.pipeline` (configs,
sweeps, cubes, queries, reports) and `rotorsweep.kernels` (the Numba numerics).

    import rotorsweep
    path = rotorsweep.run("configs/demo.toml", "out/demo.nc")      # rotorsweep run
    ds = rotorsweep.open_cube(path)                                # an xarray.Dataset
    rotorsweep.unstable_intervals(ds)                              # rotorsweep query --unstable
    ds, kind = rotorsweep.open_result(path)                        # any result kind (info, query)
    rotorsweep.make_report(ds, "out/demo_report")                  # rotorsweep report
    rotorsweep.point(speed=100.0, clearance=7.6e-6)                # rotorsweep point
    ds.rotorsweep.max_multiplier()                                 # hvplot figures (explore)

Each name is loaded on first use (PEP 562 `__getattr__`), so `import rotorsweep` reads neither
Numba, xarray nor plotting (issue 35); the `ds.rotorsweep` accessor is registered on xarray
as soon as xarray is imported, before or after rotorsweep.
"""
import importlib

# The one definition of the version (pyproject.toml reads it: [tool.setuptools.dynamic]); a
# literal, so the command line knows it without importlib.metadata (25 ms of `info`, issue 35).
__version__ = "0.1.0"

import rotorsweep.pipeline as pipeline  # noqa: E402

# public name -> (module, attribute in it; None: the module itself)
_API = {
    "explore": ("rotorsweep.pipeline.explore", None),
    "make_report": ("rotorsweep.pipeline", "make_report"), "open_cube": ("rotorsweep.pipeline", "open_cube"),
    "open_result": ("rotorsweep.pipeline", "open_result"), "point": ("rotorsweep.pipeline", "point"), "run": ("rotorsweep.pipeline", "run"),
    "unstable_intervals": ("rotorsweep.pipeline", "unstable_intervals"),
    "SweepError": ("rotorsweep.pipeline.cluster", "SweepError"),
    "ConfigError": ("rotorsweep.pipeline.config", "ConfigError"), "load_config": ("rotorsweep.pipeline.config", "load_config"),
    "parse_config": ("rotorsweep.pipeline.config", "parse_config"),
    "CubeError": ("rotorsweep.pipeline.cube", "CubeError"),
    "QueryError": ("rotorsweep.pipeline.query", "QueryError"), "attractor_intervals": ("rotorsweep.pipeline.query", "attractor_intervals"),
}

__all__ = sorted([*_API, "__version__"])


def __getattr__(name):
    if name not in _API:
        raise AttributeError(f"module 'rotorsweep' has no attribute {name!r}")
    module, attribute = _API[name]
    value = importlib.import_module(module)
    value = value if attribute is None else getattr(value, attribute)
    globals()[name] = value          # once loaded, a plain module attribute
    return value


def __dir__():
    return sorted(set(globals()) | set(_API))


pipeline.register_accessor_when_xarray_loads()

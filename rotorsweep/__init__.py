"""rotorsweep: stability maps of rotors on ball bearings (shooting, Floquet, Lyapunov) into
netCDF result cubes. The public API in one place; the work is done by `pipeline` (configs,
sweeps, cubes, queries, reports) and `rotorkernels` (the Numba numerics).

    import rotorsweep
    path = rotorsweep.run("configs/demo.toml", "out/demo.nc")      # rotorsweep run
    ds = rotorsweep.open_cube(path)                                # an xarray.Dataset
    rotorsweep.unstable_intervals(ds)                              # rotorsweep query --unstable
    ds, kind = rotorsweep.open_result(path)                        # any result kind (info, query)
    rotorsweep.make_report(ds, "out/demo_report")                  # rotorsweep report
    rotorsweep.point(speed=100.0, clearance=7.6e-6)                # rotorsweep point
    ds.rotorsweep.max_multiplier()                                 # hvplot figures (explore)
"""
from pipeline import explore, make_report, open_cube, open_result, point, run, unstable_intervals
from pipeline.cluster import VERSION as __version__
from pipeline.cluster import SweepError
from pipeline.config import ConfigError, load_config, parse_config
from pipeline.cube import CubeError
from pipeline.query import QueryError, attractor_intervals

__all__ = ["ConfigError", "CubeError", "QueryError", "SweepError", "__version__", "attractor_intervals",
           "explore", "load_config", "make_report", "open_cube", "open_result", "parse_config", "point", "run",
           "unstable_intervals"]

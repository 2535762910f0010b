"""Fixtures shared by test modules, and the suite's own cache directory."""
import os
import shutil
import tempfile
from pathlib import Path

import pytest

# What the suite measures (pipeline/workload.py: $ROTORSWEEP_CACHE/costs.json) goes to a cache of
# its own, not the user's: set before anything imports rotorsweep.kernels, and inherited by the CLI's
# subprocesses and Dask workers. Its numba/ links to the user's, where rotorsweep.kernels keeps the
# compiled kernels under the same variable, so the suite does not compile them again.
PRIVATE_CACHE = Path(tempfile.mkdtemp(prefix="rotorsweep-test-cache-"))


def pytest_configure(config):
    user = Path(os.environ.get("ROTORSWEEP_CACHE") or Path.home() / ".cache" / "rotorsweep")
    (user / "numba").mkdir(parents=True, exist_ok=True)
    (PRIVATE_CACHE / "numba").symlink_to(user / "numba", target_is_directory=True)
    os.environ["ROTORSWEEP_CACHE"] = str(PRIVATE_CACHE)


def pytest_unconfigure(config):
    shutil.rmtree(PRIVATE_CACHE, ignore_errors=True)       # the link only, not the user's kernels

# A real sweep, small: 19 um, 62-66 Hz (period 2 after the period doubling, period 1 above the
# refined boundary at ~64.9 Hz), both directions. Built in-process as sweep.run does it, without
# starting a Dask cluster.
TINY_SCENE = """
[scene]
name = "tiny_attractor"
model = "jeffcott_clearance"
[bearing]
preset = "209"
stiffness = "bai2006"
[sweep]
speed = {start = 62.0, stop = 66.0, step = 2.0}
clearance = [19.0e-6]
[analysis]
attractor = true
sweep_direction = "both"
poincare_samples = 32
max_period = 8
lyapunov_max_periods = 300
"""


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory):
    """(cube path, the chunk's results as the workers return them) of the TINY_SCENE sweep."""
    from rotorsweep.pipeline import boundaries, config, cube, sweep
    cfg = config.parse_config(TINY_SCENE)
    ids, index, results, _ = sweep.compute_chunk(cfg.scene, sweep.segments(cfg.scene))
    ds = cube.assemble(cfg.axes, sweep.fixed_coords(cfg.scene), [(ids, index, results, None)],
                       sweep.provenance(cfg), n_multipliers=4)
    ds = boundaries.add_boundary_table(cfg.scene, ds)
    return cube.write_cube(ds, tmp_path_factory.mktemp("tiny") / "tiny.nc"), results


@pytest.fixture(scope="session")
def tiny_cube(tiny_run):
    return tiny_run[0]


@pytest.fixture
def small_config(tmp_path):
    """tests/test_pipeline.py's SMALL sweep as a config file (that module has a module-scoped one)."""
    from tests.harness import config_file
    from tests.test_pipeline import SMALL
    return config_file(tmp_path, "small.toml", SMALL)

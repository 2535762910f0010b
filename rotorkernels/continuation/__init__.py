"""Strategies that follow periodic-orbit problems (rotorkernels.orbits) along a parameter:
natural continuation (`natural`: each point started from its neighbours) and events (`events`:
locating where a multiplier crosses the unit circle between two solved points). Pseudo-arclength
continuation through folds joins them here."""
from rotorkernels.continuation.natural import (  # noqa: F401 (the package's API)
    COLD_RETRIES, QUICK_ITERATIONS, PointSolution, natural, solve_orbit)

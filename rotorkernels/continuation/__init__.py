"""Strategies that follow periodic-orbit problems (rotorkernels.orbits) along a parameter:
natural continuation (`natural`: each point started from its neighbours) and events (`events`:
locating where a multiplier crosses the unit circle between two solved points) on a grid, and
pseudo-arclength continuation through folds with located fold / period-doubling /
Neimark-Sacker points and period-doubling branch switching (`arclength`).

`follow(model, params, opts, strategy=...)` is the one entry point: it follows the forced-orbit
problems at the parameter vectors `params` and returns a Branch with a status per step."""
from collections import namedtuple

from rotorkernels import shooting
from rotorkernels.continuation.natural import (  # noqa: F401 (the package's API)
    COLD_RETRIES, QUICK_ITERATIONS, PointSolution, natural, solve_orbit)

STRATEGIES = {"natural": natural}

# solutions: one PointSolution per step (its status and reason say how that step ended);
# complete: every step found its orbit; failed: the indices of the steps that did not.
Branch = namedtuple("Branch", "solutions complete failed")


def follow(model, params, opts, strategy="natural", **kw):
    """Follow the periodic orbit of `model` along the parameter vectors `params` with a strategy
    of STRATEGIES (keyword arguments as `solve_orbit`'s)."""
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown continuation strategy {strategy!r}; known: {', '.join(STRATEGIES)}")
    solutions = list(STRATEGIES[strategy](model, params, opts, **kw))
    failed = [k for k, sol in enumerate(solutions) if sol.status != shooting.CONVERGED]
    return Branch(solutions, not failed, failed)

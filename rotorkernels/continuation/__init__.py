"""Following periodic orbits (rotorsweep.kernels.orbits) along parameters. What is what:

- On a grid: `natural` solves the forced orbit at each given parameter vector, each started from
  its neighbours; `follow(model, params, opts, strategy=...)` below runs it over a grid and returns
  a Branch with a status per step (the grid sweeps' entry point, not the arclength engine's);
  `events.locate_boundary` refines where a multiplier crosses the unit circle between two grid
  values.
- Pseudo-arclength: `engine.follow(problem, first, bounds, settings, events)` is the one loop
  (predictor, corrector call, step control, edges, END_REASONS, closed loops, event location);
  its docstring is the problem contract. The problems: `arclength.Family` (forced orbits along one
  parameter: `continue_orbit`, `follow_branch`, `switch_period_doubling`), `backbone.Shooting`
  (autonomous orbits along their amplitude: `follow_backbone`) and `twoparam.BifurcationCurve`
  (fold / period-doubling / Neimark-Sacker points along two parameters: `continue_bifurcation`,
  `follow_curve`). The branch events (fold, branch point, period doubling, Neimark-Sacker, levels,
  codimension-2 flags, and user events) are objects in `events`."""
from collections import namedtuple

from rotorsweep.kernels import shooting
from rotorsweep.kernels.continuation.natural import (  # noqa: F401 (the package's API)
    COLD_RETRIES, QUICK_ITERATIONS, PointSolution, natural, solve_orbit)

STRATEGIES = {"natural": natural}

# solutions: one PointSolution per step (its status and reason say how that step ended);
# complete: every step found its orbit; failed: the indices of the steps that did not.
Branch = namedtuple("Branch", "solutions complete failed")


def follow(model, params, opts, strategy="natural", **kw):
    """Follow the periodic orbit of `model` along the grid of parameter vectors `params` with a
    strategy of STRATEGIES (keyword arguments as `solve_orbit`'s)."""
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown continuation strategy {strategy!r}; known: {', '.join(STRATEGIES)}")
    solutions = list(STRATEGIES[strategy](model, params, opts, **kw))
    failed = [k for k, sol in enumerate(solutions) if sol.status != shooting.CONVERGED]
    return Branch(solutions, not failed, failed)

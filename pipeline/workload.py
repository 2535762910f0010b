"""How much work a command's plan is, to choose where it runs (rotorsweep.pipeline.cluster.runs_in_process):
the number of units (sweep points, continuation or backbone lines) times the cost of a unit of
that kind for the scene's model, the largest measured by earlier in-process runs on this machine
(units of one model cost 100-fold more in one scene than in another: a chaotic point, a line through
a period-doubling cascade) and kept in the cache directory ($ROTORSWEEP_CACHE, default
~/.cache/rotorsweep: costs.json), else a conservative default. A wrong estimate costs only time, never results: they are the same bit for
bit wherever a command runs."""
import json
import os
import time

# Default CPU seconds of one unit, where this machine has measured none: above the measured costs
# of the paper scenes (warm, Intel Xeon / AMD EPYC): a periodic orbit and its multipliers 1-5 ms
# (Fig. 13: 12,005 points in 6.8 s on 2 workers), with attractor diagnostics ~5 ms on average and
# up to ~400 ms at a chaotic point; a Duffing or Bai fold continuation line 0.07-0.15 s, the Bai
# 19 um line through its period-doubling cascade about a minute; a backbone line (manifold and
# continuation of a few modes) about a second.
DEFAULT_COSTS = {"point": 0.01, "point_attractor": 0.2, "continuation_line": 2.0, "backbone_line": 2.0}


def costs_path():
    base = os.environ.get("ROTORSWEEP_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "rotorsweep")
    return os.path.join(base, "costs.json")


def _key(unit, model):
    return f"{unit}:{model}"


def _measured():
    try:
        with open(costs_path()) as f:
            costs = json.load(f)
        return costs if isinstance(costs, dict) else {}
    except (OSError, ValueError):
        return {}


# Units whose cost depends on the branch far more than on the model (a Bai fold line 0.15 s, its
# 19 um line through the cascade a minute): a measured cost only raises their default, so that a
# quick line measured once does not keep a scene of slow lines off the cluster.
FLOORED = ("continuation_line", "backbone_line")


def unit_cost(unit, model):
    """CPU seconds of one `unit` (a DEFAULT_COSTS key) of `model`: measured, else the default
    (at least the default for FLOORED units)."""
    cost = _measured().get(_key(unit, model))
    if not isinstance(cost, (int, float)) or cost < 0:
        return DEFAULT_COSTS[unit]
    return max(float(cost), DEFAULT_COSTS[unit]) if unit in FLOORED else float(cost)


def estimate(unit, model, n):
    """CPU seconds of n units of `model`."""
    return n * unit_cost(unit, model)


def record(unit, model, n, seconds):
    """Keep the measured cost of a unit (seconds of n units) where it is the largest so far; a
    cache that cannot be written is left as it is."""
    if n <= 0:
        return
    costs = _measured()
    earlier = costs.get(_key(unit, model))
    if isinstance(earlier, (int, float)) and earlier >= seconds / n:
        return
    costs[_key(unit, model)] = seconds / n
    path = costs_path()
    tmp = f"{path}.{os.getpid()}.tmp"
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(tmp, "w") as f:
            json.dump(costs, f, indent=1, sort_keys=True)
        os.replace(tmp, path)
    except OSError:
        pass


class Meter:
    """CPU seconds spent in this process while open (`with Meter() as m: ...; m.seconds`)."""

    def __enter__(self):
        self.start = time.process_time()
        return self

    def __exit__(self, *exc):
        self.seconds = time.process_time() - self.start

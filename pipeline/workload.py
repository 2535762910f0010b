"""How much work a command's plan is, to choose where it runs (rotorsweep.pipeline.cluster.runs_in_process):
the number of units (sweep points, continuation or backbone lines) times the cost of a unit of
that kind for the scene's model, the median of the last RECENT measured by earlier in-process runs
on this machine, kept in the cache directory ($ROTORSWEEP_CACHE, default ~/.cache/rotorsweep:
costs.json), else a conservative default. The median, not the largest: a run's units may carry
one-off costs (a kernel the warm-up did not load, loaded from the Numba cache or compiled; a busy
machine), which the largest measurement kept for good; one such run among RECENT moves the
median little. A wrong estimate costs only time, never results: they are the same bit for bit
wherever a command runs."""
import json
import math
import os
import statistics
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


# How many of the latest measurements of a unit's cost the cache keeps (their median is the cost)
RECENT = 5


def _measured():
    """{key: [latest costs, oldest first]} from the cache (a file of one cost per key, as written
    before RECENT, reads as one measurement each; anything else as none)."""
    try:
        with open(costs_path()) as f:
            costs = json.load(f)
    except (OSError, ValueError):
        return {}
    if not isinstance(costs, dict):
        return {}
    return {k: [float(c) for c in (v if isinstance(v, list) else [v]) if _is_cost(c)] for k, v in costs.items()}


def _is_cost(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and value >= 0 and math.isfinite(value)


# Units whose cost depends on the branch far more than on the model (a Bai fold line 0.15 s, its
# 19 um line through the cascade a minute): a measured cost only raises their default, so that a
# quick line measured once does not keep a scene of slow lines off the cluster.
FLOORED = ("continuation_line", "backbone_line")


def unit_cost(unit, model):
    """CPU seconds of one `unit` (a DEFAULT_COSTS key) of `model`: the median of the RECENT
    latest measured, else the default (at least the default for FLOORED units)."""
    recent = _measured().get(_key(unit, model))
    if not recent:
        return DEFAULT_COSTS[unit]
    cost = statistics.median(recent)
    return max(cost, DEFAULT_COSTS[unit]) if unit in FLOORED else cost


def estimate(unit, model, n):
    """CPU seconds of n units of `model`."""
    return n * unit_cost(unit, model)


def record(unit, model, n, seconds):
    """Add the measured cost of a unit (seconds of n units) to the RECENT latest kept; a cache
    that cannot be written is left as it is."""
    if n <= 0 or not _is_cost(seconds / n):
        return
    costs = _measured()
    key = _key(unit, model)
    costs[key] = (costs.get(key, []) + [seconds / n])[-RECENT:]
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

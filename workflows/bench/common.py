"""What both benchmarks share: paths, logging, best-of-N timing and the machine description."""
import contextlib
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "benchmarks"


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def loadavg():
    return [round(x, 2) for x in os.getloadavg()]


def steal_seconds():
    """CPU seconds the hypervisor gave to other guests while this machine's CPUs had work (the
    'steal' column of /proc/stat, summed over CPUs; None where it is not reported). A shared
    host steals mostly when every vCPU of this guest is busy: it slows 2-worker runs, not
    1-worker ones, and no scheduler here can win that time back."""
    with contextlib.suppress(OSError, IndexError, ValueError):
        with open("/proc/stat") as f:
            fields = f.readline().split()
        return int(fields[8]) / os.sysconf("SC_CLK_TCK")
    return None


def since(start, now):
    """now - start, rounded to 10 ms (the clock tick), or None where either was not measured."""
    return None if start is None or now is None else round(now - start, 2)


def peak_rss_kib():
    """This process's peak resident set size in KiB. Linux's VmHWM, not getrusage's ru_maxrss:
    a worker process is forked from the driver and then exec'd, and ru_maxrss survives the exec,
    so it reported the driver's size at the fork (up to 550 MiB for 230 MiB workers late in a
    scaling run). ru_maxrss where /proc is missing."""
    with contextlib.suppress(OSError, StopIteration, ValueError):
        with open("/proc/self/status") as f:
            return int(next(line for line in f if line.startswith("VmHWM:")).split()[1])
    import resource
    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)


def _batch_size(fn, min_batch):
    """Calls of fn per timed batch so that a batch lasts at least min_batch seconds."""
    if min_batch <= 0:
        return 1
    t0 = time.perf_counter()
    fn()
    single = time.perf_counter() - t0
    return max(1, int(np.ceil(min_batch / max(single, 1e-7))))


def _time_batch(fn, number):
    t0 = time.perf_counter()
    for _ in range(number):
        fn()
    return (time.perf_counter() - t0) / number


def best_time(fn, repeats, min_batch=0.002):
    """(best seconds per call, result of the warm-up call): one warm-up, then the best of
    `repeats` batches; a batch repeats fn until it lasts at least `min_batch` seconds. Batches are
    kept short (2 ms) so that on a shared machine some of them run without being preempted."""
    result = fn()
    number = _batch_size(fn, min_batch)
    return min(_time_batch(fn, number) for _ in range(repeats)), result


class RoundRobin:
    """Best-of-N timing of many calls, interleaved: each round times every registered call once
    (a batch of at least `min_batch` seconds), so that a noisy stretch of a shared machine hits all
    of them alike and each call's best comes from the whole run, not from one moment."""

    def __init__(self, min_batch=0.002):
        self.min_batch = min_batch
        self.calls = {}

    def add(self, key, fn):
        """Register fn (after a warm-up call, whose result is returned)."""
        result = fn()
        self.calls[key] = [fn, _batch_size(fn, self.min_batch), np.inf]
        return result

    def run(self, rounds):
        for _ in range(rounds):
            for entry in self.calls.values():
                entry[2] = min(entry[2], _time_batch(entry[0], entry[1]))
        return {key: entry[2] for key, entry in self.calls.items()}


def add_render_options(ap, outputs, inputs, quick_dir):
    """--render-only and --data: write `outputs` again from the JSON `inputs` without measuring."""
    ap.add_argument("--render-only", action="store_true",
                    help=f"measure nothing: {outputs} from the {inputs} in --data")
    ap.add_argument("--data", type=Path, default=None,
                    help=f"directory with the JSON for --render-only (default: docs/benchmarks/, "
                         f"{quick_dir.relative_to(ROOT)}/ with --quick)")


def _cpu_model():
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or "unknown"


def machine_info():
    """CPU, cores and the numerical stack (imported here: only the benchmarks need numba etc.)."""
    import numba
    import scipy

    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    return dict(cpu=_cpu_model(), cores=os.cpu_count(), usable_cores=usable,
                platform=platform.platform(), python=platform.python_version(),
                numpy=np.__version__, scipy=scipy.__version__, numba=numba.__version__)


def provenance(load_before, module, argv):
    """What every benchmark result records beside its numbers: date, machine, load before and
    after, and the command that reproduces it."""
    return {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "machine": machine_info(),
            "load": f"{load_before} before, {loadavg()} after",
            "command": f"python -m {module} " + " ".join(argv or sys.argv[1:])}

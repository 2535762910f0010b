"""The Dask runtime of every command that runs on a cluster (run, continue, backbone): the local
cluster (TLS with a per-run certificate) and its workers' setup, connecting to a scheduler
given by address (its Dask handshake checked first, under a timeout; TLS files),
closing quietly, submitting tasks, the driver's frozen heap, and the provenance every result
file records (the version, the command, the model, the config).

The sweep (rotorsweep.pipeline.sweep) and the per-line commands (rotorsweep.pipeline.results) use this module; none of
them starts or closes a cluster another way. It imports only the standard library at import time
(the command line reads the version here, rotorsweep.__version__; Dask is imported where a cluster starts).

Commands run their tasks through an executor (`executor()`): a Dask cluster (`DaskExecutor`) or,
for small work, this process (`InProcess`), with one interface (submitter, as_completed, lost,
n_workers, close), so a command's task loop is written once for both."""
import contextlib
import functools
import gc
import heapq
import itertools
import json
import logging
import os
import socket
import sys
import types
from datetime import datetime, timezone

from rotorsweep import __version__ as VERSION


class SweepError(Exception):
    """A run that cannot start or finish: no scheduler, output in the way, workers lost
    (message for the user)."""


# Each worker process takes one core: no thread pools of its own.
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
              "MKL_NUM_THREADS": "1"}
# The local cluster's housekeeping, relaxed: the driver process (scheduler, nannies, client)
# shares the cores with the workers, and with Dask's defaults (an event-loop tick every 20 ms in
# every process, nannies polling worker memory every 100 ms, each worker sampling its own stack
# every 10 ms for the dashboard's profile page) an idle 2-worker cluster took 74 ms of CPU per
# second, 3.7% of 2 cores (13 ms/s relaxed). The system monitor (host CPU, memory, network and
# disk counters for the dashboard's System page and the heartbeats, every 500 ms in the scheduler,
# each nanny and each worker) then took a third of what was left: an idle 2-worker cluster used
# 33-38 ms/s with it, 24 ms/s sampling every 5 s (AMD EPYC, 2 cores). The workers' memory limits
# do not wait for it (they sample their process memory themselves). A scheduler given by address
# keeps its own settings.
LOCAL_CLUSTER_CONFIG = {"distributed.admin.tick.interval": "1s",
                        "distributed.admin.system-monitor.interval": "5s",
                        "distributed.worker.memory.monitor-interval": "500ms",
                        "distributed.worker.profile.enabled": False}
SCHEDULER_TIMEOUT_S = 5


def local_workers(workers):
    """Worker processes of a local cluster: as asked, else one per core, at least 2."""
    return workers or max(2, os.cpu_count() or 2)


def local_cluster(n_workers):
    """A LocalCluster of n_workers single-threaded worker processes on 127.0.0.1 (dashboard on a
    free port), as every command starts it; rotorsweep.pipeline.workerinit sets each worker up. Its
    scheduler, nannies and workers speak TLS with a certificate made for this cluster alone
    (Security.temporary(), both ends present it): a process that does not hold it (another
    local user's) cannot connect, so cannot run code in the workers (plain TCP let any local
    process call client.run on them). It starts 0.3-0.5 s slower (README, Security)."""
    import dask
    from dask.distributed import LocalCluster
    from distributed.security import Security

    # the servers and the nannies' worker processes take their settings when they are created
    with dask.config.set(LOCAL_CLUSTER_CONFIG):
        return LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                            dashboard_address="127.0.0.1:0", env=dict(WORKER_ENV),
                            preload=["rotorsweep.pipeline.workerinit"], security=Security.temporary(),
                            protocol="tls://")


def connect(workers, scheduler):
    """(client, local cluster or None): a client of the scheduler `scheduler` (an address or a
    Scheduler, see scheduler_of), else of a new local cluster of `workers` processes (default
    local_workers), speaking TLS with the cluster's own certificate."""
    from dask.distributed import Client

    if scheduler:
        target = scheduler_of(scheduler)
        return Client(target.address, security=target.security(), timeout=f"{4 * target.timeout}s"), None
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    cluster = local_cluster(local_workers(workers))
    return Client(cluster, security=cluster.security), cluster


def close(client, cluster):
    """Close silently: after Ctrl-C or an error the nannies warn that they kill workers still busy
    in a kernel, and the in-process scheduler logs CRITICAL tracebacks for results of tasks in
    flight it can no longer send to the closed client; both are the intent here, and the run's
    outcome is already decided (its part files are written)."""
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.CRITICAL + 1)
    try:
        client.close()
        if cluster is not None:
            cluster.close()
    finally:
        logger.setLevel(level)


class DaskExecutor:
    """Tasks on a Dask cluster: a client and the local cluster it started (None for a scheduler
    given by address)."""

    def __init__(self, client, local):
        self.client, self.local = client, local

    @property
    def n_workers(self):
        return max(1, len(self.client.scheduler_info()["workers"]))

    @property
    def lost(self):
        """The exception of a task whose workers died (KilledWorker)."""
        from dask.distributed import KilledWorker
        return KilledWorker

    def submitter(self, fn, *fixed, **options):
        return submitter(self.client, fn, *fixed, **options)

    def as_completed(self, futures):
        from dask.distributed import as_completed
        return as_completed(futures)

    def close(self):
        close(self.client, self.local)


class Task:
    """A task of InProcess: run (once) when its result is first asked for; an exception it
    raises is raised there, as a Dask future's result() raises it."""

    def __init__(self, fn, args, priority):
        self.fn, self.args, self.priority = fn, args, priority
        self._outcome = None

    def result(self):
        if self._outcome is None:
            try:
                self._outcome = (True, self.fn(*self.args))
            except Exception as exc:        # noqa: BLE001 (raised again below, and on every call)
                self._outcome = (False, exc)
        ok, value = self._outcome
        if not ok:
            raise value
        return value

    def release(self):
        """Nothing is held elsewhere (the Dask future's counterpart)."""


class Pending:
    """InProcess's as_completed: the tasks in order of priority (higher first), then of
    submission; each is run as it is yielded, so progress lines come as with a cluster."""

    def __init__(self, tasks):
        self._heap, self._order = [], itertools.count()
        for task in tasks:
            self.add(task)

    def add(self, task):
        heapq.heappush(self._heap, (-task.priority, next(self._order), task))

    def __iter__(self):
        while self._heap:
            task = heapq.heappop(self._heap)[2]
            with contextlib.suppress(Exception):
                task.result()       # run it now; the caller's result() raises what it raised
            yield task


class InProcess:
    """Tasks run in this process, one at a time: no cluster to start (seconds) for work that
    takes less. The same functions, arguments and order of results as on a cluster, so results
    are the same bit for bit."""
    n_workers = 1
    lost = ()           # no worker to lose: `except executor.lost` catches nothing

    def submitter(self, fn, *fixed, priority=0, **_options):
        return lambda *args: Task(functools.partial(fn, *fixed), args, priority)

    def as_completed(self, tasks):
        return Pending(tasks)

    def close(self):
        pass


# Below this estimate of a command's work (CPU seconds, rotorsweep.pipeline.workload) it runs in the driver
# process: a local cluster of 2 workers took 2-3 s to start and load the kernels (2 cores), and
# halves at best the time of the work, so it pays from about twice its start-up. Overridden by
# the scene's [run] in_process_below, else $ROTORSWEEP_IN_PROCESS_BELOW_S (0: always a cluster).
IN_PROCESS_BELOW_S = 3.0
IN_PROCESS_VARIABLE = "ROTORSWEEP_IN_PROCESS_BELOW_S"


def in_process_below_s(scene_value=None):
    """The threshold of in-process execution: a scene's [run] in_process_below (seconds, validated
    with the config; rotorsweep.pipeline.scene.Scene.in_process_below), else $ROTORSWEEP_IN_PROCESS_BELOW_S,
    else IN_PROCESS_BELOW_S."""
    if scene_value is not None:
        return float(scene_value)
    text = os.environ.get(IN_PROCESS_VARIABLE, "").strip()
    try:
        value = float(text) if text else IN_PROCESS_BELOW_S
    except ValueError:
        value = -1.0
    if not value >= 0:
        raise SweepError(f"${IN_PROCESS_VARIABLE}={text!r}: expected a number of seconds >= 0")
    return value


def runs_in_process(workers, scheduler, estimate_s, tasks=None, below=None):
    """Whether a command runs in this process: never with a scheduler or a worker count given,
    always with workers=0, else when its estimated work is below in_process_below_s(below) (below:
    the scene's threshold, None where it gives none) or it is one task (`tasks`: how many it can be split into at most;
    a cluster cannot speed up one)."""
    if scheduler or workers:
        return False
    return workers == 0 or tasks == 1 or estimate_s < in_process_below_s(below)


def executor(workers, scheduler):
    """An executor of `workers` processes (0: InProcess) or of the scheduler at `scheduler`;
    close() it when done. A local cluster's workers are started with the script that calls this
    hidden from them (main_hidden)."""
    if workers == 0 and not scheduler:
        return InProcess()
    with main_hidden():
        return DaskExecutor(*connect(workers, scheduler))


@contextlib.contextmanager
def main_hidden():
    """Start worker processes without the calling script: multiprocessing's spawn runs the
    `__main__` module again in each new process (as `__mp_main__`), and a plain script that calls
    rotorsweep.run at module level would then start the run again in every worker (issue 37).
    A `__main__` with no file and no spec, as in a notebook, is not run again."""
    main = sys.modules.get("__main__")
    if main is None or not (getattr(main, "__file__", None) or getattr(main, "__spec__", None)):
        yield
        return
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        yield
    finally:
        sys.modules["__main__"] = main


class Scheduler:
    """A scheduler given by address (--scheduler), with the TLS files a client of it needs (none:
    those of the Dask config, `distributed.comm.tls.*`) or a ready Security (`known`: a running
    cluster's own), and the seconds it has to answer."""

    def __init__(self, address, tls_ca_file=None, tls_cert=None, tls_key=None, timeout=SCHEDULER_TIMEOUT_S,
                 known=None):
        self.tls = {key: str(path) if path else None for key, path in
                    (("tls_ca_file", tls_ca_file), ("tls_client_cert", tls_cert), ("tls_client_key", tls_key))}
        if any(self.tls.values()) and "://" not in address:
            address = f"tls://{address}"
        self.address, self.timeout, self.known = address, timeout, known

    def __str__(self):
        return self.address

    def security(self):
        """The client's Security: the TLS files given (all three: Dask's TLS authenticates both
        ends), else the Dask config's."""
        from distributed.security import Security

        if self.known is not None:
            return self.known
        if not any(self.tls.values()):
            return Security()
        missing = [TLS_OPTIONS[k] for k, v in self.tls.items() if not v]
        if missing:
            raise SweepError(f"--scheduler {self.address}: TLS needs {', '.join(TLS_OPTIONS.values())}; "
                             f"{', '.join(missing)} missing")
        for key, path in self.tls.items():
            if not os.path.isfile(path) or not os.access(path, os.R_OK):
                raise SweepError(f"{TLS_OPTIONS[key]} {path}: not a readable file")
        return Security(**self.tls, require_encryption=True)


TLS_OPTIONS = {"tls_ca_file": "--tls-ca-file", "tls_client_cert": "--tls-cert", "tls_client_key": "--tls-key"}


def scheduler_of(scheduler):
    """A Scheduler from what the Python API takes: a Scheduler, an address, or a running cluster
    (a local_cluster: its address and its own certificate)."""
    if isinstance(scheduler, Scheduler):
        return scheduler
    if hasattr(scheduler, "scheduler_address"):
        return Scheduler(scheduler.scheduler_address, known=scheduler.security)
    return Scheduler(str(scheduler))


def check_scheduler(scheduler):
    """Fail within seconds (not Dask's 30 s or a hang, and before kernels compile or any file is
    made) unless a Dask scheduler answers at a --scheduler address: nothing listening, a service
    that says nothing (a silent listener, an HTTP server) or something else (an HTTP reply read as
    a Dask frame header asked for 3.07 EiB) is one line."""
    import asyncio                # here, not at start: the command line's parsing reads this module
    import concurrent.futures

    target = scheduler_of(scheduler)
    host, _, port = target.address.split("://", 1)[-1].rpartition(":")
    if not host or not port.isdigit():
        raise SweepError(f"--scheduler {target.address}: expected an address like tcp://HOST:PORT")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=target.timeout).close()
    except OSError as exc:
        raise SweepError(f"--scheduler {target.address}: nothing reachable within {target.timeout} s "
                         f"({exc.strerror or exc}); is the scheduler running, and is the address right?") from None
    security = target.security()
    try:
        with concurrent.futures.ThreadPoolExecutor(1) as pool:     # a loop of its own, whoever calls
            kind = pool.submit(asyncio.run, _identity(target.address, security, target.timeout)).result()
    except Exception as exc:         # whatever answered there: a timeout, a closed stream, a huge frame
        raise SweepError(f"--scheduler {target.address}: {_no_handshake_text(exc, target.timeout)}; is a Dask "
                         "scheduler listening there, with the TLS setting it expects (--tls-*)?") from None
    if kind != "Scheduler":
        raise SweepError(f"--scheduler {target.address}: a Dask {kind or 'service'} answers there, not a scheduler")


def _no_handshake_text(exc, timeout):
    if isinstance(exc, TimeoutError):
        return f"something listens there but no Dask scheduler answered within {timeout} s"
    detail = str(exc).splitlines()[0] if str(exc) else "no detail"
    return f"what answers there does not speak Dask's protocol ({type(exc).__name__}: {detail})"


async def _identity(address, security, timeout):
    """The `type` of the Dask server at `address` (its identity reply), all within `timeout` s."""
    import asyncio

    from distributed.comm import connect as dask_connect

    async def ask():
        comm = await dask_connect(address, timeout=timeout, **security.get_connection_args("client"))
        try:
            await comm.write({"op": "identity", "reply": True})
            reply = await comm.read()
        finally:
            comm.abort()
        return reply.get("type") if isinstance(reply, dict) else None

    return await asyncio.wait_for(ask(), timeout)


def submitter(client, fn, *fixed, **options):
    """submit(*args) -> the future of fn(*fixed, *args) on the cluster. The fixed arguments (the
    config: a few kB) go with every task, not scattered: a scattered copy lives only on workers
    and is lost for good once every worker holding it has died. They ride in the task's function,
    which Dask does not scan for futures as it scans a task's arguments, item by item (Fig. 13's
    config: 2476 objects, ~1.5 ms of driver time a task)."""
    return functools.partial(client.submit, functools.partial(fn, *fixed), pure=False, **options)


@contextlib.contextmanager
def heap_frozen():
    """Leave the objects alive now (the imported modules': 300k+ in a driver with Dask, xarray and
    the kernels loaded) out of garbage collections until the outermost such block ends: each
    full collection walked them all (0.1 s, once or twice a sweep, with the workers waiting for
    the next task). A nested block adds what was created since (a local cluster started inside
    the run) and leaves the unfreezing to the outermost one; a heap the caller froze before
    counts as an outer block (what the run adds stays frozen until the caller unfreezes)."""
    global _frozen_blocks
    # gc.get_freeze_count() walks the frozen objects (21 ms for a sweep driver's, before the first
    # task): only a first block asks it, to learn whether the caller froze the heap
    outermost = not _frozen_blocks and not gc.get_freeze_count()
    _frozen_blocks += 1
    gc.freeze()
    try:
        yield
    finally:
        _frozen_blocks -= 1
        if outermost:
            gc.unfreeze()


_frozen_blocks = 0      # heap_frozen blocks open in this process


def provenance(cfg, kind):
    """The global attributes every result file of `kind` (rotorsweep.pipeline.result_kinds) records:
    `history` names the command that wrote it (run, continue, backbone), the version, the model,
    the config and its hash."""
    from rotorsweep.pipeline import result_kinds

    kind = result_kinds.KINDS[kind]
    model = cfg.model
    created = datetime.now(timezone.utc).isoformat(timespec="seconds")
    return {
        "history": f"{created} rotorsweep {VERSION}: {kind.command} {cfg.path or 'scene ' + cfg.data['scene']['name']}",
        "source": f"rotorsweep {VERSION}, model {model.name} version {model.version}: {model.description}",
        "references": model.references or f"none given by model {model.name}",
        "config_toml": cfg.source,
        "config_hash": cfg.hash(),
        "scene": cfg.data["scene"]["name"],
        "model": cfg.data["scene"]["model"],
        "model_version": model.version,
        "continued_axis": cfg.continued_axis,
        "numerics": json.dumps(cfg.data["numerics"], sort_keys=True),
        "rotorsweep_version": VERSION,
        "created": created,
        "title": f"{kind.title}: {cfg.data['scene']['name']}",
    }

"""Dask worker preload for the local cluster of `rotorsweep run`.

Ctrl-C in a terminal sends SIGINT to the whole process group: the driver and every worker. The
driver turns it into one line and closes the cluster; a worker would instead die with a
KeyboardInterrupt traceback each (~70 lines for 2 workers). Workers therefore ignore SIGINT and
are stopped by the driver's cluster.close() (or with it, when the driver is killed)."""
import gc
import logging
import signal


def dask_setup(worker):
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # the chunk tasks' module (numpy, xarray, the kernels: ~1 s), imported while the cluster
    # starts and the driver loads the kernels, not when the first task arrives
    import rotorsweep.pipeline.sweep  # noqa: F401
    # The imports left ~200k objects, which the first full garbage collection would walk in
    # the first task (60 ms, once per worker); they live as long as the worker does.
    gc.freeze()
    # its warnings at close are about the tasks the driver cancels; task errors reach the driver
    logging.getLogger("distributed.worker.state_machine").setLevel(logging.ERROR)


def dask_teardown(worker):
    # Called when the worker starts closing (the driver's cluster.close() after Ctrl-C or an
    # error): a heartbeat still in flight when it closes its connections then logs "Failed to
    # communicate with scheduler" with a ~50-line traceback. From here on the worker logs only
    # its own shutdown; the run's outcome is the driver's to report (as rotorsweep.pipeline.cluster.close does).
    logging.getLogger("distributed").setLevel(logging.CRITICAL + 1)

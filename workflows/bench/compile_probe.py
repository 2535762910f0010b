"""`python workflows/bench/compile_probe.py OUT.json CLI_MODULE ARGS...`: run `rotorsweep ARGS...`
(the command line module CLI_MODULE of the tree, workflows/bench/trees.py) and write
the CPU seconds of every Numba compilation in this process, each without the compilations it
started (exclusive), summed by function: where a cold first result's compile time goes.

Run as a script, not a module, so that it measures the code of the tree it runs in (another
revision's tree) and needs nothing from it but the CLI. Compilations in Dask workers are not
seen (the driver compiles a scene's kernels before they start)."""
import sys

del sys.path[0]     # this script's directory: its modules (compile.py, common.py, ...) shadow no import

import importlib  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from numba.core import event  # noqa: E402


class ExclusiveTimes(event.Listener):
    """CPU seconds per compiled function, less those of the compilations nested in it."""

    def __init__(self):
        self.stack, self.seconds = [], {}

    def on_start(self, ev):
        self.stack.append([ev.data["dispatcher"].py_func.__qualname__, time.process_time(), 0.0])

    def on_end(self, ev):
        name, start, nested = self.stack.pop()
        spent = time.process_time() - start
        self.seconds[name] = self.seconds.get(name, 0.0) + spent - nested
        if self.stack:
            self.stack[-1][2] += spent


def main(argv):
    out, cli_module, *args = argv
    times = ExclusiveTimes()
    event.register("numba:compile", times)
    cli = importlib.import_module(cli_module)

    try:
        return cli.main(args)
    finally:
        Path(out).write_text(json.dumps({k: round(v, 3) for k, v in times.seconds.items()}))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

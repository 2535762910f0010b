"""Phase lines, progress and the log file of `run`, `continue` and `backbone`, through Python logging.

Every phase line ("starting 2 local Dask workers", "kernels ready (0.4 s)") and every progress
step is a record of the logger "rotorsweep" (INFO). A command shows the phase lines on its
stream (stderr; `-q`: none) as "== text", and writes them with the progress lines, timestamped,
into the log file next to its output (`<output>.log`) whether or not it is quiet. A script sees
the same records by adding a handler: `logging.getLogger("rotorsweep").addHandler(...)`.
"""
import contextlib
import logging
import math
import time

LOG = logging.getLogger("rotorsweep")
LOG.setLevel(logging.INFO)

PHASE = "== "     # the start of a phase line (a log reader can tell them from progress lines)
TIME_FORMAT = "%Y-%m-%d %H:%M:%S"


class _StreamOfRecord(logging.Handler):
    """Writes a phase record to the stream it names (record.stream; None: none), whole lines even
    where a progress bar redraws one line, so a non-interactive log reads in order."""

    def emit(self, record):
        stream = getattr(record, "stream", None)
        if stream is not None:
            stream.write(f"{PHASE}{record.getMessage()}\n")
            stream.flush()


class _LogFile(logging.FileHandler):
    """The log file; a record it cannot write (a full disk) is dropped without logging's traceback:
    the command itself reports the disk's state where it matters, on its result."""

    def handleError(self, record):
        pass


class _FileFormat(logging.Formatter):
    def format(self, record):
        prefix = PHASE if getattr(record, "phase", False) else ""
        return f"{self.formatTime(record, TIME_FORMAT)} {prefix}{record.getMessage()}"


if not any(isinstance(h, _StreamOfRecord) for h in LOG.handlers):   # once, also if reloaded
    LOG.addHandler(_StreamOfRecord())


def phase_printer(stream):
    """say(text): one phase line, shown on `stream` (None: not shown) and logged."""
    def say(text):
        LOG.info(text, extra={"stream": stream, "phase": True})
    return say


@contextlib.contextmanager
def log_file(output, command, append=False):
    """The records of one command into `<output>.log` (appended to on a resume), opened by a
    line naming the command and closed by its outcome and wall time."""
    path = f"{output}.log"
    handler = _LogFile(path, mode="a" if append else "w", encoding="utf-8")
    handler.setFormatter(_FileFormat())
    LOG.addHandler(handler)
    t0 = time.monotonic()
    LOG.info(f"rotorsweep {command} -> {output}")
    try:
        yield path
        LOG.info(f"done in {fmt_seconds(time.monotonic() - t0)}")
    except BaseException as exc:
        LOG.info(f"stopped after {fmt_seconds(time.monotonic() - t0)}: {type(exc).__name__}: {exc}")
        raise
    finally:
        LOG.removeHandler(handler)
        handler.close()


class Progress:
    """Units of work done (points, unless `unit` says otherwise), rate and ETA on `stream` (one
    updating line on a terminal, else a line per ~5% of the work; None: none) and in the log
    (a line per ~5%)."""

    def __init__(self, total, done=0, stream=None, unit="points"):
        self.total, self.done, self.stream, self.unit = total, done, stream, unit
        self.tty = stream is not None and stream.isatty()
        self.last_reported = -1
        self.restart()

    def restart(self):
        """Measure the rate from now (after the cluster start and the compilation)."""
        self.start_done, self.t0 = self.done, time.monotonic()

    def update(self, n):
        self.done += n
        elapsed = time.monotonic() - self.t0
        rate = (self.done - self.start_done) / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("nan")
        frac = self.done / self.total if self.total else 1.0
        bar = "#" * int(30 * frac) + "." * (30 - int(30 * frac))
        line = (f"[{bar}] {self.done}/{self.total} {self.unit}  {rate:7.1f} {self.unit}/s  "
                f"ETA {fmt_seconds(eta)}")
        step = int(frac * 20)
        new_step = step != self.last_reported or self.done >= self.total
        if new_step:
            LOG.info(line)
        if self.tty:
            self.stream.write("\r" + line + ("\n" if self.done >= self.total else ""))
        elif self.stream is not None and new_step:
            self.stream.write(line + "\n")
        self.last_reported = step
        if self.stream is not None:
            self.stream.flush()


def fmt_seconds(s):
    if not math.isfinite(s):
        return "--"
    s = int(round(s))
    return f"{s // 3600}h{s // 60 % 60:02d}m" if s >= 3600 else f"{s // 60}m{s % 60:02d}s"


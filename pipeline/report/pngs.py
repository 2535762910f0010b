"""The report's PNGs (matplotlib), drawn by a second Python process while this one draws the HTML
page (bokeh); whichever finishes first helps with the PNGs left. The halves take about as long
as each other (the 4-D atlas: 29 s of PNGs, 35 s of HTML) and share nothing but the cube's data.

The second process is a fresh interpreter with this one's sys.path (`python -c`, main() here),
not a multiprocessing child: forking a process that holds Dask's or bokeh's threads can inherit a
lock held by one of them, and spawning re-imports the caller's __main__, which a script without
an `if __name__ == "__main__"` guard does not survive. It starts first and imports HoloViews
while this process loads the cube; then it reads the path of a job file (what to draw, pickled:
a CubePngs) from its stdin and draws the PNGs in order, each one it claims first. After
the HTML this process claims and draws from the other end, then waits. A claim is a file created
with O_EXCL in the job's directory, so each PNG is drawn once. The drawer's stderr (warnings, a
traceback) is kept in a file and passed on when it ends. With one usable CPU, and where no
process or temporary directory can be made or the job does not pickle, every PNG is drawn here.
"""
import contextlib
import functools
import json
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from rotorsweep.pipeline.report import style
from rotorsweep.pipeline.report.figures.point import fig_point
from rotorsweep.pipeline.report.registry import figure_named

_CHILD = "import json, sys; sys.path[:] = json.loads(sys.argv[1]); from rotorsweep.pipeline.report.pngs import main; main()"
_STDERR_TAIL = 4000                                   # characters of a failed drawer's stderr to show


class CubePngs:
    """The PNGs of a cube's report: figures of the registry (by name) drawn from the report's data
    and unstable intervals, then the points in detail ([(point detail, file name)])."""

    def __init__(self, data, intervals, names, points):
        self.data, self.intervals, self.names, self.points = data, intervals, names, points

    def __call__(self, backend):
        """[(file name, build() -> the figure for backend)]; each figure is built when drawn."""
        figs = [figure_named(name) for name in self.names]
        return ([(fig.filename, functools.partial(fig.build, self.data, backend, self.intervals)) for fig in figs]
                + [(name, functools.partial(fig_point, pt, backend)) for pt, name in self.points])


def write_pngs(pngs, out, claim=lambda i: True, reverse=False):
    """Draw pngs("matplotlib") (a CubePngs) into the directory `out`, each one for which
    claim(its index) is true, in reverse order if asked."""
    with style.backend("matplotlib") as hv:
        items = pngs("matplotlib")
        order = range(len(items))
        for i in reversed(order) if reverse else order:
            if claim(i):
                name, build = items[i]
                hv.save(build(), Path(out) / name, backend="matplotlib", dpi=style.DPI)


def usable_cpus():
    with contextlib.suppress(AttributeError):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


@contextlib.contextmanager
def drawer(parallel=None):
    """Yield draw(pngs, out), which draws pngs (a CubePngs) into the directory `out`.
    parallel (default: when this process may use 2 or more CPUs): draw hands them to a second
    process, and the end of the block draws those it has not begun, then waits for it; a failure
    there raises RuntimeError with its stderr. A block left by an exception stops the second
    process."""
    if parallel is None:
        parallel = usable_cpus() >= 2
    tmp = _job_dir() if parallel else None
    proc = _start(tmp / "stderr.txt") if tmp else None
    if proc is None:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
        yield write_pngs
        return
    sent = []
    try:
        yield lambda pngs, out: _send(proc, tmp, pngs, out, sent)
        for pngs, out in sent:
            write_pngs(pngs, out, claim=_claimer(tmp), reverse=True)
        _finish(proc, tmp / "stderr.txt")
    finally:
        _stop(proc)
        shutil.rmtree(tmp, ignore_errors=True)


def _job_dir():
    """A new temporary directory for the job, its claims and the drawer's stderr; None where none
    can be made (then every PNG is drawn here)."""
    try:
        return Path(tempfile.mkdtemp(prefix="rotorsweep-pngs-"))
    except OSError:
        return None


def _claimer(directory):
    """claim(i): True for the first process to ask for PNG i (an O_EXCL file in `directory`)."""
    def claim(i):
        try:
            os.close(os.open(os.path.join(directory, f"claim{i}"), os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        except FileExistsError:
            return False
        return True
    return claim


def _start(err_path):
    """The drawing process (its stderr into err_path), None where it cannot be started."""
    try:
        with open(err_path, "wb") as err:
            return subprocess.Popen([sys.executable, "-c", _CHILD, json.dumps(sys.path)],
                                    stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=err)
    except (OSError, ValueError):         # no executable (embedded Python), no process left
        return None


def _send(proc, tmp, pngs, out, sent):
    """Hand the drawing of pngs into `out` to the drawer; keep it in `sent` for this process's
    help. What cannot be pickled or written is left to that help: the drawer is told there is no
    job."""
    if sent:
        raise RuntimeError("a PNG drawer takes one job")
    job_path = tmp / "job.pickle"
    try:
        with open(job_path, "wb") as f:
            pickle.dump({"pngs": pngs, "out": str(out)}, f, protocol=pickle.HIGHEST_PROTOCOL)
    except (pickle.PicklingError, AttributeError, TypeError, OSError):   # a lambda in it; a full disk
        job_path = ""
    with contextlib.suppress(BrokenPipeError):     # it has ended already: _finish says why
        proc.stdin.write(f"{job_path}\n".encode())
        proc.stdin.close()
    sent.append((pngs, out))


def _stop(proc):
    """Kill the drawer unless it has ended (an exception left the block), then reap it."""
    if proc.poll() is None:
        proc.kill()
    with contextlib.suppress(OSError):
        proc.stdin.close()
    proc.wait()


def _finish(proc, err_path):
    with contextlib.suppress(OSError):     # no job sent: the drawer reads EOF and exits
        proc.stdin.close()
    code = proc.wait()
    err = err_path.read_text(errors="replace")
    if code != 0:
        raise RuntimeError(f"drawing the report's PNGs (its own process) failed with "
                           f"exit status {code}:\n{err[-_STDERR_TAIL:]}")
    sys.stderr.write(err)


def main():
    """Import HoloViews (while the caller loads the cube), read a job file's path from stdin
    (nothing: exit), draw the PNGs it claims first."""
    style.holoviews()
    job_path = sys.stdin.readline().strip()
    if not job_path:
        return
    with open(job_path, "rb") as f:
        job = pickle.load(f)
    write_pngs(job["pngs"], job["out"], claim=_claimer(os.path.dirname(job_path)))

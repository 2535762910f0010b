"""What every command that writes checks before any work (issue 36): its output path (a file
path, not a directory; a directory it may write in), a --report directory that would be refused
only at the end, the free disk space against an estimate of what it writes, and the output's
lock. Each failure is a FileIOError: one line naming the path, exit code 2. A check that passes
is not a promise (the disk may fill meanwhile); the writes themselves fail as cleanly."""
import os
from pathlib import Path

from rotorsweep.pipeline import fileio, gridsize
from rotorsweep.pipeline.fileio import FileIOError

# Free space asked for where a command's output has no size estimate (a continuation, a
# backbone result, a report, a Campbell table: kB to a few MB): room for it and its temp file.
MIN_FREE_BYTES = 16 << 20
# A sweep holds its part files and the cube (written before the parts are deleted) at once.
SWEEP_COPIES_ON_DISK = 2


def existing_dir(path):
    """The nearest directory of `path`'s ancestors that exists (where a file or directory would
    be created); a file in the way is refused."""
    parent = Path(path).absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise FileIOError(f"{parent} is not a directory; cannot create {path} under it")
    return parent


def check_writable_dir(path):
    """The directory `path` would be created in exists or can be made, and is writable."""
    parent = existing_dir(path)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise FileIOError(f"{parent}: permission denied; cannot write {Path(path).absolute()} there")
    return parent


def check_output_file(path):
    """A file output: not an existing directory, its directory writable."""
    path = Path(path).absolute()
    if path.is_dir():
        raise FileIOError(f"{path} is a directory; give the path of a file for the output (-o FILE)")
    check_writable_dir(path)


def check_free_space(path, need_bytes):
    """At least `need_bytes` free on the file system `path` would be written to."""
    parent = existing_dir(path)
    st = os.statvfs(parent)
    free = st.f_bavail * st.f_frsize
    if free < need_bytes:
        raise FileIOError(f"{parent}: {free / 2**20:.0f} MiB free, but writing {Path(path).absolute()} needs about "
                          f"{need_bytes / 2**20:.0f} MiB; free some space or choose another output path")


def sweep_bytes(cfg):
    """Disk a sweep of cfg needs at its peak: part files and the cube (gridsize's per-point size)."""
    return SWEEP_COPIES_ON_DISK * cfg.n_points * gridsize.bytes_per_point(cfg.data) + MIN_FREE_BYTES


def check(output, need_bytes=MIN_FREE_BYTES, lock=False, report=None, report_identity=None, overwrite=False):
    """Every check for a command writing the file `output` (None: a command writing only a report);
    lock: it will lock `output` (refused now while another run holds it); report: a report
    directory it will write at its end, for the result `report_identity`."""
    if output is not None:
        check_output_file(output)
        check_free_space(output, need_bytes)
        if lock:
            fileio.check_unlocked(Path(output).absolute())
    if report is not None:
        check_report(report, report_identity, overwrite)


def check_report(out, identity=None, overwrite=False):
    """A report directory: refused now as it would be at the end (a file, another result's
    report, a foreign directory; identity None: the report command checks that itself once it
    has opened the result), the directory it is built in (next to it) writable, room for it."""
    if identity is not None:
        fileio.check_report_dir(out, identity, overwrite)
    check_writable_dir(out)
    check_free_space(out, MIN_FREE_BYTES)

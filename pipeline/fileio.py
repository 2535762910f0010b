"""File-system plumbing shared by sweeps, cubes and reports: atomic writes that respect the umask,
an exclusive lock on a sweep's output, and OS errors turned into one line for the user."""
import contextlib
import errno
import fcntl
import json
import os
import shutil
import socket
import tempfile
from datetime import datetime, timezone
from pathlib import Path


class FileIOError(Exception):
    """A file-system problem the user can fix (message for the user: path, cause, what to do)."""


def os_error_text(exc, path=None):
    """'<path>: <cause>' of an OSError; `path` where the error names none."""
    where = exc.filename if getattr(exc, "filename", None) else path
    cause = exc.strerror if getattr(exc, "strerror", None) else str(exc)
    return f"{where}: {cause}" if where else cause


def _umask():
    """The process umask. Linux shows it in /proc; os.umask can only read it by setting it, which
    for a moment gives other threads (Dask's) the wrong one."""
    with contextlib.suppress(OSError, StopIteration, ValueError):
        with open("/proc/self/status") as f:
            return int(next(line for line in f if line.startswith("Umask:")).split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def fsync_path(path):
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temp path next to `path`; on success it replaces `path` in one step, so readers see
    the old file or the complete new one. mkstemp creates files 0600; a normal open() would give
    0666 & ~umask, so the temp file gets that mode before it becomes visible."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        fsync_path(tmp)
        os.replace(tmp, path)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.remove(tmp)
        failure = _named_failure(exc, tmp, path)
        if failure is None:
            raise
        raise failure from None
    fsync_path(path.parent)


def _named_failure(exc, tmp, path):
    """An OSError naming `path` for a write into `tmp` that failed (the user never sees the temp
    file's name): an OSError of the temp file, or netCDF-C's RuntimeError (a full disk is "NetCDF:
    HDF error"). None for anything else."""
    if isinstance(exc, OSError) and str(exc.filename) == str(tmp):
        return OSError(exc.errno, exc.strerror or str(exc), str(path))
    if isinstance(exc, RuntimeError) and ("NetCDF" in str(exc) or "HDF" in str(exc)):
        return OSError(errno.EIO, f"netCDF write failed ({exc}; is the disk full?)", str(path))
    return None


# --- the output lock --------------------------------------------------------------------------

def lock_path(output):
    """`<cube>.lock` next to the cube: outside `<cube>.parts/`, which a run deletes at its end."""
    output = Path(output)
    return output.with_name(output.name + ".lock")


def _holder_text(holder):
    return (f"pid {holder.get('pid', '?')} on {holder.get('host', '?')}, started "
            f"{holder.get('started', '?')}, config {holder.get('config', '?')}")


def _lock_fd(path):
    """An fd holding an exclusive flock on `path`, or None while another process holds it. The
    kernel drops a flock whenever its process ends (even by SIGKILL), so a killed run leaves no
    stale lock behind. If the file was unlinked by a finishing run between our open and flock,
    we locked an orphan inode: open the path again."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            return None
        with contextlib.suppress(FileNotFoundError):
            if os.fstat(fd).st_ino == os.stat(path).st_ino:
                return fd
        os.close(fd)


def _locked_text(output, holder):
    return (f"{output} is being written by another rotorsweep run ({_holder_text(holder)}); wait for it "
            "to finish or use another output path")


def check_unlocked(output):
    """Refuse at once (before any work) while a live run holds `output`'s lock; creates nothing
    (the run takes the lock itself later)."""
    path = lock_path(output)
    try:
        fd = os.open(path, os.O_RDONLY)
    except FileNotFoundError:
        return
    except OSError as exc:
        raise FileIOError(f"cannot write the output: {os_error_text(exc, path)}") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        raise FileIOError(_locked_text(output, _read_json(path) or {})) from None
    finally:
        os.close(fd)


@contextlib.contextmanager
def output_lock(output, config_label):
    """Hold `<output>.lock` for the duration of a run; refuse while another live run holds it.
    The file names the holder (pid, host, start time, config) for that refusal."""
    path = lock_path(output)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = _lock_fd(path)
        if fd is None:
            raise FileIOError(_locked_text(output, _read_json(path) or {}))
        holder = {"pid": os.getpid(), "host": socket.gethostname(), "config": str(config_label),
                  "started": datetime.now(timezone.utc).isoformat(timespec="seconds")}
        os.ftruncate(fd, 0)
        os.write(fd, json.dumps(holder).encode())
    except OSError as exc:
        raise FileIOError(f"cannot write the output: {os_error_text(exc, path)}") from None
    try:
        yield path
    finally:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()                    # while still locked: no one else is using the name
        os.close(fd)


# --- report directories ------------------------------------------------------------------------

REPORT_MARKER = "report.json"      # which cube a report directory was made from


def report_identity(ds, cube_path=None):
    """What makes two reports 'of the same cube': the cube file and its config hash."""
    return result_identity(cube_path, ds.attrs.get("config_hash"))


def result_identity(path, config_hash):
    """report_identity of the result a run will write to `path` from a config of `config_hash`."""
    return {"cube": str(Path(path).absolute()) if path is not None else None, "config_hash": config_hash}


def check_report_dir(out, identity, overwrite):
    """Refuse to write a report into `out` where it would mix with other files: a report of
    another cube (unless overwrite, which replaces it) or anything that is not a report."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise FileIOError(f"{out} exists and is not a directory; the report needs a directory (-o DIR)")
    if not out.is_dir() or not any(out.iterdir()):
        return
    marker = out / REPORT_MARKER
    if not marker.exists() and not (out / "report.html").exists():
        raise FileIOError(f"{out} is a non-empty directory that holds no rotorsweep report; "
                          "choose a new or empty directory for the report")
    owner = _read_json(marker) or {}          # {}: a report from before markers existed
    if owner != identity and not overwrite:
        raise FileIOError(f"{out} holds the report of {owner.get('cube') or 'another cube'} (config hash "
                          f"{str(owner.get('config_hash', '?'))[:12]}), not of {identity['cube'] or 'this cube'}; "
                          "pass --overwrite to replace it, or choose another directory")


def _read_json(path):
    """The JSON in a file, or None (missing, unreadable, or still being written)."""
    try:
        return json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None


@contextlib.contextmanager
def replaced_dir(out):
    """Yield a new temp directory next to `out`; on success it takes the place of `out` (the
    old directory and every file in it go), so no file of an earlier report survives. A failure
    or Ctrl-C before the end leaves `out` as it was (or absent) and removes the temp directory."""
    out = Path(out).absolute()
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp"))
    try:
        yield tmp
        os.chmod(tmp, 0o777 & ~_umask())            # mkdtemp makes it 0700
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    _swap_in(tmp, out)


def _swap_in(tmp, out):
    """Rename `tmp` to `out`, the old `out` set aside first and removed after; interrupted between
    the two renames (Ctrl-C lands between any two Python statements), the old `out` comes back."""
    old = tmp.with_suffix(".old")
    try:
        if out.exists():
            os.rename(out, old)
        os.rename(tmp, out)
    except BaseException:
        if old.exists() and not out.exists():
            os.rename(old, out)
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    shutil.rmtree(old, ignore_errors=True)


def report_into(out, build, identity=None):
    """The report `build(directory)` -> its paths (a dict, as make_report returns) built in a temp
    directory next to `out`, with the marker of `identity` (None: none), then put in `out`'s place
    whole (replaced_dir); returns the paths as they are in `out`. Check `out` first (check_report_dir):
    whatever `out` holds is replaced."""
    with replaced_dir(out) as tmp:
        files = build(tmp)
        if identity is not None:
            (tmp / REPORT_MARKER).write_text(json.dumps(identity, indent=2) + "\n")
    return moved(files, tmp, out)


def moved(paths, old_dir, new_dir):
    """`paths` (a dict of paths and lists of paths under old_dir) as they are under new_dir."""
    def move(p):
        return Path(new_dir).absolute() / Path(p).relative_to(old_dir)
    return {k: [move(p) for p in v] if isinstance(v, list) else move(v) for k, v in paths.items()}

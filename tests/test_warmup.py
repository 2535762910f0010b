"""The Numba cache lock (`warmup.cache_lock`), between processes: loading cached kernels holds it
shared, so readers run together; compiling holds it exclusive, so a writer excludes readers and
writers (issue 35). Each process compiles or loads a one-line kernel in its own cache directory."""
import fcntl
import os
import select
import subprocess
import sys
import textwrap

import pytest

KERNEL = "import numba\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2.0 * x\n"
OTHER = KERNEL.replace("2.0", "3.0")      # another kernel, in its own module and cache index
# load (or compile) the kernel under the lock, say so, and hold the lock until stdin closes
HOLDER = textwrap.dedent("""
    import sys
    import numba
    from rotorsweep.pipeline import warmup
    kernel = __import__(sys.argv[1]).twice
    with warmup.cache_lock():
        kernel.compile((numba.float64,))
        print("cached" if kernel.stats.cache_hits else "compiled", flush=True)
        sys.stdin.read()
""")


@pytest.fixture
def cache(tmp_path):
    (tmp_path / "kernel.py").write_text(KERNEL)
    (tmp_path / "other.py").write_text(OTHER)
    return tmp_path


def start(cache, module="kernel"):
    """A process that loads (or compiles) `module`'s kernel under the lock, then holds it."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache / "numba"), PYTHONPATH=str(cache))
    return subprocess.Popen([sys.executable, "-c", HOLDER, module], env=env, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)


def answered(proc, seconds):
    return bool(select.select([proc.stdout], [], [], seconds)[0])


def holder(cache, module="kernel"):
    """A process holding the lock once it has loaded the kernel: (process, 'cached' or 'compiled')."""
    proc = start(cache, module)
    # generous: it imports rotorsweep and may compile, on a loaded machine
    if not answered(proc, 120):
        proc.kill()
        pytest.fail("the lock holder did not load the kernel within 120 s: blocked on the lock?")
    return proc, proc.stdout.readline().strip()


def release(proc):
    proc.stdin.close()
    assert proc.wait(timeout=60) == 0


def can_lock(cache, mode):
    """Whether this process could take the lock in `mode` now, without waiting."""
    fd = os.open(cache / "numba" / "compile.lock", os.O_RDWR)
    try:
        fcntl.flock(fd, mode | fcntl.LOCK_NB)
        return True
    except BlockingIOError:
        return False
    finally:
        os.close(fd)


def test_a_compilation_holds_the_lock_exclusively(cache):
    proc, how = holder(cache)
    assert how == "compiled"
    assert not can_lock(cache, fcntl.LOCK_SH)
    release(proc)
    assert can_lock(cache, fcntl.LOCK_EX)


def test_readers_share_the_lock_and_exclude_a_writer(cache):
    release(holder(cache)[0])                    # compiles the kernel into the cache
    first, how = holder(cache)
    assert how == "cached"
    assert can_lock(cache, fcntl.LOCK_SH) and not can_lock(cache, fcntl.LOCK_EX)
    second, how = holder(cache)                  # not blocked by the first reader
    assert how == "cached"
    release(first)
    release(second)


def test_a_compilation_waits_for_the_readers(cache):
    release(holder(cache)[0])
    reader, how = holder(cache)
    assert how == "cached"
    writer = start(cache, "other")               # must compile: waits while the reader holds the lock
    # (a writer that did not wait would answer within seconds; a slow one passes this step anyway)
    assert not answered(writer, 10)
    release(reader)
    assert answered(writer, 120) and writer.stdout.readline().strip() == "compiled"
    release(writer)

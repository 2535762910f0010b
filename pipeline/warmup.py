"""Compile (or load from Numba's disk cache) every kernel a model's scenes run, without running
any: `rotorsweep warmup [MODEL...]`, once in a cluster image or before a sweep fans out.

Kernels are compiled per kernel group (`ModelSpec.group`), so warming one model warms the other
models of its group, and per integrator (the class of `integrators.settings()`): a scene compiles
only its own; `rotorsweep warmup` compiles both unless told one (`--integrator`). Each entry point
(listed by the kernel packages) is compiled for the argument types the Python orchestration passes it
(`Dispatcher.compile(signature)`, which loads a cached compilation when there is one); the values
are never used.

Numba's cache index is read, extended and rewritten without a lock, and its data files are
numbered by the index's length: two processes compiling different signatures of one function at
once (two models' groups) may both write `<function>.1.nbc`, and the index may then point one
signature at the other's machine code. Compiling under an exclusive lock on the cache directory
serialises them; the process that waited then loads what the other compiled. Loading what is
cached only reads, so it holds the lock shared: small commands that only load run side by side,
and none waits behind another's load, only behind a compilation (issue 35)."""
import contextlib
import fcntl
import os
import time

import numba
import numba.core.event

import rotorsweep.kernels.attractor as diagnostics
from rotorsweep.kernels import integrators as ig, models, orbits


INTEGRATORS = ig.METHODS


def entry_points(spec, attractor=True, integrator="dop853"):
    """(jitted function, example arguments) of each kernel that Python code calls for `spec`
    with `integrator`, as the kernel packages list them (`orbits.entry_points`,
    `attractor.entry_points`); without `attractor`, only those of periodic orbits. Each costs
    about a second of compiling, so a scene gets only those it calls."""
    opts = ig.settings(integrator)
    return orbits.entry_points(spec, opts) + (diagnostics.entry_points(spec, opts) if attractor else [])


class _ExclusiveOnCompile(numba.core.event.Listener):
    """Turns the cache lock held on `fd` exclusive when Numba starts compiling, that is after it
    found no cached compilation to load and before it writes one; once is enough."""

    def __init__(self, fd):
        self.fd, self.exclusive = fd, False

    def on_start(self, event):
        if not self.exclusive:
            # not atomic (flock drops the shared lock first), so two upgrading readers cannot
            # deadlock; one that compiled meanwhile makes this compilation redundant, not unsafe
            fcntl.flock(self.fd, fcntl.LOCK_EX)
            self.exclusive = True

    def on_end(self, event):
        pass


@contextlib.contextmanager
def cache_lock():
    """A flock on the Numba cache directory (blocking; released on leaving, or when the process
    ends): shared while Numba only loads cached kernels, exclusive from the first kernel it compiles
    (and writes to the cache) on. Yields the listener: `.exclusive`, whether a kernel was compiled."""
    os.makedirs(numba.config.CACHE_DIR, exist_ok=True)
    fd = os.open(os.path.join(numba.config.CACHE_DIR, "compile.lock"), os.O_RDWR | os.O_CREAT, 0o666)
    listener = _ExclusiveOnCompile(fd)
    try:
        fcntl.flock(fd, fcntl.LOCK_SH)
        with numba.core.event.install_listener("numba:compile", listener):
            yield listener
    finally:
        os.close(fd)


def compile_model(spec, attractor=True, integrators=INTEGRATORS):
    """Compile (or load) the kernels of `spec`'s group for `integrators`; returns the seconds it took."""
    start = time.perf_counter()
    with cache_lock():
        for integrator in integrators:
            for function, args in entry_points(spec, attractor, integrator):
                function.compile(tuple(numba.typeof(a) for a in args))
    return time.perf_counter() - start


def compile_scene(scene, say):
    """Compile (or load) a scene's kernels (rotorsweep.pipeline.scene.Scene) in the driver before its workers
    start solving, so that they load them from the disk cache instead of each compiling them again."""
    model = scene.model
    say(f"compiling the kernels of {model.name}: under a minute the first time on a machine, then "
        f"loaded from the cache ({numba.config.CACHE_DIR})")
    seconds = compile_model(model, attractor=scene.analysis.attractor, integrators=(scene.integrator_name,))
    say(f"kernels ready ({seconds:.1f} s)")


@contextlib.contextmanager
def kernels_on_first_use(scene, say):
    """For work in this process: the scene's kernels load (or compile) when first called, under the
    cache lock, instead of all of them before (compile_scene): those the work never calls are not
    loaded (a continuation line with peaks: the orbits' extrema pass; 0.05 s of the Bai 7.6 um
    line's 1.3-s command, issue 35). Yields cache_lock's listener (`.exclusive`: a kernel was
    compiled, and the time spent is no measure of the work)."""
    say(f"the kernels of {scene.model.name} load on first use: compiled the first time on a machine "
        f"(under a minute), then loaded from the cache ({numba.config.CACHE_DIR})")
    with cache_lock() as listener:
        yield listener


def warmup(names=None, say=print, integrators=INTEGRATORS):
    """Compile the kernels of the named models (default: all registered) for `integrators`, one
    group at a time; {model: seconds}, 0 for a model whose group was compiled just before."""
    specs = [models.get(name) for name in names] if names else list(models.REGISTRY.values())
    done, seconds = set(), {}
    for spec in specs:
        seconds[spec.name] = 0.0 if spec.group in done else compile_model(spec, integrators=integrators)
        done.add(spec.group)
        say(f"{spec.name} (kernel group {spec.group}): {seconds[spec.name]:.1f} s")
    return seconds

"""rotorsweep pipeline: configs, Dask sweeps, result cubes, queries and reports.

The Python API mirrors the command line:

    import rotorsweep.pipeline as pipeline
    path = pipeline.run("configs/demo.toml", "out/demo.nc")        # rotorsweep run
    ds = pipeline.open_cube(path)                                  # an xarray.Dataset
    pipeline.unstable_intervals(ds)                                # rotorsweep query --unstable
    pipeline.continue_branches("configs/bai2006_fold.toml", "out/fold.nc")   # rotorsweep continue
    ds, kind = pipeline.open_result(path)                          # a result of any kind (info, query)
    pipeline.make_report(ds, "out/demo_report")                    # rotorsweep report
    pipeline.point(speed=100.0, clearance=7.6e-6)                  # rotorsweep point

Importing pipeline imports nothing heavy and installs import hooks for short commands (issue
35): the `rotorsweep` accessor registers itself when xarray is imported
(register_accessor_when_xarray_loads), Numba's BLAS check does not import scipy.linalg
(_quick_blas_check), and the command line's process sets up no cffi typing (numba_without_cffi),
reads Numba's configuration without yaml where it has no file to read (numba_config_without_yaml)
and collects no reference cycles during its start-up (collector_after_startup).
"""
import contextlib
import importlib.abc
import importlib.util
import sys


def _accessor(ds):
    """ds.rotorsweep: rotorsweep.pipeline.explore.CubeAccessor, imported on the first use of an accessor."""
    from rotorsweep.pipeline import explore

    return explore.CubeAccessor(ds)


def register_accessor():
    """Register the `rotorsweep` accessor on xarray Datasets (once; xarray must be imported)."""
    xr = sys.modules["xarray"]
    if getattr(xr.Dataset, "rotorsweep", None) is not _accessor:
        xr.register_dataset_accessor("rotorsweep")(_accessor)


class _AroundImport(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Runs the import of the module `name` inside the context manager `around()`: it finds that
    module's spec with the other finders and wraps its loader, once."""

    def __init__(self, name, around):
        self.name, self.around, self.loader = name, around, None

    def find_spec(self, fullname, path=None, target=None):
        if fullname != self.name or self.loader is not None:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(fullname)
        if spec is None or spec.loader is None:
            return spec
        self.loader, spec.loader = spec.loader, self
        return spec

    def create_module(self, spec):
        return self.loader.create_module(spec)

    def exec_module(self, module):
        module.__spec__.loader = module.__loader__ = self.loader
        with self.around():
            self.loader.exec_module(module)


def _around_import(name, around):
    """around() about the import of `name`, unless it is imported (or hooked) already."""
    if name not in sys.modules and not any(isinstance(f, _AroundImport) and f.name == name for f in sys.meta_path):
        sys.meta_path.insert(0, _AroundImport(name, around))


@contextlib.contextmanager
def _then_register_accessor():
    yield
    register_accessor()


def register_accessor_when_xarray_loads():
    """The `rotorsweep` accessor without importing xarray (0.4 s, issue 35): registered now where
    xarray is already imported, else right after its import."""
    if "xarray" in sys.modules:
        register_accessor()
    _around_import("xarray", _then_register_accessor)


@contextlib.contextmanager
def _quick_blas_check():
    """Numba's check for BLAS, run once where its typing starts (numba.np.arraymath), imports the
    whole of scipy.linalg and numpy.f2py with it: 0.15-0.4 s of a 1-s command (issue 35 item 3).
    A cached kernel needs none of it: one calling LAPACK imports scipy.linalg.cython_lapack itself
    at its first call, and numba checks again (ensure_lapack) where it compiles one. Here the
    check asks only that scipy be installed (a dependency of rotorsweep) and, where this Numba
    has it, that scipy's LAPACK integer width be the one Numba was built for (scipy.__config__)."""
    from numba.np import linalg

    full = linalg.ensure_blas
    if importlib.util.find_spec("scipy") is not None:
        linalg.ensure_blas = getattr(linalg, "_check_lapack_int_width", lambda: None)
    try:
        yield
    finally:
        linalg.ensure_blas = full


_around_import("numba.np.arraymath", _quick_blas_check)


def _unimportable(name):
    """A context manager inside which `import name` fails where `name` is not imported yet
    (sys.modules maps it to None), and imports again after."""
    @contextlib.contextmanager
    def inside():
        if name in sys.modules:
            yield
            return
        sys.modules[name] = None
        try:
            yield
        finally:
            if sys.modules.get(name, 0) is None:
                del sys.modules[name]
    return inside


def numba_without_cffi():
    """For the command line's own process: Numba's typing of cffi functions off. Numba sets it up
    where its typing starts (numba.core.typing.cffi_utils) by importing cffi and pycparser and
    building an FFI: 14 ms (quiet machine) to 33 ms (loaded) in every command that loads a kernel
    (issue 35), for a feature no rotorsweep kernel uses. Numba then treats cffi as not installed:
    a plugin model whose kernel calls cffi functions runs from Python, not from the command line."""
    _around_import("numba.core.typing.cffi_utils", _unimportable("cffi"))


def numba_config_without_yaml():
    """For the command line's own process: numba.core.config imports yaml (16 ms of every command
    that integrates, issue 35) only to read a .numba_config.yaml in the working directory; where
    there is none, Numba is imported without it (a file created later in the process is not
    read: Numba warns that yaml is missing)."""
    import os

    if not os.path.isfile(".numba_config.yaml"):
        _around_import("numba.core.config", _unimportable("yaml"))


# Seconds from the command line's start without the cyclic garbage collector (collector_after_startup).
STARTUP_WITHOUT_COLLECTOR_S = 2.0


def collector_after_startup(seconds=STARTUP_WITHOUT_COLLECTOR_S):
    """For the command line's own process: no cyclic garbage collection in its first `seconds`,
    then the objects made so far frozen (never walked again) and collection back on. Start-up makes
    long-lived objects only (modules, Numba's typing tables, 300k+ with numba or xarray), and each
    full collection walks all of them: 30-60 ms of a one-second command (issue 35). Reference
    counting still frees everything else; a process forked meanwhile collects from its start."""
    import gc
    import os
    import threading

    def resume():
        gc.freeze()
        gc.enable()

    gc.disable()
    os.register_at_fork(after_in_child=gc.enable)
    timer = threading.Timer(seconds, resume)
    timer.daemon = True
    timer.start()
    return timer


def pools_as_a_worker():
    """For the command line's own process, before numpy loads: no BLAS or Numba thread pools of its
    own (cluster.WORKER_ENV, where the user has not set them), as each Dask worker has. Small work
    runs in this process (cluster.InProcess) one task at a time, like a worker; with OpenBLAS's
    default threads, which spin while waiting, a torus branch's 631 x 631 solve took 136 ms of CPU
    on a loaded 2-core machine instead of 7 ms single-threaded (issue 38)."""
    import os

    from rotorsweep.pipeline.cluster import WORKER_ENV

    for key, value in WORKER_ENV.items():
        os.environ.setdefault(key, value)


def as_config(cfg, allow_large=False, whole_grid=True):
    """A validated Config from a path (or the name of a shipped scene: rotorsweep.pipeline.scenes), a Config
    (as it is) or None (the embedded demo scene).
    whole_grid: the caller computes the whole sweep grid (`run`), whose size is then checked."""
    from rotorsweep.pipeline import config as config_mod

    if isinstance(cfg, config_mod.Config):
        return cfg
    if cfg is None:
        return config_mod.parse_config(config_mod.DEFAULT_CONFIG_TOML, path="<default scene>",
                                       allow_large=allow_large, whole_grid=whole_grid)
    from rotorsweep.pipeline import scenes

    return config_mod.load_config(scenes.resolve(cfg), allow_large=allow_large, whole_grid=whole_grid)


def _is_path(cube_or_path):
    return isinstance(cube_or_path, (str, bytes)) or hasattr(cube_or_path, "__fspath__")


def _dataset(cube_or_path):
    return open_cube(cube_or_path) if _is_path(cube_or_path) else cube_or_path


def run(config=None, output=None, *, allow_large=False, **kwargs):
    """Run a sweep (config: path, Config or None for the demo scene); returns the cube path.
    kwargs: workers (None: in this process for small work, else a local cluster of one per core;
    0: in this process; N: a local cluster of N), scheduler, resume, overwrite, chunk_points,
    progress. Safe at a plain script's module level (cluster workers do not run the script).

    >>> import tempfile, rotorsweep
    >>> scene = rotorsweep.parse_config('''
    ... [scene]
    ... name = "two_points"
    ... model = "jeffcott_clearance"
    ... [bearing]
    ... stiffness = "bai2006"
    ... [sweep]
    ... speed = [79.0, 82.0]        # either side of the period doubling at 80.88 Hz
    ... clearance = ["7.6 um"]
    ... ''')
    >>> path = rotorsweep.run(scene, f"{tempfile.mkdtemp()}/two_points.nc", workers=1, progress=False)
    >>> dict(rotorsweep.open_cube(path).sizes)["speed"]
    2
    """
    from rotorsweep.pipeline import sweep

    cfg = as_config(config, allow_large)
    return sweep.run(cfg, output or f"out/{cfg.data['scene']['name']}.nc", **kwargs)


def continue_branches(config=None, output=None, **kwargs):
    """Pseudo-arclength branches of a config's [continuation] (rotorsweep continue); returns the
    result's path. kwargs: workers (as for run), scheduler, overwrite, stream."""
    from rotorsweep.pipeline import continuation

    cfg = as_config(config, whole_grid=False)
    return continuation.run(cfg, output or f"out/{cfg.data['scene']['name']}_continuation.nc", **kwargs)


def open_cube(path):
    """A sweep cube (rotorsweep run) as an xarray.Dataset in memory; CubeError for any other file.
    `cube_path` here and below: a cube written by `run` (see its example), speeds 79 and 82 Hz at
    7.6 um, with the attractor diagnostics.

    >>> ds = rotorsweep.open_cube(cube_path)
    >>> ds["stable"].values.ravel().tolist()      # stable at 79 Hz, period-doubled at 82 Hz
    [1, 0]
    """
    from rotorsweep.pipeline import cube

    return cube.open_cube(path)


def unstable_intervals(cube_or_path):
    """The unstable runs of the continued axis (`rotorsweep query --unstable`), from a cube or
    its path: see rotorsweep.pipeline.query.unstable_intervals.

    >>> (run,) = rotorsweep.unstable_intervals(cube_path)
    >>> run["start"], run["type"], round(run["onset"], 2)
    (82.0, 'period_doubling', 80.88)
    """
    from rotorsweep.pipeline import query

    return query.unstable_intervals(_dataset(cube_or_path))


def open_result(path):
    """(dataset, its result kind) of any result file: a sweep cube, a continuation or a backbone
    result (rotorsweep.pipeline.result_kinds), opened once into memory.

    >>> ds, kind = rotorsweep.open_result(cube_path)
    >>> kind.name
    'sweep'
    """
    from rotorsweep.pipeline import result_kinds

    return result_kinds.open_result(path)


def make_report(cube_or_path, out_dir, points=None, overwrite=False, over=None, stream=None):
    """HTML + PNG report of a result (rotorsweep report); returns the written paths. The result:
    a path, or an opened dataset of any kind (rotorsweep.pipeline.result_kinds).
    points: grid points of a sweep cube to show in detail (orbit, Poincare section, spectrum,
    table), each a dict {axis: value} or "speed=36 clearance=19e-6" (nearest grid point). A
    directory holding the report of another cube is refused unless overwrite; the report is built
    next to it and then takes its place, so no file of the earlier report is left. over: for a
    backbone result, a continuation result (path) of a forced response to draw the backbones
    over. stream: where a sweep cube's report writes its phase lines (what it draws where, when
    the HTML page and the PNGs are written; None: nowhere).

    >>> import tempfile
    >>> files = rotorsweep.make_report(cube_path, f"{tempfile.mkdtemp()}/report")
    >>> files["html"].name
    'report.html'
    """
    from rotorsweep.pipeline import fileio, result_kinds, sweep

    if _is_path(cube_or_path):
        ds, kind = result_kinds.open_result(cube_or_path)
    else:
        ds, kind = cube_or_path, result_kinds.kind_of(cube_or_path)
    identity = fileio.report_identity(ds, cube_or_path if _is_path(cube_or_path) else None)
    fileio.check_report_dir(out_dir, identity, overwrite)
    result_kinds.refuse_options(kind, {"point": points, "over": over is not None}, "report_options")
    forced = None
    if over is not None:
        from rotorsweep.pipeline.report import backbone_result

        forced = result_kinds.open_kind(over, result_kinds.CONTINUATION)
        backbone_result.check_forced(ds, forced)
    return fileio.report_into(out_dir, lambda tmp: kind.report(ds, tmp, points=points, forced=forced,
                                                               say=sweep.phase_printer(stream)), identity)


def backbones(config=None, output=None, **kwargs):
    """Backbone curves of a conservative model's nonlinear normal modes (rotorsweep backbone):
    manifold and continuation; returns the result's path."""
    from rotorsweep.pipeline import backbone

    cfg = as_config(config, whole_grid=False)
    return backbone.run(cfg, output or f"out/{cfg.data['scene']['name']}_backbone.nc", **kwargs)


def point(speed=None, clearance=None, contact_angle=None, preload=None, config=None, **values):
    """Periodic orbit and Floquet multipliers at one point, as the cube variables of that point
    (a dict of numpy values). The point's axis values: the keywords (speed, clearance,
    contact_angle [deg], preload for jeffcott_clearance; any axis of the scene's model as
    `**values`), else the scene's fixed values.

    >>> row = rotorsweep.point(speed=60.0, clearance=7.6e-6)     # the default scene (Bai 2006)
    >>> int(row["orbit_status"]), int(row["stable"]), row["multiplier_real"].shape
    (0, 1, (4,))
    """
    from dataclasses import replace

    from rotorsweep.pipeline import compute

    cfg = as_config(config, whole_grid=False)
    given = {"speed": speed, "clearance": clearance, "contact_angle": contact_angle, "preload": preload, **values}
    pt = compute.point_values(cfg, given)
    # the periodic orbit only, even where the scene also asks for attractors (`point --attractor`)
    scene = replace(cfg.scene, analysis=replace(cfg.scene.analysis, floquet=True, attractor=False))
    row = compute.solve_segment(scene, [pt])
    return {k: v[0] for k, v in row.items()}

"""`rotorsweep` command line: run, continue, backbone, point, query, report, modes, warmup, info, scenes.

User mistakes (bad config, bad cube, bad query) print one clear message and exit with code 2;
no traceback."""
import argparse
import gc
import json
import logging
import os
import signal
import sys
import threading


import rotorsweep.pipeline as pipeline
from rotorsweep.pipeline import cluster, fileio, preflight

EXIT_USAGE = 2

# The user errors of the modules a command may import, by module: a command that did not import
# a module cannot raise its error, so `point` never imports xarray, pandas or Dask (cube, query,
# sweep) only to name their errors (a warm one-point command is mostly its imports).
USER_ERRORS = (("rotorsweep.pipeline.config", "ConfigError"), ("rotorsweep.pipeline.cube", "CubeError"), ("rotorsweep.pipeline.query", "QueryError"),
               ("rotorsweep.pipeline.cluster", "SweepError"), ("rotorsweep.kernels.continuation.events", "BoundaryError"),
               ("rotorsweep.pipeline.fileio", "FileIOError"))


def _confirm_large(args):
    """--yes, or on a terminal a yes/no question, lets a grid above numerics.max_points run."""
    from rotorsweep.pipeline import config as config_mod

    if args.yes:
        return True
    try:
        pipeline.as_config(args.config)
        return False
    except config_mod.ConfigError as exc:
        if exc.grid_points is None or not sys.stdin.isatty():
            raise
        answer = input(f"{exc}\nRun all {exc.grid_points} points anyway? [y/N] ")
        if answer.strip().lower() not in ("y", "yes"):
            raise
        return True


def _scheduler(args):
    """--scheduler with its TLS files and timeout as a cluster.Scheduler, or None (a local cluster,
    which makes its own certificate)."""
    tls = (args.tls_ca_file, args.tls_cert, args.tls_key)
    if not args.scheduler:
        if any(tls):
            raise cluster.SweepError("--tls-ca-file, --tls-cert and --tls-key go with --scheduler "
                                     "(the local cluster makes a certificate of its own)")
        return None
    return cluster.Scheduler(args.scheduler, *tls, timeout=args.scheduler_timeout)


def _preflight(args, cfg, out, need_bytes):
    """The checks before any work of a command writing `out` from cfg (rotorsweep.pipeline.preflight), and
    the scheduler's answer."""
    identity = fileio.result_identity(out, cfg.hash())
    preflight.check(out, need_bytes, lock=True, report=args.report, report_identity=identity,
                    overwrite=args.overwrite)
    scheduler = _scheduler(args)
    if scheduler:
        cluster.check_scheduler(scheduler)
    return scheduler


def cmd_run(args):
    cfg = pipeline.as_config(args.config, allow_large=_confirm_large(args))
    out = args.output or f"out/{cfg.data['scene']['name']}.nc"
    scheduler = _preflight(args, cfg, out, preflight.sweep_bytes(cfg))
    path = pipeline.run(cfg, out, workers=args.workers, scheduler=scheduler, resume=args.resume,
                        overwrite=args.overwrite, chunk_points=args.chunk_points, progress=not args.quiet)
    print(f"cube: {path}")
    if args.report:
        from rotorsweep.pipeline import sweep
        stream = None if args.quiet else sys.stderr
        sweep.phase_printer(stream)(f"writing the report into {args.report}")
        files = pipeline.make_report(path, args.report, overwrite=args.overwrite, stream=stream)
        print(f"report: {files['html']}")
    return 0


def _run_result(args, module, suffix, label):
    """`continue` / `backbone`: module.run(config) into out/<scene>_<suffix>.nc (or -o), then
    the report when asked."""
    cfg = pipeline.as_config(args.config, whole_grid=False)
    out = args.output or f"out/{cfg.data['scene']['name']}_{suffix}.nc"
    scheduler = _preflight(args, cfg, out, preflight.MIN_FREE_BYTES)
    path = module.run(cfg, out, workers=args.workers, scheduler=scheduler, overwrite=args.overwrite,
                      resume=args.resume, stream=None if args.quiet else sys.stderr)
    print(f"{label}: {path}")
    if args.report:
        files = pipeline.make_report(path, args.report, overwrite=args.overwrite)
        print(f"report: {files['html']}")
    return 0


def cmd_backbone(args):
    from rotorsweep.pipeline import backbone

    return _run_result(args, backbone, "backbone", "backbones")


def cmd_continue(args):
    from rotorsweep.pipeline import continuation

    return _run_result(args, continuation, "continuation", "continuation")


def _attractor_row(args, cfg):
    """The point's cube variables with the attractor diagnostics (compute.point_detail; the
    trajectory it also returns is not needed here, so it is kept short)."""
    from rotorsweep.pipeline import compute

    pt = compute.point_values(cfg, _given(args, cfg))
    return compute.point_detail(cfg.scene, pt, periods=16, steps_per_period=8)["row"]


def _given(args, cfg):
    """The point's axis values from --speed/--clearance/--contact-angle/--preload and --at: SI
    numbers, or unit strings in the axis's unit ("7.6 um", "600 rpm")."""
    from rotorsweep.pipeline import point_input

    flags = {"speed": ("--speed", args.speed), "clearance": ("--clearance", args.clearance),
             "contact_angle": ("--contact-angle", args.contact_angle), "preload": ("--preload", args.preload)}
    return point_input.flag_values({**flags, **_at(args.at)}, cfg.model)


def _at(items):
    """{axis: (flag, text)} from --at AXIS=VALUE options (VALUE: SI number or unit string)."""
    from rotorsweep.pipeline import config as config_mod

    given = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise config_mod.ConfigError(f"--at {item}: expected AXIS=VALUE, e.g. speed=100 or speed=\"600 rpm\"")
        given[name.strip()] = (f"--at {item}", value.strip().strip("'\""))
    return given


def cmd_modes(args):
    from rotorsweep.pipeline import modes, point_input

    cfg = pipeline.as_config(args.config, whole_grid=False)
    if args.output:
        preflight.check(args.output)
    if args.report:     # refused now as modes_report would refuse it after the analysis: a foreign directory
        fileio.check_report_dir(args.report, None, overwrite=True)
        preflight.check_report(args.report)
    print(modes.command(cfg, point_input.flag_values(_at(args.at), cfg.model), args.campbell, args.output, args.json,
                        args.report))
    return 0


def cmd_point(args):
    from rotorsweep.pipeline import point_result

    cfg = pipeline.as_config(args.config, whole_grid=False)
    if args.attractor:
        row = _attractor_row(args, cfg)
    else:
        row = pipeline.point(config=cfg, **_given(args, cfg))
    result = point_result.result_of(row, args.attractor)
    print(json.dumps(result, indent=2) if args.json else point_result.text(result))
    return 0


def cmd_query(args):
    from rotorsweep.pipeline import result_kinds

    ds, kind = result_kinds.open_result(args.cube)
    options = {"where": args.where, "var": args.var, "unstable": args.unstable, "attractors": args.attractors,
               "bistable": args.bistable}
    result_kinds.refuse_options(kind, options, "query_options")
    print(kind.query(ds, args.format, **{k: v for k, v in options.items() if k in kind.query_options}))
    return 0


def cmd_report(args):
    from rotorsweep.pipeline import report as report_mod

    out = args.output or str(args.cube).rsplit(".", 1)[0] + "_report"
    points = [report_mod.parse_point(items) for items in args.point or []]
    preflight.check_report(out)
    files = pipeline.make_report(args.cube, out, points=points or None, overwrite=args.overwrite, over=args.over,
                                 stream=None if args.quiet else sys.stderr)
    print(f"report: {files['html']}")
    for png in files["png"]:
        print(f"figure: {png}")
    return 0


def cmd_info(args):
    from rotorsweep.pipeline import result_kinds

    ds, kind = result_kinds.open_result(args.cube)
    print(kind.describe(ds))
    return 0


def _positive_int(text):
    """argparse type: an integer >= 1 (a worker count or chunk size of 0 or less is a typo)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1 (got {text!r})") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1 (got {value})")
    return value


def _worker_count(text):
    """argparse type: an integer >= 0 (0: in this process, no cluster)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0 (0: in this process; got {text!r})")
    return value


def cmd_warmup(args):
    import numba

    from rotorsweep.pipeline import warmup

    print(f"Numba cache: {numba.config.CACHE_DIR}")
    warmup.warmup(args.models, integrators=args.integrator or warmup.INTEGRATORS)
    return 0


def _positive_float(text):
    """argparse type: a number > 0 (seconds)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number > 0 (got {text!r})") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0 (got {text})")
    return value


def _cluster_options(parser):
    """Where run, continue and backbone run: in this process for small work (estimated below the
    scene's [run] in_process_below or $ROTORSWEEP_IN_PROCESS_BELOW_S, default 3 s of CPU), else on
    a local Dask cluster, or on a given scheduler (always used when given); the flags choose."""
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_worker_count,
                       help="local Dask worker processes (default: one per core, at least 2, or none for small "
                            "work); 0: in this process")
    where.add_argument("--in-process", dest="workers", action="store_const", const=0,
                       help="run in this process, no cluster (as --workers 0)")
    parser.add_argument("--scheduler", help="address of an existing Dask scheduler, e.g. tcp://10.0.0.5:8786 "
                                            "(tls://... with the --tls-* files)")
    parser.add_argument("--scheduler-timeout", type=_positive_float, default=cluster.SCHEDULER_TIMEOUT_S,
                        metavar="SECONDS", help="seconds the scheduler has to answer before the command "
                                                f"stops (default {cluster.SCHEDULER_TIMEOUT_S})")
    parser.add_argument("--tls-ca-file", metavar="PEM", help="CA certificate of a TLS cluster (with --scheduler)")
    parser.add_argument("--tls-cert", metavar="PEM", help="this client's certificate (with --scheduler)")
    parser.add_argument("--tls-key", metavar="PEM", help="this client's private key (with --scheduler)")


def build_parser():
    ap = argparse.ArgumentParser(prog="rotorsweep", description=__doc__.splitlines()[0])
    ap.add_argument("--version", action="version", version=f"rotorsweep {cluster.VERSION}")
    sub = ap.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="run a sweep from a config into a netCDF cube")
    r.add_argument("config", nargs="?", help="scene TOML, or the name of a shipped scene (`rotorsweep scenes`; "
                                             "default: the embedded demo scene)")
    r.add_argument("-o", "--output", help="cube path (default out/<scene name>.nc)")
    _cluster_options(r)
    r.add_argument("--chunk-points", type=_positive_int, help="points per Dask task (default: automatic)")
    r.add_argument("--resume", action="store_true", help="finish an interrupted run from its part files")
    r.add_argument("--overwrite", action="store_true", help="replace an existing cube (and --report DIR)")
    r.add_argument("--yes", action="store_true", help="allow grids above numerics.max_points")
    r.add_argument("--report", metavar="DIR", help="also write the report into DIR")
    r.add_argument("-q", "--quiet", action="store_true", help="no phase lines and no progress bar")
    r.set_defaults(func=cmd_run)

    for name, func, help_text, config_help in (
            ("continue", cmd_continue, "pseudo-arclength branches (folds, period doublings, branch switching) of a "
             "config's [continuation] into a netCDF result",
             "scene TOML with a [continuation] section (default: the demo scene, along speed)"),
            ("backbone", cmd_backbone, "nonlinear normal modes and backbone curves of a conservative model "
             "(invariant manifold and continuation) into a netCDF result",
             "scene TOML of a conservative model (symmetric4, asymmetric5, ...), [backbone] section optional")):
        c = sub.add_parser(name, help=help_text)
        c.add_argument("config", nargs="?" if name == "continue" else None, help=config_help)
        c.add_argument("-o", "--output", help=f"result path (default out/<scene name>_{name.replace('continue', 'continuation')}.nc)")
        _cluster_options(c)
        c.add_argument("--resume", action="store_true", help="finish an interrupted run from its finished lines")
        c.add_argument("--overwrite", action="store_true", help="replace an existing result (and --report DIR)")
        c.add_argument("--report", metavar="DIR", help="also write the report into DIR")
        c.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
        c.set_defaults(func=func)

    p = sub.add_parser("point", help="periodic orbit and Floquet multipliers at one point")
    p.add_argument("--config", help="scene TOML (default: Bai 2006, 209 bearing, the paper's constant)")
    p.add_argument("--speed", help="shaft speed [Hz, or with a unit: \"600 rpm\"]")
    p.add_argument("--clearance", help="radial clearance [m, or with a unit: \"7.6 um\"] (default: the scene's)")
    p.add_argument("--contact-angle", help="contact angle [deg, or with a unit: \"0.26 rad\"] (default: from clearance)")
    p.add_argument("--preload", help="axial preload [N, or with a unit: \"0.4 kN\"] (default: the scene's, 0)")
    p.add_argument("--at", action="append", metavar="AXIS=VALUE",
                   help="value of any axis of the scene's model, SI or with a unit, e.g. --at speed=100 or --at speed=\"600 rpm\"; repeatable")
    p.add_argument("--attractor", action="store_true",
                   help="also diagnose the attractor: class, period, largest Lyapunov exponent, multipliers")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_point)

    q = sub.add_parser("query", help="select points of a cube and print them",
                       description="Select points of a cube and print them. Values are in the cube's "
                                   "units (SI: speed in Hz, clearance in m, contact angle in degree, "
                                   "preload in N), in --where as in the output; the report shows "
                                   "clearances in um.")
    q.add_argument("cube", help="result cube (.nc) written by rotorsweep run")
    q.add_argument("--where", action="append", metavar="AXIS=SEL",
                   help="speed=80:120 (range), clearance=3.8e-6 (value, m), preload=0,100 (list); repeatable")
    q.add_argument("--var", action="append", metavar="NAME", help="variable to print; repeatable")
    q.add_argument("--unstable", action="store_true", help="print the unstable speed intervals (unstable and failed tori "
                   "too); of a continuation result: the unstable stretches of its branches")
    q.add_argument("--bistable", action="store_true",
                   help="print the bistable speed intervals: between the fold pair of each jump of the sweep")
    q.add_argument("--attractors", nargs="?", const="up", choices=["up", "down"],
                   help="print the speed intervals of constant attractor class and period "
                        "(the up sweep, or the down sweep of a sweep_direction = \"both\" cube)")
    q.add_argument("--format", choices=["table", "csv", "json"], default="table",
                   help="aligned text table (default), CSV, or JSON records (null for NaN)")
    q.set_defaults(func=cmd_query)

    rp = sub.add_parser("report", help="HTML + PNG stability-map report of a cube")
    rp.add_argument("cube", help="result cube (.nc) written by rotorsweep run")
    rp.add_argument("-o", "--output", help="report directory (default <cube>_report)")
    rp.add_argument("--point", action="append", nargs="+", metavar="AXIS=VALUE",
                    help="a grid point to show in detail (orbit, Poincare section, spectrum): "
                         "speed=36 clearance=19e-6 (cube units; nearest grid point); repeatable")
    rp.add_argument("-q", "--quiet", action="store_true", help="no phase lines")
    rp.add_argument("--overwrite", action="store_true",
                    help="replace a report of another cube in the directory")
    rp.add_argument("--over", metavar="CONTINUATION_NC",
                    help="backbone results: draw each mode's backbone over this forced response (a "
                         "`rotorsweep continue` result along a frequency in Hz, e.g. rigid_preloaded, law = cubic)")
    rp.set_defaults(func=cmd_report)

    m = sub.add_parser("modes", help="static equilibrium, natural frequencies, damping, whirl, Campbell table "
                                     "(every model with a linearization)")
    m.add_argument("config", help="scene TOML of a model with a linearization")
    m.add_argument("--at", action="append", metavar="AXIS=VALUE", help="axis value, SI or with a unit (default: the first grid value)")
    m.add_argument("--campbell", metavar="START:STOP:NUM", help="shaft speeds [Hz, or with a unit: \"600 rpm:3000 rpm:5\"] of the Campbell table")
    m.add_argument("-o", "--output", help="Campbell table CSV (speed_hz, mode, frequency_hz, damping_ratio, whirl, label)")
    m.add_argument("--json", action="store_true", help="print the equilibrium and the modes as JSON")
    m.add_argument("--report", metavar="DIR", help="write an HTML report (modes table, Campbell diagram with the "
                                                   "critical speeds, mode shapes; PNGs, modes.csv) into DIR")
    m.set_defaults(func=cmd_modes)

    w = sub.add_parser("warmup", help="compile the kernels of models into the Numba cache (a cluster "
                                      "image, before the first run); idempotent")
    w.add_argument("models", nargs="*", metavar="MODEL", help="model names (default: every registered model)")
    w.add_argument("--integrator", action="append", choices=("dop853", "rk4"),
                   help="compile for this integrator only, repeatable (default: both; a scene compiles only its own)")
    w.set_defaults(func=cmd_warmup)

    i = sub.add_parser("info", help="what a cube holds")
    i.add_argument("cube", help="result cube (.nc) written by rotorsweep run")
    i.set_defaults(func=cmd_info)

    s = sub.add_parser("scenes", help="list the shipped scenes (the papers' configs), or --copy one to edit")
    s.add_argument("--copy", metavar="NAME", help="copy the shipped scene NAME to DEST (default ./NAME.toml)")
    s.add_argument("dest", nargs="?", metavar="DEST", help="with --copy: the file or directory to copy to")
    s.add_argument("--overwrite", action="store_true", help="with --copy: replace an existing file")
    s.set_defaults(func=cmd_scenes)
    return ap


def cmd_scenes(args):
    from rotorsweep.pipeline import config as config_mod, scenes

    if args.copy is None:
        if args.dest is not None:
            raise config_mod.ConfigError(f"{args.dest}: DEST goes with --copy NAME")
        rows = scenes.listing()
        width = max(len(name) for name, _ in rows)
        for name, text in rows:
            print(f"{name:<{width}}  {text}")
        return 0
    print(f"{args.copy} -> {scenes.copy(args.copy, args.dest, overwrite=args.overwrite)}")
    return 0


def user_errors():
    """The exception classes that mean a user mistake, of the modules imported so far."""
    found = [getattr(sys.modules[module], name) for module, name in USER_ERRORS if module in sys.modules]
    return (ValueError, *found)


def _recording_interrupts(seen):
    """A SIGINT handler that raises KeyboardInterrupt as Python's does and first appends to `seen`
    and turns logging off: a library may turn the KeyboardInterrupt into another error (numpy's
    comparison of structured arrays, in np.unique(axis=0), reports it as a TypeError), and the run
    must still end as interrupted, with the one line _interrupted prints. What the libraries'
    event-loop threads log from then on is their teardown racing the interrupt (Dask's sync()
    schedules a cancel callback that raises NameError when Ctrl-C came before its future existed,
    and tornado.application logs the traceback). The previous handler, or None where SIGINT is
    not Python's default (ignored by the parent, or a caller's own) or this is not the main
    thread."""
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        return None

    def handler(signum, frame):
        seen.append(signum)
        logging.disable(logging.CRITICAL)
        signal.default_int_handler(signum, frame)

    return signal.signal(signal.SIGINT, handler)


def main(argv=None):
    """The command line (argv None: sys.argv, and the process exits when this returns)."""
    args = build_parser().parse_args(argv)
    if argv is None:
        pipeline.collector_after_startup()
        pipeline.pools_as_a_worker()
        pipeline.numba_without_cffi()
        pipeline.numba_config_without_yaml()
    interrupts = []
    disabled = logging.root.manager.disable
    previous = _recording_interrupts(interrupts)
    try:
        return _dispatch(args, interrupts)
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
        logging.disable(disabled)
        if argv is None:
            # the interpreter's shutdown collections walk every object left (the imports' 300k+
            # with numba and xarray: 0.1-0.4 s CPU, a third of a small command); frozen, they
            # are still freed, only not walked (objects in reference cycles stay unfreed)
            gc.freeze()


def _dispatch(args, interrupts):
    from rotorsweep.kernels import models

    if models.PLUGIN_ERRORS:
        return _error(args, "; ".join(models.PLUGIN_ERRORS))
    try:
        return args.func(args)
    except Exception as exc:
        if interrupts:
            return _interrupted(args)
        if isinstance(exc, BrokenPipeError):      # output piped into head & co.
            sys.stdout = open(os.devnull, "w")
            return 0
        message = error_text(exc)
        if message is None:
            raise
        return _error(args, message)
    except KeyboardInterrupt:
        return _interrupted(args)


def error_text(exc):
    """The one line for an error the user can act on, or None for a bug (a traceback): the
    modules' user errors; OS errors (read-only directory, disk full, a file where a directory
    goes, a lost scheduler connection) and netCDF/HDF write errors name the path (rotorsweep.pipeline.fileio
    names the output, never its temp file); Dask giving up on a task whose workers kept dying."""
    if isinstance(exc, user_errors()):
        return str(exc)
    if isinstance(exc, OSError):
        return fileio.os_error_text(exc)
    if type(exc).__name__ == "KilledWorker":
        return (f"Dask gave up on a task: {str(exc).split('. ')[0]}; is the machine short of memory? "
                "(the workers' logs say more)")
    if isinstance(exc, RuntimeError) and ("NetCDF" in str(exc) or "HDF" in str(exc)):
        return f"netCDF/HDF error: {exc}"
    return None


# What each command keeps when Ctrl-C stops it: (what its finished work is written as, where it
# can resume with --resume; what is left as it was otherwise). Every output is written atomically,
# so none is ever partial. A command with a --resume option keeps its finished work.
INTERRUPTED = {
    "run": ("chunks", "the output"),
    "continue": ("lines", "the output"),
    "backbone": ("lines", "the output"),
    "report": (None, "the report directory"),
    "modes": (None, "the Campbell table file (-o) and the report directory"),
}


def _interrupted(args):
    print(f"rotorsweep: {interrupted_text(args)}", file=sys.stderr)
    return 130


def interrupted_text(args):
    """The truth about what an interrupted command kept (INTERRUPTED)."""
    parts, unchanged = INTERRUPTED.get(args.command, (None, None))
    if parts and getattr(args, "resume", None) is not None:
        return f"interrupted; finished {parts} are kept, rerun with --resume"
    if unchanged:
        return f"interrupted; nothing was written, {unchanged} is as it was"
    return "interrupted"


def _error(args, message):
    print(f"rotorsweep {args.command}: error: {message}", file=sys.stderr)
    return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())

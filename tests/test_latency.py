"""Small work answers without a cluster (issue 35): where a command runs (in this process or on a
Dask cluster) changes no result bit; `import rotorsweep`, the command line's parsing, `info`,
`query` and `point` import no module they do not use (plotting, Dask, scipy's solvers, ...); the
README's Python example runs as a plain script and in an exec (issue 37)."""
import gc
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.pipeline import backbone, cluster, config, continuation, cube, sweep, torus_branches, workload
from rotorsweep.pipeline.continuation_result import TORUS_STATUS
from tests.test_backbone_command import scene as backbone_scene
from tests.test_continue_command import DUFFING
from tests.test_pipeline import SMALL

ROOT = Path(__file__).resolve().parents[1]
CLI = [str(Path(sys.executable).with_name("rotorsweep"))]
PLOTTING = ("hvplot", "panel", "holoviews", "bokeh", "matplotlib")
DASK = ("dask", "distributed")
SCIPY_SOLVERS = ("scipy.linalg", "scipy.interpolate", "scipy.integrate", "scipy.optimize", "numpy.f2py")
HEAVY = PLOTTING + DASK + SCIPY_SOLVERS
# what each command must not import (issue 35): nothing heavy where nothing is computed or read;
# a result file needs xarray (with pandas) but no numba (the model registry holds specs, not kernels),
# a point only numba
NOTHING_READ = HEAVY + ("numba", "xarray", "pandas", "netCDF4", "pint")
RESULT_READ = HEAVY + ("numba", "llvmlite", "pint")
COMMANDS = {
    "import rotorsweep": (["-c", "import rotorsweep"], NOTHING_READ),
    "argument parsing": (["-m", "rotorsweep.pipeline.cli", "--help"], NOTHING_READ),
    "info": (["-m", "rotorsweep.pipeline.cli", "info", "{cube}"], RESULT_READ),
    "query --unstable": (["-m", "rotorsweep.pipeline.cli", "query", "{cube}", "--unstable"], RESULT_READ),
    "query --attractors": (["-m", "rotorsweep.pipeline.cli", "query", "{cube}", "--attractors"], RESULT_READ),
    "query --where --var": (["-m", "rotorsweep.pipeline.cli", "query", "{cube}", "--where", "speed=0:1e4", "--var",
                             "max_abs_multiplier"], RESULT_READ),
    "point": (["-m", "rotorsweep.pipeline.cli", "point", "--speed", "100", "--clearance", "7.6e-6"],
              HEAVY + ("xarray", "pandas", "netCDF4", "pint")),
    # a unit string loads pint, and pint alone (not the Dask it would import: units._pint_without_dask)
    "point with units": (["-m", "rotorsweep.pipeline.cli", "point", "--speed", "600 rpm", "--clearance", "7.6 um"],
                         HEAVY + ("xarray", "pandas", "netCDF4")),
    # a small continuation writes its result with netCDF4 alone (rotorsweep.pipeline.plainnc)
    "continue": (["-m", "rotorsweep.pipeline.cli", "continue", "configs/duffing_resonance.toml", "-o", "{out}",
                  "--workers", "0", "-q"], HEAVY + ("xarray", "pandas")),
}


def env():
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}


def test_a_sweep_in_process_and_on_a_cluster_give_the_same_bits(tmp_path):
    cfg = config.parse_config(SMALL)
    here = cube.open_cube(sweep.run(cfg, tmp_path / "here.nc", workers=0, progress=False))
    there = cube.open_cube(sweep.run(cfg, tmp_path / "there.nc", workers=2, progress=False))
    for name in here.data_vars:
        if name != "compute_time":          # the only variable that measures the machine
            np.testing.assert_array_equal(here[name].values, there[name].values, err_msg=name)


def test_a_continuation_in_process_and_on_a_cluster_give_the_same_bits(tmp_path):
    cfg = config.parse_config(DUFFING)
    import xarray as xr
    here = xr.load_dataset(continuation.run(cfg, tmp_path / "here.nc", workers=0, stream=None))
    there = xr.load_dataset(continuation.run(cfg, tmp_path / "there.nc", workers=1, stream=None))
    assert set(here.data_vars) == set(there.data_vars)
    for name in here.data_vars:
        np.testing.assert_array_equal(here[name].values, there[name].values, err_msg=name)


def same_bits(a, b):
    """Nested records (dicts, lists, tuples, arrays, numbers, text) equal bit for bit."""
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same_bits(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(same_bits(x, y) for x, y in zip(a, b))
    if isinstance(a, str) or a is None:
        return a == b
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


BAI_FOLD_76 = (ROOT / "configs" / "bai2006_fold.toml").read_text().replace("clearance = [7.6e-6, 19.0e-6]",
                                                                           "clearance = [7.6e-6]")


@pytest.mark.parametrize("text", [DUFFING, BAI_FOLD_76], ids=["duffing", "bai2006_fold_7.6um"])
def test_kernel_inputs_kept_per_parameter_value_change_no_bit(text, monkeypatch):
    scene = config.parse_config(text).scene
    where, = continuation.plan(scene).lines
    kept = continuation.continue_line(scene, where)
    monkeypatch.setattr(continuation, "BUILT_KEPT", 0)         # every value built again
    assert same_bits(kept, continuation.continue_line(scene, where))


def test_where_a_command_runs():
    assert cluster.runs_in_process(None, None, 0.1)
    assert not cluster.runs_in_process(None, None, 1e3)
    assert cluster.runs_in_process(0, None, 1e3)                        # --workers 0 / --in-process
    assert not cluster.runs_in_process(2, None, 0.1)                    # a worker count asks for a cluster
    assert not cluster.runs_in_process(None, "tcp://127.0.0.1:1", 0.1)  # a scheduler is always used
    assert cluster.runs_in_process(None, None, 1e3, tasks=1)            # one task: a cluster cannot help


def test_the_threshold_is_overridable(monkeypatch):
    monkeypatch.setenv(cluster.IN_PROCESS_VARIABLE, "0")
    assert not cluster.runs_in_process(None, None, 0.1)
    monkeypatch.setenv(cluster.IN_PROCESS_VARIABLE, "ten")
    with pytest.raises(cluster.SweepError, match=cluster.IN_PROCESS_VARIABLE):
        cluster.in_process_below_s()


def test_the_scene_sets_the_threshold_and_keeps_its_hash(monkeypatch):
    monkeypatch.setenv(cluster.IN_PROCESS_VARIABLE, "0")
    plain = config.parse_config(DUFFING)
    scene = config.parse_config(DUFFING + '\n[run]\nin_process_below = "1 min"\n')
    assert cluster.in_process_below_s(plain.scene.in_process_below) == 0
    assert cluster.in_process_below_s(scene.scene.in_process_below) == 60
    assert cluster.runs_in_process(None, None, 59.0, below=scene.scene.in_process_below)
    assert not cluster.runs_in_process(None, None, 59.0, below=plain.scene.in_process_below)
    assert scene.hash() == plain.hash()        # where a scene runs is not what it computes: --resume works
    with pytest.raises(config.ConfigError, match="run.in_process_below: must be >= 0"):
        config.parse_config(DUFFING + "\n[run]\nin_process_below = -1\n")
    with pytest.raises(config.ConfigError, match="run.in_process_below: .* not a quantity of unit s"):
        config.parse_config(DUFFING + '\n[run]\nin_process_below = "3 m"\n')


def test_the_suite_measures_into_a_cache_of_its_own():
    """tests/conftest.py: what the suite's runs measure stays out of the user's costs.json, while
    the compiled kernels are the user's (not compiled again for the suite)."""
    from tests.conftest import PRIVATE_CACHE
    assert os.path.dirname(workload.costs_path()) == str(PRIVATE_CACHE)
    assert not Path(os.path.realpath(os.environ["NUMBA_CACHE_DIR"])).is_relative_to(PRIVATE_CACHE.resolve())


def test_measured_unit_costs_are_kept_in_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("ROTORSWEEP_CACHE", str(tmp_path))
    assert workload.estimate("point", "duffing", 10) == 10 * workload.DEFAULT_COSTS["point"]
    workload.record("point", "duffing", 4, 2.0)
    assert workload.estimate("point", "duffing", 10) == pytest.approx(5.0)
    assert workload.unit_cost("point", "jeffcott_clearance") == workload.DEFAULT_COSTS["point"]


def test_a_unit_costs_the_median_of_its_latest_measurements(tmp_path, monkeypatch):
    """A run inflated by loading or compiling kernels (the largest cost, which the cache once kept
    for good) moves the estimate little, and is forgotten after workload.RECENT more runs."""
    monkeypatch.setenv("ROTORSWEEP_CACHE", str(tmp_path))
    workload.record("point", "duffing", 10, 200.0)            # compiling: 20 s a point
    for seconds in (0.1, 0.3, 0.2):
        workload.record("point", "duffing", 10, seconds)
    assert workload.unit_cost("point", "duffing") == pytest.approx(0.025)     # median of 20, 0.01, 0.03, 0.02
    workload.record("point", "duffing", 10, 0.2)
    assert workload.unit_cost("point", "duffing") == pytest.approx(0.02)
    for _ in range(workload.RECENT):
        workload.record("point", "duffing", 10, 0.5)
    assert workload.unit_cost("point", "duffing") == pytest.approx(0.05)
    assert len(json.loads(Path(workload.costs_path()).read_text())["point:duffing"]) == workload.RECENT


def test_a_cache_written_before_keeps_its_cost_as_one_measurement(tmp_path, monkeypatch):
    monkeypatch.setenv("ROTORSWEEP_CACHE", str(tmp_path))
    Path(workload.costs_path()).write_text(json.dumps({"point:duffing": 0.3, "point:other": "bad"}))
    assert workload.unit_cost("point", "duffing") == pytest.approx(0.3)
    assert workload.unit_cost("point", "other") == workload.DEFAULT_COSTS["point"]
    workload.record("point", "duffing", 1, 0.1)
    workload.record("point", "duffing", 1, 0.2)
    assert workload.unit_cost("point", "duffing") == pytest.approx(0.2)


def test_a_quick_line_does_not_lower_the_default(tmp_path, monkeypatch):
    monkeypatch.setenv("ROTORSWEEP_CACHE", str(tmp_path))
    workload.record("continuation_line", "duffing", 1, 0.07)       # a quick line does not lower the default
    assert workload.unit_cost("continuation_line", "duffing") == workload.DEFAULT_COSTS["continuation_line"]


def test_only_the_command_line_process_freezes_its_heap_for_the_exit(capsys):
    """cli.main() as the process (argv from sys.argv) leaves its objects out of the interpreter's
    shutdown collections; called with arguments (from Python, the tests) it leaves gc as it was."""
    from rotorsweep.pipeline import cli

    frozen = gc.get_freeze_count()
    assert cli.main(["scenes"]) == 0 and gc.get_freeze_count() == frozen
    program = ("import gc, sys; from rotorsweep.pipeline import cli; sys.argv = ['rotorsweep', 'scenes']; "
               "code = cli.main(); print(code, gc.get_freeze_count() > 0, file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, env=env(), cwd=ROOT,
                          timeout=300)
    assert proc.returncode == 0 and proc.stderr.split()[-2:] == ["0", "True"], proc.stderr[-2000:]


def test_the_command_line_process_starts_without_the_cyclic_collector():
    """cli.main() as the process turns the collector off for its start-up (cli.main() from Python
    leaves it on); collector_after_startup turns it back on after its seconds, with the objects
    made so far frozen, and a process forked meanwhile collects from its start."""
    from rotorsweep.pipeline import cli

    assert cli.main(["scenes"]) == 0 and gc.isenabled()
    program = ("import gc, os, sys; import rotorsweep.pipeline as p; from rotorsweep.pipeline import cli; "
               "asked = []; p.collector_after_startup = lambda: asked.append(1); "
               "sys.argv = ['rotorsweep', 'scenes']; cli.main(); print(asked, file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, env=env(), cwd=ROOT,
                          timeout=300)
    assert proc.returncode == 0 and proc.stderr.split()[-1] == "[1]", proc.stderr[-2000:]
    program = ("import gc, os, sys; import rotorsweep.pipeline as p; timer = p.collector_after_startup(0.5); "
               "off = not gc.isenabled(); frozen = gc.get_freeze_count(); pid = os.fork()\n"
               "if pid == 0: os._exit(0 if gc.isenabled() else 1)\n"
               "child = os.waitpid(pid, 0)[1] == 0; timer.join(); "
               "print(off, frozen == 0, child, gc.isenabled(), gc.get_freeze_count() > 1_000, file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, env=env(), cwd=ROOT,
                          timeout=300)
    assert proc.returncode == 0 and proc.stderr.split()[-5:] == ["True"] * 5, proc.stderr[-2000:]


def test_in_process_tasks_run_by_priority_and_raise_on_result():
    ex = cluster.InProcess()
    ran = []
    low, high = ex.submitter(ran.append), ex.submitter(ran.append, priority=1)
    tasks = [low("a"), high("b")]
    assert [t.result() is None for t in ex.as_completed(tasks)] == [True, True] and ran == ["b", "a"]
    failing = ex.submitter(lambda: 1 / 0)()
    for task in ex.as_completed([failing]):
        with pytest.raises(ZeroDivisionError):
            task.result()


def imported_modules(args):
    """The modules a Python process imports (from `-X importtime`)."""
    proc = subprocess.run([sys.executable, "-X", "importtime", *args], capture_output=True, text=True,
                          env=env(), timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return {m.group(1) for m in re.finditer(r"^import time:.*\|\s*([\w.]+)\s*$", proc.stderr, re.M)}


def heavy(modules, listed):
    return sorted(m for m in modules if any(m == h or m.startswith(h + ".") for h in listed))


@pytest.mark.parametrize("command", COMMANDS)
def test_a_command_imports_only_what_it_uses(command, tiny_cube, tmp_path):
    args, listed = COMMANDS[command]
    args = [a.replace("{cube}", str(tiny_cube)).replace("{out}", str(tmp_path / "out.nc")) for a in args]
    assert heavy(imported_modules(args), listed) == []


@pytest.fixture(scope="module")
def continuation_result(tmp_path_factory):
    return continuation.run(config.parse_config(DUFFING), tmp_path_factory.mktemp("read") / "fold.nc", workers=0,
                            stream=None)


READS = {
    "cube": (["info"], ["query", "--unstable"], ["query", "--attractors"], ["query", "--attractors", "down"],
             ["query", "--bistable"], ["query", "--where", "speed=60:65", "--var", "max_abs_multiplier", "--var",
                                       "attractor", "--format", "csv"], ["query", "--format", "json"]),
    "continuation": (["info"], ["query"], ["query", "--format", "json"], ["query", "--unstable"]),
    "backbone": (["info"], ["query"], ["query", "--format", "csv"]),
}


@pytest.mark.parametrize("kind", READS)
def test_a_result_read_without_numba_prints_what_it_prints_with_everything_loaded(kind, request, capfd):
    """info and query in a fresh process (which imports no Numba: above) print the same bytes and
    exit with the same status as in this process, where the kernels, Numba and the whole pipeline are loaded."""
    from rotorsweep.pipeline import cli
    path = str(request.getfixturevalue("tiny_cube" if kind == "cube" else f"{kind}_result"))
    for command in READS[kind]:
        args = [command[0], path, *command[1:]]
        proc = subprocess.run([*CLI, *args], capture_output=True, text=True, env=env(), timeout=300, cwd=ROOT)
        capfd.readouterr()
        status = cli.main(args) or 0
        here = capfd.readouterr()
        assert (proc.returncode, proc.stdout, proc.stderr) == (status, here.out, here.err), args


def test_the_accessor_registers_without_hvplot_and_draws_with_it(tiny_cube):
    code = ("import sys, rotorsweep; ds = rotorsweep.open_cube(sys.argv[1]); assert 'hvplot' not in sys.modules; "
            "ds.rotorsweep.max_multiplier(); assert 'hvplot' in sys.modules")
    subprocess.run([sys.executable, "-c", code, str(tiny_cube)], check=True, env=env(), timeout=300, cwd=ROOT)
    before = ("import xarray as xr, rotorsweep, rotorsweep.pipeline.explore; "
              "assert type(xr.Dataset().rotorsweep).__name__ == 'CubeAccessor'")    # once: no override warning
    subprocess.run([sys.executable, "-W", "error", "-c", before], check=True, env=env(), timeout=300, cwd=ROOT)


def readme_example(tmp_path):
    """The README's Python example on the small scene, its paths in tmp_path."""
    text = (ROOT / "README.md").read_text()
    code = re.search(r"```python\n(import rotorsweep\n.*?)```", text, re.S).group(1)
    assert "rotorsweep.run(" in code
    (tmp_path / "small.toml").write_text(SMALL)
    code = code.replace("configs/demo.toml", str(tmp_path / "small.toml"))
    code = code.replace('"out/fold.nc"', 'path')         # no continuation result here: the cube (any result)
    return code.replace('"out/', f'"{tmp_path}/out/')


def test_the_readme_python_example_runs_as_a_plain_script(tmp_path):
    """No `if __name__ == "__main__":`: the workers must not run the script again."""
    script = tmp_path / "example.py"
    script.write_text(readme_example(tmp_path))
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env(), timeout=600,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr and (tmp_path / "out" / "demo_report").is_dir()


def test_the_readme_python_example_runs_in_an_exec(tmp_path):
    """As a notebook runs a cell."""
    (tmp_path / "cell.py").write_text(readme_example(tmp_path))
    code = "exec(compile(open('cell.py').read(), '<cell>', 'exec'), {'__name__': '__main__'})"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env(), timeout=600,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]


def test_the_overwrite_hint_names_the_python_keyword(tmp_path):
    cfg = config.parse_config(DUFFING)
    out = tmp_path / "x.nc"
    out.write_text("")
    with pytest.raises(cube.CubeError, match="overwrite=True"):
        continuation.run(cfg, out, workers=0, stream=None)


def test_an_in_process_continuation_loads_only_the_kernels_it_calls(tmp_path):
    """In this process the kernels load on first use (warmup.kernels_on_first_use): the Duffing
    line (a peak family) never calls the orbits' plain extrema pass, which a cluster's driver
    loads for its workers; the line's cost is recorded (no kernel compiled: the cache is warm)."""
    (tmp_path / "d.toml").write_text(DUFFING)
    code = ("import io, sys; from rotorsweep.pipeline import config, continuation, workload; "
            "from rotorsweep.kernels import extrema; log = io.StringIO(); "
            "cfg = config.load_config('d.toml'); continuation.run(cfg, 'warm.nc', workers=0, stream=None); "
            "before = workload._measured().get(workload._key('continuation_line', 'duffing'), []); "
            "continuation.run(cfg, 'd.nc', workers=0, stream=log); "
            "after = workload._measured().get(workload._key('continuation_line', 'duffing'), []); "
            "print(len(extrema.orbit_extent.overloads), 'load on first use' in log.getvalue(), after != before)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env(), timeout=600,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.split() == ["0", "True", "True"]


# --- the command line's process sets up no cffi typing in Numba (issue 35) ------------------------

def test_a_command_line_kernel_load_imports_no_cffi():
    args = ["-m", "rotorsweep.pipeline.cli", "point", "--speed", "100", "--clearance", "7.6e-6"]
    assert heavy(imported_modules(args), ("pycparser", "cffi.api")) == []


def test_without_cffi_numba_treats_it_as_absent_and_cffi_still_imports():
    code = ("import rotorsweep.pipeline as p; p.numba_without_cffi(); from numba.core.typing import cffi_utils; "
            "assert not cffi_utils.SUPPORTED; import cffi; cffi.FFI()")
    subprocess.run([sys.executable, "-c", code], check=True, env=env(), timeout=300, cwd=ROOT)


def test_a_command_line_kernel_load_imports_no_yaml():
    args = ["-m", "rotorsweep.pipeline.cli", "point", "--speed", "100", "--clearance", "7.6e-6"]
    assert heavy(imported_modules(args), ("yaml.loader", "yaml.cyaml")) == []     # `yaml` itself: the failed import


@pytest.mark.parametrize("config_file", [False, True])
def test_numba_reads_its_config_file_where_there_is_one_and_yaml_still_imports(tmp_path, config_file):
    """numba_config_without_yaml leaves a working directory's .numba_config.yaml to Numba (here
    debug_cache: 1, the default 0), and yaml importable after Numba's import either way."""
    if config_file:
        (tmp_path / ".numba_config.yaml").write_text("debug_cache: 1\n")
    code = ("import sys, rotorsweep.pipeline as p; p.numba_config_without_yaml(); import numba; "
            "print(numba.config.DEBUG_CACHE, bool(sys.modules.get('yaml'))); import yaml; yaml.safe_load('a: 1')")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env(), timeout=300,
                          cwd=tmp_path, check=True)
    assert proc.stdout.split() == (["1", "True"] if config_file else ["0", "False"])


# --- the command line's process has no thread pools of its own, as a worker (issue 38) ----------

def test_the_command_line_process_sets_single_threaded_pools_before_numpy_and_keeps_the_users():
    """numpy reads OPENBLAS_NUM_THREADS when it loads: the command line's own process (small work
    runs there) must have it set by then, to what each Dask worker gets, unless the user set it."""
    code = ("import os, sys; sys.argv = ['rotorsweep', 'scenes']; from rotorsweep.pipeline import cli, cluster; "
            "assert 'numpy' not in sys.modules; cli.main(); "
            "print(','.join(os.environ[k] for k in sorted(cluster.WORKER_ENV)))")
    base = {k: v for k, v in env().items() if k not in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS",
                                                        "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    run = lambda extra: subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,  # noqa: E731
                                       env={**base, **extra}, timeout=300, cwd=ROOT, check=True).stdout
    assert run({}).splitlines()[-1] == "1,1,1,1"
    assert run({"OPENBLAS_NUM_THREADS": "2"}).splitlines()[-1] == "1,1,1,2"


# --- info and query on a continuation or backbone result import no Numba (issue 35) ---------------

@pytest.fixture(scope="module")
def backbone_result(tmp_path_factory):
    """The axial rotor's first backbone at 9 amplitudes, computed in this process (~10 s)."""
    cfg = config.parse_config(backbone_scene(modes="1", amplitude_max=4e-6, amplitude_points=9))
    return backbone.run(cfg, tmp_path_factory.mktemp("read") / "backbone.nc", workers=0, stream=None)


@pytest.mark.parametrize("kind, command", [(kind, command) for kind in ("continuation", "backbone")
                                           for command in READS[kind]])
def test_info_and_query_on_a_continuation_or_backbone_result_import_no_numba(kind, command, request):
    path = str(request.getfixturevalue(f"{kind}_result"))
    args = ["-m", "rotorsweep.pipeline.cli", command[0], path, *command[1:]]
    assert heavy(imported_modules(args), RESULT_READ) == []


def test_the_reader_names_the_torus_stability_codes_the_writer_writes():
    assert TORUS_STATUS == torus_branches.TORUS_STATUS

"""The model registry: generated dispatch, unknown ids, and a throwaway model run end to end
through point, sweep, cube, query and report without touching any file of rotorsweep."""
import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from rotorsweep.kernels import integrators as ig, models, shooting
from rotorsweep.kernels.models import generate
from tests import plugin_models

ROOT = Path(__file__).resolve().parents[1]


def test_committed_dispatch_is_generated_from_the_registry():
    """`python -m rotorsweep.kernels.models.generate` after adding a built-in model: a stale file fails here."""
    assert generate.PATH.read_text() == generate.builtin_source()


def test_unknown_id_in_a_group_is_an_error_status_not_another_model():
    """The tag's type picks the kernel group at compile time; within the group an id that is no
    model reaches no model's equations."""
    duffing = models.get("duffing")
    group = type(duffing.kernel.tag)
    unknown = duffing.kernel._replace(tag=group(99))
    assert not models.dispatch.known(group(99)) and models.dispatch.known(duffing.kernel.tag)
    opts = ig.settings()
    z, status, n_rhs, _ = ig.flow(unknown, 0.0, 1.0, np.zeros(2), np.zeros(4), False, opts, 0.0)
    assert status == ig.STATUS_UNKNOWN_MODEL and n_rhs == 0
    out = shooting.shoot(unknown, np.zeros(2), np.zeros(4), 1.0, opts, 1e-9, 5)
    assert out[2] == shooting.NOT_CONVERGED and out[3] == shooting.R_UNKNOWN_MODEL
    du = np.zeros(2)
    models.dispatch.rhs(group(99), 0.0, np.ones(2), np.zeros(4), du)
    assert np.isnan(du).all()


def test_models_are_compiled_in_their_kernel_groups():
    """Each model's tag type is its group's: the test-only validation models share one, every
    model with a scene is alone (its first result compiles no other model's equations)."""
    tags = {name: models.get(name).kernel.tag for name in models.BUILTIN_NAMES}
    groups = {}
    for n in tags:
        groups.setdefault(models.get(n).group, set()).add(n)
    assert groups["validation"] == {"linear_oscillator", "damped_mathieu", "duffing2"}
    with_scene = {tomllib.loads(p.read_text())["scene"]["model"] for p in (ROOT / "configs").glob("*.toml")}
    assert with_scene >= {"jeffcott_clearance", "duffing", "rigid_preloaded", "symmetric4", "asymmetric5"}
    assert all(groups[models.get(n).group] == {n} for n in with_scene)
    assert all(len({type(tags[n]) for n in members}) == 1 for members in groups.values())
    assert len({type(t) for t in tags.values()}) == len(groups)
    assert all(tags[n].id == models.get(n).id for n in tags)


def test_a_spec_missing_from_the_dispatch_has_no_kernel():
    from dataclasses import replace
    with pytest.raises(models.ModelError, match="'ghost' .* is not in the kernels' dispatch"):
        replace(models.get("duffing"), name="ghost").kernel


def test_registry_refuses_a_second_model_with_a_taken_name_or_id():
    jeff = models.get("jeffcott_clearance")
    with pytest.raises(models.ModelError, match="registered twice"):
        models.register(jeff)
    from dataclasses import replace
    with pytest.raises(models.ModelError, match="kernel id 0 is already used"):
        models.register(replace(jeff, name="copy"))
    with pytest.raises(models.ModelError, match="unknown model 'nope'"):
        models.get("nope")



SCENE = """
[scene]
name = "chain"
model = "chain3"

[chain]
damping = 2.0

[sweep]
frequency = {start = 1.0, stop = 10.0, step = 0.5}
stiffness = [1000.0, 2000.0]

[analysis]
attractor = true
transient_periods = 50
lyapunov_max_periods = 300

[numerics]
amplitude_limit = 1.0    # m: the default (1 mm) is a bearing's scale, the chain moves by mm
"""


def _chain_response(f, k, m=1.0, c=2.0, force=1.0):
    """Closed form: amplitude of the first and last mass, (K - w^2 M + i w C) X = F e1."""
    w = 2 * np.pi * f
    K = k * np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 1]])
    X = np.linalg.solve(K - w * w * m * np.eye(3) + 1j * w * c * np.eye(3), [force, 0, 0])
    return np.abs(X[0]), np.abs(X[2])


@pytest.fixture(scope="module")
def chain_env(tmp_path_factory):
    d = tmp_path_factory.mktemp("chain")
    return d, plugin_models.plugin_env(d, {"chain3_model": plugin_models.CHAIN}, {"chain.toml": SCENE})


def _cli(env, *args):
    return plugin_models.cli(env, *args).stdout


# slow: the plugin's dispatch is a second compilation of every kernel (about 2 minutes on 2 cores)
@pytest.mark.slow
def test_a_throwaway_model_runs_through_point_sweep_cube_query_and_report(chain_env):
    d, env = chain_env
    cube_path, report_dir = d / "chain.nc", d / "report"
    _cli(env, "run", d / "chain.toml", "-o", cube_path, "--workers", "2", "-q")
    info = _cli(env, "info", cube_path)
    assert "frequency" in info and "stiffness" in info and "chain3" in info
    table = _cli(env, "query", cube_path, "--where", "frequency=2:3", "--var", "amplitude_q1",
                 "--format", "json")
    rows = json.loads(table)
    assert {r["frequency"] for r in rows} == {2.0, 2.5, 3.0} and len(rows) == 6
    # Independent value: the linear chain's steady state. Shooting converges to newton_tol 1e-9 on
    # DOP853 at rtol 1e-10, the orbit samples resolve the peak to the sampling of 32 per period
    # (amplitude as half peak-to-peak of samples: relative error <= 1 - cos(pi / 32) = 4.8e-3).
    for r in rows:
        exact = _chain_response(r["frequency"], r["stiffness"])[0]
        assert r["amplitude_q1"] == pytest.approx(exact, rel=5e-3)
    _cli(env, "query", cube_path, "--unstable")
    _cli(env, "report", cube_path, "-o", report_dir)
    assert (report_dir / "report.html").exists()
    point = json.loads(_cli(env, "point", "--config", d / "chain.toml", "--at", "frequency=4",
                            "--at", "stiffness=1500", "--json"))
    # proportional damping: every multiplier has modulus exp(-c T / (2 m)), T = 1 / f
    mods = [np.hypot(re, im) for re, im in point["multipliers"]]
    np.testing.assert_allclose(mods, np.exp(-2.0 / (2 * 4.0)), rtol=1e-8)
    assert point["status"] == "converged" and point["stable"]


def test_python_only_modules_hold_no_compiled_code_and_no_kernel_reads_them():
    """Why they may be left out of the Numba cache's hash (rotorsweep.kernels.PYTHON_ONLY)."""
    import re
    from pathlib import Path

    import rotorsweep.kernels as rotorkernels

    root = Path(rotorkernels.__file__).parent
    kernel = set(rotorkernels.kernel_sources(root))
    python_only = [p for p in root.rglob("*.py") if p not in kernel]
    assert python_only and all("numba" not in p.read_text() for p in python_only)
    names = "|".join(re.escape(n.removesuffix(".py")) for n in rotorkernels.PYTHON_ONLY)
    for path in kernel:
        if "numba" in path.read_text():
            assert not re.search(rf"^\s*(from|import) rotorsweep.kernels(\.| import ).*\b({names})\b",
                                 path.read_text(), re.M), path


def test_warmup_compiles_what_a_point_with_attractor_then_runs(capsys):
    """`rotorsweep warmup duffing --integrator dop853` compiles Duffing's entry points for the
    types the pipeline passes: a Duffing point (dop853) with its attractor afterwards compiles
    nothing. (Only where this process has not compiled them before: the slow test below starts
    from an empty cache.)"""
    from numba.core import event

    import rotorsweep.pipeline as pipeline
    from rotorsweep.pipeline import cli, compute, scene

    assert cli.main(["warmup", "duffing", "--integrator", "dop853"]) == 0
    assert "duffing (kernel group duffing)" in capsys.readouterr().out
    cfg = pipeline.as_config(str(ROOT / "configs" / "duffing_resonance.toml"))
    data = scene.from_data({**cfg.data, "analysis": {**cfg.data["analysis"], "attractor": True}})
    compiled = event.RecordingListener()
    with event.install_listener("numba:compile", compiled):
        compute.point_detail(data, compute.point_values(cfg, {"omega": 1.0}), periods=4, steps_per_period=8)
    assert [ev.data["dispatcher"].py_func.__qualname__ for _, ev in compiled.buffer] == []


# Run in a fresh process on an empty cache: in this one, an earlier test's compilation (or a cache
# load) would hide an entry point the warm-up misses. Three kernel groups compiled cold: ~45 s.
_WARM_THEN_RUN = """
import sys
from numba.core import event
import rotorsweep.pipeline as pipeline
from rotorsweep.pipeline import backbone, compute, scene as scenes, sweep, warmup
from workflows.bench.scaling_scene import scene_config

def compiled_by(run):
    rec = event.RecordingListener()
    with event.install_listener("numba:compile", rec):
        run()
    return [ev.data["dispatcher"].py_func.__qualname__ for _, ev in rec.buffer]

def scene(data):
    warmup.compile_scene(data, lambda text: None)   # what the driver does before the workers start

fig13 = scene_config()                          # orbits only
segs = sweep.segments(fig13.scene)
scene(fig13.scene)
chunk = lambda: sweep.compute_chunk(fig13.scene, segs[:2])
print("sweep", compiled_by(chunk))
sym = pipeline.as_config(sys.argv[1])
scene(sym.scene)
print("backbone", compiled_by(lambda: backbone.backbone_line(sym.scene, backbone.plan(sym.scene).lines[0])))
duff = pipeline.as_config(sys.argv[2])
data = scenes.from_data({**duff.data, "analysis": {**duff.data["analysis"], "attractor": True}})
scene(data)
print("attractor", compiled_by(lambda: compute.point_detail(data, compute.point_values(duff, {"omega": 1.0}),
                                                            periods=4, steps_per_period=8)))
"""


@pytest.mark.slow
def test_a_scene_compiles_nothing_after_its_warmup_from_an_empty_cache(tmp_path):
    """What `compile_scene` compiles in the driver is all a worker then calls: an orbits-only
    sweep chunk (Fig. 13), a conservative model's backbone line (symmetric4) and a point with its
    attractor (Duffing) compile nothing more, starting from an empty kernel cache."""
    env = {**os.environ, "ROTORSWEEP_CACHE": str(tmp_path), "PYTHONPATH": str(ROOT)}
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("ROTORSWEEP_NUMBA_CACHE_DIR", None)
    scenes = [str(ROOT / "configs" / name) for name in ("filipkovsky2010_symmetric.toml", "duffing_resonance.toml")]
    proc = subprocess.run([sys.executable, "-c", _WARM_THEN_RUN, *scenes], capture_output=True, text=True,
                          timeout=900, cwd=ROOT, env=env)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split("\n")[:3] == ["sweep []", "backbone []", "attractor []"], proc.stdout
    assert (tmp_path / "numba").is_dir()     # the empty cache was the one used


@pytest.mark.parametrize("plugins, why", [("no_such_model_module", "ModuleNotFoundError"),
                                          ("broken_model_module", "ZeroDivisionError")])
def test_a_model_module_that_cannot_load_is_one_line_and_version_still_works(tmp_path, plugins, why):
    """A typo in $ROTORSWEEP_MODELS (or a module that fails on import) gave a traceback for every
    command, --version included."""
    env = {**plugin_models.plugin_env(tmp_path, {"broken_model_module": "1 / 0\n"}), "ROTORSWEEP_MODELS": plugins}
    version = plugin_models.cli(env, "--version")
    assert version.returncode == 0 and "rotorsweep" in version.stdout
    info = plugin_models.cli(env, "info", str(tmp_path / "x.nc"), rc=2)
    assert info.returncode == 2 and "Traceback" not in info.stderr
    [line] = info.stderr.strip().splitlines()
    assert line.startswith(f"rotorsweep info: error: $ROTORSWEEP_MODELS: model module {plugins!r}: {why}: ")


@pytest.mark.parametrize("path, edit, message", [
    ("configs/filipkovsky2016_quick.toml", "[rotor]\ndisk_position = 0.8\n",
     "rotor.disk_position: 0.8 m is beyond the shaft: the disk sits between the bearings, at most rotor.length = 0.5 m"),
    ("configs/filipkovsky2016_quick.toml", "[rotor]\nlength = 1e6\n", "rotor.length: must be > 0 and <= 10 (got 1e+06)"),
    ("configs/filipkovsky2016_quick.toml", "[bearing]\ncontact_angle = 1e-9\n",
     "bearing.contact_angle: must be >= 1 and <= 60 (got 1e-09) (contact angle [deg] imposed in the force law"),
    ("configs/filipkovsky2010_symmetric.toml", "[bearing]\ncontact_angle = 1e-9\n",
     "P0 = Z Q sin(alpha) needs unbounded ball loads"),
    ("configs/filipkovsky2010_symmetric.toml", "", "rotor.length: must be > 0 and <= 10 (got 1e+06)")])
def test_physically_impossible_geometry_is_refused_naming_the_key(path, edit, message):
    """Issue 36 item 11: the disk on the shaft, a shaft of at most 10 m (modelled rigid), an
    imposed contact angle of an angular-contact bearing (1 to 60 deg), each with its reason."""
    from rotorsweep.pipeline import config

    text = (ROOT / path).read_text()
    section = edit.split("\n")[0]
    text = text.replace(section + "\n", edit) if edit and section in text else text + "\n" + edit
    if not edit:
        text = text.replace("length = 0.5", "length = 1e6")
    with pytest.raises(config.ConfigError) as err:
        config.parse_config(text)
    assert message in str(err.value)
    assert config.parse_config(text.replace("0.8", "0.4").replace("1e6", "0.5").replace("1e-9", "15.0"))

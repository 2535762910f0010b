"""Packaging (issue 37): one import name, `rotorsweep`, over the repository's layout (pipeline/ ->
rotorsweep.pipeline, rotorkernels/ -> rotorsweep.kernels, configs/ -> rotorsweep.scenes); the
shipped scenes (`rotorsweep scenes`, `rotorsweep run NAME`, `scenes --copy`); and the wheel,
built, inspected and installed into a fresh virtual environment that runs from an empty
directory."""
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from rotorsweep.pipeline import as_config, cli, scenes
from rotorsweep.pipeline.config import ConfigError

ROOT = Path(__file__).resolve().parents[1]
MAPPING = {"rotorsweep": "rotorsweep", "rotorsweep/pipeline": "pipeline", "rotorsweep/kernels": "rotorkernels"}


# --- the shipped scenes, from this checkout ----------------------------------------------------
def test_shipped_scenes_are_the_configs():
    assert scenes.names() == sorted(p.stem for p in (ROOT / "configs").glob("*.toml"))
    assert scenes.path_of("demo.toml") == scenes.path_of("demo") == scenes.scene_dir() / "demo.toml"
    assert scenes.path_of("no_such_scene") is None


def test_description_is_the_header_comments_first_sentence():
    text = "# Filipkovsky 2016, Figs. 5-6: the motion at a point\n# of a branch. More here.\n[scene]\n# not header\n"
    assert scenes.description(text) == "Filipkovsky 2016, Figs. 5-6: the motion at a point of a branch."
    assert scenes.description("[scene]\n") == ""
    long = scenes.description("# " + "word " * 40)
    assert len(long) == scenes.DESCRIPTION_CHARS and long.endswith("...")
    assert all(text for _, text in scenes.listing())           # every shipped scene has a header


def test_a_name_resolves_to_the_shipped_scene_from_any_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert as_config("duffing_resonance").path == str(scenes.path_of("duffing_resonance"))
    # a file of that name wins over the shipped scene
    (tmp_path / "duffing_resonance.toml").write_text(
        scenes.path_of("duffing_resonance").read_text().replace('name = "duffing_resonance"', 'name = "mine"'))
    assert as_config("duffing_resonance.toml").data["scene"]["name"] == "mine"
    with pytest.raises(ConfigError, match=r"no_such: no such config file, nor a shipped scene .*: atlas4d, "):
        as_config("no_such")
    with pytest.raises(ConfigError, match="no such config file"):
        as_config("sub/demo.toml")                               # a path is never a scene name


def test_scenes_command_lists_and_copies(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["scenes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == scenes.names()
    assert any(line.startswith("demo ") and "Demo scene" in line for line in lines)

    assert cli.main(["scenes", "--copy", "demo"]) == 0
    assert (tmp_path / "demo.toml").read_text() == scenes.path_of("demo").read_text()
    (tmp_path / "sub").mkdir()
    assert cli.main(["scenes", "--copy", "bai2006_fold.toml", "sub"]) == 0
    assert (tmp_path / "sub" / "bai2006_fold.toml").exists()
    capsys.readouterr()
    assert cli.main(["scenes", "--copy", "demo"]) == 2              # kept: no --overwrite
    assert "demo.toml: exists; pass --overwrite" in capsys.readouterr().err
    assert cli.main(["scenes", "--copy", "demo", "mine.toml", "--overwrite"]) == 0
    assert cli.main(["scenes", "--copy", "nope"]) == 2
    assert "nope: no shipped scene of that name" in capsys.readouterr().err


def test_every_package_of_the_checkout_is_listed_in_pyproject():
    """pyproject lists the packages (find cannot rename them): a new subpackage must be added."""
    import tomllib
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {"rotorsweep.scenes"}
    for package, folder in MAPPING.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            found.add(".".join((package, *init.parent.relative_to(ROOT / folder).parts)).replace("/", "."))
    assert listed == found


# --- the wheel -----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """The wheel `pip wheel` builds from a copy of this checkout (setuptools builds in the source
    tree, whose build/ would keep modules deleted since; its own build environment)."""
    out, source = tmp_path_factory.mktemp("wheel"), tmp_path_factory.mktemp("source") / "rotorsweep"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(".git", ".venv*", "build", "out", "docs", "__pycache__",
                                                                "*.egg-info", ".pytest_cache"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w", str(out), str(source)],
                   check=True, capture_output=True, text=True)
    return next(out.glob("rotorsweep-*.whl"))


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory):
    """A fresh venv with the wheel installed; the dependencies are this environment's (a .pth
    file: no download). Returns its bin directory."""
    venv = tmp_path_factory.mktemp("venv")
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    purelib = Path(subprocess.run([venv / "bin" / "python", "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                                  check=True, capture_output=True, text=True).stdout.strip())
    # a .pth line only adds a directory: this environment's own .pth files (an editable
    # install of the checkout) are not run there
    deps = {p for p in sys.path if Path(p).name in ("site-packages", "dist-packages")}
    (purelib / "zz_dependencies.pth").write_text("\n".join(sorted(deps)) + "\n")
    subprocess.run([sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python"), "install", "--no-deps",
                    "--no-index", "--quiet", str(wheel)], check=True, capture_output=True, text=True)
    return venv / "bin"


def test_wheel_installs_only_the_rotorsweep_name(wheel):
    files = zipfile.ZipFile(wheel).namelist()
    assert {f.split("/")[0] for f in files} == {"rotorsweep", wheel.name.split("-py")[0] + ".dist-info"}
    top_level = {f.split("/")[0] for f in files if f.endswith(".py") or f.endswith(".so")}
    assert top_level == {"rotorsweep"}
    for package, folder in MAPPING.items():                    # every module of the mapped folders
        sources = {p.relative_to(ROOT / folder) for p in (ROOT / folder).rglob("*.py")}
        if folder == "rotorsweep":
            sources = {p for p in sources if p.parts[0] not in ("pipeline", "kernels", "scenes")}
        assert {f"{package}/{p.as_posix()}" for p in sources} <= set(files), folder
    assert {f"rotorsweep/scenes/{p.name}" for p in (ROOT / "configs").glob("*.toml")} <= set(files)
    assert not [f for f in files if "workflows" in f or "tests/" in f or f.startswith("configs/")]


def _in_empty_dir(tmp_path, *cmd, env=None):
    cwd = tmp_path / "empty"
    cwd.mkdir(exist_ok=True)
    env = {k: v for k, v in {**os.environ, **(env or {})}.items() if k != "PYTHONPATH"}
    return subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, capture_output=True, text=True, timeout=900)


def test_installed_wheel_lists_its_scenes_from_an_empty_directory(installed, tmp_path):
    where = _in_empty_dir(tmp_path, installed / "python", "-c",
                          "import rotorsweep.pipeline as p, rotorsweep.kernels as k; print(p.__file__, k.__file__)")
    assert where.returncode == 0, where.stderr
    assert all(Path(f).is_relative_to(installed.parent) for f in where.stdout.split())
    for other in ("pipeline", "rotorkernels", "workflows"):
        assert _in_empty_dir(tmp_path, installed / "python", "-c", f"import {other}").returncode == 1, other
    listed = _in_empty_dir(tmp_path, installed / "rotorsweep", "scenes")
    assert listed.returncode == 0, listed.stderr
    assert [line.split()[0] for line in listed.stdout.splitlines()] == scenes.names()


@pytest.mark.slow      # the kernels compile cold in the new environment: ~1 min on 2 loaded cores
def test_installed_wheel_runs_a_shipped_scene_from_an_empty_directory(installed, tmp_path):
    env = {"ROTORSWEEP_CACHE": str(tmp_path / "cache")}        # not the user's cache
    done = _in_empty_dir(tmp_path, installed / "rotorsweep", "run", "duffing_resonance", "-o", "out.nc", "-q",
                         env=env)
    assert done.returncode == 0, done.stderr
    info = _in_empty_dir(tmp_path, installed / "rotorsweep", "info", "out.nc", env=env)
    assert info.returncode == 0 and "duffing_resonance" in info.stdout, info.stdout + info.stderr
    copied = _in_empty_dir(tmp_path, installed / "rotorsweep", "scenes", "--copy", "duffing_resonance", env=env)
    assert copied.returncode == 0 and (tmp_path / "empty" / "duffing_resonance.toml").exists(), copied.stderr


# --- the revision benchmarks run other trees' code ------------------------------------------------
def test_bench_runs_a_trees_own_code_under_its_names(tmp_path):
    """workflows/bench/trees.py: a tree of the package-dir layout runs its own folders (not this
    checkout's install) under rotorsweep.*; an older tree keeps its folder names as import names."""
    from workflows.bench import trees
    new, old = tmp_path / "new", tmp_path / "old"
    for name in ("rotorsweep", "pipeline", "rotorkernels", "configs"):
        shutil.copytree(ROOT / name, new / name, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", new)
    (old / "pipeline").mkdir(parents=True)
    (old / "pyproject.toml").write_text('[project]\nname = "rotorsweep"\n')
    assert (trees.pipeline_module(old), trees.env(old)["PYTHONPATH"]) == ("pipeline", str(old))
    assert trees.cli_module(new) == "rotorsweep.pipeline.cli"
    code = "import rotorsweep.pipeline.cli as c, rotorsweep.kernels.models as m; print(c.__file__, m.__file__)"
    done = subprocess.run([sys.executable, "-c", code], cwd=new, env=trees.env(new), capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert [Path(f) for f in done.stdout.split()] == [new / "pipeline" / "cli.py",
                                                      new / "rotorkernels" / "models" / "__init__.py"]

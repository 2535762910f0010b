"""Running the code of another revision's tree (the revision benchmarks: latency, revisions,
compile), in a process of its own with the tree as working directory.

Up to the packaging change of issue 37 a tree's code was importable under its folder names
(pipeline/, rotorkernels/) with the tree on PYTHONPATH. Since then it installs as `rotorsweep.pipeline` and
`rotorsweep.kernels` (pyproject's package-dir), names that PYTHONPATH alone does not map (and an
editable install of this checkout would map them to this checkout's folders instead). For such a
tree, env() also puts treesite/ on PYTHONPATH, whose sitecustomize maps the package-dir names to
the tree's folders in every process started with that environment, Dask workers included.
"""
import json
import os
import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

SITE = Path(__file__).with_name("treesite")
DIRS_VARIABLE = "ROTORSWEEP_TREE_PACKAGE_DIRS"      # read by treesite/sitecustomize.py


def package_dirs(tree):
    """{import name: folder} of a tree installing under other names than its folders' ({} when
    its packages are its folders)."""
    pyproject = Path(tree) / "pyproject.toml"
    if not pyproject.exists():
        return {}
    mapping = tomllib.loads(pyproject.read_text()).get("tool", {}).get("setuptools", {}).get("package-dir", {})
    return {name: str(Path(tree).resolve() / folder) for name, folder in mapping.items() if name}


def pipeline_module(tree):
    """The import name of the tree's pipeline package."""
    return "rotorsweep.pipeline" if "rotorsweep.pipeline" in package_dirs(tree) else "pipeline"


def cli_module(tree):
    return f"{pipeline_module(tree)}.cli"


def env(tree, base=None):
    """The environment of a process running the tree's code: the tree first on PYTHONPATH, and
    its package-dir names mapped to its folders."""
    env = dict(os.environ if base is None else base)
    dirs = package_dirs(tree)
    env["PYTHONPATH"] = os.pathsep.join([str(tree), str(SITE)] if dirs else [str(tree)])
    env.pop(DIRS_VARIABLE, None)
    if dirs:
        env[DIRS_VARIABLE] = json.dumps(dirs)
    return env

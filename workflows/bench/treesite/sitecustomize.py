"""Maps the package-dir import names of a tree (workflows/bench/trees.py) to its folders, ahead of
any installed copy: imported at the start of every Python process whose PYTHONPATH holds this
directory, Dask workers included."""
import importlib.util
import json
import os
import sys
from pathlib import Path


class TreeFinder:
    """A meta path finder for the names in $ROTORSWEEP_TREE_PACKAGE_DIRS ({name: folder});
    subpackages are then found in their parent's folder as usual."""

    def __init__(self, dirs):
        self.dirs = dirs

    def find_spec(self, fullname, path=None, target=None):
        folder = self.dirs.get(fullname)
        if folder is None or not (Path(folder) / "__init__.py").exists():
            return None
        return importlib.util.spec_from_file_location(fullname, Path(folder) / "__init__.py",
                                                      submodule_search_locations=[folder])


if os.environ.get("ROTORSWEEP_TREE_PACKAGE_DIRS"):
    sys.meta_path.insert(0, TreeFinder(json.loads(os.environ["ROTORSWEEP_TREE_PACKAGE_DIRS"])))

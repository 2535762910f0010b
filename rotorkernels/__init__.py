"""Numba kernels of rotorsweep: models, integrators, shooting, Floquet, Lyapunov.

Numba's on-disk cache checks only the source file of the function it caches, yet a cached
function holds the machine code of every kernel it calls (shooting holds the integrator, the
integrator holds the models), so editing one module would leave stale code in the others' caches.
The cache therefore lives in a directory named after a hash of all kernel sources, those of the
user's models in $ROTORSWEEP_MODELS included:
$ROTORSWEEP_CACHE (default ~/.cache/rotorsweep)/numba/<hash>. NUMBA_CACHE_DIR, if the user sets it, wins.
The pure-Python orchestration (PYTHON_ONLY: no compiled function is defined there or reads
anything from there, which a test checks) is left out of the hash, so editing it does not
recompile the kernels.
"""
import hashlib
import importlib.util
import os
import sys
from pathlib import Path


PLUGINS_VARIABLE = "ROTORSWEEP_MODELS"


def plugin_modules():
    """Module names of the user's models, from $ROTORSWEEP_MODELS (comma-separated)."""
    return [m.strip() for m in os.environ.get(PLUGINS_VARIABLE, "").split(",") if m.strip()]


def _plugin_sources():
    found = [importlib.util.find_spec(name) for name in plugin_modules()]
    return [Path(spec.origin) for spec in found if spec is not None and spec.origin]


PYTHON_ONLY = ("continuation", "nnm", "orbits.py", "floquet.py")


def kernel_sources(src=Path(__file__).parent):
    """The sources compiled code may depend on: everything but PYTHON_ONLY."""
    return [p for p in sorted(Path(src).rglob("*.py")) if p.relative_to(src).parts[0] not in PYTHON_ONLY]


def _cache_dir(src=Path(__file__).parent):
    sources = kernel_sources(src) + _plugin_sources()
    digest = hashlib.sha256(b"".join(p.name.encode() + p.read_bytes() for p in sources)).hexdigest()
    base = os.environ.get("ROTORSWEEP_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "rotorsweep")
    return os.path.join(base, "numba", digest[:16])


# Set through the environment, not only numba.config: Numba re-reads its whole configuration from
# os.environ whenever the environment changes (a LocalCluster setting NUMBA_NUM_THREADS does), which
# would silently reset a CACHE_DIR set in numba.config alone. The marker tells our own setting,
# inherited by a child process that may have other models, from a user's NUMBA_CACHE_DIR.
# Numba itself is not imported here: reading a result file (the model registry) needs none, and
# Numba, once a kernel module imports it, reads the directory from the environment.
_OWN = "ROTORSWEEP_NUMBA_CACHE_DIR"
if os.environ.get("NUMBA_CACHE_DIR", "") in ("", os.environ.get(_OWN)):
    os.environ["NUMBA_CACHE_DIR"] = os.environ[_OWN] = _cache_dir()
    if "numba" in sys.modules:
        sys.modules["numba"].config.CACHE_DIR = os.environ[_OWN]


# Compile options of a body that an `overload` picks at typing time (a group's model equations
# for a kernel tag, an integrator for a settings class). To type the call Numba compiles the
# picked body in full, even for an overload inlined at its IR (inline="always"), whose inlined
# copy every caller then compiles again: Jeffcott's step loop took ~5 s that way. A body that
# is called instead is compiled once, cached on disk like the kernels, and inlined by LLVM
# (forceinline), with the same machine speed.
PICKED_BODY = {"forceinline": True, "cache": True}

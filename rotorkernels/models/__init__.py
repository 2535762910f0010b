"""The model registry: one module per model defining its `SPEC`, one line each in BUILTIN below.
A built-in model's njit `rhs`, `jac`, `rhs_jac` live in its kernel module (`ModelSpec.module`,
`models.duffing` -> `models.duffing_kernels`), which only the kernels' dispatch imports: the
registry and the specs import no Numba, so reading a result does not either (issue 35). The
dispatch (`models.dispatch`) is loaded on first use, when something integrates.

Further models come from modules named in $ROTORSWEEP_MODELS (comma-separated, importable, each
defining `SPEC`): a user's own model needs no edit of rotorsweep. Dask workers inherit the
variable from a local cluster; set it on remote workers too. With such models the kernels' dispatch
is generated for the extended registry into the Numba cache directory instead of using the
committed `dispatch.py`.

Kernels are compiled per kernel group (`ModelSpec.group`: the model alone unless it names one;
the two test-only validation models share one), so a scene compiles only its own model's group and adding a
model does not slow the first result of another (see `models.generate`).
"""
import importlib
import importlib.util
import os
import sys

from rotorsweep.kernels import PLUGINS_VARIABLE, plugin_modules
from rotorsweep.kernels.models import (asymmetric5, damped_mathieu, duffing, duffing2, jeffcott_clearance,
                                 linear_oscillator, rigid_preloaded, symmetric4)
from rotorsweep.kernels.models.spec import Built, KernelId, ModelSpec, Observable, Parameter  # noqa: F401 (API)

BUILTIN = (jeffcott_clearance, linear_oscillator, damped_mathieu, duffing, rigid_preloaded, symmetric4, asymmetric5,
           duffing2)
BUILTIN_NAMES = tuple(m.SPEC.name for m in BUILTIN)

REGISTRY = {}


class ModelError(ValueError):
    """A model that cannot be registered or found."""


def register(spec):
    """Add a ModelSpec; names and kernel ids are unique."""
    if spec.name in REGISTRY:
        raise ModelError(f"model {spec.name!r} is registered twice")
    clash = [s.name for s in REGISTRY.values() if s.id == spec.id]
    if clash:
        raise ModelError(f"model {spec.name!r}: kernel id {spec.id} is already used by {clash[0]!r}")
    for par in spec.parameters:
        # a default would count as "given" and clash with sweeping the axis: `unset` is its value
        if par.axis and par.section is not None and par.default is not None:
            raise ModelError(f"model {spec.name!r}: axis parameter {par.name!r} has a default; "
                             "give it as `unset` (the value when neither given nor swept)")
    REGISTRY[spec.name] = spec


def get(name):
    try:
        return REGISTRY[name]
    except KeyError:
        left_out = "".join(f" ({e})" for e in PLUGIN_ERRORS)
        raise ModelError(f"unknown model {name!r}; registered: {', '.join(REGISTRY)}{left_out}") from None


def kernel_tag(spec):
    """The tag of `spec` in the kernels' dispatch (`ModelSpec.kernel.tag`): its type names the
    model's kernel group, its id the model within the group."""
    tags = _dispatch().TAGS
    tag = tags.get(spec.name)
    if tag is None or tag.id != spec.id:
        raise ModelError(f"model {spec.name!r} (id {spec.id}) is not in the kernels' dispatch; "
                         f"it has: {', '.join(tags)}")
    return tag


def __getattr__(name):
    """`models.dispatch`, loaded (with Numba and every model's kernels) on first use."""
    if name != "dispatch":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return _dispatch()


def _dispatch():
    if "dispatch" not in globals():
        globals()["dispatch"] = _load_dispatch()      # once loaded, a plain module attribute
    return globals()["dispatch"]


def _load_dispatch():
    """The committed dispatch for the built-in models, else one generated for the registry."""
    if set(REGISTRY) == set(BUILTIN_NAMES):
        return importlib.import_module(f"{__name__}.dispatch")
    import numba

    from rotorsweep.kernels.models.generate import dispatch_source

    source = dispatch_source(REGISTRY.values())
    os.makedirs(numba.config.CACHE_DIR, exist_ok=True)
    path = os.path.join(numba.config.CACHE_DIR, "dispatch_plugins.py")
    if not os.path.exists(path) or open(path).read() != source:
        tmp = f"{path}.{os.getpid()}"
        with open(tmp, "w") as fh:
            fh.write(source)
        os.replace(tmp, path)
    spec = importlib.util.spec_from_file_location(f"{__name__}.dispatch", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def _register_plugins():
    """Register the models of $ROTORSWEEP_MODELS; one that cannot be imported or registered is
    left out and its one-line reason kept in PLUGIN_ERRORS (the command line refuses to run with
    it, but `--version` and `--help` still work and nothing prints a traceback)."""
    errors = []
    for name in plugin_modules():
        try:
            register(importlib.import_module(name).SPEC)
        except Exception as exc:      # a typo, a broken module, a clash: the user's to fix
            errors.append(f"${PLUGINS_VARIABLE}: model module {name!r}: {type(exc).__name__}: {exc}")
    return tuple(errors)


for _module in BUILTIN:
    register(_module.SPEC)
PLUGIN_ERRORS = _register_plugins()
if set(REGISTRY) != set(BUILTIN_NAMES):
    # the generated dispatch takes the committed one's module name: it must be there before a
    # pickled kernel tag (a Dask task's) imports that name; a plugin's kernels import Numba anyway
    _dispatch()

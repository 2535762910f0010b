"""xarray without importing Dask where no Dask object can exist: xarray asks, for each Variable
it builds, whether the data is a Dask array (importing dask.array: 0.5-0.9 s of `rotorsweep
info`, `query` or `continue`, which never hold one), and writing a netCDF file asks which Dask
scheduler is active (importing dask and distributed: ~0.2 s of CPU, 0.6 s wall on a loaded
machine). No object is an array of a module not imported yet and no Dask scheduler is active
before Dask is imported, so until then the answers "no such type", "not a Dask collection" and
"no scheduler" are exact; once it is imported, xarray answers as before. Importing this module
installs that by wrapping those lookups of xarray (where this version of xarray has them; others
are left as they are)."""
import importlib
import sys

import xarray  # noqa: F401  (the package whose lookups are wrapped below)

# the duck-array module xarray names -> the module that must be imported before one of its arrays exists
DEFINING_MODULE = {"dask": "dask.array", "pint": "pint", "cupy": "cupy", "sparse": "sparse", "cubed": "cubed"}


class NotImported:
    """What xarray learns of a duck-array module not imported yet: no array type."""
    module = None
    type = ()
    available = False


def _duck_module_if_imported(lookup):
    def duck_module(mod):
        defining = DEFINING_MODULE.get(mod)
        return NotImported if defining is not None and defining not in sys.modules else lookup(mod)
    return duck_module


def _if_dask(otherwise):
    """lookup(...) once dask is imported, else `otherwise`."""
    def wrap(lookup):
        def if_dask(*args, **kwargs):
            return lookup(*args, **kwargs) if "dask" in sys.modules else otherwise
        return if_dask
    return wrap


# (xarray module, function, wrapper): a function imported by name into another module is wrapped there too
WRAPPED = (("xarray.namedarray.pycompat", "_get_cached_duck_array_module", _duck_module_if_imported),
           ("xarray.namedarray.utils", "is_dask_collection", _if_dask(False)),
           ("xarray.backends.locks", "get_dask_scheduler", _if_dask(None)),
           ("xarray.backends.writers", "get_dask_scheduler", _if_dask(None)),
           ("xarray.backends.locks", "_get_scheduler", _if_dask(None)))


def install():
    """Wrap the lookups of WRAPPED that this xarray has (once)."""
    for module_name, name, wrapper in WRAPPED:
        try:
            module = importlib.import_module(module_name)
        except ImportError:
            continue
        original = getattr(module, name, None)
        if original is not None and not getattr(original, "rotorsweep_wrapped", False):
            wrapped = wrapper(original)
            wrapped.rotorsweep_wrapped = True
            setattr(module, name, wrapped)


install()

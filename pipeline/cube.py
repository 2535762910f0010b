"""Result cubes: build, write (atomically), open and describe the netCDF files of rotorsweep.pipeline.schema,
plus the part files a sweep writes per finished chunk and assembles at the end.

The schema (axes, variables, dtypes, attrs, flags) lives in rotorsweep.pipeline.schema; this module only
applies it.
"""
import contextlib
import errno
import json
import sys
import zipfile
import zlib
from pathlib import Path

import numpy as np

from rotorsweep.pipeline import fileio, schema

CONVENTIONS = "CF-1.10"
# zlib level 1 after the byte shuffle: on an atlas cube as small as level 4 without shuffle (the
# float mantissas do not compress either way) at a seventh of the write time (docs/benchmarks/atlas.md).
COMPRESSION = {"zlib": True, "complevel": 1, "shuffle": True}
# A cube of less data than this is written without filters: compression saved 30 % of Fig. 13's
# orbits-only cube (2.2 -> 1.5 MB) but took half of its write time (45 of 85 ms, serial after the
# sweep: ~1 % of a 2-worker run). Attractor cubes (Poincare samples) and atlases are compressed.
COMPRESS_FROM_BYTES = 8 << 20
# A netCDF chunk of a per-point variable is one line along the continued axis (all of its extra
# dims), at most CHUNK_BYTES: reading a line, or a slice across the other axes, then decompresses
# only the lines it needs (an atlas slice over contact angle x preload reads 64 line chunks).
CHUNK_BYTES = 4 << 20
# An axis parameter that is neither swept nor fixed (given as NaN) is derived per point: it gets no
# coordinate (CF: no NaN coordinates) but a line in the global attribute DERIVED_ATTR saying where
# its per-point value comes from.
# The text, the model's (ModelSpec.derived_axes), says what the value is derived from ("derived
# from X ..."; plan.fmt shows "from X").
DERIVED_ATTR = "derived_parameters"
_NETCDF_MAGIC = (b"CDF\x01", b"CDF\x02", b"CDF\x05", b"\x89HDF\r\n\x1a\n")


def _xarray():
    """xarray, imported on first use (`continue` and `backbone` use this module's part files without
    it, issue 35), after rotorsweep.pipeline.duckarrays (xarray without importing Dask for every array)."""
    from rotorsweep.pipeline import duckarrays  # noqa: F401
    import xarray
    return xarray


class CubeError(Exception):
    """A cube that cannot be built, written or read (message for the user)."""


# --- building -------------------------------------------------------------------------------

def build_dataset(axes, fixed, results, attrs, extra_attrs=None):
    """A schema-conforming Dataset. axes: swept axis -> 1-D values (the axes of the model named
    by attrs["model"], default jeffcott_clearance, in the model's order); fixed: other axis
    parameters -> value (NaN: not fixed); results: variable -> array of shape point dims + extra
    dims; extra_attrs: attrs of variables not in the schema (point dims only)."""
    spec = schema.model_of(attrs)
    axis_table = schema.axes_of(spec)
    _check_axes(axes, fixed, axis_table)
    variables = schema.variables_of(spec)
    dims = tuple(axes)
    shape = tuple(len(v) for v in axes.values())
    coords = {name: (name, np.asarray(values, float), _axis_attrs(axis_table[name])) for name, values in axes.items()}
    derived = [name for name, value in fixed.items() if np.isnan(value)]
    coords.update({name: ((), float(value), _axis_attrs(axis_table[name]))
                   for name, value in fixed.items() if name not in derived})
    data_vars = {}
    for name, data in results.items():
        data = np.asarray(data)
        extra, dtype, var_attrs = _variable_spec(name, data, variables, extra_attrs or {})
        _check_shape(name, data, shape, extra)
        data_vars[name] = (dims + extra, data.astype(dtype, copy=False), var_attrs)
        for dim, n in zip(extra, data.shape[len(dims):]):
            coords.setdefault(dim, (dim, np.arange(n), {"long_name": f"{dim} index", "units": "1"}))
    # one Dataset of all variables: assigning them one by one aligns and merges the whole
    # dataset each time (Fig. 13's 17 variables: 14 ms instead of 2, serial after the sweep)
    ds = _xarray().Dataset(data_vars, coords)
    ds.attrs = {"Conventions": CONVENTIONS, "title": "rotorsweep result cube", **attrs,
                "rotorsweep_schema_version": schema.SCHEMA_VERSION}
    if derived:
        notes = spec.derived_axes
        ds.attrs[DERIVED_ATTR] = "; ".join(f"{name}: {notes.get(name, 'not fixed')}" for name in derived)
    return ds


def derived_parameters(ds):
    """{axis parameter: where its value comes from} for those the cube derives per point."""
    items = (item.partition(":") for item in ds.attrs.get(DERIVED_ATTR, "").split(";"))
    return {name.strip(): how.strip() for name, _, how in items if name.strip()}


def _check_axes(axes, fixed, axis_table):
    unknown = [a for a in list(axes) + list(fixed) if a not in axis_table]
    if unknown:
        raise CubeError(f"unknown axis {unknown[0]!r}; cube axes are {', '.join(axis_table)}")
    order = [a for a in axis_table if a in axes]
    if list(axes) != order:
        raise CubeError(f"swept axes must come in schema order ({', '.join(order)}), got {', '.join(axes)}")
    both = set(axes) & set(fixed)
    if both:
        raise CubeError(f"{sorted(both)[0]} is both swept and fixed")
    for name, values in axes.items():
        if np.ndim(values) != 1 or len(values) == 0:
            raise CubeError(f"axis {name} must be a non-empty 1-D array")


def _axis_attrs(entry):
    units, long_name = entry
    return {"units": units, "long_name": long_name}


def _variable_spec(name, data, variables, extra_attrs):
    """(extra dims, dtype, attrs) of a variable: from the schema, else from extra_attrs."""
    if name in variables:
        extra, dtype, attrs = variables[name]
        return tuple(extra), np.dtype(dtype), dict(attrs)
    if name in extra_attrs:
        return (), data.dtype, dict(extra_attrs[name])
    raise CubeError(f"variable {name!r} is not in the cube schema; pass its attrs in extra_attrs")


def _check_shape(name, data, shape, extra):
    if data.shape[:len(shape)] != shape or data.ndim != len(shape) + len(extra):
        dims = " x ".join(map(str, shape)) + "".join(f" x n_{d}" for d in extra)
        raise CubeError(f"variable {name}: shape {data.shape} does not fit the grid ({dims})")


# --- writing and opening --------------------------------------------------------------------

def write_cube(ds, path, overwrite=False):
    """Write a cube atomically: a temp file in the same directory, fsync, then os.replace, so
    `path` holds either the previous file or the complete new one."""
    path = Path(path).absolute()
    if path.exists() and not overwrite:
        raise CubeError(f"{path} exists; pass --overwrite (overwrite=True from Python) to replace it")
    path.parent.mkdir(parents=True, exist_ok=True)
    with fileio.atomic_path(path) as tmp, _local_write_lock():
        try:
            ds.drop_encoding().to_netcdf(tmp, engine="netcdf4", encoding=_encoding(ds))
        except RuntimeError as exc:   # netCDF-C reports a full disk as "NetCDF: HDF error"
            raise OSError(errno.EIO, f"netCDF write failed ({exc}; is the disk full?)", str(path)) from None
    return path


def _local_write_lock():
    """xarray guards each netCDF write with a lock of the active Dask scheduler; with a distributed
    Client alive in the process (a notebook's, a benchmark's) that is a lock held by the scheduler,
    a round trip per call (Fig. 13's cube: 0.22 s instead of 0.06 s). A cube is in memory: a
    process-local lock does. Without Dask imported no scheduler is active (rotorsweep.pipeline.duckarrays)."""
    if "dask" not in sys.modules:
        return contextlib.nullcontext()
    import dask

    return dask.config.set(scheduler="synchronous")


def _encoding(ds):
    """Data variables chunked by line (_chunks), compressed from COMPRESS_FROM_BYTES on; no fill
    value on coordinates and integers (schema.INT_FILL_COMMENT), NaN on floats."""
    enc = {name: {"_FillValue": None} for name in ds.coords}
    points = schema.point_axes(ds) if "orbit_status" in ds else []
    along = ds.attrs.get("continued_axis") or (points[0] if points else None)
    filters = COMPRESSION if ds.nbytes >= COMPRESS_FROM_BYTES else {}
    for name, var in ds.data_vars.items():
        enc[name] = {**filters, **({"_FillValue": None} if var.dtype.kind in "iu" else {})}
        if along in var.dims and set(points) <= set(var.dims):
            enc[name]["chunksizes"] = _chunks(var, points, along)
    return enc


def _chunks(var, points, along):
    """One line along `along` (capped at CHUNK_BYTES) x 1 on the other point axes x whole extra dims."""
    extra = int(np.prod([n for d, n in var.sizes.items() if d not in points]))
    cap = max(1, CHUNK_BYTES // (var.dtype.itemsize * extra))
    return tuple(min(n, cap) if d == along else 1 if d in points else n for d, n in var.sizes.items())


def open_cube(path):
    """Open a sweep cube into memory (the file is closed on return); integers stay integers.
    A continuation or backbone result is refused with its kind named (rotorsweep.pipeline.result_kinds
    opens every kind)."""
    ds = read_netcdf(path)
    kind = ds.attrs.get("result_kind")
    if kind is not None:
        raise CubeError(f"{path} is a {kind} result, not a sweep cube; rotorsweep.open_result opens it "
                        "(and rotorsweep info / query / report read it)")
    check_cube(path, ds)
    return ds


def read_netcdf(path):
    """A rotorsweep result file of any kind, read into memory once (the file is closed on
    return): netCDF checked first, integers kept integer (no mask and scale)."""
    path = Path(path)
    _check_is_netcdf(path)
    try:
        with _xarray().open_dataset(path, engine="netcdf4", mask_and_scale=False) as ds:
            return ds.load()
    except (OSError, ValueError) as exc:
        raise CubeError(f"{path}: cannot be read as netCDF ({exc})") from None


def check_cube(path, ds):
    """CubeError unless ds (read by read_netcdf) is a cube of this schema version with every
    required variable; the fill values stay where the writer put them (in the encoding)."""
    _check_version(path, ds)
    _check_variables(path, ds)
    for var in ds.variables.values():
        if "_FillValue" in var.attrs:
            var.encoding["_FillValue"] = var.attrs.pop("_FillValue")


def _check_is_netcdf(path):
    if not path.exists():
        raise CubeError(f"{path}: no such file (expected a rotorsweep result cube, .nc)")
    if not path.is_file():
        raise CubeError(f"{path} is not a file (expected a rotorsweep result cube, .nc)")
    with open(path, "rb") as f:
        head = f.read(8)
    if not any(head.startswith(m) for m in _NETCDF_MAGIC):
        raise CubeError(f"{path} is not a netCDF file (expected a rotorsweep result cube, netCDF4)")


def _check_version(path, ds):
    version = ds.attrs.get("rotorsweep_schema_version")
    if version is None:
        raise CubeError(f"{path} is a netCDF file but not a rotorsweep result cube "
                        "(no rotorsweep_schema_version attribute)")
    if int(version) != schema.SCHEMA_VERSION:
        raise CubeError(f"{path} is a rotorsweep cube of schema version {int(version)}; this rotorsweep "
                        f"reads version {schema.SCHEMA_VERSION} (re-run the sweep with this version)")


def required_variables():
    """What every cube holds: the periodic-orbit variables (present, as not_applicable, even
    when only attractors were asked for); the attractor variables are optional."""
    return [name for name in schema.VARIABLES if name not in schema.ATTRACTOR_VARIABLES]


def _check_variables(path, ds):
    missing = [name for name in required_variables() if name not in ds.data_vars]
    along = ds.attrs.get("continued_axis", "speed")
    if along not in ds.dims:
        missing.insert(0, f"{along} (axis)")
    if missing:
        raise CubeError(f"{path} is an incomplete rotorsweep cube: missing {', '.join(missing)} "
                        f"(every cube has {', '.join(required_variables())}); re-run the sweep")


# --- describing -----------------------------------------------------------------------------

def describe(ds):
    """What a cube holds, as text for `rotorsweep info`."""
    lines = [f"{ds.attrs.get('title', 'rotorsweep result cube')} "
             f"(schema version {ds.attrs.get('rotorsweep_schema_version', '?')})", "", "axes:"]
    for name in schema.point_axes(ds):
        v = ds[name]
        lines.append(f"  {name:<14} {v.size:>5} values  {v.values.min():g} .. {v.values.max():g} "
                     f"{v.attrs.get('units', '')}  ({v.attrs.get('long_name', '')})")
    fixed = [name for name in schema.axes_of(schema.model_of(ds)) if name in ds.coords and ds[name].ndim == 0]
    derived = derived_parameters(ds)
    if fixed or derived:
        lines += ["", "fixed parameters:"]
        lines += [_describe_fixed(name, ds[name]) for name in fixed]
        lines += [f"  {name:<14} {'-':<12} {how}" for name, how in derived.items()]
    axes = schema.point_axes(ds)
    lines += ["", "variables:"] + [_describe_variable(name, var, axes) for name, var in ds.data_vars.items()]
    if "orbit_status" in ds:
        lines += ["", "points per orbit_status:"] + _flag_counts(ds["orbit_status"])
        lines += _describe_classes(ds)
    if "torus_status" in ds:
        lines += ["", "points per torus_status:"] + _flag_counts(ds["torus_status"])
    lines += ["", "provenance:"]
    lines += [f"  {k}: {v}" for k, v in ds.attrs.items() if k not in ("title", "config_toml")]
    if "config_toml" in ds.attrs:
        lines += ["", "config:"] + ["  " + line for line in ds.attrs["config_toml"].rstrip().splitlines()]
    return "\n".join(lines)


def _describe_classes(ds):
    """The stability classes of the grid points and their intervals, in the one vocabulary of the
    map, the report and `query` (query.point_classes)."""
    from rotorsweep.pipeline import query

    if "stable" not in ds or "bifurcation" not in ds:
        return []
    runs = query.class_runs(ds)
    along = schema.continued_axis(ds)
    totals = {}
    for run in runs:
        totals[run["class"]] = totals.get(run["class"], 0) + run["n_points"]
    lines = ["", "points per stability class (stable, bistable, no_orbit, not_applicable: what the grid "
             "point is; fold, period_doubling, neimark_sacker, none: how stability was lost before its "
             "unstable interval, as `query --unstable` says"
             + (f"; {query.TORUS_CLASS_LEGEND}" if "torus_status" in ds else "") + "):"]
    lines += [f"  {name:<16} {n:>8}" for name, n in totals.items()]
    lines += ["", f"stability intervals along {along}:"]
    for run in runs:
        where = "".join(f"{a}={run[a]:g} " for a in run if a not in ("start", "end", "n_points", "class"))
        lines.append(f"  {where}{run['start']:g} .. {run['end']:g}  {run['class']} ({run['n_points']} points)")
    return lines


def _describe_fixed(name, coord):
    value = float(coord)
    shown = "-" if np.isnan(value) else f"{value:g} {coord.attrs.get('units', '')}"
    return f"  {name:<14} {shown:<12} {coord.attrs.get('long_name', '')}"


def _describe_variable(name, var, axes):
    extra = "".join(f" (per {d}: {var.sizes[d]})" for d in var.dims if d not in axes)
    text = f"  {name:<20} {var.attrs.get('long_name', '')}{extra}"
    if "flag_meanings" in var.attrs:
        return f"{text}  flags: {var.attrs['flag_meanings']}"
    return f"{text}  [{var.attrs.get('units', '')}]{_same_everywhere(var, axes)}"


def _same_everywhere(var, axes):
    """" = value" for a per-point number equal at every point (a scene's constant, e.g. a bearing
    value used and whether the scene gave it), else ""."""
    if set(var.dims) - set(axes) or var.dtype.kind not in "fiu" or var.size == 0:
        return ""
    values = np.asarray(var.values).ravel()
    return f" = {values[0]:g}" if np.isfinite(values[0]) and (values == values[0]).all() else ""


def _flag_counts(var):
    values = np.asarray(var.values).ravel()
    meanings = var.attrs["flag_meanings"].split()
    flags = np.asarray(var.attrs["flag_values"]).tolist()
    lines = [f"  {m:<16} {int((values == f).sum()):>8}" for f, m in zip(flags, meanings)]
    unset = int((~np.isin(values, flags)).sum())
    return lines + ([f"  {'(no value)':<16} {unset:>8}"] if unset else [])


# --- part files -----------------------------------------------------------------------------

def parts_dir(cube_path):
    """Directory of a sweep's part files: `<cube file name>.parts` next to the cube."""
    cube_path = Path(cube_path)
    return cube_path.with_name(cube_path.name + ".parts")


def write_part(parts_dir, chunk_id, index, results, meta):
    """Save one finished chunk as `<chunk_id>.npz` (numeric arrays only, meta as a JSON string),
    atomically so a killed sweep never leaves a truncated part."""
    if not chunk_id or "/" in chunk_id or chunk_id.startswith("."):
        raise CubeError(f"bad chunk id {chunk_id!r}")
    parts_dir = Path(parts_dir)
    parts_dir.mkdir(parents=True, exist_ok=True)
    arrays = {"index": np.asarray(index, np.int64), "meta": np.array(json.dumps(meta))}
    arrays.update({f"result_{name}": np.asarray(value) for name, value in results.items()})
    path = parts_dir / f"{chunk_id}.npz"
    with fileio.atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays)
    return path


def read_parts(parts_dir):
    """All part files of a directory as (chunk_id, index, results, meta), in chunk-id order."""
    return list(iter_parts(parts_dir))


def iter_parts(parts_dir):
    """read_parts one part at a time (assembling a 768k-point atlas holds one part in memory, not
    all of them next to the full arrays)."""
    return (_read_part(path) for path in _part_paths(parts_dir))


def part_metas(parts_dir):
    """The meta dict of every part file, in chunk-id order, without reading their arrays."""
    metas = []
    for path in _part_paths(parts_dir):
        with _open_part(path) as f:
            metas.append(json.loads(str(f["meta"])))
    return metas


def _part_paths(parts_dir):
    parts_dir = Path(parts_dir)
    return sorted(parts_dir.glob("[!.]*.npz")) if parts_dir.is_dir() else []


@contextlib.contextmanager
def _open_part(path):
    """np.load of a part file; one that cannot be read (truncated, not an npz, a key missing, a
    damaged zip: CRC or directory errors, a broken deflate stream) is a CubeError naming it."""
    try:
        with np.load(path, allow_pickle=False) as f:
            yield f
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise CubeError(f"{path}: unreadable part file ({exc}); delete it to recompute its points") from None


def _read_part(path):
    with _open_part(path) as f:
        results = {k[len("result_"):]: f[k] for k in f.files if k.startswith("result_")}
        return path.stem, f["index"], results, json.loads(str(f["meta"]))


class Assembly:
    """The full-grid arrays of a cube (NaN / INT_FILL where no part has the point), filled part by
    part: a sweep adds each chunk as it arrives instead of reading its part file back at the end.
    With config_hash, a part of another config (another run writing into the same directory)
    is an error at dataset(), never mixed in."""

    def __init__(self, axes, model, n_multipliers, config_hash=None):
        self.axes, self.n_multipliers, self.config_hash = axes, n_multipliers, config_hash
        self.shape = tuple(len(v) for v in axes.values())
        self.variables = schema.variables_of(schema.model_of({"model": model}))
        self.have = np.zeros(self.shape, bool)
        self.full, self.seen, self.foreign = {}, 0, []

    def add(self, chunk_id, index, results, meta):
        self.seen += 1
        if self.config_hash is not None and (meta or {}).get("config_hash") != self.config_hash:
            self.foreign.append(chunk_id)
            return
        at = tuple(np.asarray(index).T)
        self.have[at] = True
        for name, values in results.items():
            if name not in self.full:
                self.full[name] = _empty(name, self.shape, values, self.n_multipliers, self.variables)
            self.full[name][at] = values

    def dataset(self, fixed, attrs, allow_missing=False):
        """The cube; a point no part holds is an error unless allow_missing."""
        if self.foreign:
            raise CubeError(f"{len(self.foreign)} of {self.seen} part files (first: {self.foreign[0]}.npz) "
                            f"belong to another config than this run's (hash {self.config_hash[:12]}); their "
                            "results are not mixed into the cube: rerun with --overwrite into a path no other "
                            "run uses")
        missing = int((~self.have).sum())
        if missing and not allow_missing:
            raise CubeError(f"{missing} of {self.have.size} grid points have no result in the part files "
                            f"(first: {_point(self.axes, np.argwhere(~self.have)[0])})")
        return build_dataset(self.axes, fixed, self.full, attrs)


def assemble(axes, fixed, parts, attrs, n_multipliers, allow_missing=False, config_hash=None):
    """The cube of a sweep from its parts ((chunk_id, index, results, meta) each): an Assembly
    of them."""
    assembly = Assembly(axes, attrs.get("model", schema.DEFAULT_MODEL), n_multipliers, config_hash)
    for part in parts:
        assembly.add(*part)
    return assembly.dataset(fixed, attrs, allow_missing)


def _empty(name, shape, values, n_multipliers, variables):
    """A full-grid array for a variable, filled with its 'no value' (NaN or INT_FILL)."""
    if name not in variables:
        raise CubeError(f"part files hold variable {name!r}, which the cube schema does not know")
    extra_dims, dtype, _ = variables[name]
    extra = tuple(n_multipliers if d in ("multiplier", "state", "exponent") else n
                  for d, n in zip(extra_dims, values.shape[1:]))
    dtype = np.dtype(dtype)
    fill = schema.INT_FILL if dtype.kind in "iu" else schema.FLOAT_FILL
    return np.full(shape + extra, fill, dtype)


def _point(axes, idx):
    return ", ".join(f"{name}={values[i]:g}" for (name, values), i in zip(axes.items(), idx))

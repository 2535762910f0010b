"""A result's plain variables (dims, values, attributes) written as netCDF with the netCDF4 library
directly: `rotorsweep continue` and `backbone` write their results without importing xarray and
pandas (0.6 s of CPU, half of a small continuation end to end; issue 35).

The file is the one xarray's `to_netcdf(engine="netcdf4")` writes with the result encoding (see
`write`), and xarray reads it back identically (tests/test_plain_write.py builds results both ways).
The CF rules xarray applies on the way are the ones reproduced here:
- text as UTF-8 character arrays: a trailing dimension `string<N>` (N: the longest value in bytes,
  at least 1) and the attribute `_Encoding = "utf-8"`; an empty object array is written as float64;
- numbers of a data variable compressed (cube.COMPRESSION), floats with `_FillValue` NaN,
  integers without a fill value (a plain xarray.open_dataset keeps the flags integer); coordinates
  neither compressed nor filled;
- a coordinate that is not a dimension named in the `coordinates` attribute of every data variable
  whose dimensions hold its own (sorted), the ones named nowhere in a global `coordinates`.
Sweep cubes, whose Dask-backed assembly needs xarray anyway, keep xarray's writer (cube.write_cube).
"""
from typing import NamedTuple

import netCDF4
import numpy as np

from rotorsweep.pipeline import cube

# xarray's netCDF4 backend passes these to createVariable before a variable's own encoding
_DEFAULTS = {"zlib": False, "complevel": 4, "shuffle": True, "fletcher32": False, "contiguous": False,
             "chunksizes": None, "endian": "native", "least_significant_digit": None}


class Plain(NamedTuple):
    """A result as plain variables: data_vars and coords {name: (dims, values, attrs)} (dims a
    tuple or one name), attrs the global attributes."""
    data_vars: dict
    coords: dict
    attrs: dict

    def to_xarray(self):
        """The xarray.Dataset of these variables (imports xarray)."""
        import xarray as xr
        return xr.Dataset(self.data_vars, coords=self.coords, attrs=self.attrs)


def of_dataset(ds):
    """The Plain variables of an xarray.Dataset."""
    def plain(variables):
        return {name: (var.dims, var.values, dict(var.attrs)) for name, var in variables.items()}
    return Plain(plain(ds.data_vars), plain(ds.coords), dict(ds.attrs))


class _Encoded(NamedTuple):
    dims: tuple
    data: np.ndarray
    attrs: dict
    fill: object
    filters: dict


def write(plain, path):
    """Write `plain` as a netCDF-4 file at `path` (replaced if there)."""
    encoded = _encode(plain)
    with netCDF4.Dataset(path, mode="w", format="NETCDF4") as nc:
        for dim, size in _dimensions(encoded).items():
            nc.createDimension(dim, size)
        for name, value in _global_attrs(plain).items():
            _set_attribute(nc, name, value)
        for name, var in encoded.items():
            out = nc.createVariable(name, var.data.dtype, var.dims,
                                    **{**_DEFAULTS, **var.filters, "fill_value": var.fill})
            out.setncatts(var.attrs)
            out.set_auto_maskandscale(False)
            out.set_auto_chartostring(False)
            if var.data.size:
                out[...] = var.data


def _encode(plain):
    """{name: _Encoded} of the data variables, then the coordinates."""
    coordinates = _coordinates_attrs(plain)
    out = {}
    for is_coord, table in ((False, plain.data_vars), (True, plain.coords)):
        for name, (dims, values, attrs) in table.items():
            attrs = {**attrs, **({"coordinates": coordinates[name]} if name in coordinates else {})}
            out[name] = _encode_variable(_dims_of(dims), np.asarray(values), attrs, is_coord)
    return out


def _encode_variable(dims, data, attrs, is_coord):
    if data.dtype.kind == "O" and data.size == 0:       # xarray infers float for an empty object array
        return _Encoded(dims, data.astype(float), attrs, None, {})
    if data.dtype.kind in "OU":
        chars = np.array([str(v).encode("utf-8") for v in data.ravel()], "S").reshape(data.shape)
        chars = chars.reshape(-1).view("S1").reshape(data.shape + (chars.dtype.itemsize,))
        return _Encoded(dims + (f"string{chars.shape[-1]}",), chars, {**attrs, "_Encoding": "utf-8"}, None, {})
    if data.dtype.kind not in "iuf":
        raise TypeError(f"cannot write a {data.dtype} variable as plain netCDF (numbers and text only)")
    if is_coord:
        return _Encoded(dims, data, attrs, None, {})
    fill = data.dtype.type(np.nan) if data.dtype.kind == "f" else None
    return _Encoded(dims, data, attrs, fill, cube.COMPRESSION)


def _dims_of(dims):
    return (dims,) if isinstance(dims, str) else tuple(dims)


def _non_dim_coords(plain):
    return {name: set(_dims_of(dims)) for name, (dims, _, _) in plain.coords.items() if _dims_of(dims) != (name,)}


def _coordinates_attrs(plain):
    """{data variable: its `coordinates` attribute}: the non-dimension coordinates on its dims."""
    coords = _non_dim_coords(plain)
    out = {}
    for name, (dims, _, attrs) in plain.data_vars.items():
        mine = sorted(c for c, c_dims in coords.items() if c_dims <= set(_dims_of(dims)))
        if mine and "coordinates" not in attrs:
            out[name] = " ".join(mine)
    return out


def _global_attrs(plain):
    """The global attributes, with `coordinates` naming the non-dimension coordinates no data
    variable names."""
    named = {c for text in _coordinates_attrs(plain).values() for c in text.split()}
    alone = sorted(set(_non_dim_coords(plain)) - named)
    return {**plain.attrs, **({"coordinates": " ".join(alone)} if alone and "coordinates" not in plain.attrs else {})}


def _dimensions(encoded):
    """{dim: size} in the order the variables first use them."""
    sizes = {}
    for var in encoded.values():
        for dim, size in zip(var.dims, var.data.shape):
            sizes.setdefault(dim, size)
    return sizes


def _set_attribute(nc, name, value):
    """A global attribute as xarray sets it: a list of texts as a netCDF string array."""
    array = np.asarray(value)
    if array.dtype.kind in "US" and array.size > 1:
        nc.setncattr_string(name, value)
    else:
        nc.setncattr(name, value)

"""Result cubes: schema, CF attributes, round trips, atomic writes, user errors, part files."""
import os
import re

import netCDF4
import numpy as np
import pytest
import xarray as xr

from rotorsweep.pipeline import cube, schema
from rotorsweep.kernels.models.jeffcott_clearance import SPEC as JEFFCOTT
from tests import cfcheck
from tests.synthetic import synthetic_cube

AXES4 = {
    "speed": np.array([50.0, 60.0, 70.0]),
    "clearance": np.array([5e-6, 1e-5]),
    "contact_angle": np.array([0.0, 15.0]),
    "preload": np.array([0.0, 100.0]),
}
PROVENANCE = {"config_toml": '[scene]\nname = "t"\n', "config_hash": "ab" * 32, "rotorsweep_version": "0.1.0",
              "created": "2026-01-01T00:00:00+00:00", "numerics": '{"newton_tol": 1e-10}',
              "history": "2026-01-01T00:00:00+00:00 rotorsweep 0.1.0: a synthetic test cube"}


def random_results(shape, n_multipliers=4, seed=0):
    """Every schema variable, with fills (-1 / NaN) sprinkled in, as compute returns them (int64)."""
    rng = np.random.default_rng(seed)
    out = {}
    for name, (extra, dtype, attrs) in schema.variables_of(schema.model_of({})).items():
        full = shape + (n_multipliers,) * len(extra)
        if "flag_values" in attrs:
            out[name] = rng.integers(schema.INT_FILL, len(attrs["flag_values"]), full)
        elif np.dtype(dtype).kind == "i":
            out[name] = rng.integers(0, 50, full)
        else:
            out[name] = np.where(rng.random(full) < 0.1, np.nan, rng.normal(size=full))
    return out


def four_d():
    return cube.build_dataset(AXES4, {}, random_results((3, 2, 2, 2)), PROVENANCE)


def test_a_netcdf_chunk_is_one_line_along_the_continued_axis(tmp_path, monkeypatch):
    """Line chunks: a speed line is one chunk, an (angle, preload) slice one chunk per line; a
    line longer than CHUNK_BYTES is cut (here 2 float64 speeds of 4 multipliers = 64 B)."""
    path = cube.write_cube(four_d(), tmp_path / "c.nc")
    with netCDF4.Dataset(path) as nc:
        assert nc["max_abs_multiplier"].chunking() == [3, 1, 1, 1]
        assert nc["multiplier_real"].chunking() == [3, 1, 1, 1, 4]
        assert nc["orbit_status"].chunking() == [3, 1, 1, 1]
    monkeypatch.setattr(cube, "CHUNK_BYTES", 64)
    path = cube.write_cube(four_d(), tmp_path / "d.nc")
    with netCDF4.Dataset(path) as nc:
        assert nc["multiplier_real"].chunking() == [2, 1, 1, 1, 4]
    xr.testing.assert_identical(cube.open_cube(path), cube.open_cube(tmp_path / "c.nc"))


def from_synthetic():
    """The synthetic cube rebuilt through build_dataset (a NaN fixed contact angle included)."""
    syn = synthetic_cube()
    results = {name: syn[name].values for name in syn.data_vars}
    fixed = {"contact_angle": np.nan, "preload": 0.0}
    attrs = {k: v for k, v in syn.attrs.items() if k not in ("Conventions", "rotorsweep_schema_version")}
    return syn, cube.build_dataset({"speed": syn.speed.values, "clearance": syn.clearance.values},
                                   fixed, results, attrs)


def assert_same(a, b):
    xr.testing.assert_identical(a, b)
    for name, var in a.variables.items():
        assert b[name].dtype == var.dtype, name


@pytest.mark.parametrize("make", [four_d, lambda: from_synthetic()[1]], ids=["4d", "synthetic"])
def test_round_trip_is_identical(make, tmp_path):
    ds = make()
    back = cube.open_cube(cube.write_cube(ds, tmp_path / "c.nc"))
    assert_same(ds, back)
    assert back["stable"].dtype == np.int8                # flags with fills stay integers


def test_build_follows_the_schema():
    syn, built = from_synthetic()
    for name in syn.data_vars:
        np.testing.assert_array_equal(built[name].values, syn[name].values)
        assert built[name].dtype == np.dtype(schema.variables_of(schema.model_of({}))[name][1])
        assert built[name].dims == syn[name].dims
    assert built.attrs["config_hash"] == syn.attrs["config_hash"]
    assert built.attrs["rotorsweep_schema_version"] == schema.SCHEMA_VERSION
    # a contact angle derived per point is no (NaN) coordinate; the cube says where it comes from
    assert "contact_angle" not in built.coords
    assert cube.derived_parameters(built) == {"contact_angle": JEFFCOTT.derived_axes["contact_angle"]}
    np.testing.assert_array_equal(built["multiplier"].values, np.arange(4))


def test_cf_attributes_and_compression_on_disk(tmp_path, monkeypatch):
    monkeypatch.setattr(cube, "COMPRESS_FROM_BYTES", 0)     # this small cube compressed as a large one
    path = cube.write_cube(four_d(), tmp_path / "c.nc")
    ds = cube.open_cube(path)
    assert ds.attrs["Conventions"] == "CF-1.10" and ds.attrs["title"]
    for name in AXES4:
        assert ds[name].attrs["units"] == schema.axes_of(schema.model_of({}))[name][0] and ds[name].attrs["long_name"]
    for name, var in ds.data_vars.items():
        assert var.attrs["long_name"]
        assert "units" in var.attrs or {"flag_values", "flag_meanings"} <= set(var.attrs), name
        assert var.encoding["zlib"] and var.encoding["shuffle"], name
        assert var.encoding["complevel"] == cube.COMPRESSION["complevel"], name
    flags = ds["bifurcation"].attrs
    assert flags["flag_meanings"].split() == list(schema.BIFURCATION)
    assert flags["flag_values"].dtype == np.int8
    with netCDF4.Dataset(path) as nc:
        assert "_FillValue" not in nc["orbit_status"].ncattrs()
        assert nc["orbit_status"].filters()["zlib"]
        assert "_FillValue" not in nc["speed"].ncattrs()


def test_small_cube_is_written_without_filters(tmp_path):
    ds = four_d()
    assert ds.nbytes < cube.COMPRESS_FROM_BYTES
    path = cube.write_cube(ds, tmp_path / "c.nc")
    with netCDF4.Dataset(path) as nc:
        assert not nc["orbit_status"].filters()["zlib"] and not nc["residual"].filters()["shuffle"]
        assert nc["residual"].chunking() != "contiguous"        # still chunked by line
    np.testing.assert_array_equal(cube.open_cube(path)["residual"].values, ds["residual"].values)


def test_existing_cube_needs_overwrite(tmp_path):
    path = tmp_path / "sub" / "c.nc"
    cube.write_cube(four_d(), path)                       # creates the parent directory
    with pytest.raises(cube.CubeError, match="exists; pass --overwrite"):
        cube.write_cube(four_d(), path)
    other = cube.build_dataset(AXES4, {}, random_results((3, 2, 2, 2), seed=1), PROVENANCE)
    cube.write_cube(other, path, overwrite=True)
    assert_same(cube.open_cube(path), other)


def test_a_distributed_client_in_the_process_does_not_lock_the_write_on_its_scheduler(tmp_path, monkeypatch):
    """xarray would take a lock on the scheduler of an active distributed Client for each netCDF
    call of the write (a round trip each); the cube is in memory and needs none."""
    from distributed import Client, Lock

    taken = []
    acquire = Lock.acquire
    monkeypatch.setattr(Lock, "acquire", lambda self, *a, **k: taken.append(self.name) or acquire(self, *a, **k))
    with Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None):
        cube.write_cube(synthetic_cube(), tmp_path / "c.nc")
        assert taken == []
        Lock("probe").acquire(timeout=5)              # the patch sees the scheduler's locks
        assert taken == ["probe"]
    assert xr.open_dataset(tmp_path / "c.nc").sizes == synthetic_cube().sizes


@pytest.mark.parametrize("interrupt", [OSError("disk full"), KeyboardInterrupt()])
def test_interrupted_write_keeps_the_previous_cube(tmp_path, monkeypatch, interrupt):
    path = cube.write_cube(four_d(), tmp_path / "c.nc")
    before = path.read_bytes()

    def half_written(self, target, *args, **kwargs):
        with open(target, "wb") as f:
            f.write(b"\x89HDF\r\n\x1a\n half a file")
        raise interrupt

    monkeypatch.setattr(xr.Dataset, "to_netcdf", half_written)
    with pytest.raises(type(interrupt)):
        cube.write_cube(four_d(), path, overwrite=True)
    with pytest.raises(type(interrupt)):
        cube.write_cube(four_d(), tmp_path / "new.nc")
    assert path.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["c.nc"]       # no temp file, no half-written new.nc


def test_open_cube_says_what_the_file_is(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("speed, clearance\n")
    with pytest.raises(cube.CubeError, match="notes.txt is not a netCDF file"):
        cube.open_cube(text)
    plain = tmp_path / "plain.nc"
    xr.Dataset({"a": ("x", [1.0, 2.0])}).to_netcdf(plain)
    with pytest.raises(cube.CubeError, match="plain.nc is a netCDF file but not a rotorsweep result cube"):
        cube.open_cube(plain)
    old = four_d()
    old.attrs["rotorsweep_schema_version"] = schema.SCHEMA_VERSION - 1
    cube.write_cube(old, tmp_path / "old.nc")
    with pytest.raises(cube.CubeError, match=f"schema version {schema.SCHEMA_VERSION - 1}.*reads version "
                                             f"{schema.SCHEMA_VERSION}"):
        cube.open_cube(tmp_path / "old.nc")
    with pytest.raises(cube.CubeError, match="missing.nc: no such file"):
        cube.open_cube(tmp_path / "missing.nc")


def test_build_rejects_what_the_schema_does_not_know():
    shape = (3, 2, 2, 2)
    with pytest.raises(cube.CubeError, match="'wear_index' is not in the cube schema"):
        cube.build_dataset(AXES4, {}, {"wear_index": np.zeros(shape)}, {})
    wear = cube.build_dataset(AXES4, {}, {"wear_index": np.zeros(shape)}, {},
                             extra_attrs={"wear_index": {"units": "1", "long_name": "bearing wear index"}})
    assert wear["wear_index"].attrs["units"] == "1"
    with pytest.raises(cube.CubeError, match="shape"):
        cube.build_dataset(AXES4, {}, {"residual": np.zeros((3, 2))}, {})
    with pytest.raises(cube.CubeError, match="schema order"):
        cube.build_dataset({"clearance": [1e-6], "speed": [1.0]}, {}, {}, {})
    with pytest.raises(cube.CubeError, match="unknown axis 'temperature'"):
        cube.build_dataset({"speed": [1.0]}, {"temperature": 20.0}, {}, {})


def test_describe_lists_axes_flags_and_provenance():
    text = cube.describe(from_synthetic()[1])
    assert "speed" in text and "121 values" in text and "10 .. 250 Hz" in text
    assert "contact_angle" in text and "from clearance" in text
    assert "max_abs_multiplier" in text and "neimark_sacker" in text
    assert any(line.split() == ["converged", "605"] for line in text.splitlines())
    assert "config_hash: " + "0" * 64 in text and 'name = "synthetic"' in text


def _write_random_parts(parts, results, shape, seed=0):
    """The grid's points shuffled into chunks of uneven size, written in that random order."""
    rng = np.random.default_rng(seed)
    index = np.argwhere(np.ones(shape, bool))[rng.permutation(int(np.prod(shape)))]
    cuts = np.sort(rng.choice(np.arange(1, len(index)), size=5, replace=False))
    for k, chunk in enumerate(np.split(index, cuts)):
        at = tuple(chunk.T)
        cube.write_part(parts, f"c{k:03d}", chunk, {n: v[at] for n, v in results.items()},
                        {"config_hash": "x", "segments": [k]})
    return len(cuts) + 1


def test_parts_in_random_order_assemble_to_the_direct_build(tmp_path):
    shape = (3, 2, 2, 2)
    results = random_results(shape)
    parts = cube.parts_dir(tmp_path / "c.nc")
    assert parts == tmp_path / "c.nc.parts"
    n = _write_random_parts(parts, results, shape)
    (parts / ".c999.npz.tmp").write_bytes(b"an interrupted write")     # ignored
    read = cube.read_parts(parts)
    assert [r[0] for r in read] == [f"c{k:03d}" for k in range(n)]
    assert read[0][3] == {"config_hash": "x", "segments": [0]}
    assembled = cube.assemble(AXES4, {}, read, PROVENANCE, n_multipliers=4)
    assert_same(assembled, cube.build_dataset(AXES4, {}, results, PROVENANCE))


def test_a_missing_part_is_reported(tmp_path):
    shape = (3, 2, 2, 2)
    _write_random_parts(tmp_path, random_results(shape), shape)
    read = cube.read_parts(tmp_path)
    lost = len(read[2][1])
    with pytest.raises(cube.CubeError, match=f"{lost} of 24 grid points have no result"):
        cube.assemble(AXES4, {}, read[:2] + read[3:], PROVENANCE, n_multipliers=4)
    partial = cube.assemble(AXES4, {}, read[:2] + read[3:], PROVENANCE, n_multipliers=4, allow_missing=True)
    assert int((partial["orbit_status"].values == schema.INT_FILL).sum()) >= lost
    assert int(np.isnan(partial["multiplier_real"].values).all(axis=-1).sum()) >= lost


def test_unreadable_part_is_a_cube_error(tmp_path):
    (tmp_path / "c000.npz").write_bytes(b"truncated")
    with pytest.raises(cube.CubeError, match="c000.npz: unreadable part file"):
        cube.read_parts(tmp_path)


@pytest.mark.parametrize("where", [1 / 3, 1 / 2, -30])
def test_a_damaged_part_is_a_cube_error(tmp_path, where):
    """A byte flipped inside a member (CRC error) or in the zip directory (names differ) was a
    BadZipFile traceback on `run --resume`; it is the one line naming the part."""
    cube.write_part(tmp_path, "c000", np.array([[0, 0, 0, 0], [1, 0, 0, 0]]),
                    {"max_abs_multiplier": np.array([0.5, 0.7])}, {"config_hash": "x"})
    path = tmp_path / "c000.npz"
    data = bytearray(path.read_bytes())
    data[int(where * len(data)) if where > 0 else where] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(cube.CubeError, match="c000.npz: unreadable part file.*delete it"):
        cube.read_parts(tmp_path)


# ----------------------------------------------------------------------------- CF rules
# The rules the CF checker (cfchecker 4.1) flagged on a demo cube, tested directly: it needs the
# udunits2 C library, so it runs only where it is installed (test_cf_checkers_find_no_problem).

# UDUNITS symbols the cubes use; a unit string is terms SYMBOL[EXPONENT] separated by spaces.
UDUNITS_SYMBOLS = {"1", "m", "s", "Hz", "N", "kg", "degree", "rad"}
UNIT_TERM = re.compile(r"^([A-Za-z]+|1)(-?\d+(\.\d+)?)?$")


def udunits_like(units):
    terms = units.split()
    return bool(terms) and all((m := UNIT_TERM.match(t)) and m.group(1) in UDUNITS_SYMBOLS for t in terms)


def cf_problems(ds):
    """Each violation of the checked CF rules in an opened cube, as text."""
    problems = []
    if not str(ds.attrs.get("Conventions", "")).startswith("CF-"):
        problems.append("no Conventions attribute")
    for name, var in ds.variables.items():
        attrs = var.attrs
        if "flag_values" in attrs:
            flags = np.asarray(attrs["flag_values"])
            if flags.dtype != var.dtype:
                problems.append(f"{name}: flag_values {flags.dtype} on {var.dtype} data")
            if len(flags) != len(attrs.get("flag_meanings", "").split()):
                problems.append(f"{name}: {len(flags)} flag_values, flag_meanings differ in count")
        elif not udunits_like(str(attrs.get("units", ""))):
            problems.append(f"{name}: units {attrs.get('units')!r} missing or not UDUNITS")
        if name in ds.coords and var.dtype.kind == "f" and not np.isfinite(var.values).all():
            problems.append(f"{name}: NaN in a coordinate")
    return problems


def test_udunits_check_knows_good_from_bad():
    assert all(udunits_like(u) for u in ("1", "m", "s-1", "N s m-1", "N m-1.5", "degree", "m s-2"))
    assert not any(udunits_like(u) for u in ("", "um/s", "flag", "1/s", "meters"))


def test_cubes_follow_the_cf_rules(tiny_cube, tmp_path):
    """The real sweep's cube (boundary table, attractors) and a 4-D cube of every variable."""
    for path in (tiny_cube, cube.write_cube(four_d(), tmp_path / "c.nc")):
        assert cf_problems(cube.open_cube(path)) == [], path
        with netCDF4.Dataset(path) as nc:      # no fill value on integers, none on coordinates
            assert [n for n, v in nc.variables.items() if "_FillValue" in v.ncattrs()
                    and (v.dtype.kind in "iu" or n in nc.dimensions)] == []
    attrs = cube.open_cube(tiny_cube).attrs
    assert attrs["Conventions"] == cube.CONVENTIONS
    assert attrs["history"].endswith("rotorsweep 0.1.0: run scene tiny_attractor")
    assert attrs["source"].startswith("rotorsweep 0.1.0, model jeffcott_clearance version 2:")
    assert "Bai" in attrs["references"] and "Applied Mathematics and Mechanics" in attrs["references"]


def test_plain_xarray_keeps_flags_integer(tiny_cube):
    """No _FillValue on integers: xarray's default decoding leaves them integer (with one it
    makes them float with NaN)."""
    with xr.open_dataset(tiny_cube) as ds:
        flags = [n for n in ds.variables if "flag_values" in ds[n].attrs]
        assert {"stable", "bifurcation", "orbit_status", "boundary_type", "boundary_direction",
                "boundary_status"} <= set(flags)
        for name in flags:
            assert ds[name].dtype == np.int8, name
        assert "contact_angle" not in ds.coords and ds.attrs[cube.DERIVED_ATTR]


def test_poincare_samples_are_float32_within_the_stated_loss(tiny_run):
    """Stored as float32: the loss against the workers' float64 samples, measured, is within
    the 2**-24 relative rounding the variable's comment states."""
    path, results = tiny_run
    ds = cube.open_cube(path)
    for name in ("poincare_x", "poincare_y", "poincare_x_down"):
        assert ds[name].dtype == np.float32 and "2**-24" in ds[name].attrs["comment"]
        exact = results[name].reshape(ds[name].shape)
        rel = np.abs(ds[name].values.astype(float) - exact) / np.abs(exact)
        assert 0 < rel.max() <= 2.0 ** -24, name


@pytest.mark.parametrize("which", ["sweep", "4-D"])
def test_cf_checkers_find_no_problem(which, tiny_cube, tmp_path):
    """cfchecker and the IOOS compliance-checker (tests/cfcheck.py; skipped where they are not
    installed): no error and no warning on the real sweep's cube (boundary table, attractors) or
    on a 4-D cube of every variable."""
    path = tiny_cube if which == "sweep" else cube.write_cube(four_d(), tmp_path / "c.nc")
    assert cfcheck.cfchecker_messages(path, tmp_path) == {"FATAL": [], "ERROR": [], "WARN": []}
    assert cfcheck.ioos_failures(path, tmp_path) == []

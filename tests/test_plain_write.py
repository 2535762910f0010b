"""The result writer without xarray (rotorsweep.pipeline.plainnc, used by results.write for
`continue` and `backbone`) against the second method it replaces: xarray's to_netcdf with the
result encoding results.write passed it before (reference_write below). Each result is written both
ways; xarray reads the two files identically (values, dtypes, attributes, fill values, encodings),
the files hold the same netCDF structure byte for byte in their data, and `info` and `query` print
the same text on both."""
import netCDF4
import numpy as np
import pytest
import xarray as xr

from rotorsweep.pipeline import backbone, cli, cluster, config, continuation, cube, plainnc, result_kinds, results
from tests.test_backbone_command import scene
from tests.test_continue_command import DUFFING


def reference_write(ds, path):
    """The writer before plainnc: xarray with the result encoding (numbers compressed, integers
    and coordinates without a fill value, text as UTF-8 character arrays)."""
    def text(var):
        return {"dtype": "S1"} if var.dtype.kind in "OU" else {}
    enc = {name: {"_FillValue": None, **text(var)} for name, var in ds.coords.items()}
    for name, var in ds.data_vars.items():
        enc[name] = text(var) or {**cube.COMPRESSION, **({"_FillValue": None} if var.dtype.kind in "iu" else {})}
    ds.to_netcdf(path, engine="netcdf4", encoding=enc)
    return path


def edge_cases():
    """What the schemas hold, at its edges: no events (empty dims, empty text), non-ASCII and
    empty text, a 0-d text, NaN padding, flag tables as attributes, coordinates on some
    variables' dims and one on no variable's, a list of texts as a global attribute."""
    return plainnc.Plain(
        {"parameter": (("branch", "point"), np.array([[1.0, np.nan]]), {"units": "Hz", "comment": "µ"}),
         "stable": (("branch", "point"), np.array([[1, -1]], "int8"),
                    {"flag_values": np.array([-1, 0, 1], "int8"), "flag_meanings": "no_point unstable stable"}),
         "branch_detail": (("branch",), np.array(["düffing ✓"], object), {}),
         "event_type": (("event",), np.array([], "int8"), {}),
         "event_note": (("event",), np.array([], object), {"long_name": "none"}),
         "empty_text": (("branch",), np.array([""], object), {}),
         "surface_info": ((), '{"mode": 1}', {}),
         "count": (("branch",), np.array([3], "int64"), {})},
        {"observable": ("observable", ["x", "theta_y"], {"long_name": "o"}),
         "clearance": ("branch", np.array([7.6e-6]), {"units": "m"}),
         "lonely": ("other", np.array([1.0, 2.0]), {})},
        {"result_kind": "continuation", "n": 3, "x": 1.5, "names": ["a", "b"], "empty": ""})


@pytest.fixture(scope="module")
def results_plain():
    """{name: Plain}: the Duffing hardening resonance's continuation and the axial rotor's first
    backbone, computed in this process as their commands' line tasks do, and the edge cases."""
    cont = config.parse_config(DUFFING)
    line = continuation.continue_line(cont.scene, {})
    bb = config.parse_config(scene(modes="1", amplitude_max=4e-6, amplitude_points=9, surface_mode=1))
    pl = backbone.plan(bb.scene)
    return {"continuation": continuation.to_result(cont.scene, continuation.plan(cont.scene), [({}, line)],
                                                   cluster.provenance(cont, result_kinds.CONTINUATION)),
            "backbone": backbone.to_result(bb.scene, pl, [backbone.backbone_line(bb.scene, w) for w in pl.lines],
                                           cluster.provenance(bb, result_kinds.BACKBONE)),
            "edge cases": edge_cases()}


@pytest.fixture(scope="module", params=["continuation", "backbone", "edge cases"])
def both(request, results_plain, tmp_path_factory):
    """(file written by xarray, file written by results.write) of one result."""
    d = tmp_path_factory.mktemp("plain")
    plain = results_plain[request.param]
    return reference_write(plain.to_xarray(), d / "xarray.nc"), results.write(plain, d / "plain.nc")


def structure(path):
    """Everything the netCDF file holds: format, dimensions, global attributes, and per variable
    (in file order) its type, dimensions, storage, filters, attributes and data bytes."""
    with netCDF4.Dataset(path) as nc:
        nc.set_auto_maskandscale(False)
        nc.set_auto_chartostring(False)
        out = [nc.data_model, [(d.name, d.size, d.isunlimited()) for d in nc.dimensions.values()],
               [(k, repr(nc.getncattr(k))) for k in nc.ncattrs()]]
        for name, v in nc.variables.items():
            out.append((name, v.dtype, v.dimensions, v.chunking(), v.filters(), v.endian(),
                        [(k, repr(v.getncattr(k))) for k in v.ncattrs()], v[...].tobytes()))
    return out


def test_the_file_holds_what_xarray_writes(both):
    reference, plain = both
    assert structure(plain) == structure(reference)


@pytest.mark.parametrize("decode", [{}, {"mask_and_scale": False}])
def test_xarray_reads_it_identically(both, decode):
    """As a plain xr.open_dataset and as the readers open results (cube.read_netcdf: no masking)."""
    reference, plain = both
    with xr.open_dataset(reference, **decode) as a, xr.open_dataset(plain, **decode) as b:
        xr.testing.assert_identical(a.load(), b.load())
        for name, var in a.variables.items():
            assert var.dtype == b[name].dtype, name
            expected = {k: v for k, v in var.encoding.items() if k != "source"}
            got = {k: v for k, v in b[name].encoding.items() if k != "source"}
            np.testing.assert_equal(got, expected, err_msg=name)      # _FillValue, char_dim_name, chunks, filters


@pytest.mark.parametrize("kind", ["continuation", "backbone"])
def test_info_and_query_print_the_same_on_both(results_plain, kind, tmp_path, capsys):
    plain = results_plain[kind]
    paths = reference_write(plain.to_xarray(), tmp_path / "xarray.nc"), results.write(plain, tmp_path / "plain.nc")
    for command in (["info"], ["query"], ["query", "--format", "json"]):
        printed = []
        for path in paths:
            assert not cli.main([command[0], str(path), *command[1:]])
            printed.append(capsys.readouterr().out.replace(str(path), "<path>"))
        assert printed[0] == printed[1] and printed[0], command


def test_an_xarray_dataset_is_written_as_its_plain_variables(results_plain, tmp_path):
    plain = results_plain["continuation"]
    a = results.write(plain.to_xarray(), tmp_path / "from_xarray.nc")
    b = results.write(plain, tmp_path / "plain.nc")
    assert structure(a) == structure(b)


def test_other_types_are_refused(tmp_path):
    with pytest.raises(TypeError, match="bool"):
        plainnc.write(plainnc.Plain({"b": ("i", np.array([True]), {})}, {}, {}), tmp_path / "b.nc")

"""Reliability of `continue` and `backbone` (issue 36 item 2): every finished line is kept as a
part file, a full disk ends in one line naming the path with those lines kept, `--resume`
computes only the missing lines and gives bitwise the uninterrupted result, also after the
driver was killed (the chaos test on a cluster: tests/test_reliability_cluster.py)."""
import subprocess

import numpy as np
import pytest
import xarray as xr

from rotorsweep.pipeline import cli, cube, results
from tests.faults import disk_full_after_one_part
from tests.harness import config_file, run_cli, wait_for_parts
from tests.test_pipeline import CLI

# three lines (clearances) of Bai 2006's rotor, ~1 s each once compiled
LINES = """
[scene]
name = "three_lines"
model = "jeffcott_clearance"

[bearing]
preset = "209"
stiffness = "bai2006"

[sweep]
speed = [70.0, 100.0]
clearance = [7.6e-6, 11.4e-6, 19.0e-6]

[continuation]
period_doubling_switches = 0
"""


@pytest.fixture(scope="module")
def lines_config(tmp_path_factory):
    return config_file(tmp_path_factory.mktemp("cfg"), "lines.toml", LINES)


@pytest.fixture(scope="module")
def reference(lines_config):
    out = lines_config.with_name("reference.nc")
    assert cli.main(["continue", str(lines_config), "-o", str(out), "--workers", "1", "-q"]) == 0
    return out


def assert_same_result(reference, other):
    """Every variable and coordinate bitwise equal (the global attributes hold the date)."""
    a, b = xr.load_dataset(reference), xr.load_dataset(other)
    assert set(a.variables) == set(b.variables)
    for name in a.variables:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


def test_a_line_result_goes_through_a_part_file_exactly(tmp_path):
    value = {"grid": np.geomspace(1e-7, 1e-5, 5), "z0": np.float64(np.nan), "modes": (0, 2), "n": 3, "ok": True,
             "records": [{"label": "axial", "kappa": 0.1 + 1e-17, "c": complex(1, -2), "notes": "", "none": None,
                          "start": (93.0, 1.0), "marked": [(1.0, 93.0)], "z": np.zeros((0, 4), complex)}],
             "surface": None}
    results.save_line(tmp_path, "h", 0, value)
    (back,) = results.earlier_lines(tmp_path, "h", 1)
    assert back.keys() == value.keys() and back["modes"] == (0, 2) and back["surface"] is None
    assert np.isnan(back["z0"]) and isinstance(back["z0"], np.float64)
    rec, orig = back["records"][0], value["records"][0]
    assert rec["kappa"] == orig["kappa"] and type(rec["kappa"]) is float and rec["c"] == orig["c"]
    assert rec["start"] == (93.0, 1.0) and rec["marked"] == [(1.0, 93.0)] and rec["z"].dtype == complex
    np.testing.assert_array_equal(back["grid"], value["grid"])
    with pytest.raises(cube.CubeError, match="different config"):
        results.earlier_lines(tmp_path, "another", 1)


def test_a_full_disk_keeps_the_finished_lines_and_resume_gives_the_uninterrupted_result(
        lines_config, reference, tmp_path, monkeypatch, capsys):
    out = tmp_path / "full.nc"
    args = ("continue", lines_config, "-o", out, "--workers", "1", "-q")
    disk_full_after_one_part(monkeypatch)
    rc, err = run_cli(capsys, *args)
    assert rc == 2 and "No space left on device" in err and "the 1 finished line(s) are kept" in err, err
    assert str(cube.parts_dir(out)) in err and "--resume" in err and len(err.strip().splitlines()) == 1
    monkeypatch.undo()
    rc, err = run_cli(capsys, *args)
    assert rc == 2 and "pass --resume" in err

    def hdf_error(*_, **__):
        raise RuntimeError("NetCDF: HDF error")          # what netCDF-C says when the disk fills

    monkeypatch.setattr("netCDF4.Dataset", hdf_error)     # the result writer's (rotorsweep.pipeline.plainnc)
    rc, err = run_cli(capsys, *args, "--resume")
    assert rc == 2 and "NetCDF: HDF error" in err and str(out) in err and "the 3 finished line(s)" in err, err
    assert not out.exists() and len(list(cube.parts_dir(out).glob("*.npz"))) == 3
    monkeypatch.undo()
    rc, err = run_cli(capsys, *args, "--resume")
    assert rc == 0 and not cube.parts_dir(out).exists()
    assert_same_result(reference, out)
    # the log keeps the interrupted runs: the first, the failed write and the resume that finished
    assert (tmp_path / "full.nc.log").read_text().count(f"rotorsweep continue -> {out}") == 3


def test_resume_after_the_driver_is_killed_gives_the_uninterrupted_result(lines_config, reference, tmp_path):
    out = tmp_path / "killed.nc"
    run = CLI + ["continue", str(lines_config), "-o", str(out), "--workers", "1"]
    proc = subprocess.Popen(run + ["-q"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    wait_for_parts(cube.parts_dir(out), proc, minimum=1)
    proc.kill()
    proc.wait()
    assert not out.exists()
    kept = len(list(cube.parts_dir(out).glob("*.npz")))
    resumed = subprocess.run(run + ["--resume"], capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    assert kept == 3 or f"{kept} of 3 line(s) read" in resumed.stderr
    assert_same_result(reference, out)


def test_a_backbone_result_from_part_files_is_bitwise_the_computed_one(tmp_path):
    """A backbone line (nested records, a surface or None, tuples of modes) read back from its part
    gives the same result file as the line computed (as --resume assembles it)."""
    from rotorsweep.pipeline import backbone, cluster, config, result_kinds
    from tests.test_backbone_command import scene

    bb = config.parse_config(scene(modes="1", amplitude_max=4e-6, amplitude_points=9, surface_mode=1))
    pl = backbone.plan(bb.scene)
    lines = [backbone.backbone_line(bb.scene, where) for where in pl.lines]
    for k, line in enumerate(lines):
        results.save_line(tmp_path / "parts", bb.hash(), k, line)
    read = results.earlier_lines(tmp_path / "parts", bb.hash(), len(lines))
    provenance = cluster.provenance(bb, result_kinds.BACKBONE)
    a = results.write(backbone.to_dataset(bb.scene, pl, lines, provenance), tmp_path / "computed.nc")
    b = results.write(backbone.to_dataset(bb.scene, pl, read, provenance), tmp_path / "read.nc")
    assert_same_result(a, b)

"""Every result kind (rotorsweep.pipeline.result_kinds) through everything that reads results: one small file
of each kind (sweep cube, continuation, backbone) opened by open_result, `rotorsweep info`,
`query` and `report` (each opening the file once) and the xarray accessor; open_cube refuses the
other kinds by name; each file's history names the command that wrote it."""
import holoviews as hv
import numpy as np
import pytest
import xarray as xr
from bokeh.models import Plot

import rotorsweep
from rotorsweep.pipeline import backbone, cli, cluster, config, continuation, cube, explore, result_kinds, results
from tests.test_backbone_command import scene
from tests.test_continue_command import DUFFING

KINDS = (result_kinds.SWEEP, result_kinds.CONTINUATION, result_kinds.BACKBONE)
COMMANDS = {result_kinds.SWEEP: "run", result_kinds.CONTINUATION: "continue", result_kinds.BACKBONE: "backbone"}
INFO_HEAD = {result_kinds.SWEEP: "rotorsweep result cube: tiny_attractor",
             result_kinds.CONTINUATION: "continuation result: scene duffing_hardening",
             result_kinds.BACKBONE: "backbone result: scene filipkovsky2010_axial"}


@pytest.fixture(scope="module")
def paths(tiny_cube, tmp_path_factory):
    """{kind: path}: the conftest's tiny sweep cube; the Duffing hardening resonance's branch and
    the axial rotor's first backbone (9 amplitudes), each computed in this process as its command's
    line task does and written with the command's provenance (no Dask cluster)."""
    d = tmp_path_factory.mktemp("kinds")
    cont = config.parse_config(DUFFING)
    line = continuation.continue_line(cont.scene, {})
    ds = continuation.to_dataset(cont.scene, continuation.plan(cont.scene), [({}, line)],
                                 cluster.provenance(cont, result_kinds.CONTINUATION))
    bb = config.parse_config(scene(modes="1", amplitude_max=4e-6, amplitude_points=9, surface_mode=1))
    pl = backbone.plan(bb.scene)
    lines = [backbone.backbone_line(bb.scene, where) for where in pl.lines]
    bds = backbone.to_dataset(bb.scene, pl, lines, cluster.provenance(bb, result_kinds.BACKBONE))
    return {result_kinds.SWEEP: tiny_cube, result_kinds.CONTINUATION: results.write(ds, d / "continuation.nc"),
            result_kinds.BACKBONE: results.write(bds, d / "backbone.nc")}


@pytest.fixture
def opens(monkeypatch):
    """The number of times xarray opens a file from here on."""
    count = []
    real = xr.open_dataset
    monkeypatch.setattr(xr, "open_dataset", lambda *a, **k: count.append(a) or real(*a, **k))
    return count


@pytest.mark.parametrize("kind", KINDS)
def test_open_result_gives_the_kind_and_history_names_the_command(paths, kind):
    ds, found = rotorsweep.open_result(paths[kind])
    assert found is result_kinds.KINDS[kind] and found.command == COMMANDS[kind]
    assert f"rotorsweep {cluster.VERSION}: {COMMANDS[kind]} scene " in ds.attrs["history"]
    assert ds.rotorsweep.kind == kind


@pytest.mark.parametrize("kind", [result_kinds.CONTINUATION, result_kinds.BACKBONE])
def test_open_cube_refuses_the_other_kinds_by_name(paths, kind):
    with pytest.raises(cube.CubeError, match=f"is a {kind} result, not a sweep cube"):
        rotorsweep.open_cube(paths[kind])


@pytest.mark.parametrize("kind", KINDS)
def test_info_and_query_open_the_file_once(paths, kind, capsys, opens):
    assert cli.main(["info", str(paths[kind])]) == 0
    info = capsys.readouterr().out
    assert info.startswith(INFO_HEAD[kind]) and len(opens) == 1
    assert cli.main(["query", str(paths[kind]), "--format", "csv"]) == 0
    rows = capsys.readouterr().out.strip().splitlines()
    assert len(rows) >= 2 and len(opens) == 2       # a header and a row at least
    ds, _ = rotorsweep.open_result(paths[kind])
    assert ds.rotorsweep.describe() == info.rstrip("\n")


@pytest.mark.parametrize("kind, option, applies", [
    (result_kinds.CONTINUATION, "bistable", "a sweep cube (rotorsweep run)"),
    (result_kinds.BACKBONE, "unstable", "a sweep cube (rotorsweep run) or a continuation result (rotorsweep continue)")])
def test_query_options_of_a_sweep_cube_are_refused_on_the_others(paths, kind, option, applies, capsys):
    assert cli.main(["query", str(paths[kind]), f"--{option}"]) == cli.EXIT_USAGE
    err = capsys.readouterr().err
    assert f"--{option} applies to {applies}, not to a {kind} result" in err


def test_query_unstable_of_a_continuation_lists_its_unstable_stretches(paths, capsys):
    assert cli.main(["query", str(paths[result_kinds.CONTINUATION]), "--unstable", "--format", "csv"]) == 0
    """The hardening resonance: unstable between its two folds, the stretch bounded by them."""
    import csv
    import io

    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    (r,) = rows
    assert (r["kind"], r["type"]) == ("periodic_orbit", "fold")
    assert float(r["onset"]) < float(r["start"]) and float(r["end"]) < float(r["offset"]) or \
        float(r["onset"]) > float(r["start"]) > float(r["end"]) > float(r["offset"])


@pytest.mark.parametrize("kind", KINDS)
def test_report_of_every_kind_opens_the_file_once(paths, kind, tmp_path, opens):
    out = tmp_path / "report"
    assert cli.main(["report", str(paths[kind]), "-o", str(out), "-q"]) == 0
    assert len(opens) == 1
    assert (out / "report.html").stat().st_size > 0 and any(out.glob("*.png"))


def test_report_options_apply_to_their_kind_only(paths, tmp_path):
    with pytest.raises(ValueError, match="--point applies to a sweep cube .*, not to a continuation result"):
        rotorsweep.make_report(paths[result_kinds.CONTINUATION], tmp_path / "a", points=["omega=1"])
    with pytest.raises(ValueError, match="--over applies to a backbone result .*, not to a sweep cube"):
        rotorsweep.make_report(paths[result_kinds.SWEEP], tmp_path / "b", over=paths[result_kinds.CONTINUATION])


FIGURE = {result_kinds.SWEEP: "max_multiplier", result_kinds.CONTINUATION: "branch_diagram",
          result_kinds.BACKBONE: "backbones"}


@pytest.mark.parametrize("kind", KINDS)
def test_the_accessor_draws_each_kind_and_refuses_the_figures_of_another(paths, kind):
    ds, _ = rotorsweep.open_result(paths[kind])
    plot = getattr(ds.rotorsweep, FIGURE[kind])()
    assert isinstance(plot, hv.core.Dimensioned)
    hv.renderer("bokeh").get_plot(plot)
    for other in KINDS:
        if other != kind:
            what = result_kinds.KINDS[kind].what
            with pytest.raises(ValueError, match=f"{FIGURE[other]}\\(\\) draws {result_kinds.KINDS[other].what} "
                                                 f".*, not {what} "):
                getattr(ds.rotorsweep, FIGURE[other])()


def test_branch_diagram_draws_stable_solid_unstable_dashed_and_backbones_both_methods(paths):
    ds, _ = rotorsweep.open_result(paths[result_kinds.CONTINUATION])
    plot = ds.rotorsweep.branch_diagram()
    stable, unstable = plot.get(0), plot.get(1)
    assert unstable.last.opts.get("style").kwargs["line_dash"] == "dashed"
    for curves, flag in ((stable, 1), (unstable, 0)):      # each point drawn once, in its own style
        assert sum(np.isfinite(c.dimension_values(1)).sum() for c in curves) == int((ds["stable"] == flag).sum()) > 0
    bb, _ = rotorsweep.open_result(paths[result_kinds.BACKBONE])
    continued, manifold = bb.rotorsweep.backbones().get(0), bb.rotorsweep.backbones().get(1)
    np.testing.assert_array_equal(continued.last.dimension_values(1), bb["frequency_continuation"].values.ravel())
    np.testing.assert_array_equal(manifold.last.dimension_values(1), bb["frequency_manifold"].values.ravel())


def _without(path, tmp_path, name):
    """A copy of a result file with the variable (or attribute) `name` dropped."""
    ds = xr.load_dataset(path)
    ds = ds.drop_vars(name) if name in ds.variables else ds.assign_attrs({name: None})
    ds.attrs = {k: v for k, v in ds.attrs.items() if v is not None}
    out = tmp_path / f"without_{name}.nc"
    ds.to_netcdf(out)
    return out


@pytest.mark.parametrize("kind, name, what", [
    (result_kinds.CONTINUATION, "branch_end", "variable branch_end"),
    (result_kinds.CONTINUATION, "range", "attribute range"),
    (result_kinds.CONTINUATION, "observable", "coordinate observable"),
    (result_kinds.BACKBONE, "master", "variable master"),
    (result_kinds.BACKBONE, "linear_frequency", "variable linear_frequency")])
def test_an_incomplete_result_is_one_line_naming_what_is_missing(paths, kind, name, what, tmp_path, capsys):
    """info, query, report and report --over (issue 36 item 6): no KeyError traceback."""
    bad = _without(paths[kind], tmp_path, name)
    line = f"{bad} is an incomplete {kind} result: {what} missing"
    commands = [["info", bad], ["query", bad], ["report", bad, "-o", tmp_path / "r", "-q"]]
    if kind == result_kinds.CONTINUATION:
        commands.append(["report", paths[result_kinds.BACKBONE], "-o", tmp_path / "o", "--over", bad, "-q"])
    for args in commands:
        assert cli.main([str(a) for a in args]) == cli.EXIT_USAGE
        err = capsys.readouterr().err
        assert line in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("kind, figure", [(k, f) for k, figures in explore.FIGURES.items() for f in figures])
def test_every_figure_of_the_accessor_draws_on_its_kind(paths, kind, figure):
    ds, _ = rotorsweep.open_result(paths[kind])
    where = {"where": {a: ds[a].values.flat[0] for a in explore.row_dims(ds)[1:]}} if figure == "multipliers" else {}
    try:
        plot = getattr(ds.rotorsweep, figure)(**where)
    except ValueError as e:                 # a figure the scene's model has no data for says so
        assert str(e).startswith(f"model {ds.attrs.get('model')}: no ") or "no attractor" in str(e)
        return
    state = hv.renderer("bokeh").get_plot(plot).state
    figures = [state] if hasattr(state, "xaxis") else [f for f in state.select(dict(type=Plot))]
    for fig in figures:
        assert "=" not in fig.title.text and not fig.xaxis[0].axis_label.endswith(("(m)", "[m]"))


@pytest.mark.parametrize("kind", KINDS)
def test_to_frame_has_one_row_per_point_of_every_kind(paths, kind):
    ds, _ = rotorsweep.open_result(paths[kind])
    table = ds.rotorsweep.to_frame()
    dims = explore.row_dims(ds)
    assert len(table) == int(np.prod([ds.sizes[d] for d in dims])) > 0
    assert not any(c.endswith("_m") for c in table.columns)

"""`rotorsweep continue` with quasi-periodic forcing (both forcings of rigid_preloaded on): the
torus branch end to end, in-process, and one point checked against iterates of the stroboscopic
map from its circle (a second method: the map iterated, not the collocation solved)."""
import contextlib
import io
import re

import numpy as np
import pytest

from rotorsweep.pipeline import cli, config, continuation, continuation_result, result_kinds, torus_branches
from tests.reference import torus_half_swing

SCENE = "configs/filipkovsky2016_fig2b_tori.toml"


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """(directory, scene) of the branch from 305 to 308 Hz, its stderr kept in directory/stderr.txt,
    with a progress line at every point solved."""
    d = tmp_path_factory.mktemp("tori")
    text = open(SCENE).read().replace("stop = 315.0", "stop = 308.0")
    (d / "tori.toml").write_text(text)
    stderr = io.StringIO()
    with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stderr(stderr):
        mp.setattr(torus_branches, "PROGRESS_SECONDS", 0.0)
        assert cli.main(["continue", str(d / "tori.toml"), "-o", str(d / "tori.nc"), "--workers", "0"]) in (0, None)
    (d / "stderr.txt").write_text(stderr.getvalue())
    return d, config.parse_config(text).scene


def test_a_torus_branch_shows_its_progress(result):
    """A long torus branch is not silent (issue 38): `continue` in-process shows progress lines for
    the torus branch on its stream and logs them, each naming the parameter reached, the points
    solved, the Fourier modes and the locked ratios passed."""
    d, _ = result
    shown = [line for line in (d / "stderr.txt").read_text().splitlines() if "torus branch:" in line]
    assert len(shown) >= 2
    pattern = (r"torus branch: support_frequency ([0-9.]+) \(\d+% of 305 to 308\) after \S+, (\d+) points solved, "
               r"(\d+) Fourier modes, locked ratios passed: ")
    matches = [re.search(pattern, line) for line in shown]
    assert all(matches)
    reached = [float(m.group(1)) for m in matches]
    assert min(reached) >= 305.0 - 1e-9 and max(reached) <= 308.0 + 1e-9
    solved = [int(m.group(2)) for m in matches]
    assert solved[0] == 1 and solved == sorted(set(solved))
    assert sum("torus branch:" in line for line in open(d / "tori.nc.log")) == len(shown)


def test_the_record_after_the_branch_shows_its_progress(result):
    """What follows the branch (polishing each point, its amplitudes, the events' orbits) is not
    silent either: with PROGRESS_SECONDS 0 each stage counts its items up, logged as shown."""
    d, _ = result
    shown = [line for line in (d / "stderr.txt").read_text().splitlines() if "torus record:" in line]
    n = int(continuation_result.open_result(d / "tori.nc")["branch_points"].values[0])
    for stage in ("polishing points:", "amplitudes of points:"):
        counts = [re.search(rf"torus record: {stage} (\d+) of (\d+) after \S+$", line) for line in shown
                  if stage in line]
        assert [(int(m.group(1)), int(m.group(2))) for m in counts] == [(k, n) for k in range(n)]
    assert sum("torus record:" in line for line in open(d / "tori.nc.log")) == len(shown)


def test_the_result_holds_a_torus_branch_with_stability_and_error(result, capsys):
    d, _ = result
    ds = continuation_result.open_result(d / "tori.nc")
    assert ds["branch_kind"].values.tolist() == [1]
    n = int(ds["branch_points"].values[0])
    assert n >= 2 and ds["parameter"].values[0, n - 1] == pytest.approx(308.0)
    assert (ds["torus_status"].values[0, :n] == 1).all() and (ds["torus_exponent"].values[0, :n] < 0).all()
    assert (ds["stable"].values[0, :n] == 1).all() and (ds["torus_error"].values[0, :n] < 1e-4).all()
    assert ds["piece_branches"].values.tolist() == ["0"] * (n - 1)     # the stability bands: stable throughout
    opened, kind = result_kinds.open_result(d / "tori.nc")
    assert kind.name == result_kinds.CONTINUATION and "torus branch 0" in kind.describe(opened)
    assert cli.main(["info", str(d / "tori.nc")]) in (0, None)
    assert "branch 0: torus" in capsys.readouterr().out
    assert cli.main(["report", str(d / "tori.nc"), "-o", str(d / "report")]) in (0, None)
    assert (d / "report" / "response_y_B.png").exists() and (d / "report" / "torus_exponent.png").exists()


def test_a_torus_point_against_a_long_scipy_transient(result):
    """From the result's state on the circle (orbit_state: u at phase 0), a DOP853 run (rtol
    1e-10) over TRANSIENT shaft turns stays on the torus and covers it densely (irrational
    rotation): its half-swing of y_B, sampled 256 times per turn, is the torus's. Both sample the
    sup from below: the result's in the forcing phase (64 phases, torus_branches docstring), the
    transient in time and phase; a swing varying smoothly over the torus is missed by each by
    ~(pi / 64)^2 / 2 ~ 1e-3 relative at most, hence the tolerance."""
    d, data = result
    ds = continuation_result.open_result(d / "tori.nc")
    k = 1
    j = list(ds["observable"].values).index("y_B")
    half_swing = torus_half_swing(data, ds, k)
    assert ds["amplitude_half_pp"].values[0, k, j] == pytest.approx(half_swing, rel=1e-3)


def test_a_torus_line_that_does_not_start_is_an_empty_branch_with_a_reason(result):
    """A failed start is data: an empty branch ending start_failed, written like any other."""
    from rotorsweep.kernels.continuation import engine

    _, data = result
    pl = continuation.plan(data)
    fam, built = torus_branches.torus_family(data, pl, pl.lines[0], 15)
    run = engine.Run([], [], engine.START_FAILED, "no torus")
    rec = torus_branches.torus_record(data.model, fam, built, run, 0)
    ds = continuation.to_dataset(data, pl, [(pl.lines[0], [rec])], {})
    assert ds["branch_points"].values.tolist() == [0] and ds["branch_end"].values.tolist() == [engine.START_FAILED]
    assert "no torus" in continuation_result.describe(ds)


def test_each_torus_point_records_its_fourier_modes(result, capsys):
    """torus_modes: K of each point's 2K + 1 nodes, matching its non-NaN torus_nodes, within the
    adaptive bounds, with its CF attributes; `info` shows it beside the error estimate."""
    d, scene = result
    ds = continuation_result.open_result(d / "tori.nc")
    n = int(ds["branch_points"].values[0])
    lo, hi = torus_branches.node_bounds(scene)
    modes = ds["torus_modes"].values[0, :n]
    held = (~np.isnan(ds["torus_nodes"].values[0, :n, :, 0])).sum(axis=1)
    assert (held == 2 * modes + 1).all()
    assert ((lo - 1) // 2 <= modes).all() and (modes <= (hi - 1) // 2).all()
    assert ds["torus_modes"].attrs["units"] == "1" and "Fourier modes" in ds["torus_modes"].attrs["long_name"]
    assert cli.main(["info", str(d / "tori.nc")]) in (0, None)
    assert f"Fourier modes {modes.min()}" in capsys.readouterr().out

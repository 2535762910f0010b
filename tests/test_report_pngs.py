"""The report's PNGs drawn in a process of their own (rotorsweep.pipeline.report.pngs) while the HTML is drawn
here: the same pixels as drawn here, failures raised with the drawer's own traceback, the drawer
stopped when the caller fails, and drawing here where there is one CPU, no process to start or
nothing that pickles."""
import importlib
import subprocess
import tempfile

import matplotlib.image as mpimg
import numpy as np
import pytest

from rotorsweep.pipeline import cube
from rotorsweep.pipeline.report import pngs

report = importlib.import_module("rotorsweep.pipeline.report")


def test_the_png_process_draws_the_pixels_drawn_here(tiny_cube, tmp_path):
    """Both ways run the same matplotlib code on the same data (pickled for the second process),
    so the images must be equal to the bit, a point in detail included."""
    ds = cube.open_cube(tiny_cube)
    point = ["speed=63.4", "clearance=19e-6"]
    there = report.make_report(ds, tmp_path / "there", points=[point], parallel=True)
    here = report.make_report(ds, tmp_path / "here", points=[point], parallel=False)
    names = [p.name for p in here["png"]]
    assert names == [p.name for p in there["png"]] and "point_64Hz_19um.png" in names
    assert sorted(p.name for p in (tmp_path / "there").iterdir()) == sorted(p.name for p in (tmp_path / "here").iterdir())
    for name in names:
        a, b = mpimg.imread(tmp_path / "here" / name), mpimg.imread(tmp_path / "there" / name)
        assert a.shape == b.shape and np.array_equal(a, b), name


def _line(data, backend, intervals):
    return report.holoviews().Curve([(0, 0), (1, 1)])


@pytest.fixture
def only_here(monkeypatch):
    """A figure registered in this process only (the drawer's registry lacks it)."""
    fig = report.Figure(name="only_here", filename="only_here.png", title="x", build=_line)
    monkeypatch.setitem(report.registry._FIGURES, fig.name, fig)
    return fig


def test_a_failure_in_the_png_process_is_raised_with_its_traceback(tmp_path, only_here):
    with pytest.raises(RuntimeError, match="(?s)exit status 1.*ValueError: no report figure 'only_here'"):
        with pngs.drawer(True) as draw:
            draw(pngs.CubePngs(None, [], [only_here.name], []), tmp_path)
    assert (tmp_path / "only_here.png").exists()    # drawn here, which takes what the drawer left


def test_what_cannot_be_pickled_is_drawn_here(tmp_path, only_here):
    """The drawer is told there is no job (it would fail, not knowing the figure)."""
    with pngs.drawer(True) as draw:
        draw(pngs.CubePngs(None, [lambda: None], [only_here.name], []), tmp_path)
    assert [p.name for p in tmp_path.iterdir()] == ["only_here.png"]


def test_an_error_here_stops_the_png_process(monkeypatch):
    started = []
    start = pngs._start
    monkeypatch.setattr(pngs, "_start", lambda err_path: started.append((err_path, start(err_path))) or started[-1][1])
    with pytest.raises(ZeroDivisionError):
        with pngs.drawer(True):
            1 / 0
    ((err_path, proc),) = started
    assert proc.returncode == -9                # killed (it was waiting for its job) and reaped
    assert not err_path.parent.exists()         # its temporary directory is gone


def test_one_cpu_no_temporary_directory_or_no_process_to_start_draws_here(monkeypatch):
    monkeypatch.setattr(pngs, "usable_cpus", lambda: 1)
    with pngs.drawer() as draw:
        assert draw is pngs.write_pngs

    def no_room(*args, **kwargs):
        raise OSError(28, "No space left on device")

    with monkeypatch.context() as m:
        m.setattr(tempfile, "mkdtemp", no_room)
        with pngs.drawer(True) as draw:
            assert draw is pngs.write_pngs

    def no_process(*args, **kwargs):
        raise OSError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(subprocess, "Popen", no_process)
    with pngs.drawer(True) as draw:
        assert draw is pngs.write_pngs

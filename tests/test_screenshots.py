"""workflows/screenshots.py: cropping, the missing-browser message, and (where Chromium is
installed) a page rendered, cropped and its JavaScript errors caught."""
import shutil

import matplotlib.image as mpimg
import numpy as np
import pytest

from tests.browser import assert_renders, needs_chromium
from workflows import screenshots


def test_crop_keeps_the_content_and_a_margin(tmp_path):
    img = np.ones((400, 50, 4))
    img[100:150, 10:20, :3] = 0.2                   # content ends at row 149
    mpimg.imsave(tmp_path / "raw.png", img)
    screenshots.crop_to_content(tmp_path / "raw.png", tmp_path / "out.png", margin=16)
    out = mpimg.imread(tmp_path / "out.png")
    assert out.shape[0] == 150 + 16 and out[120, 15, 0] < 0.5


def test_no_browser_says_how_to_get_one(monkeypatch, tmp_path, capsys):
    monkeypatch.delenv("CHROMIUM", raising=False)
    monkeypatch.setattr(shutil, "which", lambda name: None)
    assert screenshots.main([str(tmp_path)]) == 2
    assert "no Chromium found" in capsys.readouterr().err


@pytest.mark.skipif(not any(shutil.which(b) for b in screenshots.BROWSERS), reason="no Chromium installed")
def test_a_page_is_rendered_cropped_and_its_script_errors_reported(tmp_path):
    """A 300 px tall box drawn by the page's script, then an uncaught exception: the PNG holds the
    box (the script ran) and stops below it; the exception is reported."""
    page = tmp_path / "report.html"
    page.write_text('<html><body style="margin:0"><div id="box"></div><div class="figure"></div><script>'
                    'const b = document.getElementById("box"); b.style.height = "300px";'
                    'b.style.background = "rgb(0, 0, 255)"; undefinedFunction();</script></body></html>')
    shot = screenshots.capture(page, tmp_path / "shot.png")
    errors = shot.errors
    assert (shot.rendered, shot.figures) == (0, 1)          # a figure slot bokeh never drew into
    img = mpimg.imread(tmp_path / "shot.png")
    assert 300 <= img.shape[0] <= 300 + 16 + 1
    assert img[150, 100, 2] > 0.9 and img[150, 100, 0] < 0.1         # blue: the script drew it
    assert any("undefinedFunction" in line for line in errors)


@pytest.fixture(scope="module")
def sweep_report(tiny_cube, tmp_path_factory):
    """The report of the suite's tiny real sweep cube (tests/conftest.py) with a point in detail,
    drawn once."""
    from pipeline import cube
    from pipeline.report import make_report
    out = tmp_path_factory.mktemp("sweep") / "report"
    make_report(cube.open_cube(tiny_cube), out, points=["speed=64 clearance=19e-6"], parallel=False)
    return out


@needs_chromium
def test_sweep_report_renders_in_a_browser(sweep_report, tmp_path):
    assert_renders(sweep_report, tmp_path / "shot.png", kind="sweep")

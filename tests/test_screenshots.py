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
    from rotorsweep.pipeline import cube
    from rotorsweep.pipeline.report import make_report
    out = tmp_path_factory.mktemp("sweep") / "report"
    make_report(cube.open_cube(tiny_cube), out, points=["speed=64 clearance=19e-6"], parallel=False)
    return out


@needs_chromium
def test_sweep_report_renders_in_a_browser(sweep_report, tmp_path):
    assert_renders(sweep_report, tmp_path / "shot.png", kind="sweep")


def test_the_comparison_passes_a_moved_or_blurred_page_and_fails_one_missing_a_plot(tmp_path):
    """tests/browser.py's measure without a browser, on the committed backbone reference drawn back
    at page size: itself, moved by 3 and 2 px, or blurred, it matches; with its first plot (rows
    251-579, columns 38-586 of the page, found by drawing that figure blank) made white it does not."""
    from scipy import ndimage

    from tests import browser

    reference = browser.REFERENCES / "backbone.png"
    page = np.kron(browser.grey(reference), np.ones((browser.SCALE, browser.SCALE)))

    def difference(img):
        mpimg.imsave(tmp_path / "shot.png", img, cmap="gray", vmin=0.0, vmax=1.0)
        return browser.difference(tmp_path / "shot.png", reference)

    assert difference(page) == (0.0, 0)
    assert difference(np.roll(page, (3, -2), axis=(0, 1)))[0] <= browser.FRACTION_TOL
    assert difference(ndimage.gaussian_filter(page, 1.0))[0] <= browser.FRACTION_TOL
    blank = page.copy()
    blank[251:580, 38:587] = 1.0
    assert difference(blank)[0] > 2 * browser.FRACTION_TOL


@needs_chromium
def test_a_wide_table_scrolls_inside_a_page_that_fits_the_window(tmp_path):
    """A located-points table of a five-observable continuation has ~20 columns; the report page
    must still fit a 1400 px window (issue 34): its tables and config scroll sideways instead."""
    from rotorsweep.pipeline.report import page

    cols = {f"amplitude half pp of observable {k} [m]": [1.234567890123e-05] * 3 for k in range(24)}
    page.save_html(tmp_path / "report.html", "wide", "<h1>wide</h1>", [], page.columns_html("Located points", cols),
                   "x = " + "1" * 400)
    shot = screenshots.capture(tmp_path / "report.html", tmp_path / "shot.png")
    assert not shot.errors and shot.width <= screenshots.WIDTH, shot

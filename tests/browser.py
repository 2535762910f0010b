"""Opening a report page in headless Chromium (workflows/screenshots.py) from the tests: no
JavaScript errors, every figure rendered. Skipped only where no Chromium is installed."""
import shutil

import pytest

from workflows import screenshots

needs_chromium = pytest.mark.skipif(
    not any(shutil.which(b) for b in screenshots.BROWSERS), reason="no Chromium installed")


def assert_renders(report_dir, png):
    """The report in report_dir opens with no console errors, every figure drawn, nothing wider
    than the window."""
    shot = screenshots.capture(report_dir / "report.html", png)
    assert not shot.errors, shot.errors
    assert shot.figures > 0 and shot.rendered == shot.figures, shot
    assert shot.width <= screenshots.WIDTH, shot

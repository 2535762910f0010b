"""Opening a report page in headless Chromium (workflows/screenshots.py) from the tests: no
JavaScript errors, every figure rendered, and the page looking like its committed reference
screenshot (tests/screenshots/<kind>.png). Skipped only where no Chromium is installed.

The comparison is coarse on purpose: fonts, hinting and antialiasing differ between machines, so
both pages are reduced to the mean grey level of CELL x CELL px cells, the screenshot's cells taken
at every offset up to SHIFT px either way and the best match kept per cell (text a pixel or three
off, locally or everywhere, matches); a cell differs when even that moves by more than CELL_TOL,
and the page differs when, in some WINDOW cells tall stretch, more than FRACTION_TOL of the cells
differ (local: one figure left blank is a small part of a long page), or its height by more than
HEIGHT_TOL. A reference is stored at 1/SCALE of the page's size (grey, its cell means exact to
8-bit rounding), small enough to commit and still readable. References are drawn with the fonts
Debian's chromium brings (its fonts-liberation: Helvetica and Arial drawn as Liberation Sans);
elsewhere text wraps differently and only the rendering is checked. With $UPDATE set (`make
screenshots`) the tests write the references instead of comparing."""
import itertools
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from workflows import screenshots

needs_chromium = pytest.mark.skipif(
    not any(shutil.which(b) for b in screenshots.BROWSERS), reason="no Chromium installed")

REFERENCES = Path(__file__).resolve().parent / "screenshots"
UPDATE = "ROTORSWEEP_UPDATE_SCREENSHOTS"
SCALE = 4
CELL = 32            # px of the page, a multiple of SCALE
SHIFT = 3            # px
WINDOW = 6           # cells: 192 px of the page
# Measured on the three test reports (sweep, continuation, backbone; tests/test_backbone_command.py
# repeats the decisive ones): the same page rendered twice, in a window 1 px narrower or wider, or
# with font hinting none or full, gives the same pixels here, so what another machine changes was
# simulated: antialiasing (the page blurred, Gaussian sigma 1 px), the page moved by up to 3 px in
# x and y, and both at once differ in no cell. One figure of a page left blank (its slot kept; each
# of the 18 figures in turn) differs in 14-71 % of the cells of its worst window: FRACTION_TOL
# sits well below that. CELL_TOL 0.03 (about 30 px of a black 1 px line in a 32 px cell) keeps
# the cells of a blank figure's thin lines and tick labels counted; at 0.05 the sparsest blank
# figure fell to 4.7 % of its window.
CELL_TOL = 0.03
FRACTION_TOL = 0.05
HEIGHT_TOL = CELL
REFERENCE_FONT = "Liberation Sans"

# Text that differs from run to run (none of the test reports shows any today, but a report may
# grow a timing or a path): masked in the compared page's copy, outside its scripts.
RUN_SPECIFIC = re.compile(r"\b\d{4}-\d\d-\d\d[T ]\d\d:\d\d(:\d\d(\.\d+)?)?\S*"     # timestamps
                          r"|(/tmp|/var|/home|/private)/[^\s<\"']+"                # absolute paths
                          r"|\b\d+(\.\d+)? ?(s|ms|min)\b(?=[^<]*</)")               # timings
SCRIPT = re.compile(r"(<script\b.*?</script>)", re.DOTALL | re.IGNORECASE)


def masked_page(html, out):
    """A copy of the page `html` at `out` with its run-specific text replaced by a fixed mark."""
    parts = SCRIPT.split(Path(html).read_text(encoding="utf-8"))
    parts[::2] = [RUN_SPECIFIC.sub("#", text) for text in parts[::2]]      # split keeps scripts at odd indices
    Path(out).write_text("".join(parts), encoding="utf-8")
    return Path(out)


def grey(png):
    """The PNG as an array of grey levels in [0, 1] (ITU-R 601 luma)."""
    import matplotlib.image as mpimg
    img = mpimg.imread(png)
    if img.ndim == 2:
        return img.astype(float)
    return img[..., :3] @ np.array([0.299, 0.587, 0.114])


def cell_means(img, cell):
    """Mean of each cell x cell block (rows and columns past the last whole block left out)."""
    rows, cols = img.shape[0] // cell, img.shape[1] // cell
    return img[:rows * cell, :cols * cell].reshape(rows, cell, cols, cell).mean(axis=(1, 3))


def reference_image(png):
    """The page's grey levels reduced SCALE times (what is committed)."""
    return cell_means(grey(png), SCALE)


def shifted_cell_means(img, cell, shift):
    """The cell means of `img` moved by every (dy, dx) with |dy|, |dx| <= shift px (its edges
    repeated), from one summed-area table."""
    table = np.pad(np.pad(img, shift, mode="edge").cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    rows, cols = img.shape[0] // cell, img.shape[1] // cell
    for dy, dx in itertools.product(range(2 * shift + 1), repeat=2):
        s = table[np.ix_(dy + cell * np.arange(rows + 1), dx + cell * np.arange(cols + 1))]
        yield (s[1:, 1:] - s[:-1, 1:] - s[1:, :-1] + s[:-1, :-1]) / cell ** 2


def difference(shot_png, reference_png):
    """(the largest fraction of cells differing by more than CELL_TOL at their best offset in any
    WINDOW cells tall stretch, height difference [px]) between a page's screenshot and a
    reference stored by save_reference."""
    shot, ref = grey(shot_png), grey(reference_png)
    want = cell_means(ref, CELL // SCALE)
    rows, cols = min(shot.shape[0] // CELL, len(want)), min(shot.shape[1] // CELL, want.shape[1])
    if rows == 0:
        return 1.0, abs(shot.shape[0] - SCALE * ref.shape[0])
    best = np.min([np.abs(got[:rows, :cols] - want[:rows, :cols]) for got in shifted_cell_means(shot, CELL, SHIFT)],
                  axis=0)
    changed = (best > CELL_TOL).mean(axis=1)
    window = min(WINDOW, rows)
    return np.convolve(changed, np.ones(window) / window, mode="valid").max(), abs(shot.shape[0] - SCALE * ref.shape[0])


def save_reference(shot_png, reference_png):
    import matplotlib.image as mpimg
    Path(reference_png).parent.mkdir(parents=True, exist_ok=True)
    mpimg.imsave(reference_png, reference_image(shot_png), cmap="gray", vmin=0.0, vmax=1.0)


def helvetica():
    """The font family that Chromium (fontconfig) draws Helvetica with here, None if unknown."""
    try:
        found = subprocess.run(["fc-match", "-f", "%{family[0]}", "Helvetica"], capture_output=True, text=True,
                               timeout=30)
    except OSError:
        return None
    return found.stdout.strip() or None


def assert_looks_like(shot_png, kind):
    """The screenshot looks like the committed reference of this report kind (or, with $UPDATE
    set, becomes it)."""
    reference = REFERENCES / f"{kind}.png"
    if os.environ.get(UPDATE):
        save_reference(shot_png, reference)
        return
    assert reference.is_file(), f"no reference screenshot {reference}: run `make screenshot-references`"
    font = helvetica()
    if font != REFERENCE_FONT:
        pytest.skip(f"the references are drawn with {REFERENCE_FONT}, this machine draws Helvetica as {font!r}")
    fraction, height = difference(shot_png, reference)
    assert fraction <= FRACTION_TOL and height <= HEIGHT_TOL, (
        f"{kind} report differs from {reference}: {fraction:.2%} of the {CELL} px cells of its worst "
        f"{WINDOW * CELL} px stretch, its height by {height} px (see {shot_png}; if the change is meant, run "
        "`make screenshot-references` and commit tests/screenshots)")


def blank_figure(page, out, index):
    """A copy of the page with its index-th figure slot hidden (kept in the layout, drawn blank):
    a page whose plot is missing."""
    slots = Path(page).read_text(encoding="utf-8").split('<div class="figure">')
    assert len(slots) > index + 1, f"{page}: no figure {index}"
    hidden = '<div class="figure" style="visibility: hidden">'
    before, after = '<div class="figure">'.join(slots[:index + 1]), '<div class="figure">'.join(slots[index + 1:])
    Path(out).write_text(before + hidden + after, encoding="utf-8")
    return Path(out)


def assert_renders(report_dir, png, kind=None):
    """The report in report_dir opens with no console errors, every figure drawn, nothing wider
    than the window, and (kind given) looks like its reference screenshot."""
    page = masked_page(Path(report_dir) / "report.html", Path(png).with_suffix(".html"))
    shot = screenshots.capture(page, png)
    assert not shot.errors, shot.errors
    assert shot.figures > 0 and shot.rendered == shot.figures, shot
    assert shot.width <= screenshots.WIDTH, shot
    if kind:
        assert_looks_like(png, kind)

"""Screenshots of HTML reports in headless Chromium, as a user's browser renders them.

    python -m workflows.screenshots [REPORT_DIR ...] [-o docs/screenshots]

Each REPORT_DIR/report.html is opened offline (file://, no network needed: the reports inline
bokeh) with a fixed window width; the page's JavaScript runs for a virtual 20 s, the page is
captured and cropped below its last non-white row, and the browser's console is searched for
JavaScript errors, which fail the run, as does a figure that bokeh did not render (a probe script
appended to a copy of the page counts them). Defaults: the reports `make demo`, `make fold` and
`make tori` write (a sweep with attractors, a continuation, a torus continuation), into
docs/screenshots/<report dir name>.png.

Chromium is found as $CHROMIUM or chromium, chromium-browser, google-chrome on the PATH (Debian:
`apt-get install chromium`). It is not a dependency of rotorsweep: tests of the bokeh models
(tests/test_report.py: frame sizes, line dashes, hover tools) check the same properties without
a browser; this script shows them as pixels.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import NamedTuple

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_REPORTS = ("out/demo_report", "out/bai2006_fold_report", "out/filipkovsky2016_fig2b_tori_report")
BROWSERS = ("chromium", "chromium-browser", "google-chrome")
WIDTH = 1400
MAX_HEIGHT = 16000     # the window is this tall, then cropped: headless Chromium has no full-page capture
VIRTUAL_TIME_MS = 20000
# console lines of a page's uncaught exceptions and failed loads, as Chromium logs them to stderr
JS_ERROR = re.compile(r"CONSOLE.*(Uncaught|Error)|Failed to load resource", re.IGNORECASE)


class ScreenshotError(Exception):
    """No browser, a report missing, or a page that failed to render (message for the user)."""


def browser():
    """The Chromium executable to use."""
    found = os.environ.get("CHROMIUM") or next((shutil.which(b) for b in BROWSERS if shutil.which(b)), None)
    if not found:
        raise ScreenshotError("no Chromium found (set CHROMIUM, or install it: apt-get install chromium)")
    return found


# appended to a copy of the page: once loaded, the number of bokeh figure slots (div.figure), of
# those holding a rendered bokeh view (an element with a shadow root holding a canvas) and the
# page's width [px] (wider than the window: something is off-screen), on the console
RENDER_PROBE = """<script>
window.addEventListener("load", () => setTimeout(() => {
  const slots = [...document.querySelectorAll("div.figure")];
  const drawn = slots.filter(d => [...d.querySelectorAll("*")].some(
    e => e.shadowRoot && (e.shadowRoot.querySelector("canvas") || e.shadowRoot.querySelector("*"))));
  console.log("rotorsweep-render " + drawn.length + "/" + slots.length + " " + document.documentElement.scrollWidth);
}, 2000));
</script>"""
RENDERED = re.compile(r"rotorsweep-render (\d+)/(\d+) (\d+)")


class Capture(NamedTuple):
    errors: list        # the page's JavaScript errors (lines of the browser's console)
    rendered: int       # figure slots holding a rendered bokeh figure
    figures: int        # figure slots of the page
    width: int          # the page's width [px] in a WIDTH window


def capture(html, png, chromium=None, width=WIDTH, flags=()):
    """Render `html` in headless Chromium into `png`, cropped to the page, in a window `width` px
    wide (`flags`: more Chromium switches); returns a Capture (JavaScript errors, figures rendered
    of the page's figures)."""
    html, png = Path(html).resolve(), Path(png)
    if not html.is_file():
        raise ScreenshotError(f"{html}: no such report page (make it first, e.g. `make demo`)")
    with tempfile.TemporaryDirectory(prefix="rotorsweep-shot-", dir=html.parent) as tmp:
        probed = Path(tmp) / "page.html"        # beside the page: relative links resolve the same
        page = html.read_text(encoding="utf-8")
        end = page.rfind("</body>")      # the last: bokeh's inlined JavaScript holds the string too
        probed.write_text(page[:end] + RENDER_PROBE + page[end:], encoding="utf-8")
        raw = Path(tmp) / "page.png"
        cmd = [chromium or browser(), "--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
               "--no-first-run", "--enable-logging=stderr", "--v=0", f"--user-data-dir={tmp}/profile",
               f"--window-size={width},{MAX_HEIGHT}", f"--virtual-time-budget={VIRTUAL_TIME_MS}",
               *flags, f"--screenshot={raw}", probed.as_uri()]
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
        if not raw.is_file():
            raise ScreenshotError(f"{html}: Chromium wrote no screenshot (exit {done.returncode}): "
                                  f"{done.stderr.strip()[-500:]}")
        png.parent.mkdir(parents=True, exist_ok=True)
        crop_to_content(raw, png)
    counts = RENDERED.search(done.stderr)
    rendered, figures, width = (int(g) for g in counts.groups()) if counts else (0, -1, -1)
    return Capture([line for line in done.stderr.splitlines() if JS_ERROR.search(line)], rendered, figures, width)


def crop_to_content(src, dst, margin=16):
    """Copy the PNG `src` to `dst` without the white rows below its content."""
    import matplotlib.image as mpimg
    import numpy as np

    img = mpimg.imread(src)
    rows = np.flatnonzero((img[..., :3] < 0.98).any(axis=(1, 2)))
    end = min(len(img), (rows[-1] + 1 + margin) if len(rows) else len(img))
    mpimg.imsave(dst, img[:end, :, :3])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("reports", nargs="*", default=list(DEFAULT_REPORTS),
                    help="report directories holding report.html (default: %(default)s)")
    ap.add_argument("-o", "--out", default=str(ROOT / "docs" / "screenshots"), help="where the PNGs go")
    args = ap.parse_args(argv)
    try:
        chromium = browser()
        failed = False
        for report in args.reports:
            png = Path(args.out) / f"{Path(report).name}.png"
            shot = capture(Path(report) / "report.html", png, chromium)
            print(f"{png}: {'JavaScript errors: ' + '; '.join(shot.errors) if shot.errors else 'no JavaScript errors'}"
                  f", {shot.rendered} of {shot.figures} figures rendered, page {shot.width} px wide")
            failed |= bool(shot.errors) or shot.rendered != shot.figures or shot.width > WIDTH
    except ScreenshotError as exc:
        print(f"screenshots: {exc}", file=sys.stderr)
        return 2
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

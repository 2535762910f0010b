"""A long torus branch is not silent (issue 38): `continue` in-process shows progress lines for
the torus branch on its stream and logs them, each naming the parameter reached, the points
solved, the Fourier modes and the locked ratios passed."""
import io
import re

from rotorsweep.pipeline import config, continuation, torus_branches

SCENE = "configs/filipkovsky2016_fig2b_tori.toml"


def test_a_torus_branch_shows_its_progress(tmp_path, monkeypatch):
    monkeypatch.setattr(torus_branches, "PROGRESS_SECONDS", 0.0)    # a line at every point solved
    text = open(SCENE).read().replace("stop = 315.0", "stop = 306.0")
    stream = io.StringIO()
    out = continuation.run(config.parse_config(text), str(tmp_path / "tori.nc"), workers=0, stream=stream)
    shown = [line for line in stream.getvalue().splitlines() if "torus branch:" in line]
    assert len(shown) >= 2
    pattern = (r"torus branch: support_frequency ([0-9.]+) \(\d+% of 305 to 306\) after \S+, (\d+) points solved, "
               r"(\d+) Fourier modes, locked ratios passed: ")
    matches = [re.search(pattern, line) for line in shown]
    assert all(matches)
    reached = [float(m.group(1)) for m in matches]
    assert min(reached) >= 305.0 - 1e-9 and max(reached) <= 306.0 + 1e-9
    solved = [int(m.group(2)) for m in matches]
    assert solved[0] == 1 and solved == sorted(set(solved))
    assert sum("torus branch:" in line for line in open(f"{out}.log")) == len(shown)

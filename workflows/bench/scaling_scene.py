"""The scaling benchmark's scene: the Bai 2006 Fig. 13 grid (configs/bai2006_fig13.toml), or a
reduced one, and how the pipeline cuts it into chunks."""
import math
import re
import statistics

from workflows.bench.common import ROOT

FIG13 = ROOT / "configs" / "bai2006_fig13.toml"
QUICK_SPEED = (10.0, 250.0, 2.0)            # Hz: the Fig. 13 range, 2 Hz steps
QUICK_CLEARANCES = (7.6e-6, 19.0e-6)         # m: the most and the least regular Fig. 13 lines


def scene_config(speed=None, clearances=None, name=None, segment_length=None):
    """The Fig. 13 scene, optionally with another speed axis (start, stop, step) [Hz], other
    clearances [m], name or segment length, attractor diagnostics off: built by editing the TOML text of
    configs/bai2006_fig13.toml and validated by rotorsweep.pipeline.config.parse_config."""
    from rotorsweep.pipeline import config

    # orbits + Floquet only: the scaling of the paper's map, not of the attractor diagnostics
    text = re.sub(r"(?m)^attractor\s*=.*$", "attractor = false", FIG13.read_text())
    if speed is not None:
        start, stop, step = speed
        text, n = re.subn(r"(?m)^speed\s*=.*$",
                          f"speed = {{start = {start!r}, stop = {stop!r}, step = {step!r}}}", text)
        assert n == 1, "configs/bai2006_fig13.toml: no speed axis line"
    if clearances is not None:
        values = ", ".join(repr(float(c)) for c in clearances)
        text, n = re.subn(r"(?m)^clearance\s*=.*$", f"clearance = [{values}]", text)
        assert n == 1, "configs/bai2006_fig13.toml: no clearance axis line"
    if name is not None:
        text, n = re.subn(r'(?m)^name\s*=.*$', f'name = "{name}"', text)
        assert n == 1
    if segment_length is not None:
        text = re.sub(r"(?m)^segment_length\s*=.*$", "", text)
        text = text.replace("[numerics]", f"[numerics]\nsegment_length = {int(segment_length)}", 1)
    return config.parse_config(text, path=f"{FIG13.name} (bench_scaling)", allow_large=True)


def quick_config():
    return scene_config(speed=QUICK_SPEED, clearances=QUICK_CLEARANCES, name="bai2006_fig13_quick")


def full_config():
    return scene_config()


def scene_info(cfg):
    from rotorsweep.pipeline import sweep

    segs = sweep.segments(cfg.scene)
    return dict(name=cfg.data["scene"]["name"], n_points=cfg.n_points,
                axes={k: len(v) for k, v in cfg.axes.items()},
                speed_range=[float(cfg.axes["speed"][0]), float(cfg.axes["speed"][-1])],
                clearances=[float(c) for c in cfg.axes.get("clearance", [])],
                segment_length=cfg.data["numerics"]["segment_length"], n_segments=len(segs),
                config_hash=cfg.hash())


def chunk_plan(cfg, n_workers, chunk_points):
    """(number of chunks, median points per chunk) that rotorsweep.pipeline.sweep.chunks_for makes of the
    scene's segments for n_workers (chunk_points None: the pipeline's default)."""
    from rotorsweep.pipeline import sweep

    chunks = sweep.chunks_for(cfg.scene, sweep.segments(cfg.scene), n_workers, chunk_points)
    sizes = [sum(len(seg) for seg in chunk) for chunk in chunks]
    return len(chunks), int(statistics.median(sizes)) if sizes else 0


def chunk_sizes_for(cfg, n_workers=2):
    """Chunk sizes for the sensitivity runs: one continuation segment per chunk, 8 and 24
    segments per chunk (when that still leaves >= 4 chunks per worker), and one chunk per
    worker; the pipeline's default (None) is measured by the default run."""
    n = cfg.n_points
    seg = cfg.data["numerics"]["segment_length"]
    sizes = [seg]
    sizes += [k * seg for k in (8, 24) if k * seg <= n / (4 * n_workers)]
    sizes.append(int(math.ceil(n / n_workers)))
    return sorted(set(sizes))


def first_point(cfg):
    from rotorsweep.pipeline import sweep

    return dict(sweep.segments(cfg.scene)[0].points[0])

"""The documentation: the generated config reference is current, every public function of
`rotorsweep` has an example in its docstring and the examples run (doctest), and the docs
site's sources name only pages that exist."""
import doctest
import inspect
import io
import re
import sys
import tempfile
from pathlib import Path

import pytest

import rotorsweep.pipeline as pipeline
import rotorsweep
from rotorsweep.pipeline import config, config_reference, units
from rotorsweep.kernels import models

DOCS = Path(__file__).resolve().parent.parent / "docs"

# The cube the examples read as `cube_path` (what `rotorsweep.run`'s own example writes, with the
# attractor diagnostics): 79 Hz stable, 82 Hz past the period doubling at 80.88 Hz, 7.6 um.
SCENE = """
[scene]
name = "doc_examples"
model = "jeffcott_clearance"
[bearing]
stiffness = "bai2006"
[sweep]
speed = [79.0, 82.0]
clearance = ["7.6 um"]
[analysis]
attractor = true
lyapunov_max_periods = 200
"""


def public_functions():
    """rotorsweep's public functions and those of its explore module (the notebook figures)."""
    top = [(name, getattr(rotorsweep, name)) for name in rotorsweep.__all__
           if inspect.isfunction(getattr(rotorsweep, name))]
    explore = [(f"explore.{name}", f) for name, f in vars(rotorsweep.explore).items()
               if inspect.isfunction(f) and not name.startswith("_") and f.__module__ == rotorsweep.explore.__name__]
    return top + explore


def test_the_committed_config_reference_is_current():
    assert config_reference.OUTPUT.read_text() == config_reference.markdown(), \
        "docs/reference/config.md is stale: run python -m rotorsweep.pipeline.config_reference"


def test_the_config_reference_names_every_key_of_every_model():
    text = config_reference.markdown()
    for name in config.MODELS:
        sections, axes = config.model_schema(models.get(name))
        assert f"## Model `{name}`" in text
        assert all(f"`sweep.{axis}`" in text for axis in axes)
        assert all(f"`{section}.{key}`" in text for section, keys in sections.items() for key in keys)


@pytest.mark.parametrize("name, function", public_functions())
def test_every_public_function_has_an_example(name, function):
    assert function.__doc__ and ">>>" in function.__doc__, f"rotorsweep.{name} has no example in its docstring"


@pytest.fixture(scope="module")
def cube_path():
    path = rotorsweep.run(rotorsweep.parse_config(SCENE), f"{tempfile.mkdtemp()}/doc_examples.nc",
                          workers=1, progress=False)
    return str(path)


@pytest.fixture(scope="module")
def continuation_path():
    """The Duffing resonance curve of the continue command's tests, in this process (~1 s)."""
    from tests.test_continue_command import DUFFING
    return str(pipeline.continue_branches(rotorsweep.parse_config(DUFFING), f"{tempfile.mkdtemp()}/duffing.nc",
                                          workers=0))


@pytest.fixture(scope="module")
def backbone_path():
    """asymmetric5's axial mode at 5 amplitudes, in this process (~3 s): a linearization and a
    shaft speed, for the Campbell diagram and the mode shapes."""
    from tests.test_backbone_command import scene
    cfg = rotorsweep.parse_config(scene(modes="1", amplitude_max=4e-6, amplitude_points=5, surface_mode=2))
    return str(pipeline.backbones(cfg, f"{tempfile.mkdtemp()}/axial.nc", workers=0))


def run_examples(obj, name, globs):
    """Failures of obj's doctest examples (0: all pass); the report goes to the assertion."""
    out = io.StringIO()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in doctest.DocTestFinder(recurse=False).find(obj, name, globs=globs):
        runner.run(test, out=out.write)
    return runner.failures, out.getvalue()


@pytest.mark.parametrize("name, function", public_functions())
def test_the_examples_of_the_public_functions_run(name, function, cube_path, continuation_path, backbone_path):
    module = sys.modules[function.__module__]
    failures, report = run_examples(function, f"rotorsweep.{name}",
                                    {**vars(module), "rotorsweep": rotorsweep, "cube_path": cube_path,
                                     "continuation_path": continuation_path, "backbone_path": backbone_path})
    assert failures == 0, report


def test_the_unit_examples_run():
    failures, tried = doctest.testmod(units, optionflags=doctest.ELLIPSIS)
    assert tried > 0 and failures == 0


def test_every_page_of_the_site_is_in_a_toctree():
    """Sphinx warns (an error with -W) about a page in no toctree; checked here without Sphinx."""
    index = (DOCS / "index.md").read_text() + (DOCS / "benchmarks.md").read_text()
    pages = [p.relative_to(DOCS).with_suffix("").as_posix() for p in DOCS.rglob("*.md")
             if "_build" not in p.parts and p.parent.name != "benchmarks"]
    missing = [p for p in pages if p not in ("index", "benchmarks") and f"\n{p}\n" not in index]
    assert not missing, f"pages in no toctree of docs/index.md: {missing}"


def test_the_speed_page_copies_no_measured_number():
    """Numbers live on the benchmark pages (written from their JSON); docs/speed.md includes their
    headline sections instead of repeating them by hand (issue 37)."""
    prose = re.sub(r"```.*?```", "", (DOCS / "speed.md").read_text(), flags=re.DOTALL)     # the includes
    measured = re.findall(r"\d+(?:\.\d+)?\s?(?:x|s|ms|us|ns|%|MiB|GiB|points/s)(?![\w-])", prose)
    assert not measured, f"docs/speed.md repeats benchmark numbers: {measured}"

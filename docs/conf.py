"""Sphinx configuration of the documentation site (`make docs`: warnings are errors).

Pages are Markdown (myst-parser): the guides, the model pages, the generated config reference
(`python -m rotorsweep.pipeline.config_reference`), the gallery and the benchmark pages as the benchmarks write
them; the API reference comes from the docstrings of `rotorsweep` (autodoc)."""
# autodoc imports the installed package (`make docs` installs the checkout editable): its names
# (rotorsweep.pipeline, rotorsweep.kernels) map to the checkout's folders only through an install

project = "rotorsweep"
author = "rotorsweep contributors"
extensions = ["myst_parser", "sphinx.ext.autodoc"]
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build"]
myst_heading_anchors = 3           # links to a section: (page.md#section-title)
html_theme = "alabaster"
html_static_path = []
autodoc_member_order = "bysource"

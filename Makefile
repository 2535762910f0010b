# The README's two commands: `make demo` and `make test`. Each installs what it needs into .venv.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo docs test test-slow check-cf screenshots screenshot-references upgrade bench bench-scaling bench-atlas bench-chunk-plans bench-attractor bench-revisions bench-extrema bench-continuation bench-reductions bench-compile bench-backbone bench-models bench-latency fig13 cascade fold tori backbone clean

# CONSTRAINTS: the versions the tests passed with (empty: the newest versions pyproject allows)
CONSTRAINTS ?= constraints.txt

$(STAMP): pyproject.toml $(CONSTRAINTS)
	@echo "== installing rotorsweep and its dependencies into $(VENV) (about 2 minutes the first time)"
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install $(if $(CONSTRAINTS),-c $(CONSTRAINTS)) -e ".[test]"
	touch $(STAMP)

# the documentation site: Sphinx with myst-parser (the docs extra), warnings as errors
DOCS_STAMP := $(VENV)/.docs-installed

$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet $(if $(CONSTRAINTS),-c $(CONSTRAINTS)) -e ".[test,docs]"
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)  ## the documentation site -> docs/_build/html/index.html (config reference regenerated first)
	$(BIN)/python -m rotorsweep.pipeline.config_reference
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

demo: $(STAMP)  ## demo sweep on a local Dask cluster -> out/demo.nc and out/demo_report/
	$(BIN)/rotorsweep run configs/demo.toml -o out/demo.nc --overwrite --report out/demo_report

test: $(STAMP)  ## default test suite (< 15 min on 2 cores)
	$(BIN)/python -m pytest -q -m "not slow"

test-slow: $(STAMP)  ## long tests (full sweeps, cascades)
	$(BIN)/python -m pytest -q -m slow

fig13: $(STAMP)  ## the Bai 2006 Fig. 13 sweep (2401 speeds x 5 clearances)
	$(BIN)/rotorsweep run configs/bai2006_fig13.toml -o out/bai2006_fig13.nc --overwrite --report out/bai2006_fig13_report

cascade: $(STAMP)  ## 19 um route to chaos, attractors swept up and down, with the 28 Hz point in detail
	$(BIN)/rotorsweep run configs/bai2006_cascade.toml -o out/bai2006_cascade.nc --overwrite
	$(BIN)/rotorsweep report out/bai2006_cascade.nc -o out/bai2006_cascade_report --point speed=28

fold: $(STAMP)  ## Bai 2006 by continuation: the 7.6 um fold pair, the 19 um cascade's branches (~1 min)
	$(BIN)/rotorsweep continue configs/bai2006_fold.toml -o out/bai2006_fold.nc --overwrite --report out/bai2006_fold_report

tori: $(STAMP)  ## Filipkovsky 2016 Fig. 2b's quasi-periodic stretch: the torus branch with its locked 5/4 orbit (~20 s of CPU)
	$(BIN)/rotorsweep continue configs/filipkovsky2016_fig2b_tori.toml -o out/filipkovsky2016_fig2b_tori.nc --overwrite --report out/filipkovsky2016_fig2b_tori_report

backbone: $(STAMP)  ## Filipkovsky 2010 nonlinear normal modes: manifold vs continuation backbones of both rotors (~2 min)
	$(BIN)/rotorsweep backbone configs/filipkovsky2010_axial.toml -o out/filipkovsky2010_axial_backbone.nc --overwrite --report out/filipkovsky2010_axial_backbone_report
	$(BIN)/rotorsweep backbone configs/filipkovsky2010_symmetric.toml -o out/filipkovsky2010_symmetric_backbone.nc --overwrite --report out/filipkovsky2010_symmetric_backbone_report

bench: $(STAMP)  ## work-precision and baseline benchmarks -> docs/benchmarks/
	$(BIN)/python -m workflows.bench.kernels

check-cf: $(STAMP)  ## CF checks of every result kind with cfchecker and the IOOS compliance-checker (needs libudunits2: apt-get install libudunits2-0)
	$(BIN)/python -m pip install --quiet $(if $(CONSTRAINTS),-c $(CONSTRAINTS)) -e ".[test,cf]"
	$(BIN)/python -c "import cfchecker.cfchecks, compliance_checker.runner"  # fails here, not as skipped tests, without udunits2
	$(BIN)/python -m pytest -q -k cf_checkers tests/test_cube.py tests/test_continue_command.py tests/test_backbone_command.py tests/test_torus_points.py

screenshots: demo fold tori screenshot-references  ## the demo, fold and torus-continuation reports in headless Chromium (apt-get install chromium) -> docs/screenshots/*.png, and the tests' references
	$(BIN)/python -m workflows.screenshots out/demo_report out/bai2006_fold_report out/filipkovsky2016_fig2b_tori_report -o docs/screenshots

screenshot-references: $(STAMP)  ## the reference screenshots the browser tests compare with (sweep, continuation, backbone, modes report; ~3 min) -> tests/screenshots/*.png
	ROTORSWEEP_UPDATE_SCREENSHOTS=1 $(BIN)/python -m pytest -q -k renders_in_a_browser tests/test_screenshots.py tests/test_continue_command.py tests/test_backbone_command.py tests/test_modes_report.py

bench-scaling: $(STAMP)  ## 1 vs 2 workers, chunk sizes, memory of the Fig. 13 sweep (5 repeats, ~7 min, quiet machine) -> docs/benchmarks/scaling.*
	$(BIN)/python -m workflows.bench.scaling --repeats 5

bench-latency: $(STAMP)  ## tour commands and small continuations end to end, before (74f5cb3) and after, median of 5 (~5 min quiet; reports with ARGS=--reports) -> docs/benchmarks/latency.*
	$(BIN)/python -m workflows.bench.latency $(ARGS)

bench-chunk-plans: $(STAMP)  ## per-point cost spread of Fig. 13 (orbits, attractors) and the guided chunk plans simulated on it (~1 min) -> docs/benchmarks/chunk_plans.*
	$(BIN)/python -m workflows.bench.chunk_plans

bench-revisions: $(STAMP)  ## per-point cost before/after the model registry (cc006f3 vs HEAD, one run) -> docs/benchmarks/revisions.*
	$(BIN)/python -m workflows.bench.revisions

bench-extrema: $(STAMP)  ## Fig. 13 per-point CPU time before (aace0b1, sampled means) and after the exact extrema, orbits only and with attractors, 7 interleaved rounds (~5 min) -> docs/benchmarks/extrema.*
	$(BIN)/python -m workflows.bench.extrema

bench-continuation: $(STAMP)  ## pseudo-arclength continuation vs a scipy peer, Duffing resonance curve (~1 min) -> docs/benchmarks/continuation.*
	$(BIN)/python -m workflows.bench.continuation

bench-reductions: $(STAMP)  ## rigid_preloaded reductions (balanced, one frequency, cubic law) vs the fuller model (~1 min) -> docs/benchmarks/reductions.*
	$(BIN)/python -m workflows.bench.reductions

bench-backbone: $(STAMP)  ## manifold vs continuation backbones: cost and agreement per mode of both 2010 rotors (~1 min) -> docs/benchmarks/backbone.*
	$(BIN)/python -m workflows.bench.backbone

bench-models: $(STAMP)  ## rigid_preloaded, symmetric4, asymmetric5: a point vs scipy DOP853, right-hand side vs C -O3 (~3 min) -> docs/benchmarks/models.*
	$(BIN)/python -m workflows.bench.models

bench-compile: $(STAMP)  ## cold and warm first result per model, this tree (added to the revisions in compile.json; ~5 min on 2 cores) -> docs/benchmarks/compile.*
	$(BIN)/python -m workflows.bench.compile --keep

bench-attractor: $(STAMP)  ## attractor diagnostics on Fig. 13 (full grid) and the cascade: cost and accuracy of each shortcut (~10 min on a quiet 2-core machine) -> docs/benchmarks/attractor_cost.*
	$(BIN)/python -m workflows.attractor_cost

clean:
	rm -rf out .pytest_cache docs/_build

upgrade:  ## newest allowed versions: fresh venv without constraints, the tests, then constraints.txt from what passed
	rm -rf $(VENV)
	$(MAKE) CONSTRAINTS= test
	(head -2 constraints.txt; $(BIN)/python -m pip freeze --exclude-editable) > constraints.txt.new
	mv constraints.txt.new constraints.txt

bench-atlas: $(STAMP)  ## the 4-D atlas (768,320 points): phases, cube size, write and read times, memory (~5 min on 2 quiet cores, 10.5 min under load) -> docs/benchmarks/atlas.*
	$(BIN)/python -m workflows.bench.atlas

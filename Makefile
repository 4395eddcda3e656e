# citysim: every target creates .venv on first use, so a fresh clone needs only python3.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# the test tools (pytest, xdist, hypothesis, ruff) only for the targets that use them: make demo
# installs what the simulator needs and no more (about 6 s of a fresh clone's demo)
TEST_STAMP := $(VENV)/.installed-test
# the docs tools (MkDocs, Material, mkdocstrings) only for the docs site
DOCS_STAMP := $(VENV)/.installed-docs

.PHONY: install demo demo-night test test-slow bench bench-night lint docs results results-check clean

install: $(STAMP)

$(STAMP): pyproject.toml
	@echo "installing citysim and what it needs into $(VENV) (once, or after pyproject.toml changes; about a minute on a fresh clone)"
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	@echo "  pip: installing the simulator's packages (numpy, opencv, pymunk, numba, ...)"
	$(PY) -m pip install --quiet -e .
	touch $(STAMP)
	@echo "  installed"

$(TEST_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(TEST_STAMP)

$(DOCS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e '.[docs]'
	touch $(DOCS_STAMP)

# suburban_night: the whole night in fast mode (the shipped sensor model) for always_on, oracle, pir,
# schedule and detector_located, its first minute again at full fidelity as the check, and the year's figures.
# Prints each table; ends with the paths of results/demo/night/report.html and .../year/report.html.
demo: $(STAMP)
	@echo "demo: starting Python (the first run also compiles the renderer's and detector's kernels, cached after)"
	$(PY) -m experiments.demo

# The same with every controller of the scenario over the whole night.
demo-night: $(STAMP)
	$(PY) -m experiments.demo --controllers all

# one worker per core; a test file stays on one worker, so its module fixtures run once. The tests
# marked slow (real processes signalled, Dask clusters, cities, renders of a minute) are
# `make test-slow`, which CI runs too: together they would pass the 5 minutes the suite is held to
test: $(TEST_STAMP)
	$(PY) -m pytest -n auto --dist loadfile -m "not slow"

test-slow: $(TEST_STAMP)
	$(PY) -m pytest -n auto --dist loadfile -m slow

# Figures, not pass/fail: detector vs OpenCV's floor, renderer, simulation speed, sweep scaling.
bench: $(STAMP)
	$(PY) -m experiments.bench

# Every controller over the whole of suburban_night (28,800 simulated seconds) on 2 workers: long.
bench-night: $(STAMP)
	$(PY) -m experiments.bench --night

# The docs site (docs/, mkdocs.yml) into site/, every warning an error; the reference pages are
# written from the code by experiments/docs_site/hook.py during the build.
docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict

# docs/results/ (the results page and its figures, the README's headline among them) from the
# result files committed in experiments/results/
results: $(STAMP)
	$(PY) -m experiments.results

# fails when docs/results/ is not what `make results` would write
results-check: $(STAMP)
	$(PY) -m experiments.results --check

lint: $(TEST_STAMP)
	$(VENV)/bin/ruff check detector citysim experiments tests

clean:
	rm -rf $(VENV) results site .pytest_cache

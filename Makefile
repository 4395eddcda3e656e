# citysim: every target creates .venv on first use, so a fresh clone needs only python3.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# the test tools (pytest, xdist, hypothesis, ruff) only for the targets that use them: make demo
# installs what the simulator needs and no more (about 6 s of a fresh clone's demo)
TEST_STAMP := $(VENV)/.installed-test

.PHONY: install demo demo-night test bench bench-night lint clean

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

# suburban_night: the whole night in fast mode (the shipped sensor model) for always_on, oracle, pir,
# schedule and detector_located, its first minute again at full fidelity as the check, and the year's figures.
# Prints each table; ends with the paths of results/demo/night/report.html and .../year/report.html.
demo: $(STAMP)
	@echo "demo: starting Python (the first run also compiles the renderer's and detector's kernels, cached after)"
	$(PY) -m experiments.demo

# The same with every controller of the scenario over the whole night: about 5.5 minutes on 2 cores (see README).
demo-night: $(STAMP)
	$(PY) -m experiments.demo --controllers all

# one worker per core; a test file stays on one worker, so its module fixtures run once
test: $(TEST_STAMP)
	$(PY) -m pytest -n auto --dist loadfile

# Figures, not pass/fail: detector vs OpenCV's floor, renderer, simulation speed, sweep scaling.
bench: $(STAMP)
	$(PY) -m experiments.bench

# Every controller over the whole of suburban_night (28,800 simulated seconds) on 2 workers: long.
bench-night: $(STAMP)
	$(PY) -m experiments.bench --night

lint: $(TEST_STAMP)
	$(VENV)/bin/ruff check detector citysim experiments tests

clean:
	rm -rf $(VENV) results .pytest_cache

# citysim: every target creates .venv on first use, so a fresh clone needs only python3.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: install demo test bench bench-night lint clean

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

# A real scenario through every controller: about 10 simulated minutes of a suburban night.
# Ends with results/demo/report.html (plots, figures, what they mean); its path is printed last.
demo: $(STAMP)
	$(VENV)/bin/citysim run scenarios/suburban_night.yaml --out results/demo --duration 600

# one worker per core; a test file stays on one worker, so its module fixtures run once
test: $(STAMP)
	$(PY) -m pytest -n auto --dist loadfile

# Figures, not pass/fail: detector vs OpenCV's floor, renderer, simulation speed, sweep scaling.
bench: $(STAMP)
	$(PY) -m experiments.bench

# Every controller over the whole of suburban_night (28,800 simulated seconds) on 2 workers: long.
bench-night: $(STAMP)
	$(PY) -m experiments.bench --night

lint: $(STAMP)
	$(VENV)/bin/ruff check detector citysim experiments tests

clean:
	rm -rf $(VENV) results .pytest_cache

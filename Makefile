# The two commands: `make run` (the paper scene, end to end) and `make test`.
# Every target builds its own virtual environment in .venv from pyproject.toml when needed.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
SCENE  ?= configs/paper-2009.toml
ARGS   ?=

export MPLBACKEND := Agg
export PYTHONHASHSEED := 0

.PHONY: setup run test test-fast test-slow bench sweep readme clean \
        roughness dmw interface calibrate simulate accuracy report identify sensitivity

setup: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e .
	touch $(STAMP)

## the main job: the paper scene through every stage, on a local dask cluster
run: $(STAMP)
	$(BIN)/hdi run $(SCENE) $(ARGS)

## the tests: one pytest session over the whole suite, slow tests included (CI runs this).
## Its closing line ("N passed ...") counts what ran; exit code 5 (no test collected) fails.
test: $(STAMP)
	$(BIN)/python -m pytest -q tests

## the quick suite for development: everything but the tests marked slow
test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow" tests

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m slow tests

## speed and memory: medians and ratios against baselines measured in the same run
bench: $(STAMP)
	$(BIN)/python -m benchmarks.run --out benchmarks/results/bench.json

## a larger default grid: paper protrusions x 3 roughness sets x 3 damping ratios
sweep: $(STAMP)
	$(BIN)/hdi sweep configs/sweep-3x3.toml $(ARGS)

## rewrite the README's generated comparison section and figures from the last `make run`
readme: $(STAMP)
	$(BIN)/hdi report $(SCENE) --readme README.md

## parameter studies: identify the free [recon] parameters from the paper's targets; their sensitivity
roughness dmw interface calibrate simulate accuracy report identify sensitivity: $(STAMP)
	$(BIN)/hdi $@ $(SCENE) $(ARGS)

clean:
	rm -rf results .pytest_cache

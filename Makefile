# The two commands: `make run` (the paper scene, end to end) and `make test`.
# Every target builds its own virtual environment in .venv from uv.lock (pyproject.toml) when needed.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
# `make run` runs the scene that meets the most paper checks over 8 DMW realisations: the identified one
# (the bulge's air bearing, the meniscus-formation time, docs/results.md, "Reproducing the paper")
SCENE  ?= configs/paper-2009-identified.toml
ARGS   ?=
# optional extras (pyproject.toml) that `make setup` adds to .venv: `make setup EXTRAS="units cluster"`
EXTRAS ?=

# The installer: uv at the version below, installed from PyPI by pip (nothing needs to be preinstalled
# but Python); it installs exactly the versions of uv.lock (--locked: a uv.lock behind pyproject.toml is
# an error; run `uv lock`). `make UV=uv ...` uses another uv. Without uv (pip cannot install it) the
# targets fall back to pip, unlocked. pip installs uv once per machine and version, into the user's
# cache (BOOT_CACHE, beside uv's own package cache), and .bootstrap is a link to it: a second clone
# starts from it instead of pip's 3-5 s (docs/performance.md, section "The first run").
UV_VERSION := 0.13.9
BOOT   := .bootstrap
BOOT_CACHE ?= $(or $(XDG_CACHE_HOME),$(if $(HOME),$(HOME)/.cache,.cache))/hdi/uv-$(UV_VERSION)
UV     ?= $(BOOT)/bin/uv
# `make run` gets the pipeline's dependencies; `make test` adds the `test` extra (pytest, hypothesis,
# compliance-checker, cf_units). --inexact: one does not uninstall what the other added.
RUN_STAMP  := $(VENV)/.installed-run
TEST_STAMP := $(VENV)/.installed-test

export MPLBACKEND := Agg
export PYTHONHASHSEED := 0
export UV_PYTHON_DOWNLOADS := never
# Bytecode: only for what runs. Where PYTHONDONTWRITEBYTECODE is set (as on the machines this project is
# developed on) Python never caches it: every fresh process (each `hdi` command, each dask process
# worker, each test that starts one) then compiled ~300 modules again, 2-5 s of its start. Compiling the
# whole environment at install (UV_COMPILE_BYTECODE) took 14.7 s for 6,489 files of which a run imports
# ~300; so the make targets let Python write the .pyc of what they import, lazily (an empty value:
# writing on), and the later processes, make's or not, start from them (docs/performance.md, section "The first run").
export UV_COMPILE_BYTECODE := 0
export PYTHONDONTWRITEBYTECODE :=

# The stages: one make target per module of pipeline/stages/ (the runner discovers the stages there and
# each module is named after its stage, tests/structure/test_registries.py): a new stage module is a new target
STAGES := $(sort $(basename $(notdir $(filter-out %/__init__.py,$(wildcard pipeline/stages/*.py)))))

.PHONY: setup run test test-fast test-slow bench sweep readme variants docs clean $(STAGES)

## the environment alone; with EXTRAS, those extras added to it (each `--extra NAME` of uv sync; kept by
## later targets, which sync --inexact)
setup: $(RUN_STAMP)
ifneq ($(strip $(EXTRAS)),)
	$(call install,$(foreach e,$(EXTRAS),--extra $(e)),[$(subst $(SPACE),$(COMMA),$(strip $(EXTRAS)))])
endif

COMMA := ,
SPACE := $(subst ,, )
# uv into BOOT_CACHE unless it is there (pip into a temporary folder renamed into place: two installs at
# once both succeed), then .bootstrap linked to it
define bootstrap
{ [ -x "$(BOOT_CACHE)/bin/uv" ] || { mkdir -p "$(dir $(BOOT_CACHE))" && tmp=$$(mktemp -d "$(BOOT_CACHE).XXXXXX") && \
  { $(PYTHON) -m pip install --quiet --disable-pip-version-check --no-deps --no-compile --target "$$tmp" \
      "uv==$(UV_VERSION)" && { mv -T "$$tmp" "$(BOOT_CACHE)" 2>/dev/null || rm -rf "$$tmp"; } \
    || { rm -rf "$$tmp"; false; }; }; }; } && rm -rf $(BOOT) && ln -s "$(BOOT_CACHE)" $(BOOT)
endef

# $(1): uv sync options, $(2): the pip extra of the fallback. (First the metadata setuptools left in the
# clone when it built the editable install: the clone's root is on the path of uv_build's editable install,
# so a stale hdi_dynamics.egg-info there would answer for the distribution: its version, its `hdi` entry point.)
define install
	@rm -rf hdi_dynamics.egg-info
	@if [ -x "$(UV)" ] || $(bootstrap); then \
	    "$(UV)" sync --locked --inexact --python $(PYTHON) $(1); \
	else \
	    echo "make: could not install uv; installing with pip instead (versions not locked)"; \
	    test -x $(BIN)/python || $(PYTHON) -m venv $(VENV); \
	    $(BIN)/python -m pip install --quiet -e ".$(2)"; \
	fi
endef

$(RUN_STAMP): pyproject.toml uv.lock Makefile
	$(call install,)
	touch $@

$(TEST_STAMP): pyproject.toml uv.lock Makefile
	$(call install,--extra test,[test])
	touch $@ $(RUN_STAMP)

## the main job: the paper scene through every stage, on a local dask cluster
run: $(RUN_STAMP)
	$(BIN)/hdi run $(SCENE) $(ARGS)

## the tests: one pytest session over the whole suite, slow tests included (CI runs this).
## Its closing line ("N passed ...") counts what ran; exit code 5 (no test collected) fails.
test: $(TEST_STAMP)
	$(BIN)/python -m pytest -q tests

## the quick suite for development: everything but the tests marked slow
test-fast: $(TEST_STAMP)
	$(BIN)/python -m pytest -q -m "not slow" tests

test-slow: $(TEST_STAMP)
	$(BIN)/python -m pytest -q -m slow tests

## speed and memory: medians and ratios against baselines measured in the same run; each row records the
## load average and CPUs at its start and end, NOISY when it started above load 0.75 per CPU (1.5 on 2 cores).
## BENCH_STUDY=0 make bench leaves out the identify and sensitivity rows (most of the time): under 15 min.
bench: $(RUN_STAMP)
	$(BIN)/python -m benchmarks.run --out benchmarks/results/bench.json

## a larger default grid: paper protrusions x 3 roughness sets x 3 damping ratios
sweep: $(RUN_STAMP)
	$(BIN)/hdi sweep configs/sweep-3x3.toml $(ARGS)

## rewrite the generated comparison section of docs/results.md and its figures from the last `make run`
readme: $(RUN_STAMP)
	$(BIN)/hdi report $(SCENE) --readme docs/results.md

## rewrite the generated "Model variants" table of docs/model.md from the registries (tests/structure/test_variants.py)
variants: $(RUN_STAMP)
	$(BIN)/python -c "from pipeline.config.variants_table import write_variants_table; write_variants_table('docs/model.md')"

## one stage (and what it needs) on the scene: `make NAME` is `hdi NAME $(SCENE)` (sweep and identify: their own scenes)
$(filter-out sweep identify,$(STAGES)): $(RUN_STAMP)
	$(BIN)/hdi $@ $(SCENE) $(ARGS)

## the API reference (docs/api/: the Python API, every physics law, the gallery of docs/examples/ and
## docs/experiments/) as HTML in build/docs/ (git-ignored); warnings are errors. `make test` builds it too
## (tests/structure/test_api_reference.py)
docs: $(TEST_STAMP)
	$(BIN)/sphinx-build -b html -W --keep-going -q docs/api build/docs
	@echo "make docs: build/docs/index.html"

## parameter studies: identify the free [recon] parameters from the paper's targets (their sensitivity:
## `make sensitivity`, a stage target above)
# The identification of configs/paper-2009-identified.toml: on the closed-form bulge scene (with p_pad free,
# the Reynolds scene would re-solve its bulge table for every candidate); it writes
# results/paper-2009-bulge/identified.toml (nothing in configs/; to write a copy there, name it:
# make identify ARGS="--write-scene configs/paper-2009-bulge-identified.toml")
IDENTIFY_SCENE ?= configs/paper-2009-bulge.toml
identify: $(RUN_STAMP)
	$(BIN)/hdi identify $(IDENTIFY_SCENE) $(ARGS)

clean:
	rm -rf results .pytest_cache

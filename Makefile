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
# worker, each test that starts one) then compiled ~900 modules again, ~4.5 s of CPU of its start. Compiling
# the whole environment at install (UV_COMPILE_BYTECODE) took 14.7 s for 6,489 files of which a run imports
# ~1,300; so every install imports what the commands import (below) with writing on (an empty
# value), and the make targets let Python write the .pyc of anything else they import, lazily: the later
# processes, make's or not, start from cached bytecode whatever the user's shell sets (docs/performance.md,
# section "Start-up whatever the shell").
export UV_COMPILE_BYTECODE := 0
export PYTHONDONTWRITEBYTECODE :=
# What the set-up imports, in two processes at once (on two cores ~9 s of the 14 s they took one after the
# other in one process, cold, at the cost of ~1 s of CPU for the modules both compile; docs/performance.md,
# section "The set-up's bytecode and numba's implementations"): BYTECODE_IMPORTS, every module of the package
# (an `hdi` command imports most of them: the CLI, the stage registry, the API) and the ~70 modules of
# numba's implementations that numba imports when a process first loads or compiles a kernel (its CPU
# target's refresh: without their bytecode each command with a kernel compiled them again, ~0.5-1 s of CPU);
# BYTECODE_LAZY, the third-party modules the package imports inside functions (tests/structure/
# test_bytecode.py checks both lists against the sources and numba)
BYTECODE_IMPORTS := import importlib, pkgutil, pipeline; \
  [importlib.import_module(m.name) for m in pkgutil.walk_packages(pipeline.__path__, "pipeline.")]; \
  import numba.core.boxing, numba.core.runtime.context; \
  from numba.core.registry import cpu_target; cpu_target.target_context.refresh()
BYTECODE_LAZY := import ContactMechanics, ContactMechanics.Optimization, SALib.analyze, SALib.sample, \
  SurfaceTopography, SurfaceTopography.Exceptions, SurfaceTopography.IO, SurfaceTopography.Support.UnitConversion, \
  distributed, distributed.comm, matplotlib.axes, matplotlib.figure, netCDF4, numpy.linalg, scipy.integrate, \
  scipy.interpolate, scipy.linalg, scipy.ndimage, scipy.optimize, scipy.signal, scipy.special, tqdm.auto, \
  tqdm.contrib.logging, xarray, xarray.namedarray.pycompat

# The stages: one make target per module of pipeline/stages/ (the runner discovers the stages there and
# each module is named after its stage, tests/structure/test_registries.py): a new stage module is a new target
STAGES := $(sort $(basename $(notdir $(filter-out %/__init__.py,$(wildcard pipeline/stages/*.py)))))

.PHONY: setup run test test-fast test-slow bench bench-peers-setup sweep readme variants docs clean $(STAGES)

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
	$(BIN)/python -c '$(BYTECODE_LAZY)' & lazy=$$!; $(BIN)/python -c '$(BYTECODE_IMPORTS)'; own=$$?; \
	  wait $$lazy && exit $$own
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
## The peer rows (benchmarks/bench_peers.py: the kernel against numbalsoda's DOP853 and LSODA) need the `bench`
## extra; `make bench` runs `make bench-peers-setup` first and goes on without the peers when it fails (their
## rows then say why: not installed).
bench: $(RUN_STAMP)
	@$(MAKE) --no-print-directory bench-peers-setup || echo "make bench: the peers could not be installed (make bench-peers-setup failed): their rows say so"
	$(BIN)/python -m benchmarks.run --out benchmarks/results/bench.json

## the bench's peers: numbalsoda has no wheel for Python >= 3.11 on PyPI, so it builds from source (its build
## fetches cmake and ninja from PyPI) and needs Fortran and C++ compilers. Where gfortran is missing it is
## installed from the system's packages (apt-get, as root: Debian, Ubuntu); elsewhere install a Fortran compiler
## first. Then the `bench` extra (pyproject.toml) into .venv, at uv.lock's version (~15 s to build).
bench-peers-setup: $(RUN_STAMP)
	@command -v gfortran >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "make bench-peers-setup: installing gfortran (apt-get): numbalsoda builds with a Fortran compiler"; \
	    { DEBIAN_FRONTEND=noninteractive apt-get install -y -qq gfortran g++ >/dev/null 2>&1 || \
	      { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq gfortran g++ >/dev/null; }; }; \
	  else \
	    echo "make bench-peers-setup: no Fortran compiler (gfortran) on the PATH, and no apt-get as root to install one: install gfortran, then run this again" >&2; \
	    exit 1; \
	  fi; }
	$(call install,--extra bench,[bench])

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

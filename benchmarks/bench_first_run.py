"""The first run of a fresh clone: ``make run`` with empty package and numba caches, split
into install, compile and run. Target: under 30 s on 2 cores.

1. ``git clone`` of this repository (its committed HEAD) into a temporary folder: no ``.venv``, no
   ``.bootstrap``, no numba cache (the kernels' cache lives in the clone's ``pipeline/__pycache__``;
   ``NUMBA_CACHE_DIR`` is removed from the environment).
2. install: ``make setup`` (uv from PyPI by pip into the user's cache, ``BOOT_CACHE``, linked as
   ``.bootstrap``, then ``uv sync`` of ``uv.lock``). uv's download cache and the installed uv are the
   user's, reused (packages downloaded before are not fetched again, uv is not installed again; the row
   says so); then the same again in a second fresh clone with both caches an empty folder (everything from
   PyPI: the target's case, "a machine with no package cache"; steps 1-5 without the notebook,
   ``BENCH_FIRST_RUN_COLD=0`` leaves it out).
3. first run: ``make run`` (nothing compiled yet).
4. warm run: ``make run ARGS=--force`` in the same clone (the same scene, everything recomputed, kernels
   from the cache, the .pyc the first run wrote).
5. compile = first run - warm run: numba's compilation of the kernels (in part in a background process,
   :func:`pipeline.model.compiled.compile_ahead`) and the interpreter's first compilation of the bytecode
   of what the run imports (the make targets write it lazily; uv compiles none at install).
6. a notebook's first call (target: under 10 s): in the same clone, between the first and the warm run, a
   fresh process runs ``build_model`` of ``make run``'s scene on its results folder (its inputs current) and
   ``simulate(model, [9.0])`` with an empty numba cache (``NUMBA_CACHE_DIR`` a new empty folder each time),
   :data:`NOTEBOOK_REPEAT` times: the kernel's compile in the background process the API starts, and the
   waiting process's own compiles (docs/performance.md, section "A notebook's first call, shared").

Each command's CPU time (user + system, the processes it waited for included) is recorded beside its wall time
(``install_cpu_s``, ``first_run_cpu_s``, ``warm_run_cpu_s``; the notebook's ``process_cpu_s``): on a shared host
the wall time counts the other tenants' load. One measurement each of 1-4 (a fresh clone is the point; about 2
minutes), 3 of 6 (~30 s).
``BENCH_FIRST_RUN=0`` skips it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import NamedTuple

from benchmarks.common import ROOT, record, run_process

#: The scene of ``make run`` (the Makefile's ``SCENE``).
SCENE = "configs/paper-2009-identified.toml"


def _timed(cmd: list[str], cwd: Path, env: dict[str, str]) -> tuple[float, float]:
    """Wall time [s] of ``cmd`` and its CPU time [s] (user + system of the command and every process it waited
    for): on a shared host the wall time counts the other tenants' load, the CPU time what the command costs."""
    wall, cpu, _ = run_process(cmd, cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return wall, cpu


#: How often the notebook's first call is measured (each with an empty numba cache, ~8-12 s).
NOTEBOOK_REPEAT = 3
#: The notebook's first call, in a fresh process started in the clone: argv[1] the scene, argv[2] its results
#: folder. Prints the seconds from the process's first line to the dataset.
NOTEBOOK = """
import sys, time
t0 = time.perf_counter()
import pipeline as hdi
model = hdi.build_model(sys.argv[1], sys.argv[2], progress=False)
ds = hdi.simulate(model, [9.0], progress=False)
assert ds.sizes["protrusion"] == 1
print(time.perf_counter() - t0)
"""


def notebook_first_calls(clone: Path, env: dict[str, str], scene: str, repeat: int = NOTEBOOK_REPEAT
                         ) -> tuple[list[float], list[float], list[float]]:
    """Wall times [s] of a notebook's first ``build_model`` + ``simulate`` in ``clone`` (module docstring,
    step 6): the process's own count, and the whole process's (interpreter start and exit included); and the
    whole process's CPU time [s] (the background compile's process included)."""
    folders = [f for f in (clone / "results").iterdir() if f.is_dir()]
    if len(folders) != 1:
        raise RuntimeError(f"{clone / 'results'}: expected the one results folder of `make run`, found "
                           f"{sorted(f.name for f in folders)}")
    inside, whole, cpus = [], [], []
    python = str(clone / ".venv" / "bin" / "python")
    for _ in range(repeat):
        with tempfile.TemporaryDirectory(prefix="hdi-numba-") as cache:
            wall, cpu, out = run_process([python, "-c", NOTEBOOK, scene, str(folders[0])], clone,
                                         env={**env, "NUMBA_CACHE_DIR": cache}, capture_output=True, text=True)
            whole.append(wall)
            cpus.append(cpu)
        inside.append(float(out.stdout.strip().splitlines()[-1]))
    return inside, whole, cpus


class Clone(NamedTuple):
    """One fresh clone's timed commands (:func:`first_run`): ``wall`` and ``cpu`` [s] by command (``install``,
    ``first``, ``warm``), and the notebook's first calls (:func:`notebook_first_calls`) when they were timed."""

    wall: dict[str, float]
    cpu: dict[str, float]
    notebook: tuple[list[float], list[float], list[float]] | None


def first_run(cold: bool, notebook: bool) -> Clone:
    """One fresh clone's install, first and warm ``make run`` (module docstring, steps 1-5; 6 with ``notebook``),
    uv's caches the user's or (``cold``) empty folders."""
    wall: dict[str, float] = {}
    cpu: dict[str, float] = {}
    calls = None
    with tempfile.TemporaryDirectory(prefix="hdi-first-run-") as tmp:
        clone = Path(tmp) / "hdi"
        subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
        env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "VIRTUAL_ENV", "UV")}
        if cold:
            env["UV_CACHE_DIR"] = str(Path(tmp) / "uv-cache")
            env["BOOT_CACHE"] = str(Path(tmp) / "uv-bootstrap")
        wall["install"], cpu["install"] = _timed(["make", "setup"], clone, env)
        wall["first"], cpu["first"] = _timed(["make", "run"], clone, env)
        if notebook:
            calls = notebook_first_calls(clone, env, SCENE)
        # the same command again, everything recomputed (the same scene: another scene's effects would be
        # another kernel signature, compiled in the "warm" run)
        wall["warm"], cpu["warm"] = _timed(["make", "run", "ARGS=--force"], clone, env)
        shutil.rmtree(clone / "results", ignore_errors=True)
    return Clone(wall, cpu, calls)


def _record_first_run(results: list[dict], run: Clone, cold: bool) -> None:
    """The row of one fresh clone (:func:`first_run`)."""
    # (the rows' names kept: the bench compares rows by name; "uv cache" covers the installed uv too)
    cache = "empty uv cache (all packages from PyPI)" if cold else "the local uv cache reused (no download)"
    install, first, warm, cpu = run.wall["install"], run.wall["first"], run.wall["warm"], run.cpu
    record(results, f"fresh clone: make setup + make run, {cache}", [install + first], target_s=30.0,
           install_s=round(install, 1), compile_s=round(first - warm, 1), run_s=round(warm, 1),
           first_run_s=round(first, 1), uv_cache="empty" if cold else "reused",
           cpu_s=round(cpu["install"] + cpu["first"], 1), install_cpu_s=round(cpu["install"], 1),
           first_run_cpu_s=round(cpu["first"], 1), warm_run_cpu_s=round(cpu["warm"], 1))
    print(f"  install {install:.1f} s, first make run {first:.1f} s = compile {first - warm:.1f} s + run "
          f"{warm:.1f} s ({cache}); CPU: install {cpu['install']:.1f} s, first make run {cpu['first']:.1f} s, "
          f"warm make run {cpu['warm']:.1f} s", flush=True)


def run(results: list[dict]) -> None:
    if os.environ.get("BENCH_FIRST_RUN", "1") == "0":
        print("bench_first_run: skipped (BENCH_FIRST_RUN=0)")
        return
    reused = first_run(cold=False, notebook=True)
    _record_first_run(results, reused, cold=False)
    notebook, notebook_process, notebook_cpu = reused.notebook
    record(results, "a notebook's first build_model + simulate (make run's scene and results, one protrusion), "
           "empty numba cache, fresh process", notebook, target_s=10.0, scene=SCENE,
           process_s=[round(t, 2) for t in notebook_process], process_cpu_s=[round(t, 2) for t in notebook_cpu])
    if os.environ.get("BENCH_FIRST_RUN_COLD", "1") == "0":
        print("bench_first_run: the clone with an empty uv cache skipped (BENCH_FIRST_RUN_COLD=0)")
        return
    _record_first_run(results, first_run(cold=True, notebook=False), cold=True)

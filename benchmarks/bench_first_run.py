"""The first run of a fresh clone (issue 18): ``make run`` with empty package and numba caches, split
into install, compile and run. Target (issue 36): under 30 s on 2 cores (it was 60 s).

1. ``git clone`` of this repository (its committed HEAD) into a temporary folder: no ``.venv``, no
   ``.bootstrap``, no numba cache (the kernels' cache lives in the clone's ``pipeline/__pycache__``;
   ``NUMBA_CACHE_DIR`` is removed from the environment).
2. install: ``make setup`` (uv from PyPI by pip into the user's cache, ``BOOT_CACHE``, linked as
   ``.bootstrap``, then ``uv sync`` of ``uv.lock``). uv's download cache and the installed uv are the
   user's, reused (packages downloaded before are not fetched again, uv is not installed again; the row
   says so), unless ``BENCH_FIRST_RUN_COLD=1``, which gives both an empty folder (everything from PyPI).
3. first run: ``make run`` (nothing compiled yet).
4. warm run: ``make run ARGS=--force`` in the same clone (the same scene, everything recomputed, kernels
   from the cache, the .pyc the first run wrote).
5. compile = first run - warm run: numba's compilation of the kernels (in part in a background process,
   :func:`pipeline.model.compiled.compile_ahead`) and the interpreter's first compilation of the bytecode
   of what the run imports (the make targets write it lazily; uv compiles none at install).

One measurement each (a fresh clone is the point; about 2 minutes). ``BENCH_FIRST_RUN=0`` skips it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

from benchmarks.common import ROOT, record


def _timed(cmd: list[str], cwd: Path, env: dict[str, str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=cwd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return time.perf_counter() - t0


def run(results: list[dict]) -> None:
    if os.environ.get("BENCH_FIRST_RUN", "1") == "0":
        print("bench_first_run: skipped (BENCH_FIRST_RUN=0)")
        return
    cold = os.environ.get("BENCH_FIRST_RUN_COLD") == "1"
    with tempfile.TemporaryDirectory(prefix="hdi-first-run-") as tmp:
        clone = Path(tmp) / "hdi"
        subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
        env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "VIRTUAL_ENV", "UV")}
        if cold:
            env["UV_CACHE_DIR"] = str(Path(tmp) / "uv-cache")
            env["BOOT_CACHE"] = str(Path(tmp) / "uv-bootstrap")
        install = _timed(["make", "setup"], clone, env)
        first = _timed(["make", "run"], clone, env)
        # the same command again, everything recomputed (the same scene: another scene's effects would be
        # another kernel signature, compiled in the "warm" run)
        warm = _timed(["make", "run", "ARGS=--force"], clone, env)
        shutil.rmtree(clone / "results", ignore_errors=True)
    # (the row's name kept: the bench compares rows by name; "uv cache" covers the installed uv too)
    cache = "empty uv cache (all packages from PyPI)" if cold else "the local uv cache reused (no download)"
    total = install + first
    record(results, f"fresh clone: make setup + make run, {cache}", [total], target_s=30.0,
           install_s=round(install, 1), compile_s=round(first - warm, 1), run_s=round(warm, 1),
           first_run_s=round(first, 1), uv_cache="empty" if cold else "reused")
    print(f"  install {install:.1f} s, first make run {first:.1f} s = compile {first - warm:.1f} s + run "
          f"{warm:.1f} s ({cache})", flush=True)

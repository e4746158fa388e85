"""Timing helpers shared by the benchmark modules.

Machines are shared and noisy: report medians of repeated runs and ratios against a baseline
measured in the same run, never a single timing.
"""

from __future__ import annotations

import re
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable

ROOT = Path(__file__).resolve().parents[1]
#: What every ``hdi`` command runs before its stage: the CLI and the stage registry (every stage module).
STARTUP = "import pipeline.cli, pipeline.runner; pipeline.runner.registry()"


def timeit(fn: Callable[[], Any], repeat: int = 7, warmup: int = 1) -> list[float]:
    """Wall times [s] of ``repeat`` calls of ``fn`` after ``warmup`` untimed calls."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return times


def record(results: list[dict], name: str, times: list[float], target_s: float | None = None,
           **extra: Any) -> dict:
    """Append one benchmark result (median, min, max [s], pass/fail against ``target_s``)."""
    med = statistics.median(times)
    row = {"name": name, "median_s": med, "min_s": min(times), "max_s": max(times), "n": len(times)}
    if target_s is not None:
        row["target_s"] = target_s
        row["meets_target"] = bool(med < target_s)
    row.update(extra)
    results.append(row)
    flag = "" if target_s is None else ("  OK" if med < target_s else f"  MISSES target {target_s:g} s")
    print(f"{name:<55} median {med * 1e3:10.2f} ms{flag}", flush=True)
    return row


def run_process(cmd: list[str], cwd: Any, **kwargs: Any) -> tuple[float, float, subprocess.CompletedProcess]:
    """Run ``cmd`` to completion: ``(wall time [s], CPU time of the child, user + system [s], the process)``.

    On a shared machine the CPU time says what the command costs when the wall time is inflated
    by other load (CPU time above wall time: the command ran in parallel).
    """
    import resource
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=cwd, check=True, **kwargs)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, done


def hdi(*args: str, **kwargs: Any) -> tuple[float, float, subprocess.CompletedProcess]:
    """One fresh ``hdi`` process (interpreter start included), output discarded unless ``kwargs`` say
    otherwise: ``(wall [s], CPU [s], the process)`` (:func:`run_process`)."""
    kwargs.setdefault("stdout", subprocess.DEVNULL)
    kwargs.setdefault("stderr", subprocess.DEVNULL)
    return run_process([sys.executable, "-m", "pipeline.cli", *args], ROOT, **kwargs)


def startup_seconds(repeat: int = 5) -> list[float]:
    """Wall times [s] of a fresh interpreter doing what every ``hdi`` command does first (:data:`STARTUP`):
    the floor no stage can go below."""
    return [run_process([sys.executable, "-c", STARTUP], ROOT)[0] for _ in range(repeat)]


def makefile_scene(variable: str) -> str:
    """The scene a Makefile variable names (``SCENE ?= ...``: the one ``make run`` runs)."""
    m = re.search(rf"^{variable} *\?= *(\S+)", (ROOT / "Makefile").read_text(), re.M)
    if m is None:
        raise ValueError(f"Makefile: no '{variable} ?= <scene>' line")
    return str(ROOT / m.group(1))

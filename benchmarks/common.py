"""Timing helpers shared by the benchmark modules.

Machines are shared and noisy: report medians of repeated runs and ratios against a baseline
measured in the same run, never a single timing. Every row also records the machine's 1-minute load
average and CPU count at its start and its end (:func:`load_sample`), and a row that started above
:data:`NOISY_LOAD_PER_CPU` x CPUs is flagged ``"noisy"`` (docs/performance.md, section
"Tests and benchmarks"). The load does not say how fast a CPU is on a shared host, so each module's start
also times a fixed workload (:mod:`benchmarks.reference`) and its rows carry it (``ref_compiled_s``,
``ref_python_s``): a row's time in those units compares across days.
"""

from __future__ import annotations

import os
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


#: A row is noisy when the 1-minute load average at its start exceeds this many per CPU: 0.75, i.e. load 1.5
#: on the project's 2 cores, where the bench's own process accounts for about 1 of it.
NOISY_LOAD_PER_CPU = 0.75


def load_sample() -> dict[str, float]:
    """The machine's state now: 1-minute load average [runnable processes] and the CPUs this process may use."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cpus = os.cpu_count() or 1
    return {"load_1min": os.getloadavg()[0], "cpus": cpus}


def reference_sample() -> dict[str, float]:
    """The machine's speed now: the fixed workloads of :func:`benchmarks.reference.machine_reference` [s]."""
    from .reference import machine_reference
    return machine_reference()


#: Where :func:`record` reads the load (tests replace it with a fake source).
LOAD_SOURCE: Callable[[], dict[str, float]] = load_sample
#: Where :func:`row_start` times the reference workloads (tests replace it with a fake source).
REFERENCE_SOURCE: Callable[[], dict[str, float]] = reference_sample
#: The sample at the start of the row being measured: set by :func:`row_start` (before each module,
#: by benchmarks/run.py) and by :func:`record` after each row (one row's end is the next one's start).
_row_start: dict[str, float] | None = None
#: The reference times of the current module's start (:func:`row_start`), recorded in each of its rows.
_reference: dict[str, float] = {}


def row_start() -> None:
    """Mark the start of the next row (a module's first): time the reference workloads, then sample the load."""
    global _row_start, _reference
    _reference = dict(REFERENCE_SOURCE())
    _row_start = LOAD_SOURCE()


def current_reference() -> dict[str, float]:
    """The reference times [s] of the current module's start (:func:`row_start`)."""
    return dict(_reference)


def load_fields(start: dict[str, float], end: dict[str, float]) -> dict[str, Any]:
    """The load fields of one row from its ``start`` and ``end`` samples (:func:`load_sample`).

    ``noisy`` is decided at the start (the machine as the row found it): the end's load includes the
    row's own processes (two workers raise it by 2 on 2 cores), so it is recorded to show a load that
    rose during the row, not used to flag.
    """
    limit = NOISY_LOAD_PER_CPU * start["cpus"]
    fields: dict[str, Any] = {"load_start": start["load_1min"], "load_end": end["load_1min"],
                              "cpus": start["cpus"], "noisy": bool(start["load_1min"] > limit)}
    if fields["noisy"]:
        fields["noisy_reason"] = (f"1-minute load {start['load_1min']:.2f} at the start > {limit:g} "
                                  f"({NOISY_LOAD_PER_CPU:g} x {start['cpus']:g} CPUs)")
    return fields


def record_failure(results: list[dict], name: str, message: str, **extra: Any) -> dict:
    """Append a row that could not be measured (``failed``: why; ``extra``: fields of its own, e.g. the numbers
    of a peer's disagreement), with the load at its start and end like :func:`record`, so every row of
    bench.json says how busy the machine was."""
    global _row_start
    end = LOAD_SOURCE()
    row = {"name": name, "failed": message, **extra,
           **load_fields(_row_start if _row_start is not None else end, end), **_reference}
    results.append(row)
    _row_start = end
    print(f"{name}: FAILED: {message}", flush=True)
    return row


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
           noisy_reason: str | None = None, **extra: Any) -> dict:
    """Append one benchmark result (median, min, max [s], pass/fail against ``target_s``) with the load at
    its start and end (:func:`load_fields`; the start is the last :func:`row_start` or :func:`record`).
    ``noisy_reason``: a reason of the row's own to flag it noisy beside the load's (e.g. the host's two cores
    measured busy next to a 2-over-1 row: ``bench_sweep.host_limited``)."""
    global _row_start
    end = LOAD_SOURCE()
    start = _row_start if _row_start is not None else end
    med = statistics.median(times)
    row = {"name": name, "median_s": med, "min_s": min(times), "max_s": max(times), "n": len(times)}
    if target_s is not None:
        row["target_s"] = target_s
        row["meets_target"] = bool(med < target_s)
    row.update(extra)
    row.update(load_fields(start, end))
    if noisy_reason:
        row["noisy_reason"] = "; ".join(filter(None, (row.get("noisy_reason"), noisy_reason)))
        row["noisy"] = True
    row.update(_reference)
    if _reference.get("ref_compiled_s"):
        row["in_compiled_reference_units"] = med / _reference["ref_compiled_s"]
    results.append(row)
    _row_start = end
    flag = "" if target_s is None else ("  OK" if med < target_s else f"  MISSES target {target_s:g} s")
    load = f"  load {row['load_start']:.2f}->{row['load_end']:.2f}/{row['cpus']:g}"
    noisy = "  NOISY" if row["noisy"] else ""
    print(f"{name:<55} median {med * 1e3:10.2f} ms{flag}{load}{noisy}", flush=True)
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

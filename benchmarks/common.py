"""Timing helpers shared by the benchmark modules.

Machines are shared and noisy: report medians of repeated runs and ratios against a baseline
measured in the same run, never a single timing.
"""

from __future__ import annotations

import statistics
import time
from typing import Any, Callable


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

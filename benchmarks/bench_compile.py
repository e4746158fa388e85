"""The dynamics kernel's compile for the main scene, empty numba cache: CPU.

The first run's critical path is this compile (docs/performance.md, section "The first run"): one fresh
process, ``NUMBA_CACHE_DIR`` empty, the main scene's kernel compiled for one run's argument types
(:mod:`benchmarks.compile_time`). The row's time is the CPU of the compile [s] (``time.process_time``,
less sensitive to the load than a wall time); its extras: the per-function exclusive CPU of the compiled
functions above 0.2 s. Target: 12 s of CPU, so that a fresh clone's first ``make run`` can approach 30 s.
One measurement (about 30 s); ``BENCH_COMPILE=0`` skips it.
"""

from __future__ import annotations

import os

from .common import record
from .compile_time import measure

#: The target of the kernel's compile CPU [s], the first run's critical path
TARGET_CPU_S = 12.0


def run(results: list[dict]) -> None:
    if os.environ.get("BENCH_COMPILE", "1") == "0":
        print("bench_compile: skipped (BENCH_COMPILE=0)")
        return
    m = measure()
    functions = {name: round(row["cpu_s"], 2) for name, row in m["functions"].items() if row["cpu_s"] >= 0.2}
    record(results, "dynamics kernel compile, main scene, empty numba cache (CPU)", [m["total_cpu_s"]],
           target_s=TARGET_CPU_S, cpu_by_function_s=functions)
    for name, cpu in functions.items():
        print(f"  {name:<53} {cpu:6.2f} s CPU", flush=True)

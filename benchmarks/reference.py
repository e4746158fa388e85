"""A fixed workload timed beside the benchmark rows: how fast the machine is right now.

The load average says how many processes compete for this machine's CPUs, not how fast a CPU is: on a
shared host the same code ran 1.7-2.4x slower on one day than two days earlier at the same load below 1
(the naive ``solve_ivp`` baseline of ``bench_dynamics``, pure Python and scipy: 826 / 3792 ms against 477 /
1592 ms). A row's time is comparable across days only in units of something measured beside it. Two
references, each the median of a few calls:

* ``ref_compiled_s``: a numba-compiled scalar loop like the kernel's (a damped, forced Duffing oscillator,
  classic RK4 with a fixed step, :func:`duffing_rk4`): floating-point arithmetic, ``sin``, branches, no
  memory traffic beyond the L1 cache;
* ``ref_python_s``: the same oscillator stepped by the interpreter (:func:`duffing_python`), for the rows
  that are mostly Python (start-up, assembly, the naive baseline).

A row's median over the reference of its module's start (``median_s / ref_compiled_s``) is its time in
reference units (docs/performance.md, section "Tests and benchmarks").
"""

from __future__ import annotations

import math
import statistics
import threading
import time
from typing import Callable

from numba import njit
from numba.extending import register_jitable

#: Steps of the compiled reference (about 10 ms on the project's 2-core machine).
COMPILED_STEPS = 160_000
#: Steps of the interpreted reference (about 20 ms there).
PYTHON_STEPS = 10_000


@register_jitable
def _duffing(x: float, v: float, t: float) -> tuple[float, float]:
    """Velocity and acceleration of ``x'' + 0.1 x' + x + x^3 = 0.5 cos(1.2 t)`` (dimensionless; a plain
    Python function called from Python, compiled inline where :func:`duffing_rk4` calls it)."""
    return v, 0.5 * math.cos(1.2 * t) - 0.1 * v - x - x * x * x


def duffing_python(n: int, h: float = 1e-3) -> float:
    """``x`` after ``n`` classic RK4 steps of :func:`_duffing` from ``x = 1, v = 0`` (the interpreter's work)."""
    x, v, t = 1.0, 0.0, 0.0
    for _ in range(n):
        k1x, k1v = _duffing(x, v, t)
        k2x, k2v = _duffing(x + 0.5 * h * k1x, v + 0.5 * h * k1v, t + 0.5 * h)
        k3x, k3v = _duffing(x + 0.5 * h * k2x, v + 0.5 * h * k2v, t + 0.5 * h)
        k4x, k4v = _duffing(x + h * k3x, v + h * k3v, t + h)
        x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        t += h
    return x


#: :func:`duffing_python` compiled: the same source, so the same arithmetic in the same order (the same ``x``).
duffing_rk4 = njit(cache=True)(duffing_python)


def _median_time(fn, arg: int, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn(arg)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def machine_reference(repeat: int = 5) -> dict[str, float]:
    """The two reference times now [s]: ``ref_compiled_s`` (:func:`duffing_rk4`, compiled or loaded from the
    cache first, untimed) and ``ref_python_s`` (:func:`duffing_python`), medians of ``repeat`` calls."""
    duffing_rk4(10)
    return {"ref_compiled_s": _median_time(duffing_rk4, COMPILED_STEPS, repeat),
            "ref_python_s": _median_time(duffing_python, PYTHON_STEPS, repeat)}


#: :func:`duffing_python` compiled without the GIL, like the dynamics kernel, for :func:`two_core_speedup`.
duffing_rk4_nogil = njit(cache=True, nogil=True)(duffing_python)


def _reference_work() -> None:
    duffing_rk4_nogil(30 * COMPILED_STEPS)  # (~0.3 s on the project's 2-core machine)


def two_core_speedup(work: Callable[[], object] = _reference_work, repeat: int = 3) -> float:
    """What two cores give this host now on GIL-free work [1]: ``2 x t_alone / t_both``, the median over
    ``repeat`` alternations of ``work()`` alone in one thread (``t_alone`` [s]) and two ``work()`` at once in
    two threads (``t_both`` [s], wall time). 2 on two free cores; less where the host's second core is busy
    with other tenants' work or both share one core's resources. A snapshot of a few seconds: the host's
    capacity moves within seconds, so it flags a 2-over-1 measured beside it rather than bounds it
    (``bench_sweep.host_limited``; docs/performance.md, section "The whole `make bench` again, and the host's
    two cores")."""
    work()  # (compiled or loaded from the cache, untimed)
    ratios = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        work()
        alone = time.perf_counter() - t0
        threads = [threading.Thread(target=work) for _ in range(2)]
        t0 = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        ratios.append(2 * alone / (time.perf_counter() - t0))
    return statistics.median(ratios)

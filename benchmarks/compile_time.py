"""numba's compile time of the dynamics kernel for the main scene, per compiled function.

In a fresh process whose ``NUMBA_CACHE_DIR`` is an empty temporary folder: build the model of
``configs/paper-2009-identified.toml`` (the calibrated ``k`` of ``make run``, given: no calibration), type
the kernel's arguments for one run as :func:`pipeline.model.dynamics.integrate` would
(:func:`pipeline.model.dynamics.kernel_arguments`, :func:`pipeline.model.compiled.signature`), then compile
``dynamics._integrate`` for them (``Dispatcher.compile(sig)``). Reported: the CPU of that compile
(``time.process_time``), and per compiled function (numba's ``numba:compile`` event, which fires on a
compile, not on a cache load) its exclusive CPU (``time.thread_time``, the nested compiles it triggers
subtracted) and how many signatures it compiled. What the model's assembly compiles before is not counted.

Run it from the repository (about 30 s)::

    .venv/bin/python -m benchmarks.compile_time            # a table
    .venv/bin/python -m benchmarks.compile_time --json     # one JSON line (benchmarks/bench_compile.py)

``--keep-cache DIR`` compiles into ``DIR`` instead of a temporary folder (it must be empty for a
compile to be measured). ``--step-first`` measures the kernel's compile split over two processes that share
one cache: the first compiles only the Dormand-Prince step (:func:`pipeline.model.stepper.step`, the
kernel's largest function) for the types the kernel calls it with (:func:`_step_arguments`), the second then
the kernel, which loads the step from the cache (its table has no ``step`` row): what a second process
compiling the step in parallel would take off the kernel's compile. The number depends on the machine's load far less than a wall time does, but a
busy machine still inflates it (shared caches, frequency): say the load with it (``uptime``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "configs" / "paper-2009-identified.toml"
#: The contact constant of the main scene's calibration (as tests/model/test_compiled.py): given, so the
#: model builds without running the calibration (which would compile the kernel itself).
K = 1.0736
#: The protrusion of the typed run [nm]: any gives the same types.
PROTRUSION_NM = 5.0


def _step_arguments(args: tuple) -> tuple:
    """Stand-ins of the arguments :func:`pipeline.model.dynamics._integrate` calls the step with, from the
    kernel's arguments ``args`` (:func:`pipeline.model.dynamics.kernel_arguments`): the time, the step and
    the flags as scalars, its work arrays as C-contiguous float64 arrays of the state's length, the
    parameter record, the slots as they are."""
    import numpy as np

    from pipeline.model.dynamics import SLOTS

    y0, params = args[0], args[3]
    slots = args[8:8 + len(SLOTS)]  # (the kernel's slots; the loop's own heating slot after them is not the step's)
    work = [np.zeros(len(y0)) for _ in range(11)]  # y, k1, ynew, k7, err, tmp, k2..k6
    return (0.0, work[0], work[1], 0.0, params[0], False, np.bool_(True), *work[2:], np.zeros(2), *slots)


def _measure(results: str, only_step: bool = False) -> dict:
    """In this process (``NUMBA_CACHE_DIR`` already set): build the model, compile the kernel (or with
    ``only_step`` its step alone), return the per-function CPU (see the module docstring)."""
    import time

    import numpy as np
    from numba.core import event

    import pipeline as hdi
    from pipeline.model import dynamics as dyn
    from pipeline.model.kernel_inputs import run_parameters
    from pipeline.model.state import N_STATE
    from pipeline.units import NM

    scene = hdi.load_scene(str(SCENE))
    model = hdi.build_model(scene, results, k=K, progress=False)
    p, tables, variants = run_parameters(model, PROTRUSION_NM * NM)
    args = dyn.kernel_arguments(np.zeros(N_STATE), dyn.Grid(1e-3, np.zeros(3)), p, tables, variants,
                                dyn.Solver(1e-6, model.atol, 1e-7, 10))
    target = dyn._integrate
    if only_step:
        from pipeline.model.stepper import step as target
        args = _step_arguments(args)
    sig = dyn.compiled.signature(target, args)

    rows: dict[str, dict] = {}
    stack: list[list] = []  # [name, start thread time, CPU of the nested compiles]

    class Listener(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            d = ev.data["dispatcher"]
            stack.append([f"{d.py_func.__module__}.{d.py_func.__qualname__}", time.thread_time(), 0.0])

        def on_end(self, ev: event.Event) -> None:
            name, t0, nested = stack.pop()
            total = time.thread_time() - t0
            if stack:
                stack[-1][2] += total
            row = rows.setdefault(name, {"cpu_s": 0.0, "inclusive_s": 0.0, "compiles": 0})
            row["cpu_s"] += total - nested
            row["inclusive_s"] += total
            row["compiles"] += 1

    listener = Listener()
    event.register("numba:compile", listener)
    t0 = time.process_time()
    try:
        target.compile(sig)
    finally:
        event.unregister("numba:compile", listener)
    total = time.process_time() - t0
    functions = dict(sorted(rows.items(), key=lambda kv: -kv[1]["cpu_s"]))
    return {"total_cpu_s": total, "functions": functions, "load_1min": os.getloadavg()[0]}


def measure(cache_dir: str | None = None, step_first: bool = False) -> dict:
    """Run :func:`_measure` in a fresh interpreter with ``NUMBA_CACHE_DIR`` an empty folder (``cache_dir``
    or a temporary one) and return its result; with ``step_first``, a first interpreter compiles the step
    alone into that folder, and its result is the returned one's ``"step_first"``."""
    with tempfile.TemporaryDirectory(prefix="hdi-compile-time-") as tmp:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir or os.path.join(tmp, "numba"),
                   HDI_COMPILE_AHEAD="0")
        children = (["--child-step"] if step_first else []) + ["--child"]
        results = [_child(child, os.path.join(tmp, "results"), env) for child in children]
    if step_first:
        results[-1]["step_first"] = results[0]
    return results[-1]


def _child(option: str, results: str, env: dict) -> dict:
    """The result of ``python -m benchmarks.compile_time OPTION RESULTS`` under ``env``."""
    out = subprocess.run([sys.executable, "-m", "benchmarks.compile_time", option, results], cwd=ROOT, env=env,
                         capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"the compile failed: {out.stderr.strip()[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str]) -> None:
    if argv[:1] in (["--child"], ["--child-step"]):
        print(json.dumps(_measure(argv[1], only_step=argv[0] == "--child-step")))
        return
    cache = argv[argv.index("--keep-cache") + 1] if "--keep-cache" in argv else None
    result = measure(cache, step_first="--step-first" in argv)
    if "--json" in argv:
        print(json.dumps(result))
        return
    print(f"{'function':<52} {'compiles':>8} {'CPU [s]':>8} {'incl. [s]':>9}")
    for name, row in result["functions"].items():
        print(f"{name:<52} {row['compiles']:>8} {row['cpu_s']:>8.2f} {row['inclusive_s']:>9.2f}")
    print(f"{'dynamics._integrate.compile(sig), process CPU':<52} {'':>8} {result['total_cpu_s']:>8.2f}"
          f"   (1-minute load {result['load_1min']:.2f})")
    if "step_first" in result:
        print(f"{'stepper.step.compile(sig) before, its own process CPU':<52} {'':>8} "
              f"{result['step_first']['total_cpu_s']:>8.2f}")


if __name__ == "__main__":
    main(sys.argv[1:])

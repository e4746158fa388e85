"""Start-up whatever the shell: ``hdi --help`` and a study's fixed part, fresh processes, with the user's
``PYTHONDONTWRITEBYTECODE=1`` and without it.

Where ``PYTHONDONTWRITEBYTECODE`` is set Python writes no bytecode: a process starts from the ``.pyc`` that
others wrote or compiles every module it imports again (~900 of them for ``hdi --help``, ~4.5 s of CPU). The
set-up writes the bytecode of what the commands import (the Makefile's ``BYTECODE_IMPORTS``), so both rows of
each pair should read the same (docs/performance.md, section "Start-up whatever the shell").

Rows (each the median of :data:`REPEAT` fresh processes, wall time and the child's CPU time, ``cpu_median_s``):

1. ``hdi --help`` with ``PYTHONDONTWRITEBYTECODE=1``, then without it (after one process that writes what
   is missing);
2. a study's fixed part: ``hdi sweep`` of the paper scene restricted to one protrusion (:data:`ONE_SCENE`)
   in a folder holding its inputs, the kernels loaded from the numba cache (one untimed run first): the
   interpreter, the imports, the scheduler, reading the inputs, loading the kernels, one ~5-ms scene and the
   dataset's write. Target <= 1.5 s (:data:`FIXED_TARGET_S`), with and without the variable.

Each row of the set ``=1`` also says how many of the modules such a process imported had no bytecode
cached (``modules_without_bytecode`` of ``modules_imported``, :data:`WITHOUT_BYTECODE`): 0 after the set-up.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from .common import ROOT, hdi, record, run_process

PAPER = str(ROOT / "configs" / "paper-2009.toml")
#: The paper sweep restricted to one protrusion: a study's command with (almost) nothing but its fixed part.
ONE_SCENE = ("--set", "sweep.protrusion_nm={start=5.0,stop=5.0,step=0.2}")
INPUTS = ("roughness.nc", "dmw.nc", "interface.nc", "calibration.nc")
REPEAT = 5
#: A study's fixed part's target [s]: the imports and the kernels loaded from the numba cache.
FIXED_TARGET_S = 1.5
#: Runs ``hdi ARGS`` as the console script does and, as it ends (``os._exit`` or the interpreter's exit), writes to the file
#: ``HDI_BENCH_MODULES`` how many of the modules it imported from a ``.py`` file had no cached bytecode.
WITHOUT_BYTECODE = """
import atexit, importlib.util, json, os, sys
def _count():
    if os.path.exists(os.environ["HDI_BENCH_MODULES"]):
        return
    files = [getattr(m, "__file__", None) for m in list(sys.modules.values())]
    files = [f for f in files if f and f.endswith(".py")]
    missing = sorted(f for f in files if not os.path.exists(importlib.util.cache_from_source(f)))
    with open(os.environ["HDI_BENCH_MODULES"], "w") as out:
        json.dump({"imported": len(files), "without_bytecode": len(missing), "first": missing[:20]}, out)
_exit = os._exit
os._exit = lambda code: (_count(), _exit(code))
atexit.register(_count)  # (--help ends by SystemExit)
sys.argv = ["hdi", *sys.argv[1:]]
from pipeline.launch import entry
entry()
"""


def environment(dont_write: bool) -> dict[str, str]:
    """This process's environment with ``PYTHONDONTWRITEBYTECODE=1`` (``dont_write``) or without the variable."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    if dont_write:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def bytecode_census(args: list[str], env: dict[str, str], fresh: Path | None = None) -> dict[str, Any]:
    """How many modules one ``hdi ARGS`` process in ``env`` imported, and how many of them without cached
    bytecode (:data:`WITHOUT_BYTECODE`); with ``fresh``, in a new copy of that folder (``--out``), as the timed
    processes run (a command whose outputs are up to date loads no kernel, nor the numba modules that go with
    it)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "modules.json"
        extra: list[str] = []
        if fresh is not None:
            (Path(tmp) / "out").mkdir()
            for name in INPUTS:
                if (fresh / name).is_file():
                    shutil.copy(fresh / name, Path(tmp) / "out" / name)
            extra = ["--out", str(Path(tmp) / "out")]
        run_process([sys.executable, "-c", WITHOUT_BYTECODE, *args, *extra], ROOT,
                    env={**env, "HDI_BENCH_MODULES": str(out)}, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return json.loads(out.read_text())


def _times(args: list[str], env: dict[str, str], fresh: Path | None = None) -> tuple[list[float], list[float]]:
    """Wall and CPU times [s] of :data:`REPEAT` fresh ``hdi ARGS`` processes in ``env``; with ``fresh``, each in
    a new copy of that folder (``--out``)."""
    walls, cpus = [], []
    for _ in range(REPEAT):
        with tempfile.TemporaryDirectory() as tmp:
            extra: list[str] = []
            if fresh is not None:
                for name in INPUTS:
                    if (fresh / name).is_file():
                        shutil.copy(fresh / name, Path(tmp) / name)
                extra = ["--out", tmp]
            wall, cpu, _ = hdi(*args, *extra, env=env)
        walls.append(wall)
        cpus.append(cpu)
    return walls, cpus


def run(results: list[dict]) -> None:
    help_ = ["--help"]
    sweep = ["sweep", PAPER, *ONE_SCENE]
    with tempfile.TemporaryDirectory() as tmp:
        inputs = Path(tmp)
        hdi("calibrate", PAPER, "--out", str(inputs), env=environment(True))  # the inputs, once, not timed
        hdi(*sweep, "--out", str(inputs), env=environment(True))  # the kernels compiled or loaded, not timed
        for dont_write in (True, False):
            env = environment(dont_write)
            setting = "PYTHONDONTWRITEBYTECODE=1" if dont_write else "PYTHONDONTWRITEBYTECODE unset"
            census = {}
            if dont_write:  # (what the set-up left: before any process of this row writes bytecode)
                census = {"help": bytecode_census(help_, env), "sweep": bytecode_census(sweep, env, fresh=inputs)}
            else:
                hdi(*help_, env=env)  # (writes what is missing)
            walls, cpus = _times(help_, env)
            record(results, f"start-up: hdi --help, fresh process, {setting}", walls,
                   cpu_median_s=statistics.median(cpus),
                   **({"modules_imported": census["help"]["imported"],
                       "modules_without_bytecode": census["help"]["without_bytecode"]} if census else {}))
            walls, cpus = _times(sweep, env, fresh=inputs)
            record(results, f"a study's fixed part: hdi sweep of one scene (inputs present, kernels from the numba "
                   f"cache), fresh process, {setting}", walls, target_s=FIXED_TARGET_S,
                   cpu_median_s=statistics.median(cpus), meets_target_cpu=bool(statistics.median(cpus) <= FIXED_TARGET_S),
                   **({"modules_imported": census["sweep"]["imported"],
                       "modules_without_bytecode": census["sweep"]["without_bytecode"],
                       "first_without_bytecode": census["sweep"]["first"]} if census else {}))

"""Run every ``benchmarks/bench_*.py`` module and write the results file (JSON).

Each module defines ``run(results: list[dict]) -> None`` and appends rows with
:func:`benchmarks.common.record` (which adds the load at each row's start and end, and flags noisy rows).
Usage: ``python -m benchmarks.run --out benchmarks/results/bench.json`` (optionally ``--only NAME`` to run
modules whose name contains NAME). ``BENCH_STUDY=0`` leaves out the study modules (:data:`STUDY_MODULES`:
identify and sensitivity at their budgets, most of the bench's time). A module that raises does not lose
the others' rows: it gets a ``failed`` row (:func:`benchmarks.common.record_failure`, with the error), the
rest run, the file is written, and the command exits with status 1.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import platform
import sys
import time
import traceback
from collections.abc import Mapping
from pathlib import Path

from . import common

#: The modules ``BENCH_STUDY=0`` leaves out: the parameter studies, minutes each.
STUDY_MODULES = ("bench_study",)


def selected_modules(names: list[str], only: str | None = None, study: bool = True) -> list[str]:
    """The benchmark modules to run, sorted: those of ``names`` containing ``only`` (all if None),
    without :data:`STUDY_MODULES` unless ``study``."""
    return sorted(n for n in names if (only is None or only in n) and (study or n not in STUDY_MODULES))


def study_enabled(environ: Mapping[str, str] = os.environ) -> bool:
    """Whether the study modules run: ``BENCH_STUDY`` unset or anything but ``0``."""
    return environ.get("BENCH_STUDY", "1") != "0"


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--out", type=Path, default=Path("benchmarks/results/bench.json"))
    p.add_argument("--only", default=None, help="run only the modules whose name contains this")
    args = p.parse_args()
    here = Path(__file__).parent
    results: list[dict] = []
    failed: list[str] = []
    study = study_enabled()
    if not study:
        print(f"BENCH_STUDY=0: leaving out {', '.join(STUDY_MODULES)}")
    for name in selected_modules([m.stem for m in here.glob("bench_*.py")], args.only, study):
        common.row_start()
        ref = common.current_reference()
        print(f"== {name}  (reference: compiled {ref['ref_compiled_s'] * 1e3:.2f} ms, "
              f"Python {ref['ref_python_s'] * 1e3:.2f} ms)", flush=True)
        try:
            importlib.import_module(f"benchmarks.{name}").run(results)
        except Exception as exc:  # (a broken module must not lose the rows measured before and after it)
            traceback.print_exc()
            failed.append(name)
            common.record_failure(results, f"{name}: the module raised", f"{type(exc).__name__}: {exc}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    meta = {"date": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "machine": platform.machine(),
            "python": platform.python_version(), "cpus": os.cpu_count(), "study": study,
            "noisy_load_per_cpu": common.NOISY_LOAD_PER_CPU}
    tmp = args.out.with_suffix(".tmp")
    tmp.write_text(json.dumps({"meta": meta, "results": results}, indent=2))
    tmp.replace(args.out)
    noisy = [r["name"] for r in results if r.get("noisy")]
    if noisy:
        print(f"{len(noisy)} of {len(results)} rows NOISY (load above {common.NOISY_LOAD_PER_CPU:g} per CPU at "
              "their start, or their own noisy_reason in the results file): upper bounds, measure again on a "
              "quiet machine")
    print(f"results written to {args.out}")
    if failed:
        print(f"{len(failed)} module(s) failed: {', '.join(failed)}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()

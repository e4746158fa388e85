"""Run every ``benchmarks/bench_*.py`` module and write the results file (JSON).

Each module defines ``run(results: list[dict]) -> None`` and appends rows with
:func:`benchmarks.common.record`. Usage: ``python -m benchmarks.run --out benchmarks/results/bench.json``
(optionally ``--only NAME`` to run modules whose name contains NAME).
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import platform
import time
from pathlib import Path


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--out", type=Path, default=Path("benchmarks/results/bench.json"))
    p.add_argument("--only", default=None)
    args = p.parse_args()
    here = Path(__file__).parent
    results: list[dict] = []
    for mod in sorted(here.glob("bench_*.py")):
        if args.only and args.only not in mod.stem:
            continue
        print(f"== {mod.stem}", flush=True)
        importlib.import_module(f"benchmarks.{mod.stem}").run(results)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    meta = {"date": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "machine": platform.machine(),
            "python": platform.python_version(), "cpus": os.cpu_count()}
    tmp = args.out.with_suffix(".tmp")
    tmp.write_text(json.dumps({"meta": meta, "results": results}, indent=2))
    tmp.replace(args.out)
    print(f"results written to {args.out}")


if __name__ == "__main__":
    main()

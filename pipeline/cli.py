"""The ``hdi`` command: ``hdi STAGE CONFIG [--set section.key=value ...] [--out DIR] [--scheduler ADDRESS]``.

Each stage lives in ``pipeline.stages.<stage>`` and exposes ``run(scene, out, **options) -> Path``.
``hdi run`` runs every stage of the main job in order. ``hdi roughness FILE... --out DIR`` summarises
AFM files without a scene.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
import time
from pathlib import Path

from .io import DatasetError, results_dir
from .scene import SceneError, load_scene

STAGES = ("roughness", "dmw", "interface", "calibrate", "simulate", "sweep", "accuracy", "report", "run",
          "identify", "sensitivity")
#: The main job, in order (``hdi run`` / ``make run``).
MAIN_JOB = ("roughness", "dmw", "interface", "calibrate", "sweep", "report")

log = logging.getLogger("pipeline")


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="hdi", description=__doc__.split("\n\n")[0])
    p.add_argument("stage", choices=STAGES, help="the stage to run (run = the whole main job)")
    p.add_argument("inputs", nargs="+", metavar="CONFIG",
                   help="a scene file (TOML); for `roughness`, AFM files may be given instead")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
                   help="override a scene key (TOML value syntax); repeatable")
    p.add_argument("--out", type=Path, default=None, help="output folder (default results/<scene name>/)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="attach the sweep (identify, sensitivity) to an existing dask.distributed scheduler")
    p.add_argument("--workers", type=int, default=None, help="local dask workers (default: one per core)")
    p.add_argument("--channel", default=None, help="roughness: AFM channel (default: the height channel)")
    p.add_argument("--detrend", default="plane", choices=("center", "height", "plane", "curvature"),
                   help="roughness: detrending of AFM scans")
    p.add_argument("--force", action="store_true", help="recompute even when outputs are up to date")
    p.add_argument("--readme", type=Path, default=None,
                   help="report: also rewrite the generated comparison section of this README")
    p.add_argument("-v", "--verbose", action="store_true")
    return p


def run_stage(stage: str, scene, out: Path, **options) -> Path:
    """Import ``pipeline.stages.<stage>`` and run it."""
    module = importlib.import_module(f"pipeline.stages.{stage}")
    return module.run(scene, out, **options)


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    if not args.verbose:  # dask.distributed configures its own INFO loggers; keep the terminal quiet
        for name in ("distributed", "distributed.scheduler", "distributed.nanny", "distributed.core",
                     "distributed.http.proxy"):
            logging.getLogger(name).setLevel(logging.CRITICAL)  # (shutdown races log CommClosedError)
    try:
        if args.stage == "roughness" and not (len(args.inputs) == 1 and args.inputs[0].endswith(".toml")):
            from .stages import roughness
            if args.out is None:
                raise SceneError("hdi roughness FILE...: --out DIR is required when AFM files are given")
            path = roughness.run_files([Path(f) for f in args.inputs], args.out,
                                       channel=args.channel, detrend=args.detrend)
            print(path)
            return 0
        if len(args.inputs) != 1:
            raise SceneError(f"hdi {args.stage}: expected one scene file, got {args.inputs}")
        scene = load_scene(args.inputs[0], args.overrides)
        out = results_dir(scene, args.out)
        options = {"scheduler": args.scheduler, "workers": args.workers, "force": args.force,
                   "readme": args.readme}
        stages = MAIN_JOB if args.stage == "run" else (args.stage,)
        for stage in stages:
            t0 = time.perf_counter()
            path = run_stage(stage, scene, out, **options)
            print(f"{stage:>10}: {path}  ({time.perf_counter() - t0:.1f} s)", flush=True)
        return 0
    except (SceneError, DatasetError, FileNotFoundError, ValueError) as exc:
        print(f"hdi {args.stage}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"hdi {args.stage}: interrupted; finished work is kept, run again to resume", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

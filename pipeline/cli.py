"""The ``hdi`` command: ``hdi STAGE CONFIG [--set section.key=value ...] [--out DIR] [--scheduler ADDRESS|FILE]``.

The stages are the declarations :mod:`pipeline.runner` discovers in :mod:`pipeline.stages`; the runner
makes the asked stage current, with everything upstream of it (a stage whose inputs did not change is
not recomputed). ``hdi run`` makes the main job current. ``hdi roughness FILE... --out DIR``
summarises AFM files without a scene.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import traceback
from pathlib import Path

from . import __version__, cluster, interrupts, runner
from .file_errors import os_error_line
from .io import DatasetError, results_dir
from .progress import StderrHandler, interval_s
from .config.loading import find_scene, load_scene, shipped_scenes
from .config.schema import SceneError, describe_keys
from .folder_lock import folder_lock
from .stages import roughness
from .cli_checks import MAX_SCENES, check_options, integration_line, one_line_warnings
from .model import compiled
from .model.first_run import Early
from .model.running import IntegrationError

log = logging.getLogger("pipeline")


class _HelpKeys(argparse.Action):
    """``--help-keys [SECTION]``: the scene schema (:func:`pipeline.config.scene.describe_keys`), then exit."""

    def __call__(self, parser, namespace, values, option_string=None):
        try:
            text = describe_keys(values or None)
        except SceneError as exc:
            parser.exit(2, f"hdi: error: {exc}\n")
        sys.stdout.write(text)
        parser.exit(0)


def _parser(stages: dict[str, runner.Stage]) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="hdi", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="stages:\n" + "\n".join(f"  {n:<11} {s.doc}" for n, s in stages.items())
                                + "\n  run         the main job: " + " ".join(n for n, s in stages.items()
                                                                               if s.main_job))
    p.add_argument("--version", action="version", version=f"hdi {__version__}",
                   help="print the version and exit")
    p.add_argument("--help-keys", nargs="?", const="", metavar="SECTION", action=_HelpKeys,
                   help="print every scene key (or those of SECTION) with its default, type and unit, and exit")
    p.add_argument("stage", choices=[*stages, "run"], help="the stage to run (run = the whole main job)")
    p.add_argument("inputs", nargs="+", metavar="CONFIG",
                   help="a scene file (TOML) or the name of a shipped scene (" + ", ".join(shipped_scenes())
                        + "); for `roughness`, AFM files may be given instead")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
                   help="override a scene key (TOML value syntax); repeatable")
    p.add_argument("--out", type=Path, default=None, help="output folder (default results/<scene name>/)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS|FILE",
                   help="run the fan-out (sweep, calibrate, ensemble, identify, sensitivity, and the report's "
                        "upstream stages) on an existing "
                        "dask.distributed scheduler: its address (tcp://HOST:8786) or the JSON file `dask scheduler "
                        "--scheduler-file FILE` writes; without it, the address in DASK_SCHEDULER_ADDRESS if set, "
                        "else local threads; threads, processes or synchronous name the local fan-outs")
    p.add_argument("--workers", type=int, default=None, help="local dask workers (default: one per core)")
    p.add_argument("--channel", default=None, help="roughness: AFM channel (default: the height channel)")
    p.add_argument("--detrend", default=None, choices=("center", "height", "plane", "curvature"),
                   help="roughness: detrending of AFM scans (default plane)")
    p.add_argument("--force", action="store_true", help="recompute even when outputs are up to date, and replace files at output "
                        "paths that hdi did not write or that hold another scene's results")
    p.add_argument("--write-scene", type=Path, default=None, metavar="PATH",
                   help="identify: also write the identified scene to PATH (it is always written into the "
                        "results folder as identified.toml); its folder must exist and be writable, and "
                        "an existing PATH is refused unless --force (which also recomputes the identification)")
    p.add_argument("--readme", type=Path, default=None, metavar="PAGE",
                   help="report: also rewrite the generated comparison section of this page "
                        "(docs/results.md) and copy its figures to figures/ beside it")
    p.add_argument("--yes", action="store_true",
                   help=f"run a big job: a sweep of more than {MAX_SCENES:,} scenes, or tables, histories, "
                        "records or studies beyond the limits of pipeline/config/limits.py")
    talk = p.add_mutually_exclusive_group()
    talk.add_argument("-v", "--verbose", action="count", default=0,
                      help="-v: also a traceback with an error and dask's own messages; -vv: also debug messages")
    talk.add_argument("-q", "--quiet", action="store_true",
                      help="warnings and errors only: no progress bar or lines, no stage messages")
    return p


def _given(args: argparse.Namespace) -> dict:
    """The options :func:`pipeline.cli_checks.check_options` checks."""
    return {name: getattr(args, name) for name in ("out", "scheduler", "workers", "yes", "readme", "channel",
                                                    "detrend", "write_scene", "force")}


def _logging(verbose: int = 0, quiet: bool = False) -> None:
    """The stages' messages and progress (INFO of the ``pipeline`` loggers, :mod:`pipeline.progress`) on
    stderr; with ``quiet`` (``-q``) warnings and errors only; ``verbose`` 1 (``-v``) adds dask's own
    messages, 2 (``-vv``) the DEBUG ones."""
    one_line_warnings()
    if not any(isinstance(h, StderrHandler) for h in log.handlers):
        log.addHandler(StderrHandler())
    log.setLevel(logging.WARNING if quiet else logging.DEBUG if verbose >= 2 else logging.INFO)
    if not verbose:  # keep the terminal quiet (dask's shutdown races log CommClosedError; a killed scheduler)
        cluster.dask_log_level(logging.CRITICAL)


def _ended(who: str, signum: int) -> int:
    """Answer the signal ``signum``: its one line (:func:`pipeline.interrupts.message`), and its exit code."""
    interrupts.answered()
    interrupts.say(interrupts.message(who, signum))
    return interrupts.exit_code(signum)


def main(argv: list[str] | None = None) -> int:
    """``hdi`` with the arguments ``argv`` (default ``sys.argv[1:]``); returns the exit code. A signal ends it
    with its one line and 128 + its number whenever it arrives (:mod:`pipeline.interrupts`), also when it
    made a library fail first (a worker it killed, a pipe it broke): the signal is what the user did."""
    with interrupts.handling():
        try:
            code = _main(argv)
        except KeyboardInterrupt as exc:  # (outside the stage's try: parsing the arguments, just after it)
            return _ended("hdi", interrupts.signal_of(exc))
        with interrupts.deferred():
            signum = interrupts.pending()
            if signum is not None:  # (recorded, never raised to the top: swallowed where it was raised)
                code = _ended("hdi", signum)
    return code


def _names_a_scene(text: str) -> bool:
    """Whether ``hdi roughness TEXT`` names a scene (a ``.toml`` file, or a shipped scene's name that is no
    file here), not an AFM file."""
    if text.endswith(".toml"):
        return True
    try:
        return find_scene(text) != Path(text)
    except SceneError:
        return False


def _main(argv: list[str] | None = None) -> int:
    stages = runner.registry()
    args = _parser(stages).parse_args(argv)
    _logging(args.verbose, args.quiet)
    scene = out = None
    try:
        if args.stage == "roughness" and not (len(args.inputs) == 1 and _names_a_scene(args.inputs[0])):
            if args.out is None:
                raise SceneError("hdi roughness FILE...: --out DIR is required when AFM files are given")
            check_options("roughness", None, **_given(args))
            with folder_lock(args.out):
                path = roughness.run_files([Path(f) for f in args.inputs], args.out,
                                           channel=args.channel, detrend=args.detrend or "plane")
            interrupts.check()
            print(path)
            return 0
        interval_s()  # (a bad HDI_PROGRESS_S is one line now, not after the upstream stages)
        if len(args.inputs) != 1:
            raise SceneError(f"hdi {args.stage}: expected one scene file, got {args.inputs}")
        scene = load_scene(args.inputs[0], args.overrides)
        scheduler = check_options(args.stage, scene, **_given(args))  # (a scheduler file's address, the env's)
        out = results_dir(scene, args.out)
        targets = runner.main_job(scene, stages) if args.stage == "run" else [args.stage]
        options = {"scheduler": scheduler, "workers": args.workers, "readme": args.readme,
                   **({"write_scene": args.write_scene} if args.write_scene is not None else {})}
        made = runner.Runner(scene, out, stages, **options).build(targets, force=args.force)
        interrupts.check()  # (a signal swallowed inside a library's C code is answered here, never exit 0)
        for stage, paths in made.items():  # the dataset, or the folder of figures and tables
            print(f"{stage:>10}: {paths[0] if paths[0].suffix == '.nc' else paths[0].parent}", flush=True)
        return 0
    except (SceneError, DatasetError, FileNotFoundError, ValueError) as exc:
        # bad input is one line; a ValueError from numerics would be one line too, so -v shows where
        return _failed(args, str(exc))
    except IntegrationError as exc:  # (a RuntimeError: the scene, the protrusion and what to change)
        return _failed(args, integration_line(exc, scene))
    except MemoryError:  # (the sizes of config/limits.py are checked first; what they do not foresee)
        return _failed(args, "out of memory (MemoryError); finished work is kept: ask for less (the sizes bounded in "
                             "pipeline/config/limits.py), or run on a machine with more memory")
    except OSError as exc:  # the file system: a full disk, permissions, a name too long, a folder for a file
        if exc.filename is None and exc.errno is not None and (out or args.out) is not None:
            exc = OSError(exc.errno, exc.strerror, str(out or args.out))  # (a write that named no file: its folder)
        return _failed(args, os_error_line(exc))
    except KeyboardInterrupt as exc:
        return _ended(f"hdi {args.stage}", interrupts.signal_of(exc))
    except Exception:
        if interrupts.pending() is None:  # (an error of hdi's own: its traceback)
            raise
        return _ended(f"hdi {args.stage}", interrupts.pending())  # (what a signal broke: a dask worker it killed)


def _failed(args: argparse.Namespace, line: str) -> int:
    """The one line of an error (with ``-v`` its traceback first), exit code 2; a signal received meanwhile is
    answered instead (its effect, a broken pipe or a lost worker, is not the cause to report)."""
    signum = interrupts.pending()
    if signum is not None:
        return _ended(f"hdi {args.stage}", signum)
    if args.verbose:
        traceback.print_exc()
    interrupts.say(f"hdi {args.stage}: error: {line}")
    return 2


def entry(early: Early | None = None) -> None:  # pragma: no cover (the console script; tests run it as a process)
    """The ``hdi`` console script (:func:`pipeline.launch.entry`): :func:`main`, then a fast exit with its code.

    ``early``: the first run's kernel compile the console script started before importing this module
    (:func:`pipeline.model.first_run.start`), handed to the runner's compile-ahead
    (:func:`pipeline.model.compiled.adopt_early`) and stopped at the end if nothing adopted it; so is a
    background compile nothing waited for (an interrupted command: :func:`pipeline.model.compiled.stop_ahead`).
    The signals stay answered to the last instruction (:func:`pipeline.interrupts.handling`); during this
    clean-up one is recorded only (:func:`pipeline.interrupts.deferred`), then answered.

    Interpreter shutdown after a command costs ~0.3 s (numba's LLVM and the netCDF4/HDF5 teardown,
    measured on the 2-core machine: 2.0 s against 1.7 s for import + first simulation) and does
    nothing the command needs: every output is written and renamed into place, the folder lock and
    any cluster are released by their context managers. So once stdout, stderr and the log handlers
    are flushed the process ends with ``os._exit``. An exception still exits the normal way, with
    its traceback.
    """
    with interrupts.handling():
        compiled.adopt_early(early)
        try:
            code = main()
        except KeyboardInterrupt as exc:  # (between main's own answer and the clean-up below)
            code = _ended("hdi", interrupts.signal_of(exc))
        finally:  # (an exception's traceback still ends the compiles nothing adopted or waited for)
            with interrupts.deferred():
                compiled.stop_early()
                compiled.stop_ahead()
        with interrupts.deferred():
            signum = interrupts.pending()
            if signum is not None:
                code = _ended("hdi", signum)
            logging.shutdown()
            try:
                sys.stdout.flush()
                sys.stderr.flush()
            except (OSError, ValueError):  # (a reader that went away, e.g. `hdi ... | head`; a closed terminal)
                pass
            os._exit(code)


if __name__ == "__main__":  # pragma: no cover
    entry()

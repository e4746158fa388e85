"""The dynamics kernel against commit 87de7e7 (before the kernel's split into modules), in the same run.

The kernel rows of ``make bench`` can move from 3.10 / 8.29 ms to 4.96 / 13.03 ms (flying 5 nm /
sliding 11 nm) between two runs days apart, on a shared machine; only an A/B in one run separates the code
from the machine. This module extracts commit :data:`BASE` (``git archive``, once, into
``benchmarks/results/ab-<commit>/``, which keeps its numba cache between runs), captures each checkout's
kernel arguments of the paper scene (:func:`benchmarks.kernel_ab.capture`), gives the base's cases this
checkout's start states (:func:`benchmarks.kernel_ab.graft`: the static start is the model's, and moved in the
last bits since 87de7e7; the tables and parameters are equal), and times the two kernels
alternately, one fresh process per measurement (:func:`benchmarks.kernel_ab.timing`: the median of
``ROUNDS`` rounds of ``CALLS[case]`` calls), ``ALTERNATIONS`` times each.

Rows, per case (flying 5 nm, sliding 11 nm): the median over the processes of this checkout's kernel [s],
with ``base_median_s`` (87de7e7's), ``ratio_to_base`` (this / 87de7e7: below 1 is faster) and
``bit_identical`` (the two kernels' states, contact flags and extremes hash the same,
:func:`benchmarks.kernel_ab.digest`; false since the kernel fuses products and sums, docs/kernel.md, section
"Fused multiply-adds": the two then integrate the same problem to the last bits of each step). Without a
git clone (a source archive has no ``.git``), or without the commit in it, the row says so and is skipped.
"""

from __future__ import annotations

import io
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

from .common import ROOT, record, record_failure

#: The commit before the kernel's split into its compiled helpers
BASE = "87de7e7"
#: Calls per timed round, by case: ~50 ms of kernel per round
CALLS = {"flying_5": 10, "sliding_11": 4}
ROUNDS = 5
#: Processes per checkout and case, alternated A, B, A, B, ...
ALTERNATIONS = 4
SCRIPT = ROOT / "benchmarks" / "kernel_ab.py"
NAME = "dynamics kernel A/B against {base}, {case} (integrate only; ratio = this / {base})"


def base_checkout(commit: str = BASE, root: Path = ROOT) -> Path | str:
    """The source tree of ``commit`` in ``benchmarks/results/ab-<commit>/`` (extracted once), or why it
    cannot be had (a string: not a git clone, or the commit is not in it)."""
    if not (root / ".git").exists():
        return f"not a git clone ({root}/.git absent): the A/B against {commit} needs the commit"
    folder = root / "benchmarks" / "results" / f"ab-{commit}"
    if (folder / "pipeline").is_dir():
        return folder
    try:
        tar = subprocess.run(["git", "-C", str(root), "archive", "--format=tar", commit],
                             check=True, capture_output=True).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        err = getattr(exc, "stderr", b"") or b""
        return f"git archive {commit} failed ({err.decode(errors='replace').strip() or exc})"
    tmp = Path(tempfile.mkdtemp(prefix=f"ab-{commit}.", dir=folder.parent if folder.parent.is_dir() else None))
    with tarfile.open(fileobj=io.BytesIO(tar)) as t:
        t.extractall(tmp, filter="data")
    folder.parent.mkdir(parents=True, exist_ok=True)
    tmp.replace(folder)
    return folder


def _env(checkout: Path) -> dict[str, str]:
    """The environment of a kernel_ab process: the checkout's ``pipeline`` first on the path."""
    return {**os.environ, "PYTHONPATH": str(checkout), "MPLBACKEND": "Agg"}


def _script(checkout: Path, *args: object) -> None:
    """``kernel_ab.py ARGS`` with the checkout's ``pipeline``."""
    subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], check=True, capture_output=True,
                   env=_env(checkout), cwd=checkout)


def capture(checkout: Path, out: Path) -> None:
    """``kernel_ab.py capture``: the checkout's kernel arguments of the three cases into ``out``."""
    _script(checkout, "capture", out)


def time_once(checkout: Path, pkl: Path, case: str) -> tuple[float, str]:
    """One fresh process's median time [s] of one kernel call of ``case`` and its results' digest."""
    res = subprocess.run([sys.executable, str(SCRIPT), "time", str(pkl), case, str(CALLS[case]), str(ROUNDS)],
                         check=True, capture_output=True, text=True, env=_env(checkout), cwd=checkout)
    lines = res.stdout.split("\n")
    ms = next(float(ln.split()[1]) for ln in lines if ln.startswith(case + " "))
    dig = next(ln.split()[1] for ln in lines if ln.startswith("digest "))
    return ms * 1e-3, dig


def run(results: list[dict]) -> None:
    base = base_checkout()
    if isinstance(base, str):
        for case in CALLS:
            record_failure(results, NAME.format(base=BASE, case=case), f"skipped: {base}")
        return
    with tempfile.TemporaryDirectory() as tmp:
        pkl = {"this": Path(tmp) / "this.pkl", "base": Path(tmp) / "base.pkl"}
        tree = {"this": ROOT, "base": base}
        try:  # (capture, starts, graft)
            for side in ("base", "this"):  # (the first capture of the base compiles its kernels: ~1 min of CPU, once)
                capture(tree[side], pkl[side])
            # the same problem for both kernels: the base's cases start from this checkout's start states
            y0 = Path(tmp) / "y0.npz"
            _script(tree["this"], "starts", pkl["this"], y0)
            _script(tree["base"], "graft", pkl["base"], y0)
        except subprocess.CalledProcessError as exc:
            for case in CALLS:
                record_failure(results, NAME.format(base=BASE, case=case),
                               f"kernel_ab {exc.cmd[2]} failed: {(exc.stderr or b'').decode(errors='replace')[-300:]}")
            return
        for case in CALLS:
            times: dict[str, list[float]] = {"this": [], "base": []}
            digests: dict[str, set[str]] = {"this": set(), "base": set()}
            for i in range(ALTERNATIONS):
                # alternate which side goes first, so a load that rises during the row hurts both alike
                for side in (("base", "this") if i % 2 == 0 else ("this", "base")):
                    t, d = time_once(tree[side], pkl[side], case)
                    times[side].append(t)
                    digests[side].add(d)
            this, b = statistics.median(times["this"]), statistics.median(times["base"])
            record(results, NAME.format(base=BASE, case=case), times["this"], base_median_s=b, times_s=times["this"],
                   base_times_s=times["base"], ratio_to_base=this / b, base_commit=BASE,
                   bit_identical=digests["this"] == digests["base"] and len(digests["this"]) == 1,
                   calls_per_round=CALLS[case], rounds=ROUNDS, processes_per_side=ALTERNATIONS)


if __name__ == "__main__":  # pragma: no cover
    import json
    rows: list[dict] = []
    run(rows)
    print(json.dumps(rows, indent=2))

"""Upper bounds on what a scene asks to compute: the sizes of its arrays and grids, before any is made.

Every key that sizes an array or a grid is bounded here, by the size it makes (a table's rows, a
history's samples, a record's samples, a grid's scenes, a study's evaluations): a size beyond its
limit ends in one line naming the keys, the size, the limit and ``--yes``, before anything is
allocated (``--set tfc.protrusion_nm=1e6`` allocated a 20-million-row table and was OOM-killed).
``--yes`` runs a big job that is legitimate. A value that makes no physical sense is refused even
with ``--yes``: :func:`check_physical` (a protrusion beyond the flying height by more than
:data:`MAX_INTERFERENCE_NM`, where the rough-surface contact model of nm asperities has long lost
its meaning; docs/model.md, section "ISBL interface").

The limits are about 100 to 1000 times the paper scene's sizes (701 table rows, 8000 history samples,
8000 record samples, 76 scenes), far above any study here and below what exhausts a 24 GiB machine.
"""

from __future__ import annotations

import math
from typing import Any

#: Deepest interference [nm] a scene may ask for (protrusion - flying height): 100 nm, against the
#: paper's 4 nm and the 0.5 nm roughness; beyond it the asperity model (nm summits on a nominal area)
#: describes nothing physical.
MAX_INTERFERENCE_NM = 100.0
#: Rows of the interface tables (paper scene: 701), ~1 MB per million rows per quantity.
MAX_TABLE_ROWS = 200_000
#: Output samples of one run, duration / output step (paper: 8000); ~20 histories of 8 bytes each.
MAX_HISTORY_SAMPLES = 2_000_000
#: Samples of the DMW record, duration x sampling rate (paper: 8000).
MAX_RECORD_SAMPLES = 20_000_000
#: Scenes of a sweep, protrusions x roughness sets x damping ratios x realisations (paper: 76).
MAX_SCENES = 100_000
#: Evaluations (small sweeps) of a parameter study (identify's default: 1337).
MAX_EVALUATIONS = 50_000


class LimitError(ValueError):
    """A scene asks for more than a limit of this module (one line; ``--yes`` may lift it)."""


def _count(start: float, stop: float, step: float) -> int:
    return int(math.floor((stop - start) / step + 1e-9)) + 1


def deepest_protrusion_nm(scene: Any) -> float:
    """The deepest protrusion [nm] the scene or its sweep or studies ask for."""
    deepest = max(scene["tfc"]["protrusion_nm"], scene["sweep"]["protrusion_nm"]["stop"])
    grid = scene["sensitivity"]["protrusion_nm"]
    return max(deepest, grid["stop"]) if grid else deepest


def check_physical(scene: Any, where: str = "scene") -> None:
    """Refuse a protrusion beyond the flying height by more than :data:`MAX_INTERFERENCE_NM` [nm]."""
    fh0 = scene["air_bearing"]["flying_height_nm"]
    for key, value in (("tfc.protrusion_nm", scene["tfc"]["protrusion_nm"]),
                       ("sweep.protrusion_nm stop", scene["sweep"]["protrusion_nm"]["stop"]),
                       ("sensitivity.protrusion_nm stop", (scene["sensitivity"]["protrusion_nm"] or {}).get("stop"))):
        if value is not None and value - fh0 > MAX_INTERFERENCE_NM:
            raise LimitError(f"{where}: {key} = {value:g} nm: expected at most the flying height "
                             f"air_bearing.flying_height_nm = {fh0:g} nm + {MAX_INTERFERENCE_NM:g} nm; an interference "
                             f"of {value - fh0:g} nm is outside the rough-surface contact model")


def table_rows(scene: Any) -> int:
    """Rows of the interface tables (:func:`pipeline.stages.interface.separation_labels`), estimated
    from the scene's roughness sigma (an AFM surface's may differ a little)."""
    sol = scene["solver"]
    fh0 = scene["air_bearing"]["flying_height_nm"]
    lo = min(sol["table_min_sigma"] * scene["roughness"]["sigma_nm"], fh0 - deepest_protrusion_nm(scene) - 1.0)
    step = sol["table_step_nm"]
    first = math.floor(lo / step + 1e-9)
    return math.ceil((sol["table_max_nm"] - first * step) / step - 1e-9) + 1


def sizes(scene: Any, stage: str) -> list[tuple[str, int, int]]:
    """``(what, size, limit)`` of every size the stage makes for the scene."""
    sol, dmw = scene["solver"], scene["dmw"]
    out = []
    if {"contact", "adhesion"} & set(scene["scene"]["effects"]) and stage != "roughness":
        out.append((f"interface table rows (solver.table_step_nm = {sol['table_step_nm']:g}, table_min_sigma, "
                    f"table_max_nm = {sol['table_max_nm']:g}, the deepest protrusion)", table_rows(scene),
                    MAX_TABLE_ROWS))
    if stage not in ("roughness", "interface", "dmw"):
        out.append((f"history samples per run (solver.duration_ms = {sol['duration_ms']:g} / output_step_ns = "
                    f"{sol['output_step_ns']:g})",
                    int(sol["duration_ms"] * 1e6 / sol["output_step_ns"]) + 1, MAX_HISTORY_SAMPLES))
    if stage != "roughness" and "dmw" in scene["scene"]["effects"]:
        from .stages.dmw import settings  # (the record's default length: the run's plus the pads' delay)
        dur_ms = settings(scene)["duration_s"] * 1e3
        out.append((f"DMW record samples (dmw.duration_ms = {dur_ms:g} x sample_rate_mhz = "
                    f"{dmw['sample_rate_mhz']:g})", int(dur_ms * 1e3 * dmw["sample_rate_mhz"]), MAX_RECORD_SAMPLES))
    if stage in ("sweep", "run"):
        g = scene["sweep"]["protrusion_nm"]
        n = (_count(g["start"], g["stop"], g["step"]) * len(scene["sweep"]["roughness"] or [None])
             * len(scene["sweep"]["damping_ratio"] or [None]) * scene["sweep"]["realisations"])
        out.append((f"sweep scenes (sweep.protrusion_nm = {{start={g['start']:g}, stop={g['stop']:g}, "
                    f"step={g['step']:g}}} x roughness sets x damping ratios x realisations)", n, MAX_SCENES))
    if stage == "identify":
        i = scene["identify"]
        n_par = len(i["parameters"])
        n = i["population"] * n_par * (i["generations"] + 1) + i["profile_points"] * n_par
        out.append(("identify evaluations (population x parameters x (generations + 1) + profile_points x "
                    "parameters)", n, MAX_EVALUATIONS))
    if stage == "sensitivity":
        s = scene["sensitivity"]
        n_par = len(s["parameters"])
        n = (s["morris_trajectories"] * (n_par + 1) if "morris" in s["methods"] else 0) \
            + (s["sobol_samples"] * (n_par + 2) if "sobol" in s["methods"] else 0)
        g = s["protrusion_nm"] or scene["sweep"]["protrusion_nm"]
        out.append(("sensitivity scenes (evaluations x protrusions of sensitivity.protrusion_nm)",
                    n * _count(g["start"], g["stop"], g["step"]), MAX_SCENES * 10))
    return out


def check_sizes(scene: Any, stage: str, yes: bool = False, where: str = "scene") -> None:
    """Refuse the first size beyond its limit, unless ``yes`` (and, always, :func:`check_physical`)."""
    check_physical(scene, where)
    if yes:
        return
    for what, size, limit in sizes(scene, stage):
        if size > limit:
            raise LimitError(f"{where}: {size:,} {what} exceed {limit:,}; pass --yes to run them anyway")

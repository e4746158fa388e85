"""How big the work a scene asks for is, against the limits of :mod:`pipeline.config.limits`.

The command line checks a stage's sizes before anything runs (one line per limit, ``--yes`` lifts
them): interface-table rows, history samples (per run, and kept by a whole sweep), DMW record samples,
sweep scenes and study evaluations.
"""

from __future__ import annotations

import math
from typing import Any

from .config.grid import range_count
from .config.limits import (check_physical, MAX_EVALUATIONS, MAX_HISTORY_SAMPLES, MAX_KEPT_HISTORY_SAMPLES,
                            MAX_RECORD_SAMPLES, MAX_SCENES, MAX_TABLE_ROWS, POLISH_EVALUATIONS, LimitError)
from .model import interface_tables
from .model.dmw_record import settings as dmw_settings
from .model.measured_dmw import record_samples
from .units import MS, NM, NS, S_IN_MS


def deepest_studied_protrusion_nm(scene: Any) -> float:
    """The deepest protrusion [nm] the scene, its sweep (:func:`pipeline.model.interface_tables.deepest_protrusion_nm`,
    the tables' own rule) or its sensitivity study ask for (a study makes tables of its own reach)."""
    deepest = interface_tables.deepest_protrusion_nm(scene)
    grid = scene["sensitivity"]["protrusion_nm"]
    return max(deepest, grid["stop"]) if grid else deepest


def table_rows(scene: Any) -> int:
    """Rows of the interface tables (:func:`pipeline.model.interface_tables.separation_rows` from
    :func:`~pipeline.model.interface_tables.table_floor` to ``solver.table_max_nm``), estimated from the
    scene's roughness sigma (an AFM surface's, and the summits', may differ a little)."""
    sol = scene["solver"]
    lo = interface_tables.table_floor(scene, (scene["roughness"]["sigma_nm"] * NM,), deepest_studied_protrusion_nm(scene))
    return interface_tables.separation_rows(lo / NM, sol["table_max_nm"], sol["table_step_nm"])[1]


def _count(x: float) -> int:
    """A size computed in floats as an integer; an overflow (a divisor of 1e-320) as a size beyond any limit."""
    return int(x) if math.isfinite(x) else 10**30


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
                    _count(sol["duration_ms"] * MS / NS / sol["output_step_ns"]) + 1, MAX_HISTORY_SAMPLES))
    if stage != "roughness" and "dmw" in scene["scene"]["effects"]:
        # (the record's default length: the run's plus the pads' delay)
        dur_ms = dmw_settings(scene)["duration_s"] * S_IN_MS
        out.append((f"DMW record samples (dmw.duration_ms = {dur_ms:g} x sample_rate_mhz = "
                    f"{dmw['sample_rate_mhz']:g})", _count(dur_ms * 1e3 * dmw["sample_rate_mhz"]), MAX_RECORD_SAMPLES))
        if dmw["source"] != "synthetic":  # (a measured record is read whole, whatever the duration used)
            out.append((f"samples of the measured DMW record (lines of dmw.source = {dmw['source']})",
                        record_samples(dmw["source"]), MAX_RECORD_SAMPLES))
    if stage in ("sweep", "run"):
        g = scene["sweep"]["protrusion_nm"]
        n = (range_count(g) * len(scene["sweep"]["roughness"] or [None])
             * len(scene["sweep"]["damping_ratio"] or [None]) * scene["sweep"]["realisations"])
        out.append((f"sweep scenes (sweep.protrusion_nm = {{start={g['start']:g}, stop={g['stop']:g}, "
                    f"step={g['step']:g}}} x roughness sets x damping ratios x realisations)", n, MAX_SCENES))
        per_run = _count(sol["duration_ms"] * MS / NS / sol["output_step_ns"]) + 1
        kept = len(set(scene["sweep"]["histories_nm"] or scene["report"]["histories_nm"] or []))
        out.append((f"kept history samples ({kept} protrusions of sweep.histories_nm (else report.histories_nm) x "
                    "roughness sets x damping ratios x samples per run)",
                    kept * len(scene["sweep"]["roughness"] or [None]) * len(scene["sweep"]["damping_ratio"] or [None])
                    * per_run, MAX_KEPT_HISTORY_SAMPLES))
    if stage == "statics":  # (within `run` the sweep's count bounds the same grid)
        g = scene["sweep"]["protrusion_nm"]
        out.append((f"statics protrusions (sweep.protrusion_nm = {{start={g['start']:g}, stop={g['stop']:g}, "
                    f"step={g['step']:g}}})", range_count(g), MAX_SCENES))
    if stage == "identify":
        i = scene["identify"]
        n_par = len(i["parameters"])
        reopt = i["profile_evaluations"] if i["profile_method"] == "optimised" else 0
        polish = POLISH_EVALUATIONS if i["polish"] else 0
        n = (i["population"] * n_par * (i["generations"] + 1) + (i["profile_points"] + reopt + polish) * n_par) \
            * i["realisations"]
        out.append(("identify evaluations (population x parameters x (generations + 1) + (profile_points + "
                    "profile_evaluations of an optimised profile + the polish's budget) x parameters, x "
                    "realisations)", n, MAX_EVALUATIONS))
    if stage == "sensitivity":
        s = scene["sensitivity"]
        n_par = len(s["parameters"])
        n = (s["morris_trajectories"] * (n_par + 1) if "morris" in s["methods"] else 0) \
            + (s["sobol_samples"] * (n_par + 2) if "sobol" in s["methods"] else 0)
        g = s["protrusion_nm"] or scene["sweep"]["protrusion_nm"]
        out.append(("sensitivity scenes (evaluations x protrusions of sensitivity.protrusion_nm)",
                    n * range_count(g), MAX_SCENES * 10))
    return out


def check_sizes(scene: Any, stage: str, yes: bool = False, where: str = "scene", lift: str = "--yes") -> None:
    """Refuse the first size beyond its limit, unless ``yes`` (and, always, :func:`check_physical`); ``lift``:
    how the message asks for ``yes`` (``--yes``, or a Python call's ``yes=True``)."""
    check_physical(scene, where)
    if yes:
        return
    for what, size, limit in sizes(scene, stage):
        if size > limit:
            raise LimitError(f"{where}: {size:,} {what} exceed {limit:,}; pass {lift} to run them anyway")

"""Stage ``report``: figures, a summary table and a comparison with the paper, from the datasets in ``out``.

Reads (``out`` is the scene's results folder):

=========================  ========  ==========================================================
file                       needed    used for
=========================  ========  ==========================================================
``sweep.nc``               required  Figs 6-7, summary table, optimum points, comparison
``sweep_histories.nc``     optional  Figs 3-5 (the protrusions of ``[report] histories_nm``)
``calibration.nc``         optional  ``calibration.png``, the calibration outcome
``roughness.nc``           optional  ``roughness.png``
``dmw.nc``                 optional  ``dmw.png``, the DMW rms in the comparison
``interface.nc``           optional  plasticity index, shear strength line of Fig. 7
``ensemble.nc``            optional  the paper's targets over ``report.realisations`` DMW records
                                     (upstream when ``report.realisations`` > 1), with spreads
``bulge.nc``               optional  ``bulge.png``: the bulge lift versus apex gap (a tabulated
                                     bulge law: current then, as an input of the sweep)
``statics.nc``             optional  ``statics.png``, the static states versus protrusion
=========================  ========  ==========================================================

A missing optional input skips its figures (a stale PNG of an earlier run is removed) and the
reason is logged and written into ``summary.md``; nothing else fails. Run through
:mod:`pipeline.runner` (``hdi report``), the datasets are first made current for the scene, and each is
read through :meth:`pipeline.runner.Inputs.dataset`, which refuses one made from other inputs; a
dataset whose stage is not upstream of the report for this scene (``calibration.nc`` when the scene
fixes k) is not read (with :meth:`pipeline.runner.Inputs.folder`, every dataset present is).

Writes ``out/figures/`` (returned):

* ``fig3_clearance.png``: clearance histories while flying (lowest history protrusion), in light
  contact (highest) and at up to two history protrusions between (a step of the band), the paper's Fig. 3;
* ``fig4_forces.png``: contact, friction, adhesion and net force histories in light contact (Fig. 4);
* ``fig5_stresses.png``: friction coefficient, mean pressure and shear stress histories (Fig. 5);
* ``fig6_fhm.png``: FHM/BV versus protrusion, regimes shaded, the 10 % line, measured touchdown (Fig. 6);
* ``fig7_shear.png``: shear stress and mean contact pressure versus protrusion past touchdown (Fig. 7);
* ``calibration.png``, ``roughness.png``, ``dmw.png``;
* ``bulge.png`` (with ``bulge.nc``): the bulge's lift versus apex gap beside p h = const (and the lift cap of
  ``air_bearing.lift_cap_gap_nm``);
* ``statics.png`` (with ``statics.nc``): the clearance of every static state versus protrusion, stable
  solid and unstable dashed, and the barriers out of the stable states beside the DMW's energy scales;
* ``band.png`` (with ``ensemble.nc``): the bouncing BV, the fraction bouncing above 20 %, the touchdown
  probability and the contact fraction over the DMW realisations versus protrusion;

and ``out/report/``:

* ``summary.csv``: one row per protrusion from 2 nm before the first contact to the end of the grid
  (the whole grid when nothing touches), for every roughness x damping combination, the scene's
  default combination first (roughness set ``scene``, or the first set; damping
  ``air_bearing.damping_ratio`` when it is on the grid, else the first), then the others in grid
  order. Header cells carry the units, ``name [unit]``; missing values are empty cells.
* ``summary.md``: the same table, one block per combination in that order, the two optimum points
  (:mod:`pipeline.analyses.optimum`) of every combination, the figure list and the skipped figures.
* ``comparison.md``: our numbers against what the paper states (touchdown, FHM at 4-7 nm, the
  stable-flying criterion, the plasticity index, A_n at 11 nm, the contact probability of k, the two
  optimum points), each with the difference and its likely cause, for the default combination.
  The text is generated from the datasets; no parameter is adjusted to close a gap.

The work is done in :mod:`pipeline.analyses` (slices, tables, figure jobs, comparison, narrative) on
the loaded datasets; this module loads them and writes what the analyses return.

Figures and tables of the histories use the default combination. With several combinations
Figs 6-7 draw one line per combination (regime shading from the default one).
"""

from __future__ import annotations

import errno
import logging
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..analyses import narrative, report_figures, report_tables
from ..analyses.paper_comparison import comparison_markdown, identification_markdown
from ..analyses.plots import DRAWING_MODULES
from ..analyses.report_figures import (BAND_FIGURE, BULGE_FIGURE, ENSEMBLE_FIGURE, FIGURES, INTERFACE_FIGURE,
                                      STATICS_FIGURE)
from ..analyses.report_settings import FIELDS as REPORT_FIELDS, ReportSettings, wants_ensemble
from ..analyses.sweep_slices import combinations, split_ensemble
from ..file_errors import is_read_only
from ..io import DatasetError, temporary_path
from ..model.contact_rule import needs_calibration
from ..paths import refuse_links
from ..validity import OutsideValidity, describe
from ..runner import Inputs, Stage

log = logging.getLogger(__name__)

#: Optional datasets: name -> the stage that writes it.
OPTIONAL = (("sweep_histories", "sweep"), ("calibration", "calibrate"), ("roughness", "roughness"),
            ("dmw", "dmw"), ("interface", "interface"), ("bulge", "bulge"), ("statics", "statics"))


def load(inputs: Inputs) -> dict[str, xr.Dataset | None]:
    """The report's datasets through ``inputs`` (``sweep`` required, read first; the others ``None``
    when absent, unreadable, made from other inputs, or not upstream of the report).

    A sweep over DMW realisations is reported through its first realisation; the whole ensemble is
    ``"ensemble"`` (``None`` for a single realisation); a heater-stepping sweep through its upward pass
    (:func:`pipeline.analyses.sweep_slices.split_ensemble`).
    """
    sweep = inputs.dataset("sweep.nc", stage="sweep", variables=("fhm_bv", "protrusion"))
    data: dict[str, xr.Dataset | None] = dict(zip(("sweep", "ensemble"), split_ensemble(sweep)))
    for name, stage in OPTIONAL:
        data[name] = None
        # under the runner only upstream datasets are current (Inputs.folder: the caller vouches for all)
        if not inputs.path(f"{name}.nc").is_file() or (inputs.upstream and stage not in inputs.upstream):
            continue
        try:
            data[name] = inputs.dataset(f"{name}.nc", stage=stage)
        except DatasetError as exc:
            log.warning("report: %s", exc)
    # the paper's checks over DMW realisations (report.realisations > 1: the ensemble stage is upstream)
    data["checks"] = None
    if inputs.path("ensemble.nc").is_file() and (not inputs.upstream or "ensemble" in inputs.upstream):
        data["checks"] = inputs.dataset("ensemble.nc", stage="ensemble")
    data["identify"] = (inputs.dataset("identify.nc", stage="identify") if inputs.optional.get("identify")
                        else None)  # current for this scene: the three-column comparison
    return data


def _write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` by a temporary file and a rename; an existing file keeps its mode."""
    refuse_links(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_path(path)
    tmp.write_text(text, encoding="utf-8")
    if path.is_file():
        shutil.copymode(path, tmp)
    tmp.replace(path)


def compute(scene: Any, inputs: Inputs) -> dict:
    """Draw the figures (``figures/``) and write the tables (``report/``) under ``inputs.staging``
    from the datasets in ``inputs.out``; the runner moves them into place."""
    data = load(inputs)
    sweep = data["sweep"]
    refuse_invalid(sweep, inputs.path("sweep.nc"))
    settings = ReportSettings.from_scene(scene)
    name = getattr(scene, "name", None) or str(sweep.attrs.get("scene_name", inputs.out.name))
    combos = combinations(sweep, settings.damping_ratio)
    figdir = inputs.staging / "figures"
    repdir = inputs.staging / "report"
    figdir.mkdir(parents=True, exist_ok=True)
    repdir.mkdir(parents=True, exist_ok=True)
    jobs, skipped = report_figures.figure_jobs(data, combos, settings, name, figdir)
    drawn = {a.name for _, args, _ in jobs for a in args if isinstance(a, Path)}
    stale = list(skipped) + [f for f in (ENSEMBLE_FIGURE, BAND_FIGURE, INTERFACE_FIGURE, BULGE_FIGURE, STATICS_FIGURE)
                             if f not in drawn]
    for f in stale:  # never leave a figure of an earlier run next to the new ones
        (figdir / f).unlink(missing_ok=True)
    made = report_figures.draw(jobs)
    header, rows = report_tables.summary_table(combos)
    _write_text(repdir / "summary.csv", report_tables.csv_text(header, rows))
    _write_text(repdir / "summary.md",
                report_tables.summary_markdown(combos, sweep, name, [p.name for p in made], skipped))
    comparison = comparison_markdown(combos, data, settings, name)
    if data["identify"] is not None:
        comparison += identification_markdown(data["identify"])
    _write_text(repdir / "comparison.md", comparison)
    for f, why in skipped.items():
        log.info("report: skipped %s: %s", f, why)
    log.info("report: %d figures, 3 tables", len(made))
    return {}


def _upstream(scene: Any) -> tuple[str, ...]:
    up = ["roughness", "interface", "statics", "sweep"]
    if scene.has("dmw"):
        up.append("dmw")
    if needs_calibration(scene):
        up.append("calibrate")
    if wants_ensemble(scene):
        up.append("ensemble")
    return tuple(up)


def _finish(scene: Any, out: Path, options: dict[str, Any]) -> None:
    """``--readme PAGE`` (``make readme``: docs/results.md): rewrite the page's generated section from
    this report's comparison (:func:`pipeline.analyses.narrative.readme_with_comparison`) and copy its
    figures beside it."""
    if options.get("readme"):
        update_readme(Path(options["readme"]), (out / "report" / "comparison.md").read_text(), out / "figures")


STAGE = Stage(
    "report", compute,
    outputs=tuple(f"figures/{f}" for f in FIGURES + (ENSEMBLE_FIGURE, BAND_FIGURE, INTERFACE_FIGURE, BULGE_FIGURE,
                                                      STATICS_FIGURE))
    + ("report/summary.csv", "report/summary.md", "report/comparison.md"),
    reads=REPORT_FIELDS, upstream=_upstream, optional=("identify",), finish=_finish, order=60, main_job=True,
    lazy_imports=DRAWING_MODULES,
    doc="the paper's figures, a summary table and the comparison with the paper")


def refuse_invalid(sweep: xr.Dataset, path: Path) -> None:
    """Raise :class:`pipeline.model.validity.OutsideValidity` (one line: which scenes, why) when a scene of
    the sweep is flagged in ``validity``: its numbers are not results of the model."""
    if "validity" not in sweep:
        return
    v = sweep["validity"]
    labels = []
    for idx in np.ndindex(v.shape):
        labels.append(", ".join(f"{dim} {sweep[dim].values[i]:g}" if sweep[dim].dtype.kind in "fiu"
                                else f"{dim} {sweep[dim].values[i]}" for dim, i in zip(v.dims, idx)))
    why = describe(v.values.reshape(-1), [f"[{s}]" for s in labels])
    if why is not None:
        raise OutsideValidity(f"{path}: {why}; no report drawn from them (see its variable validity)")


def update_readme(readme: Path, comparison: str, figdir: Path) -> None:
    """Replace the generated section of the page ``readme`` (docs/results.md) with ``comparison`` and copy
    the page's figures (:data:`pipeline.analyses.narrative.README_FIGURES`) from ``figdir`` to the folder
    ``figures/`` beside it (docs/figures/, which the page's and the README's image links name).
    A page without the section markers is left untouched; a symbolic link is written through (its
    target is updated, the link kept); a read-only page is refused."""
    if is_read_only(readme):
        raise PermissionError(errno.EACCES, "is read-only; make it writable (chmod u+w) or leave --readme out",
                              str(readme))
    text = narrative.readme_with_comparison(readme.read_text(), comparison)
    if text is None:
        log.warning("report: %s has no generated section markers; not updated", readme)
        return
    _write_text(readme.resolve(), text)  # (the rename would replace a link by a file)
    docs = readme.parent / "figures"
    docs.mkdir(parents=True, exist_ok=True)
    for name in narrative.README_FIGURES:
        if (figdir / name).is_file():
            (docs / name).write_bytes((figdir / name).read_bytes())
    log.info("report: updated the generated section of %s and %s", readme, docs)

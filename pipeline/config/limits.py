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

from typing import Any

#: Deepest interference [nm] a scene may ask for (protrusion - flying height): 100 nm, against the
#: paper's 4 nm and the 0.5 nm roughness; beyond it the asperity model (nm summits on a nominal area)
#: describes nothing physical.
MAX_INTERFERENCE_NM = 100.0
#: Largest magnitude of a number in a scene: far beyond any physical value in the scene's units (the
#: largest default is 1e5 N/m) and far below the float range, so no conversion to SI units or size
#: computed from it overflows (``solver.duration_ms = 1e308`` ended in an OverflowError).
MAX_MAGNITUDE = 1e100
#: Largest magnitude of an integer in a scene (a 64-bit integer, as numpy holds it, and TOML's range: a
#: 400-digit integer overflowed when converted to a float).
MAX_INTEGER = 2**63 - 1
#: Deepest nesting of lists and tables in a scene value: the deepest a scene writes is 3 (``sweep.roughness``,
#: a list of tables of lists of files); TOML's parser (and Python's) met a value nested 500 deep with a
#: RecursionError.
MAX_NESTING = 8
#: Rows of the interface tables (paper scene: 701), ~1 MB per million rows per quantity.
MAX_TABLE_ROWS = 200_000
#: Output samples of one run, duration / output step (paper: 8000); ~20 histories of 8 bytes each.
MAX_HISTORY_SAMPLES = 2_000_000
#: Output samples of every history a sweep keeps, histories x roughness sets x damping ratios x samples per
#: run (paper: 2 x 8000): the sweep holds them all in memory to write ``sweep_histories.nc``, ~20 variables
#: of 8 bytes each (3.2 GB at the limit); each run within :data:`MAX_HISTORY_SAMPLES` said nothing of the total.
MAX_KEPT_HISTORY_SAMPLES = 10 * MAX_HISTORY_SAMPLES
#: Samples of the DMW record, duration x sampling rate (paper: 8000).
MAX_RECORD_SAMPLES = 20_000_000
#: Scenes of a sweep, protrusions x roughness sets x damping ratios x realisations (paper: 76).
MAX_SCENES = 100_000
#: Evaluations (small sweeps) of a parameter study, times their DMW realisations (identify's default: 1337 x 8).
MAX_EVALUATIONS = 50_000
#: Steps the integrator takes in one run before it gives up (``max_steps`` of
#: :func:`pipeline.model.running.run_model`): a run of ``solver.duration_ms`` needs at least
#: duration / ``solver.max_step_ns`` of them, so a largest step below duration / MAX_STEPS can never finish.
MAX_STEPS = 5_000_000
#: Largest work of adhesion [J/m^2] of ``lubricant.work_of_adhesion_j_m2`` (and the bridges'): 9.4 times the
#: paper scene's 0.106 and above twice the surface energy of the carbon overcoats and lubricants of a disk
#: interface (2 gamma ~ 0.05-0.3 J/m^2). Beyond it the adhesive pull takes the run nowhere the model
#: describes: at 10 J/m^2 a 0.3-ms run of the paper scene at 9 nm did not finish in 5 minutes (1 J/m^2: 5 s),
#: and 1e99 overflowed the integrator with a traceback.
MAX_WORK_OF_ADHESION = 1.0
#: Budget of the identification's polish of the search's optimum (``identify.polish``), in evaluations per free
#: parameter [1] (:func:`pipeline.analyses.identification.search._polish`; docs/model.md, section "Identification"): it
#: also stops before it, after its poll at the first step at or below the profile walks' step that finds
#: nothing better. Here, beside the other budgets, so that the sizes of a scene's work are checked
#: (:mod:`pipeline.sizing`) without importing the identification.
POLISH_EVALUATIONS = 40
#: Largest ``sensitivity.bootstrap``: resamples of the confidence intervals (default 200; the
#: resampling error of an interval's end falls as 1/sqrt(B), so 1e5 is far below any use; 1e9 took 15 GiB).
MAX_BOOTSTRAP = 100_000


class LimitError(ValueError):
    """A scene asks for more than a limit of this module (one line; ``--yes`` may lift it)."""


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



"""The report's summary tables, ``summary.csv`` and ``summary.md``, as text (pure functions).

Rows: every protrusion from :data:`BEFORE_CONTACT_NM` before the first contact to the end of the grid
(the whole grid when nothing touches), for every roughness x damping combination in the order of
:func:`pipeline.analyses.sweep_slices.combinations`. Header cells carry the units, ``name [unit]``;
missing values are empty cells in the CSV and ``–`` in Markdown.
"""

from __future__ import annotations

import csv
import io
import math
from typing import Any

import numpy as np
import xarray as xr

from . import optimum as opt
from ..variables import SCALARS, regime_name
from .markdown import header_cell, number, table
from .sweep_slices import TOL, attr_float, combo_title, first_contact

#: Summary columns: variable -> header label (the unit is appended from the dataset).
COLUMNS = (("clearance", "clearance"), ("fhm_bv", "FHM/BV"), ("interference", "interference"),
           ("mean_pressure", "mean pressure"), ("shear_stress", "shear stress"),
           ("friction_coefficient", "friction coefficient"), ("contact_force", "contact force"),
           ("friction_force", "friction force"), ("adhesion_force", "adhesion force"),
           ("contact_fraction", "contact fraction"))
#: The tables start this far before the first contact [nm].
BEFORE_CONTACT_NM = 2.0

Combos = list[tuple[dict[str, Any], xr.Dataset]]


def table_rows(ds: xr.Dataset) -> np.ndarray:
    """Indices of the summary rows: from 2 nm before the first contact to the end (all without contact)."""
    x = ds["protrusion"].values
    fc = first_contact(ds)
    if fc is None:
        return np.arange(x.size)
    return np.flatnonzero(x >= fc - BEFORE_CONTACT_NM - TOL)


def unit_of(ds: xr.Dataset, name: str) -> str:
    """Units of a sweep variable: its attribute, else its declaration in pipeline/variables.py."""
    declared = SCALARS[name].units if name in SCALARS else ""
    return str(ds[name].attrs.get("units", declared)) if name in ds else declared


def summary_table(combos: Combos) -> tuple[list[str], list[list[Any]]]:
    """Header and rows (values in dataset units) of ``summary.csv``."""
    ds0 = combos[0][1]
    present = [(n, lab) for n, lab in COLUMNS if any(n in ds for _, ds in combos)]
    header = ["roughness", "damping [1]", "protrusion [nm]", "regime"] + \
             [header_cell(lab, unit_of(ds0, n) or next((unit_of(ds, n) for _, ds in combos if n in ds), ""))
              for n, lab in present]
    rows = []
    for labels, ds in combos:
        x = ds["protrusion"].values
        reg = np.asarray(ds["regime"].values).reshape(-1) if "regime" in ds else np.full(x.size, -1)
        for i in table_rows(ds):
            row: list[Any] = [labels["roughness"] or "", labels["damping"] if labels["damping"] is not None else "",
                              float(x[i]), regime_name(reg[i])]
            for n, _ in present:
                row.append(float(np.asarray(ds[n].values).reshape(-1)[i]) if n in ds else math.nan)
            rows.append(row)
    return header, rows


def csv_text(header: list[str], rows: list[list[Any]]) -> str:
    """The table as CSV text: floats to 6 significant digits, missing (non-finite) values as empty cells."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow(["" if isinstance(v, float) and not np.isfinite(v) else
                    (f"{v:.6g}" if isinstance(v, float) else v) for v in r])
    return buf.getvalue()


def optima_lines(combos: Combos) -> list[str]:
    """The two optimum points (:mod:`pipeline.analyses.optimum`) of every combination, as Markdown list lines."""
    lines = []
    for labels, ds in combos:
        pts = opt.optimum_points(ds)
        lines.append(f"- {combo_title(labels, ds)}:")
        for p in pts.values():
            lines.append(f"  - {p.describe()}")
    return lines


def summary_markdown(combos: Combos, sweep: xr.Dataset, name: str, figures: list[str],
                     skipped: dict[str, str]) -> str:
    """``summary.md``: the table per combination, the optimum points, the figures drawn (file names)
    and the skipped ones with their reasons."""
    header, rows = summary_table(combos)
    k = attr_float(sweep, "k")
    out = [f"# Summary of the sweep: scene `{name}`", "",
           f"Contact criterion constant k = {number(k)} ({sweep.attrs.get('k_source', 'source not recorded')}); "
           f"steady window {sweep.attrs.get('steady_window', '?')}; FHM/BV measure "
           f"{sweep.attrs.get('fhm_measure', '?')} over FH0.", "",
           "Rows: every protrusion from 2 nm before the first contact to the end of the grid (the whole grid "
           "when nothing touches), in the paper's Table III spirit. Columns are steady-window values "
           "(definitions in `pipeline/model/outcomes.py`); '–' = undefined (no contact). One block per roughness x "
           "damping combination, the scene's default combination first; `summary.csv` holds the same rows.", ""]
    n_cols = len(header)
    for labels, ds in combos:
        block = [r for r in rows if r[0] == (labels["roughness"] or "") and
                 (r[1] == "" or labels["damping"] is None or abs(float(r[1]) - labels["damping"]) < 1e-12)]
        fc = first_contact(ds)
        out += [f"## {combo_title(labels, ds)}", "",
                f"First contact at {fc:g} nm." if fc is not None else "No contact anywhere on the grid.", ""]
        body = [[number(r[2], 6), r[3]] + [number(v) for v in r[4:n_cols]] for r in block]
        out += [table(header[2:], body), ""]
    out += ["## Optimum operating points", "",
            f"(a) just before touchdown: flying, FHM < {opt.FHM_LIMIT:g} %, least clearance; (b) steady sliding: "
            f"surfing, BV < {opt.BV_LIMIT:g} %, least interference (`pipeline/analyses/optimum.py`; ties go to the smaller "
            "protrusion).", ""]
    out += optima_lines(combos) + [""]
    out += ["## Figures", ""]
    out += [f"- `figures/{f}`" for f in figures]
    for f, why in skipped.items():
        out.append(f"- `figures/{f}`: skipped, {why}")
    return "\n".join(out) + "\n"

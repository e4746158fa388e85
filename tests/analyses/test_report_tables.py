"""The report's summary tables as text (pipeline/analyses/report_tables.py) on a hand-made sweep: rows from 2 nm
before the first contact to the end of the grid (all of it when nothing touches), one block per roughness x
damping combination with the default first, header cells with their units, and a CSV that reads back to the
values at 6 significant digits with missing values as empty cells."""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses import report_tables as rt
from pipeline.analyses.sweep_slices import combinations

X = np.round(np.arange(6.0, 10.01, 0.2), 10)            # 21 protrusions [nm]


def _slice(first_contact: float | None) -> xr.Dataset:
    reg = np.where(X >= first_contact - 1e-9, 2, 0) if first_contact is not None else np.zeros(X.size, int)
    clearance = 11.0 - X - 0.69
    return xr.Dataset({"regime": ("protrusion", reg), "clearance": ("protrusion", clearance, {"units": "nm"}),
                       "fhm_bv": ("protrusion", np.where(reg == 0, 1.0 / 3.0, np.nan), {"units": "%"})},
                      coords={"protrusion": X})


def test_the_rows_start_2_nm_before_the_first_contact():
    rows = rt.table_rows(_slice(9.4))
    assert X[rows[0]] == pytest.approx(7.4) and X[rows[-1]] == 10.0 and rows.size == 14
    assert rt.table_rows(_slice(6.6)).size == X.size                     # 2 nm before is off the grid
    np.testing.assert_array_equal(rt.table_rows(_slice(None)), np.arange(X.size))


def test_the_summary_table_has_a_block_per_combination_with_units_in_the_header():
    sweep = xr.concat([_slice(9.4), _slice(8.0)], dim=xr.DataArray([0.02, 0.05], dims="damping", name="damping"))
    sweep["regime"] = sweep["regime"].astype(int)
    combos = combinations(sweep, damping_ratio=0.05)
    header, rows = rt.summary_table(combos)
    assert header == ["roughness", "damping [1]", "protrusion [nm]", "regime", "clearance [nm]", "FHM/BV [%]"]
    # the scene's damping 0.05 first: contact from 8.0 nm, rows from 6.0 nm; then 0.02: from 7.4 nm
    assert len(rows) == X.size + 14
    assert rows[0][:4] == ["", 0.05, 6.0, "flying"] and rows[X.size][:3] == ["", 0.02, pytest.approx(7.4)]
    assert rows[X.size + 10][3] == "surfing"                              # 9.4 nm of the 0.02 block
    assert rows[0][4] == pytest.approx(11.0 - 6.0 - 0.69) and math.isnan(rows[-1][5])


def test_the_csv_reads_back_at_six_significant_digits_with_empty_missing_cells():
    header, rows = rt.summary_table(combinations(_slice(9.4)))
    text = rt.csv_text(header, rows)
    back = list(csv.reader(io.StringIO(text)))
    assert back[0] == header and len(back) == 1 + len(rows)
    first = back[1]
    assert first[2] == "7.4" and first[3] == "flying" and first[5] == "0.333333"
    assert back[-1][5] == ""                                              # FHM of a contact row: missing
    for got, want in zip(back[1:], rows):
        assert float(got[4]) == pytest.approx(want[4], rel=5e-6)


def test_units_come_from_the_dataset_else_from_the_declaration():
    ds = _slice(None)
    assert rt.unit_of(ds, "clearance") == "nm" and rt.unit_of(ds, "fhm_bv") == "%"
    assert rt.unit_of(ds, "contact_force") == "mN"                       # declared in pipeline/variables.py
    assert rt.unit_of(ds.assign(clearance=ds["clearance"].assign_attrs(units="um")), "clearance") == "um"

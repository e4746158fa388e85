"""The report's Markdown text (pipeline/analyses/markdown.py): numbers to a given count of significant digits, a
dash for a missing or non-finite value, signed differences with ``+0`` below 1e-9, and tables whose rows read
back cell for cell."""

from __future__ import annotations

import math

import pytest

from pipeline.analyses import markdown as md


@pytest.mark.parametrize("value, digits, text", [
    (3.14159265, 4, "3.142"), (0.000123456, 3, "0.000123"), (123456.0, 4, "1.235e+05"), (-2.5, 4, "-2.5"),
    (7.0, 1, "7"), (0.0, 4, "0")])
def test_number_keeps_the_significant_digits_asked_for(value, digits, text):
    assert md.number(value, digits) == text
    assert float(md.number(value, digits)) == pytest.approx(value, rel=0.5 * 10 ** (1 - digits))


@pytest.mark.parametrize("missing", [None, math.nan, math.inf, -math.inf])
def test_a_missing_or_infinite_value_is_a_dash(missing):
    assert md.number(missing) == md.difference(missing) == "–"


def test_a_difference_is_signed_with_its_unit_and_relative_difference():
    assert md.difference(0.123456, "nm") == "+0.123 nm"
    assert md.difference(-4.0, "nm", -12.3456) == "-4 nm (-12 %)"
    assert md.difference(2.0, "", 150.0) == "+2 (+1.5e+02 %)"
    # below 1e-9 a difference is no difference: "+0", never "-1e-12"
    assert md.difference(-1e-12, "mN", 1e-11) == "+0 mN (+0 %)"
    assert md.difference(1e-9, "nm") == "+1e-09 nm"           # (1e-9 itself is kept)
    assert md.difference(1.0, "nm", math.nan) == "+1 nm"      # no relative difference to state


def test_a_header_cell_carries_its_unit_in_brackets():
    assert md.header_cell("clearance", "nm") == "clearance [nm]"
    assert md.header_cell("regime", "") == "regime"


def test_a_table_reads_back_cell_for_cell():
    header = ["protrusion [nm]", "regime", "FHM [%]"]
    rows = [[9.5, "flying", md.number(1.23456)], [10.0, "sliding", md.number(None)]]
    lines = md.table(header, rows).split("\n")
    assert len(lines) == 2 + len(rows) and lines[1] == "|---|---|---|"
    cells = [[c.strip() for c in line.strip("|").split("|")] for line in lines]
    assert cells[0] == header
    assert cells[2:] == [["9.5", "flying", "1.235"], ["10.0", "sliding", "–"]]

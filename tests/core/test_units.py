"""The units table: every scene key's unit suffix has an SI factor and a CF unit, and they agree with UDUNITS."""

from __future__ import annotations

import math

import cf_units
import pytest

from pipeline import units
from pipeline.config.scene import SCHEMA, unit_suffix

#: The SI unit each suffix converts to (UDUNITS spelling).
SI_OF = {"nm": "m", "um": "m", "mm": "m", "m": "m", "gpa": "Pa", "mpa": "Pa", "pa": "Pa", "khz": "Hz", "hz": "Hz",
         "mhz": "Hz", "ms": "s", "us": "s", "ns": "s", "s": "s", "j_m2": "J m-2", "n_s_m": "N s m-1", "n_m": "N m-1",
         "kg_m3": "kg m-3", "kg": "kg", "n": "N", "mn": "N", "mw": "W", "nm_per_mw": "m W-1", "per_um2": "m-2", "per_m2": "m-2", "rpm": "rad s-1",
         "sigma": "1"}


def test_every_suffix_of_the_schema_is_in_the_table():
    used = {unit_suffix(k) for keys in SCHEMA.values() for k in keys} - {None}
    assert used and used <= set(units.SUFFIX_FACTORS) and used <= set(units.SUFFIX_UNITS)
    assert set(units.SUFFIX_FACTORS) == set(units.SUFFIX_UNITS) == set(SI_OF)


@pytest.mark.parametrize("suffix", sorted(units.SUFFIX_FACTORS))
def test_si_factor_is_the_udunits_conversion(suffix):
    """1 [unit] in SI, by UDUNITS, equals the table's factor (rpm: one revolution, 2 pi rad, per minute)."""
    unit = cf_units.Unit(units.cf_unit(suffix))
    expected = unit.convert(1.0, cf_units.Unit(SI_OF[suffix])) if suffix != "rpm" else 2 * math.pi / 60
    # tol: UDUNITS' factor against the table's literal: IEEE arithmetic alone, an ulp or two
    assert units.si_factor(suffix) == pytest.approx(expected, rel=1e-15)


def test_ratios_between_units_are_exact_literals():
    # the literals equal the ratio of the SI factors to the last bit that matters (they exist because
    # the quotient of two factors rounds differently from the literal)
    # tol: a quotient of two literals against a literal: IEEE arithmetic alone, an ulp or two
    assert units.NM_IN_UM == pytest.approx(units.NM / units.UM, rel=1e-15)
    # tol: a quotient of two literals against a literal: IEEE arithmetic alone, an ulp or two
    assert units.UM_IN_NM == pytest.approx(units.UM / units.NM, rel=1e-15)
    # tol: a quotient of two literals against a literal: IEEE arithmetic alone, an ulp or two
    assert units.PER_NM2_IN_PER_UM2 == pytest.approx((units.UM / units.NM) ** 2, rel=1e-15)
    # tol: a quotient of two literals against a literal: IEEE arithmetic alone, an ulp or two
    assert units.MHZ_IN_KHZ == pytest.approx(units.MHZ / units.KHZ, rel=1e-15)
    assert units.UM / units.NM != 1e3  # why the literals exist


def test_unknown_suffix_names_the_known_ones():
    with pytest.raises(KeyError, match="unit suffix 'furlong' unknown; expected one of"):
        units.si_factor("furlong")

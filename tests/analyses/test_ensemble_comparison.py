"""The report's table of the paper targets over DMW realisations (pipeline/analyses/ensemble_comparison.py) on a
hand-made ``ensemble.nc``: each value with its 10-90 % range or its mean +- 1 standard deviation, ``none`` for a
value that does not exist, the touchdown probability written from its last 0 to its first 1, and the count of
realisations in contact where the light-contact means are taken."""

from __future__ import annotations

import numpy as np
import xarray as xr

from pipeline.analyses import ensemble_comparison as ec

X = np.array([9.0, 9.2, 9.4, 9.6, 9.8, 10.0])


def _ensemble() -> xr.Dataset:
    realisations = 4
    return xr.Dataset({
        "value_touchdown": ((), 9.5, {"long_name": "touchdown protrusion over the DMW realisations", "units": "nm",
                                      "paper": "9.8 nm", "spread": "10-90 % of the realisations"}),
        "spread_touchdown": ("bound", [9.3, 9.7]),
        "single_touchdown": ((), 9.4),
        "value_sliding_bv": ((), 1.25, {"long_name": "light-contact BV over the DMW realisations", "units": "%",
                                        "paper": "1 %", "spread": ec.SPREAD_STD, "protrusions_nm": [9.6]}),
        "spread_sliding_bv": ("bound", [1.0, 1.5]),
        "single_sliding_bv": ((), np.nan),
        "touchdown_probability": ("protrusion", [0.0, 0.0, 0.25, 0.75, 1.0, 1.0]),
        "dmw_seed": ("realisation", [11, 12, 13, 14]),
    }, coords={"protrusion": X, "realisation": np.arange(realisations)})


def test_a_value_cell_carries_its_spread():
    assert ec.value_cell(9.5, 9.3, 9.7, "nm", "10-90 %") == "9.5 nm (10-90 %: 9.3-9.7)"
    assert ec.value_cell(1.25, 1.0, 1.5, "%", ec.SPREAD_STD) == "1.25 ± 0.25 %"
    assert ec.value_cell(0.5, 0.5, 0.5, "1", ec.SPREAD_STD) == "0.5 ± 0"           # no unit for "1"
    assert ec.value_cell(1.25, np.nan, np.nan, "%", ec.SPREAD_STD) == "1.25 % (one value)"
    assert ec.value_cell(9.5, np.nan, 9.7, "nm", "10-90 %") == "9.5 nm (spread: –)"
    assert ec.value_cell(np.nan, 9.3, 9.7, "nm", "10-90 %") == "none"


def test_the_targets_are_read_in_their_order():
    ens = _ensemble()
    assert ec.target_names(ens) == ["touchdown", "sliding_bv"]
    assert ec.target_cell(ens, "touchdown") == "9.5 nm (10-90 %: 9.3-9.7)"
    column = ec.main_table_column(["touchdown [nm]", "FHM at 5 nm", "A_n at 11 nm"], ens, 11.0)
    assert column == ["9.5 nm (10-90 %: 9.3-9.7)", "–", "–"]


def test_the_section_states_the_realisations_the_probability_and_the_contact_count():
    text = ec.ensemble_markdown(_ensemble())
    assert "## Paper targets over 4 DMW realisations" in text and "(seeds 11, 12, 13, 14;" in text
    rows = [line for line in text.splitlines() if line.startswith("| ")]
    assert rows[1] == "| touchdown protrusion | 9.8 nm | 9.5 nm (10-90 %: 9.3-9.7) | 9.4 nm |"
    assert rows[2] == "| light-contact BV | 1 % | 1.25 ± 0.25 % | none |"
    # from the last 0 (9.2 nm) to the first 1 (9.8 nm)
    assert ("Touchdown probability versus protrusion: 0 below 9.2 nm; 9.2 nm: 0, 9.4 nm: 0.25, 9.6 nm: 0.75, "
            "9.8 nm: 1; 1 above 9.8 nm") in text
    assert "At 9.6 nm 3 of the 4 realisations are in contact" in text

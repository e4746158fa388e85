"""The plausibility bits of a run (pipeline.validity): a rear pad beyond the flying height, a separation below
the interface tables, interface forces beyond 100 x the load, each flagged at its threshold and not below it, and
the one-line summary of the flagged scenes."""

from __future__ import annotations

import numpy as np


def test_validity_bits_of_a_run():
    from pipeline.validity import Validity, check_run, describe
    nm = 1e-9
    ok = dict(fh0=11 * nm, arms=(3e-4, 4e-4), z=np.array([1.0, -2.0]) * nm, pitch=np.array([5e-6, -5e-6]),
              d_min=-1 * nm, table_floor=-5 * nm, force=3e-3, load=7.9e-3)
    assert check_run(**ok) == 0
    # the rear pad: z - l_r theta = -2 nm - 4e-4 * 2.5e-5 = -12 nm, beyond FH0 = 11 nm
    assert check_run(**{**ok, "pitch": np.array([0.0, 2.5e-5])}) == Validity.BEARING_RANGE
    assert check_run(**{**ok, "pitch": np.array([0.0, 2.2e-5])}) == 0  # -10.8 nm
    assert check_run(**{**ok, "d_min": -5.01 * nm}) == Validity.BELOW_TABLES
    assert check_run(**{**ok, "d_min": -50 * nm, "table_floor": None}) == 0
    assert check_run(**{**ok, "force": 0.8}) == Validity.FORCE_BEYOND_LOAD  # > 100 x 7.9 mN
    assert check_run(**{**ok, "force": np.nan, "z": np.array([np.nan])}) == Validity.FORCE_BEYOND_LOAD | Validity.BEARING_RANGE
    assert describe(np.array([0, np.nan, 0]), ["a", "b", "c"]) is None
    line = describe(np.array([0, 1, 5, 1, 1]), ["a", "b", "c", "d", "e"], most=2)
    assert line.startswith("4 of 5 scenes outside the model's validity b, c and 2 more: ")
    assert "pitch" not in line and "interface forces beyond 100 x" in line and "flying height" in line

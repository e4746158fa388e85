"""Flying-height modulation (FHM) and bouncing vibration (BV) measures (docs/model.md, section "Slider dynamics").

FHM (flying) / BV (in contact) is the spread of the separation ``d`` over the steady window divided by
the nominal flying height ``FH0``, in %. The paper uses the peak-to-peak spread; 3 x the standard
deviation is the named alternative (``solver.fhm_measure``, registry :data:`FHM_MEASURES`).
"""

from __future__ import annotations

import numpy as np


def _peak_to_peak(d: np.ndarray) -> float:
    return float(np.ptp(d))


def _three_std(d: np.ndarray) -> float:
    return float(3.0 * np.std(d))


#: FHM/BV measures: name -> spread [m] of separation samples [m].
FHM_MEASURES = {"peak-to-peak": _peak_to_peak, "3std": _three_std}


def fhm(d: np.ndarray, fh0: float, measure: str = "peak-to-peak") -> float:
    """FHM / BV [%] of separation samples ``d`` [m]: the named spread over ``fh0`` [m], times 100.

    Raises
    ------
    ValueError
        For a measure not in :data:`FHM_MEASURES` (the message lists them).
    """
    if measure not in FHM_MEASURES:
        raise ValueError(f"FHM measure {measure!r} unknown; expected one of {list(FHM_MEASURES)}")
    return 100.0 * FHM_MEASURES[measure](np.asarray(d, dtype=float)) / fh0

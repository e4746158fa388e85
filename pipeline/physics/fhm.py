"""Flying-height modulation (FHM) and bouncing vibration (BV) measures (docs/model.md, section "Slider dynamics").

FHM (flying) / BV (in contact) is the spread of the separation ``d`` over the steady window divided by
the nominal flying height ``FH0``, in %. The paper uses the peak-to-peak spread; 3 x the standard
deviation is the named alternative (``solver.fhm_measure``, registry :data:`FHM_MEASURES`).
"""

from __future__ import annotations

import numpy as np

from .variants import Registry, Variant


def _peak_to_peak(d: np.ndarray) -> float:
    return float(np.ptp(d))


def _three_std(d: np.ndarray) -> float:
    return float(3.0 * np.std(d))


#: FHM/BV measures (``solver.fhm_measure``): the behaviour is the spread [m] of separation samples [m].
FHM_MEASURES: Registry[Variant] = Registry("solver.fhm_measure", {
    "peak-to-peak": Variant(behaviour=_peak_to_peak, summary="max(d) - min(d) over the steady window (the paper's)",
                            source='docs/model.md, section "FHM and BV"'),
    "3std": Variant(behaviour=_three_std, summary="3 x the standard deviation of d over the steady window",
                    source='docs/model.md, section "FHM and BV"'),
})


def fhm(d: np.ndarray, fh0: float, measure: str = "peak-to-peak") -> float:
    """FHM / BV [%] of separation samples ``d`` [m]: the named spread over ``fh0`` [m], times 100.

    Parameters
    ----------
    d : separation samples over the steady window [m]
    fh0 : the nominal flying height FH0 [m]
    measure : the spread, a name of :data:`FHM_MEASURES` (``"peak-to-peak"``, the paper's; ``"3-std"``)

    Returns
    -------
    float
        FHM (flying) or BV (in contact) [%]: ``100 spread(d) / FH0``.

    Raises
    ------
    ValueError
        For a measure not in :data:`FHM_MEASURES` (the message lists them).

    References
    ----------
    [VLP09] (the peak-to-peak FHM over FH0 of the paper's Fig. 6); docs/model.md, section "FHM and BV".
    """
    return 100.0 * FHM_MEASURES.lookup(measure).behaviour(np.asarray(d, dtype=float)) / fh0

"""The flying-height modulation measures (pipeline.physics.fhm; docs/model.md, section "FHM and BV"): on a
sine of amplitude ``a`` about its mean, peak-to-peak is ``2 a`` and 3 std is ``3 a / sqrt 2``, in % of FH0;
an unknown measure is an error naming the known ones."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.physics.fhm import FHM_MEASURES, fhm
from pipeline.config.scene import SceneError, load_scene


NM = 1e-9


@pytest.fixture(scope="module")
def paper(paper_config):
    return load_scene(paper_config, ["solver.duration_ms=1.0", "solver.transient_ms=0.3"])


def test_fhm_measures(paper):
    t = np.linspace(0.0, 1.0, 100001)
    d = 1 * NM + 0.2 * NM * np.sin(2 * np.pi * 7 * t)
    assert fhm(d, 11 * NM, "peak-to-peak") == pytest.approx(100 * 0.4 / 11, rel=1e-6)
    assert fhm(d, 11 * NM, "3std") == pytest.approx(100 * 3 * 0.2 / np.sqrt(2) / 11, rel=1e-4)
    assert set(FHM_MEASURES) == {"peak-to-peak", "3std"}
    with pytest.raises(ValueError, match="peak-to-peak"):
        fhm(d, 11 * NM, "rms")
    with pytest.raises(SceneError, match="'peak-to-peak', '3std'"):
        paper.replace(solver={"fhm_measure": "rms"})

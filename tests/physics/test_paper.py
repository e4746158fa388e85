"""The paper's published values and targets (pipeline.physics.paper; docs/model.md, section "Parameters").

The published numbers are checked against each other where the paper relates them: the disk speed of the
DMW measurement (V = 2 pi r rpm / 60 = 19.5 m/s), the two-sided contact probability of the criterion
(P(|z| > k sigma) = erfc(k / sqrt 2) = 32.8 % at k = 0.978), the light-contact mean pressure (contact
force / real area, "about" 400 MPa) and the touchdown on the 0.2 nm actuation grid. The target declarations
are checked for what their readers rely on: a known measurement kind, unique keys, defaults that pass their
own checks and templates whose fields the report can fill.
"""

from __future__ import annotations

import math
import string

import numpy as np
import pytest

from pipeline.physics import paper

#: The contact criterion k of the paper's calibration (docs/model.md, section "Contact criterion").
K_PAPER = 0.978


def test_disk_speed_of_the_dmw_measurement_is_19_5_m_s():
    v = 2 * math.pi * paper.TRACK_RADIUS_MM * 1e-3 * paper.DISK_RPM / 60.0  # [m/s]
    assert v == pytest.approx(19.49, abs=0.01)


def test_contact_probability_is_two_sided_at_the_paper_k():
    # P(|z| > k sigma) for a Gaussian z: erfc(k / sqrt 2); the one-sided tail would be half of it
    assert math.erfc(K_PAPER / math.sqrt(2)) == pytest.approx(paper.CONTACT_PROBABILITY, abs=5e-4)
    assert 0.5 * math.erfc(K_PAPER / math.sqrt(2)) < 0.2


def test_light_contact_pressure_is_force_over_real_area():
    # 1 mN / 2.7 um^2 = 370 MPa: "about 400 MPa" (the paper's numbers are rounded, within 10 %)
    pressure_mpa = paper.CONTACT_FORCE_MN * 1e-3 / (paper.REAL_AREA_UM2 * 1e-12) / 1e6
    assert pressure_mpa == pytest.approx(370.37, abs=0.01)
    assert pressure_mpa == pytest.approx(paper.MEAN_PRESSURE_MPA, rel=0.1)
    assert paper.REAL_AREA_UM2 < paper.NOMINAL_AREA_UM2


def test_touchdown_and_bands_lie_on_the_actuation_grid():
    start, stop, step = paper.PROTRUSION_GRID_NM
    grid = np.round(np.arange(start, stop + step / 2, step), 9)
    assert grid.size == 76 and grid[-1] == stop
    for value in (paper.TOUCHDOWN_NM, paper.PREVIOUS_STEP_NM, paper.LIGHT_CONTACT_NM, *paper.BOUNCING_RANGE_NM,
                  *paper.FHM_FLYING_RANGE_NM, paper.FHM_TOUCHDOWN_AT_NM):
        assert np.min(np.abs(grid - value)) < 1e-9, value
    assert paper.TOUCHDOWN_NM - paper.PREVIOUS_STEP_NM == pytest.approx(step, abs=1e-12)
    # the bouncing band opens at touchdown; the flying FHM and its value before touchdown come before it
    assert paper.BOUNCING_RANGE_NM[0] == paper.TOUCHDOWN_NM
    assert paper.FHM_FLYING_RANGE_NM[1] < paper.FHM_TOUCHDOWN_AT_NM < paper.TOUCHDOWN_NM < paper.LIGHT_CONTACT_NM
    assert paper.FHM_TOUCHDOWN_PERCENT < paper.STABLE_FHM_PERCENT < paper.FHM_FLYING_PERCENT
    assert paper.FLYING_HEIGHT_NM == paper.LIGHT_CONTACT_NM  # light contact at a protrusion of FH0


CHECKS = {"positive": lambda v: v > 0, "nonnegative": lambda v: v >= 0,
          "lo <= hi": lambda v: v[0] <= v[1], "lo < hi": lambda v: v[0] < v[1]}


def test_every_target_declaration_is_complete_and_consistent():
    assert list(paper.TARGETS) == [t.name for t in paper.TARGETS.values()]
    for name, t in paper.TARGETS.items():
        assert t.measure.how in paper.MEASURES, name
        assert t.kind in ("equal", "above", "below", "touchdown"), name
        assert t.measure.statistic in ("median", "mean"), name
        keys = [s.key for s in t.keys()]
        assert len(set(keys)) == len(keys), name
        assert t.keys()[-1] is t.tolerance
        for s in t.keys():
            assert s.check in CHECKS and CHECKS[s.check](s.default), (name, s.key)
            assert s.doc.strip() and "[" in s.doc, (name, s.key)  # a unit in the one-line doc
        # the templates' fields: measured protrusions, the value and the keys of the target's definition
        where = t.measure.where if isinstance(t.measure.where, tuple) else (t.measure.where,)
        allowed = {"lo", "hi", "at", "open_lo", "value"} | {k.split(".")[-1] for k in (*keys, *where)}
        for template in (t.long_name, t.paper):
            fields = {f for _, f, _, _ in string.Formatter().parse(template) if f}
            assert fields <= allowed, (name, fields - allowed)


def test_targets_carry_the_published_values():
    values = {name: t.value.default for name, t in paper.TARGETS.items() if isinstance(t.value, paper.Setting)}
    assert values == {"fhm_flying": 12.5, "fhm_touchdown": 9.0, "bouncing": 20.0, "sliding_bv": 2.0,
                      "interference": 0.58, "contact_force": 1.0, "real_area": 2.7, "mean_pressure": 400.0,
                      "friction_coefficient": 1.2}
    assert paper.TARGETS["touchdown"].value == "touchdown.onset_nm"
    assert paper.TARGETS["net_force"].value == 0.0 and paper.TARGETS["net_force"].kind == "below"
    # every light-contact target is measured at the one shared protrusion key
    at_sliding = [t.name for t in paper.TARGETS.values() if t.measure.where == paper.SLIDING_AT.key]
    assert len(at_sliding) == 7 and paper.SLIDING_AT.default == paper.LIGHT_CONTACT_NM

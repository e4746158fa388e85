"""The report's generated prose (pipeline/analyses/narrative.py): the generated section of the results page
replaced between its markers with the comparison's headings one level down and the page around it kept byte
for byte, the last identification table kept when the new comparison has none, ``None`` without markers; and
the observations on hand-made slices (a jump from flying to surfing with no bouncing point, flying points
after the first contact, an attractive mean net force, a saturated meniscus at constant adhesion pressure)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.analyses import narrative as nv
from pipeline.analyses.sweep_slices import SweepSlice

PAGE = ("# Results\n\nIntro text.\n\n" + nv.README_BEGIN + "\nold section\n\n" + nv.IDENTIFICATION_HEADING
        + "\n\n| old identification |\n\n## Next part of the old section\n" + nv.README_END + "\n\n## After\ntail\n")


def test_the_generated_section_is_replaced_and_the_page_around_it_kept():
    new = nv.readme_with_comparison(PAGE, "# Comparison\n\ntext\n\n## Touchdown\n\nrow\n")
    head, rest = new.split(nv.README_BEGIN)
    body, tail = rest.split(nv.README_END)
    assert head == "# Results\n\nIntro text.\n\n" and tail == "\n\n## After\ntail\n"
    assert body.startswith("\n## Comparison\n\ntext\n\n### Touchdown\n\nrow")          # headings demoted
    # the new comparison has no identification table: the page keeps its last one, to the next heading
    assert body.rstrip("\n").endswith(nv.IDENTIFICATION_HEADING + "\n\n| old identification |")
    assert "Next part of the old section" not in body and "old section\n" not in body
    # a comparison with its own identification table replaces the old one
    own = nv.readme_with_comparison(PAGE, "# C\n\n## Paper, reconstructed scene, identified scene\n\n| new |\n")
    assert "| new |" in own and "| old identification |" not in own
    # twice in a row gives the same page (the generated section is all that changes)
    assert nv.readme_with_comparison(new, "# Comparison\n\ntext\n\n## Touchdown\n\nrow\n") == new


def test_a_page_without_both_markers_is_left_to_the_caller():
    assert nv.readme_with_comparison("# Results\n", "# C\n") is None
    assert nv.readme_with_comparison(nv.README_BEGIN + "\nno end\n", "# C\n") is None
    assert nv.identification_subsection("no table here") == ""


def _slice(reg, **columns) -> SweepSlice:
    x = 9.0 + 0.2 * np.arange(len(reg))
    data = {"regime": ("protrusion", np.asarray(reg)), "fhm_bv": ("protrusion", np.full(x.size, 1.0))}
    data.update({k: ("protrusion", np.asarray(v, float)) for k, v in columns.items()})
    ds = xr.Dataset(data, coords={"protrusion": x})
    return SweepSlice.of(ds, xr.Dataset(attrs={"k": 0.978, "k_source": "scene"}))


def test_a_jump_from_flying_to_surfing_and_a_flying_point_after_contact_are_observed():
    obs = nv.observations(_slice([0, 0, 2, 2, 0, 2]), None)
    assert obs[0] == ("No bouncing regime: the sweep goes straight from flying (9.2 nm) to surfing (9.4 nm) at 0.2 nm "
                      "resolution (snap-in, consistent with the touchdown note).")
    assert obs[1] == "Flying points after the first contact (9.8 nm): contact is not monotone in protrusion."
    assert nv.observations(_slice([0, 0, 0]), None) == []                   # nothing to observe while flying


def test_an_attractive_net_force_and_a_saturated_meniscus_are_observed():
    area = np.array([np.nan, 120.0, 100.0, 80.0])               # [um^2], shrinking as the bulge grows
    adhesion = 0.01 * np.nan_to_num(area)                       # [mN]: 0.01 mN/um^2 = 10 MPa
    obs = nv.observations(_slice([0, 2, 2, 2], nominal_area=area, adhesion_force=adhesion,
                                 contact_force=[np.nan, 1.2, 1.0, 0.8], net_force=[np.nan, -0.1, -0.05, 0.02]), None)
    assert "The mean net interface force is attractive (adhesion > contact) at 2 of 3 contact points, up to 9.4 nm" \
        in " ".join(obs)
    saturated = next(o for o in obs if o.startswith("In contact the adhesion pressure is constant"))
    assert float(saturated.split("constant, ")[1].split(" MPa")[0]) == pytest.approx(10.0)
    assert any(o.startswith("The mean contact force falls from 1.2 to 0.8 mN") for o in obs)

"""Stage ``statics`` (pipeline/stages/statics.py): every static state versus protrusion, ``statics.nc``.

Checked with numbers: on the air bearing alone (no adhesion, no contact) each protrusion of the sweep grid has
one state, stable, at the clearance flying height less protrusion less summit offset (a linear-in-protrusion
shift: 6.309, 5.309, 4.309 nm at 4, 5, 6 nm), with both eigenvalues of its static stiffness positive and its
path stiffness the bearing's stiffness at the TFC point; without DMW its energy scales are undefined. On the
paper scene with contact at k = 0.978 the adhesion holds the slider in contact at 8-12 nm (one stable contact
state, below the summit datum) and the DMW's energy scales are positive."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.config.scene import load_scene
from pipeline.runner import ensure
from pipeline.stages import statics

AIR = ['scene.effects=["air_bearing","pitch"]', "sweep.protrusion_nm={start=4.0, stop=6.0, step=1.0}"]
PAPER_K = ["contact.k=0.978", "sweep.protrusion_nm={start=8.0, stop=12.0, step=1.0}"]


def _statics(paper_config, sets, out):
    scene = load_scene(paper_config, sets)
    ensure("statics", scene, out)
    return scene, statics.load(out / "statics.nc")


def test_on_the_air_bearing_alone_each_protrusion_has_its_one_equilibrium(tmp_path, paper_config):
    scene, ds = _statics(paper_config, AIR, tmp_path)
    assert list(ds["protrusion"].values) == [4.0, 5.0, 6.0]
    assert list(ds["state_count"].values) == list(ds["stable_count"].values) == [1, 1, 1]
    c = ds["clearance"].isel(state=0).values
    offset = ds.attrs["summit_offset_y_s_nm"]
    assert offset == pytest.approx(0.6909, abs=1e-4)
    fh0 = scene["air_bearing"]["flying_height_nm"]
    np.testing.assert_allclose(c, fh0 - ds["protrusion"].values - offset, atol=1e-6)
    np.testing.assert_allclose(np.diff(c), -1.0, atol=1e-6)               # the protrusion shifts it 1 for 1
    np.testing.assert_allclose(c, [6.309, 5.309, 4.309], atol=1e-3)
    assert (ds["stiffness_eigenvalue"].values > 0).all()
    np.testing.assert_allclose(ds["path_stiffness"].values, float(ds["bearing_stiffness_tfc"]), rtol=1e-5)
    assert np.isnan(float(ds["dmw_energy"])) and np.isnan(ds["barrier"].values).all()
    assert ds["clearance"].attrs["units"] == "nm"


def test_on_the_paper_scene_the_adhesion_holds_the_slider_in_contact(tmp_path, paper_config):
    scene, ds = _statics(paper_config, PAPER_K, tmp_path)
    assert sorted(p.name for p in tmp_path.glob("*.nc")) == ["dmw.nc", "interface.nc", "statics.nc"]
    assert list(ds["stable_count"].values) == [1] * 5
    c = ds["clearance"].isel(state=0).values
    assert (c < 0).all() and (np.diff(c) < 0).all()                       # below the datum, deeper with protrusion
    assert (ds["state_type"].values == 1).all()
    assert float(ds["dmw_energy"]) > float(ds["dmw_kinetic_energy"]) > 0
    assert ds.attrs["k"] == 0.978 and ds.attrs["k_source"] == "scene (contact.k)"

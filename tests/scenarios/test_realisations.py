"""DMW ensembles: the ``realisation`` dimension of the sweep (``[sweep] realisations``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.io import read_dataset
from pipeline.config.scene import load_scene
from pipeline.model import dmw_record
from pipeline.analyses import ensemble_rules as ensemble
from pipeline.stages import sweep as sweep_stage

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "configs" / "paper-2009.toml"
# k fixed (no calibration); protrusions across the adhesive snap-in, where the realisations disagree
SMALL = ["contact.k=0.978", "solver.duration_ms=0.6", "solver.transient_ms=0.2",
         "sweep.protrusion_nm={start=6.6, stop=8.0, step=0.2}", "sweep.batch_size=4", "sweep.histories_nm=[7.0]"]


def test_seeds_nest_and_start_with_the_scene_seed():
    a, b = dmw_record.realisation_seeds(20090601, 3), dmw_record.realisation_seeds(20090601, 6)
    assert a[0] == 20090601 and a == b[:3]
    assert len(set(b)) == 6
    seq = np.random.SeedSequence(20090601).spawn(5)
    assert b[1:] == [int(c.generate_state(1, np.uint32)[0]) for c in seq]


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory):
    one = tmp_path_factory.mktemp("one")
    three = tmp_path_factory.mktemp("three")
    p1 = sweep_stage.run_sweep(load_scene(PAPER, SMALL), one, scheduler="synchronous")
    p3 = sweep_stage.run_sweep(load_scene(PAPER, SMALL + ["sweep.realisations=3"]), three)
    return read_dataset(p1), read_dataset(p3), three


def test_one_realisation_is_the_first_of_an_ensemble_bit_for_bit(sweeps):
    one, three, _ = sweeps
    assert "realisation" not in one.dims and "touchdown_probability" not in one
    first = three.isel(realisation=0)
    for name in one.data_vars:
        np.testing.assert_array_equal(one[name].values, first[name].values, err_msg=name)
    assert list(three.dmw_seed.values) == dmw_record.realisation_seeds(20090601, 3)
    # the other realisations are other records: they change the FHM of the flying points
    assert not np.array_equal(three.fhm_bv.isel(realisation=1).values, first.fhm_bv.values)


def test_ensemble_statistics(sweeps):
    _, three, out = sweeps
    fhm = three.fhm_bv.values
    # tol: numpy's mean of the same numbers, a few roundings apart
    np.testing.assert_allclose(three.fhm_bv_mean.values, fhm.mean(axis=-1), rtol=1e-12)
    # tol: numpy's std of the same numbers, a few roundings apart
    np.testing.assert_allclose(three.fhm_bv_std.values, fhm.std(axis=-1, ddof=1), rtol=1e-12)
    p = three.touchdown_probability.values
    np.testing.assert_array_equal(p, np.mean(three.regime.values != 0, axis=-1))
    assert set(np.unique(p)) <= {0.0, 1 / 3, 2 / 3, 1.0}
    assert p[0].item() == 0.0 and p[-1].item() == 1.0  # flying at 6.6 nm, snapped in at 8 nm
    for name in ("fhm_bv_mean", "fhm_bv_std", "touchdown_probability"):
        assert three[name].attrs["units"] and three[name].attrs["long_name"]
    # the records travel by path: one file per extra realisation
    assert len(list((out / "sweep.parts").glob("dmw-*/dmw.nc"))) == 2
    hist = read_dataset(out / "sweep_histories.nc")
    assert "realisation" not in hist.dims  # histories of the scene's own record only


def test_measured_record_has_one_realisation(tmp_path):
    rec = tmp_path / "rec.csv"
    rec.write_text("x\n1\n")
    scene = load_scene(PAPER, SMALL + ["sweep.realisations=2"])
    with pytest.raises(ValueError, match="synthetic"):
        sweep_stage.realisation_record(scene.replace(dmw={"source": str(rec)}), tmp_path / "r", 1)


def test_touchdown_probability_counts_computed_realisations_only():
    """A realisation not computed (regime fill value, NaN scalars) counts neither as contact nor as flying."""
    from pipeline.variables import SCALARS
    dims = ("protrusion", "realisation")
    regime = np.array([[0.0, 1.0, np.nan], [2.0, np.nan, np.nan], [np.nan, np.nan, np.nan]])
    fhm = np.where(np.isnan(regime), np.nan, 10.0)
    stats = ensemble.statistics({"regime": SCALARS["regime"].data(regime, dims),
                                             "fhm_bv": SCALARS["fhm_bv"].data(fhm, dims)})
    p = stats["touchdown_probability"].values
    np.testing.assert_array_equal(p[:2], [0.5, 1.0])   # 1 of 2 computed, 1 of 1
    assert np.isnan(p[2])                              # none computed: no probability
    np.testing.assert_array_equal(stats["fhm_bv_mean"].values[:2], [10.0, 10.0])


def test_ensemble_sweep_passes_cf_1_8(sweeps):
    """``dmw_seed`` was written int64, which CF-1.8 does not allow (the README says every dataset
    passes; nor unsigned int): the 32-bit seeds are stored exactly as doubles."""
    import netCDF4
    from cf_check import cf_report
    _, three, out = sweeps
    failures, crashed = cf_report(out / "sweep.nc")
    assert crashed == [] and failures[3] == [] and failures[2] + failures[1] == []
    with netCDF4.Dataset(out / "sweep.nc") as nc:
        assert nc.variables["dmw_seed"].dtype == np.float64
    assert list(three.dmw_seed.values) == dmw_record.realisation_seeds(20090601, 3)


def test_dmw_seed_beyond_32_bits_is_refused_in_one_line():
    from pipeline.config.scene import SceneError
    with pytest.raises(SceneError, match=r"dmw\.seed = 4294967296: expected an integer in \[0, 2\*\*32 - 1\]"):
        load_scene(PAPER, ["dmw.seed=4294967296"])

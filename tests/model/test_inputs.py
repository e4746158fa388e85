"""A simulation's inputs (pipeline.model.inputs): one object, one caching rule, keys checked when read."""

from __future__ import annotations

import os
import shutil

import numpy as np
import pytest
import xarray as xr

from pipeline.io import KEY_ATTR, DatasetError
from pipeline.model.inputs import SimulationInputs, Source, cached, from_folder


def _write(path, key=None, value=1.0):
    ds = xr.Dataset({"x": ("n", np.array([value, 2.0]))})
    if key is not None:
        ds.attrs[KEY_ATTR] = key
    ds.to_netcdf(path, engine="netcdf4")
    return path


def _record(path, key):
    n, fs = 8, 4.0e6
    ds = xr.Dataset({"displacement": ("time", np.linspace(0.0, 1.0, n)), "sample_rate": ((), fs)},
                    coords={"time": ("time", np.arange(n) / fs)})
    ds.attrs[KEY_ATTR] = key
    ds.to_netcdf(path, engine="netcdf4")
    return path


def test_a_dataset_is_read_once_per_stage_and_key(tmp_path):
    a = _write(tmp_path / "a.nc", "key-a")
    b = shutil.copy(a, tmp_path / "b.nc")  # (the same dataset in another folder: same key, same data)
    first = Source.file("bulge", a, "key-a").load()
    assert float(first["x"][0]) == 1.0
    assert Source.file("bulge", b, "key-a").load() is first
    # a dataset made in memory for the same key is that same copy (a study's candidate, the base's key)
    assert cached("bulge", "key-a", lambda: pytest.fail("made again")) is first


def test_a_dataset_made_from_other_inputs_is_refused(tmp_path):
    a = _write(tmp_path / "a.nc", "key-made")
    with pytest.raises(DatasetError, match=r"a\.nc: made from other inputs .* bulge stage"):
        Source.file("bulge", a, "key-expected").load()
    unkeyed = _write(tmp_path / "u.nc")
    with pytest.raises(DatasetError, match="made from other inputs"):  # (the runner expects a key: none is not it)
        Source.file("bulge", unkeyed, "key-expected").load()


def test_without_a_given_key_a_file_is_known_by_the_key_it_carries_else_by_its_version(tmp_path):
    assert Source.file("bulge", _write(tmp_path / "a.nc", "key-carried")).key == "key-carried"
    u = _write(tmp_path / "u.nc", value=1.0)
    first = Source.file("bulge", u)
    assert first.key.startswith("file:") and float(first.load()["x"][0]) == 1.0
    _write(u, value=3.0)
    os.utime(u, ns=(1, 1))  # (a new version, whatever the clock's resolution)
    again = Source.file("bulge", u)
    assert again.key != first.key and float(again.load()["x"][0]) == 3.0  # read again, not the old copy


def test_a_record_is_shared_read_only(tmp_path):
    rec = Source.file("dmw", _record(tmp_path / "dmw.nc", "key-record"), "key-record").load()
    w, fs = rec
    assert fs == 4.0e6 and w.shape == (8,) and not w.flags.writeable


def test_inputs_in_memory_and_from_a_folder(tmp_path, paper_scene):
    w = np.zeros(4)
    mem = SimulationInputs.of(record=(w, 1.0e6), k=0.5, k_source="test")
    assert mem.record()[0] is w and mem.tables() is None and mem.bulge_table() is None and mem.k == 0.5
    assert mem.with_record(None).record() is None and mem.record() is not None  # (a copy, not an edit)
    # a folder: the scene's inputs by file, with the keys the runner gives, checked when read
    scene = paper_scene.replace(contact={"k": 0.7})
    _record(tmp_path / "dmw.nc", "key-dmw")
    sim = from_folder(scene, tmp_path, {"interface": "key-i", "dmw": "key-dmw"})
    assert (sim.k, sim.k_source) == (0.7, "scene (contact.k)")
    assert sim.interface.path == str(tmp_path / "interface.nc") and sim.interface.key == "key-i"
    assert sim.record()[1] == 4.0e6
    with pytest.raises(DatasetError, match=r"interface\.nc: dataset does not exist \(run `hdi interface` first\)"):
        sim.tables()
    assert sim.identity() == ("key-i", "key-dmw", None, 0.7)

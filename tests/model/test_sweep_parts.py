"""The sweep's part files (pipeline/model/sweep_parts.py): a batch's dataset stacked by dimensions, read back to
the last bit, and the rule that keeps a part for its batch only."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.io import KEY_ATTR, read_dataset, write_dataset
from pipeline.model.simulation import simulate
from pipeline.model.sweep_parts import (LAYOUT_ATTR, Batch, kept_parts, pack_part, part_path, part_problem, read_part,
                                        unpack_part)
from damage import edit_value
from slider_scenes import ALL, build, make_scene

SHORT = {"duration_ms": 0.3, "transient_ms": 0.1}
PROTRUSIONS = (4.0, 10.0)  # flying, and in contact (k = 0.445 on the 11-nm slider)


@pytest.fixture(scope="module")
def model():
    return build(make_scene(ALL, solver=SHORT))


def _part(model, batch: Batch, protocol: str = "independent", key: str = "key") -> xr.Dataset:
    """The dataset of ``batch`` with the attributes the sweep gives a part."""
    ds = simulate(model, batch.protrusions, histories=(PROTRUSIONS[1],), protocol=protocol)
    ds.attrs.update({KEY_ATTR: key, "roughness_label": batch.label, "damping_ratio": batch.damping,
                     "batch": batch.index, "realisation": batch.realisation})
    return ds


def _write(ds: xr.Dataset, path) -> None:
    write_dataset(pack_part(ds), path, stage="sweep-part", compress=False)


BATCH = Batch(0, "set", 0.05, (0, 1), PROTRUSIONS)


@pytest.mark.parametrize("protocol", ["independent", "stepping"])
def test_a_part_file_gives_back_its_batch_bit_for_bit(model, tmp_path, protocol):
    """A part is written with its variables stacked by dimensions (one NetCDF variable per set of dimensions
    instead of one per quantity) and read back as the dataset its batch computed: the same variables in the
    same order, the same values to the last bit (float32 and int8 flags through float64), dtypes, attributes
    and missing values; the file is a dataset of declared variables."""
    ds = _part(model, BATCH, protocol)
    assert "h_separation" in ds and len(ds.data_vars) > 20
    assert {v.dtype.kind for v in ds.data_vars.values()} >= {"f", "i"}
    path = part_path(tmp_path, BATCH)
    assert path == tmp_path / "batch-00000.nc"
    _write(ds, path)
    on_disk = read_dataset(path)
    assert len(on_disk.data_vars) == len({v.dims for v in ds.data_vars.values()}) <= 3
    assert LAYOUT_ATTR in on_disk.attrs
    back = read_part(path)
    assert LAYOUT_ATTR not in back.attrs
    assert list(back.data_vars) == list(ds.data_vars) and list(back.coords) == list(ds.coords)
    xr.testing.assert_identical(back.drop_attrs(), ds.drop_attrs())
    for name, v in ds.variables.items():
        assert back[name].dtype == v.dtype, name
        if v.dtype.kind in "fiub":  # (to the bit: NaN payloads too)
            assert back[name].values.tobytes() == v.values.tobytes(), name
        assert back[name].encoding.get("_FillValue") == v.encoding.get("_FillValue"), name
    for key, value in ds.attrs.items():
        assert back.attrs[key] == value, key
    # (in memory too, and a dataset that is no packed part is left as it is)
    xr.testing.assert_identical(unpack_part(pack_part(ds)), ds)
    assert unpack_part(ds) is ds


def test_a_part_is_kept_only_for_its_own_batch_and_inputs(model, tmp_path):
    """A part is refused for a batch it is not (index, roughness, damping, protrusions), for other inputs, when
    missing, unreadable or edited since written; :func:`kept_parts` reads the accepted ones and fails in one
    line naming the file and why on the others."""
    path = part_path(tmp_path, BATCH)
    assert part_problem(path, "key", BATCH) == "missing"
    _write(_part(model, BATCH), path)
    assert part_problem(path, "key", BATCH) is None
    assert part_problem(path, "other", BATCH) == "made from other inputs"
    assert part_problem(path, "key", Batch(1, "set", 0.05, (0, 1), PROTRUSIONS)) == "holds batch 0, not 1"
    assert part_problem(path, "key", Batch(0, "rough", 0.05, (0, 1), PROTRUSIONS)).startswith("holds roughness 'set'")
    assert part_problem(path, "key", Batch(0, "set", 0.1, (0, 1), PROTRUSIONS)).endswith("expected 'set', 0.1")
    assert part_problem(path, "key", Batch(0, "set", 0.05, (0, 1), (4.0, 10.2))) == \
        "holds protrusions [4.0, 10.0], expected [4.0, 10.2]"
    (tmp_path / "bad").mkdir()
    bad = part_path(tmp_path / "bad", BATCH)
    bad.write_bytes(b"not a netCDF file")
    assert part_problem(bad, "key", BATCH).startswith("unreadable (")
    # a value edited in place (the file's checksums no longer match)
    stack = next(v for v in read_dataset(path).data_vars if v.startswith("stack__protrusion"))
    edit_value(path, stack, (0, 0), 1e3)
    assert "values differ from the checksum" in part_problem(path, "key", BATCH)
    second = Batch(1, "set", 0.05, (0, 1), PROTRUSIONS)
    _write(_part(model, second), part_path(tmp_path, second))
    kept = list(kept_parts(tmp_path, [BATCH, second], "key", added={0}))
    assert [b.index for b, _ in kept] == [1] and "fhm_bv" in kept[0][1]
    with pytest.raises(RuntimeError, match=r"batch-00000\.nc: batch 0: part .*; run the sweep again"):
        list(kept_parts(tmp_path, [BATCH, second], "key", added=set()))
    np.testing.assert_array_equal(kept[0][1]["protrusion"].values, PROTRUSIONS)

"""The kernel's inputs (pipeline.model.kernel_inputs): the caching rule of the per-protrusion inputs (one rule
for every cache, made on the first ask, at most its size, the oldest dropped first, permanent entries kept); the
stand-in arguments of a scene, whose types are the kernel's signature of that scene's model (the first run's
compile ahead), for every shipped scene."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline import runner
from pipeline.config.loading import load_scene, shipped_scenes
from pipeline.model import compiled, running
from pipeline.model import dynamics as dyn
from pipeline.model import kernel_inputs as ki
from pipeline.units import NM


def test_a_cache_makes_an_entry_once_and_drops_the_oldest_past_its_size():
    cache: dict = {}
    made: list = []

    def ask(key):
        return ki._cached(cache, key, 3, lambda: made.append(key) or f"table {key}")

    assert [ask(k) for k in (1.0, 2.0, 1.0)] == ["table 1.0", "table 2.0", "table 1.0"]
    assert made == [1.0, 2.0]  # the second ask of 1.0 read the cache
    for k in (3.0, 4.0, 5.0):
        ask(k)
    assert list(cache) == [3.0, 4.0, 5.0] and made == [1.0, 2.0, 3.0, 4.0, 5.0]
    ask(1.0)  # dropped before: made anew
    assert made[-1] == 1.0 and list(cache) == [4.0, 5.0, 1.0]


def test_a_permanent_entry_is_never_dropped():
    cache: dict = {"capped_area": "cap"}
    for k in range(10):
        ki._cached(cache, (float(k), 1.0), ki.INTEGRATED_CACHE, lambda: "tables")
    assert cache["capped_area"] == "cap" and len(cache) == ki.INTEGRATED_CACHE
    assert list(cache)[1:] == [(float(k), 1.0) for k in range(10 - ki.INTEGRATED_CACHE + 1, 10)]


# ------------------------------------------------------------------ the kernel's signature from the scene


class _FirstCall(Exception):
    """Raised by the stand-in kernel with the arguments of the first call."""


@pytest.mark.parametrize("name", sorted(shipped_scenes()) + ["paper-2009+heating"])
def test_the_stand_ins_of_a_scene_type_as_its_models_first_kernel_call(name, tmp_path, monkeypatch):
    # each shipped scene's inputs made by the runner (a coarse Reynolds grid for the bulge tables: numbers
    # only), its model, and the arguments its first run hands the compiled kernel, caught there; and one with
    # the frictional heat (its loop's slot, Variants.heating)
    base, _, heating = name.partition("+")
    scene = load_scene(shipped_scenes()[base], ["solver.bulge_cells_per_a=4", "solver.bulge_cells_per_b=2"]
                       + (["tfc.frictional_heating_nm_per_mw=0.05"] if heating else []))
    model = runner.current_inputs(scene, tmp_path, k=1.0).model(scene)
    kernel = dyn._integrate

    def first_call(*args):
        raise _FirstCall(args)

    monkeypatch.setattr(dyn, "_integrate", first_call)
    with pytest.raises(_FirstCall) as call:
        running.run_model(model, 5.0 * NM, y0=np.zeros(4))  # (a given start: no static solve)
    real = compiled.signature(kernel, call.value.args[0])
    ahead = compiled.signature(kernel, dyn.kernel_arguments(*ki.stand_in_arguments(scene)))
    assert ahead == real
    # the scene's effects show in the slots: no DMW slot without the dmw effect, the meniscus state a float
    slots = dict(zip(dyn.SLOTS + ("heating",), real[-len(dyn.SLOTS) - 1:]))
    assert (str(slots["dmw"]) == "none") == ("dmw" not in scene.effects)
    assert (str(slots["meniscus"]) == "none") == (model.meniscus is None)
    assert (str(slots["tfc"]) == "none") == (not model.tfc_tabulated)
    assert (str(slots["heating"]) == "none") == (model.heating is None)


def test_the_stand_ins_tell_effects_apart():
    # a scene without DMW, adhesion or pitch, with the linear rear law: another signature, each slot as off
    base = load_scene(shipped_scenes()["paper-2009"])
    other = base.replace(scene={"effects": ["air_bearing", "contact", "friction"]},
                         air_bearing={"rear_law": "linear"})
    sig = dict(zip(dyn.SLOTS, compiled.signature(dyn._integrate, dyn.kernel_arguments(
        *ki.stand_in_arguments(other)))[-len(dyn.SLOTS) - 1:-1]))
    assert [n for n, t in sig.items() if str(t) == "none"] == ["dmw", "adhesion", "tfc", "pitch", "gap_power",
                                                               "meniscus"]
    assert "linear" in str(sig["rear_law"])
    assert sig != dict(zip(dyn.SLOTS, compiled.signature(dyn._integrate, dyn.kernel_arguments(
        *ki.stand_in_arguments(base)))[-len(dyn.SLOTS) - 1:-1]))

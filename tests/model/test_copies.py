"""Copies of a model that share its caches (pipeline.model.copies): a solver copy (``with_solver``) reuses
the model's fold and starts where a fresh model starts, a criterion copy (``with_criterion``) starts where a
fresh model with that criterion starts without its own fold search, and the realisations of an ensemble
(``share_statics``) share one set of static starts and run exactly as each does alone.

Scenes are built in code (tests/slider_scenes.py's ``make_scene``); the reference is always a fresh model.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from pipeline.model import copies, running
from pipeline.model.simulation import simulate
from pipeline.units import NM
from slider_scenes import build, make_scene, synthetic_record


#: modal damping 0.05: the slower mode (120 kHz) decays as exp(-zeta omega t), 1/(zeta omega) = 26.5 us,
#: so a 0.3 ms transient leaves exp(-11.3) ~ 1e-5 of the start's offset (< 1 nm) in the window
#: tolerances 1e3 below the scene's (rtol 1e-6, atol 1e-4 nm), whose own error in the window's exact
#: minimum is ~1e-3 nm (measured: the accuracy stage's rtol knob): the comparison is then of states,
#: not of integration errors (rtol 1e-9: 2e-6 nm in the minimum clearance at 5 nm)
SOLVER = {"duration_ms": 0.6, "transient_ms": 0.3, "rtol": 1e-9, "atol_nm": 1e-7}


def test_a_solver_copy_shares_the_fold_and_reaches_the_same_start():
    # with_solver changes how the dynamics are integrated, not the statics: its copy reuses the model's
    # fold (no new search) and starts where a fresh model starts; a change of force is refused
    model = build(make_scene(("air_bearing", "pitch", "adhesion", "contact"), solver=SOLVER))
    fresh = replace(model)  # (dataclasses.replace: its own, empty fold cache)
    delta = 11 * NM  # past the fold: the start needs it
    y_model, note_model = running.start(model, delta)
    assert "fold" in model.statics
    copy = copies.with_solver(model, duration=0.1e-3, transient=0.0, rtol=1e-7)
    assert copy.statics is model.statics and copy.duration == 0.1e-3
    assert fresh.statics is not model.statics and not fresh.statics
    y_copy, note_copy = running.start(copy, delta)
    y_fresh, _ = running.start(fresh, delta)
    assert note_copy == note_model and "contact" in note_model
    assert (y_copy == y_model).all() and (y_fresh == y_model).all()
    with pytest.raises(ValueError, match="solver settings only"):
        copies.with_solver(model, k=0.5)


def test_a_criterion_copy_starts_where_a_fresh_model_does_without_its_own_fold_search():
    # with_criterion(model, k): the contact-off fold bounds every k's fold (contact is off on the flying
    # branch under either criterion); the copy's starts, below the bound (continued to the protrusion)
    # and past it (the contact branch), equal a fresh model's with k, which searches its own fold
    model = build(make_scene(("air_bearing", "pitch", "adhesion", "contact"), solver=SOLVER))
    off = replace(model, k=-1e300)
    running.start(off, 0.0)
    bound = off.statics["fold"]
    assert 5 * NM < bound < 11 * NM  # the adhesion fold of this scene
    # k sigma 0.5 nm ends the flying branch before the adhesion fold: a bound, not the fold itself
    for k in (-1.0, 0.0, 1.0, 3.0):
        copy = copies.with_criterion(off, k)
        fresh = replace(model, k=k)
        for delta in (5 * NM, bound - 0.3 * NM, bound, 11 * NM):
            y_copy, note_copy = running.start(copy, delta)
            y_fresh, note_fresh = running.start(fresh, delta)
            assert (y_copy == y_fresh).all(), (k, delta / NM, note_copy, note_fresh)
            assert note_copy.split(":")[0] == note_fresh.split(":")[0]  # same kind of state and values
            assert ("contact" in note_copy) == (delta >= fresh.statics["fold"]), (k, delta / NM)
        assert "fold" not in copy.statics and copy.statics["bound"] == bound
        assert fresh.statics["fold"] <= bound, k
    # a model's own fold bounds a higher criterion's, not a lower one's (whose fold may lie past it)
    one = replace(model, k=1.0)
    running.start(one, 0.0)
    assert copies.with_criterion(one, 2.0).statics["bound"] == one.statics["fold"]
    assert "bound" not in copies.with_criterion(one, 0.5).statics


def test_the_realisations_of_an_ensemble_share_their_static_starts():
    # the static equilibria are on the mean disk: models of one scene on other DMW records start from the
    # same states, found once for all (share_statics), and run exactly as each does alone
    scene = make_scene(("air_bearing", "pitch", "adhesion", "contact", "dmw"),
                       solver={"duration_ms": 0.6, "transient_ms": 0.3})
    records = [synthetic_record(scene)] + [synthetic_record(make_scene(
        ("air_bearing", "pitch", "adhesion", "contact", "dmw"), solver={"duration_ms": 0.6, "transient_ms": 0.3},
        dmw={"seed": seed})) for seed in (7, 8)]
    assert not np.array_equal(records[0][0], records[1][0])
    alone = [build(scene, rec) for rec in records]
    shared = [build(scene, rec) for rec in records]
    copies.share_statics(shared)
    deltas = [5.0, 11.0]  # flying; past the fold (contact branch)
    for a, s in zip(alone, shared):
        ra, rs = simulate(a, deltas), simulate(s, deltas)
        for name in ra.data_vars:
            assert_array_equal(ra[name].values, rs[name].values, err_msg=name)
    assert all(s.statics is shared[0].statics for s in shared)
    assert sorted(mu for _, mu in shared[0].statics["starts"]) == [5 * NM, 11 * NM]  # one dict: found once for the three
    assert not np.array_equal(simulate(shared[0], [5.0])["fhm_bv"], simulate(shared[1], [5.0])["fhm_bv"])
    with pytest.raises(ValueError, match="one scene and criterion"):
        copies.share_statics([alone[0], replace(alone[1], k=0.5)])
    # without the contact law k is NaN on every model: one criterion all the same
    flying = make_scene(("air_bearing", "pitch", "dmw"), solver={"duration_ms": 0.6, "transient_ms": 0.3})
    pair = [build(flying, rec) for rec in records[:2]]
    assert np.isnan(pair[0].k)
    copies.share_statics(pair)
    assert pair[1].statics is pair[0].statics

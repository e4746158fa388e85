"""Copies of a model that share its caches where their forces are the same: another contact criterion
(:func:`with_criterion`), other solver settings (:func:`with_solver`), and the models of one scene on
different DMW records (:func:`share_statics`; caching rule: :mod:`pipeline.model.kernel_inputs`)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Sequence

import numpy as np

from .assembly import Model


def share_statics(models: Sequence[Model]) -> None:
    """Give the models of one scene on different DMW records (the realisations of an ensemble) one
    ``statics``: the static equilibria are those of the mean disk (``w = 0``: docs/model.md, section
    "Start state"), so the fold and the start states of one hold for all, found once.

    Raises
    ------
    ValueError
        When the models are not of one scene and criterion (other forces, other statics).
    """
    first = models[0]
    for m in models[1:]:
        same_k = m.k == first.k or (np.isnan(m.k) and np.isnan(first.k))  # (NaN: no contact law)
        if m.scene is not first.scene or not same_k or m.start != first.start:
            raise ValueError("share_statics: the models must be of one scene and criterion k "
                             "(they may differ in their DMW record only)")
        m.statics = first.statics
        m.tfc_tables = first.tfc_tables


def with_criterion(model: Model, k: float) -> Model:
    """A copy of the model with the contact criterion ``k`` [1] (``d < k sigma``), for a search over k.

    When ``k`` is at or above the model's own and the model's static-start fold is known, the copy
    starts with that fold as an upper bound of its own (:func:`pipeline.model.start.start_state`): on
    the flying branch the contact law is off under either criterion, so the forces agree and a higher
    criterion can only end the branch earlier (where ``d`` reaches ``k sigma``). Starts past the bound
    then go to the contact branch, and starts below it continue the flying branch to their protrusion,
    without a fold search of the copy's own (~0.2 s each): a bisection on k past the touchdown
    (:func:`pipeline.analyses.calibration.k_threshold`) runs many such copies. The start states are
    those of a fresh model with ``k`` (tests/model/test_copies.py).
    """
    copy = replace(model, k=float(k))
    copy.tfc_tables = model.tfc_tables  # (the criterion changes no force law)
    fold = model.statics.get("fold")
    if fold is not None and copy.k_sigma >= model.k_sigma:
        copy.statics["bound"] = fold
        copy.statics["bound_ladder"] = model.statics.get("ladder")
    return copy


#: The model's fields that only the integration reads: a copy that changes no others has the same
#: static equilibria, so it shares the static start's fold (:func:`with_solver`).
SOLVER_FIELDS = frozenset({"duration", "transient", "output_step", "rtol", "atol", "max_step"})


def with_solver(model: Model, **changes: Any) -> Model:
    """A copy of the model with solver settings changed (:data:`SOLVER_FIELDS`: ``rtol``, ``atol``,
    ``max_step``, ``duration``, ...). The copy shares the model's fold cache (the static equilibria do
    not depend on how the dynamics are integrated), so its static starts cost no new fold search.

    Raises
    ------
    ValueError
        For a field outside :data:`SOLVER_FIELDS` (a copy with other forces: ``dataclasses.replace``).
    """
    other = set(changes) - SOLVER_FIELDS
    if other:
        raise ValueError(f"with_solver changes solver settings only ({sorted(SOLVER_FIELDS)}), not {sorted(other)}")
    copy = replace(model, **changes)
    copy.statics = model.statics
    copy.tfc_tables = model.tfc_tables
    return copy

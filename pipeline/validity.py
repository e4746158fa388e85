"""Whether a run stayed inside the model's validity: the steady-window ``validity`` flags of a scene.

The model is a rigid slider on a linearised/power-law air bearing over nm-scale asperities, with the
rough-surface interface tabulated over a separation range (docs/model.md, sections "Air bearing", "ISBL
interface" and "Interface tables"). A run that leaves that picture still integrates and produces numbers (FHM/BV of
159,000 %, clearances of 9 um, contact forces of 38 N were reported as "bouncing"), so each run is
checked here and the bits of :class:`Validity` say what it left:

* ``bearing_range``: a pad of the slider moved by more than the flying height FH0 (the front pad
  by ``z + l_f theta``, the rear one by ``z - l_r theta``, theta leading edge up): its gap closed or
  doubled, where the bearing laws, stiffnesses from small-amplitude modes, hold no longer;
* ``below_tables``: the separation went below the interface tables' first row, where the kernel
  extrapolates them linearly instead of evaluating the ISBL integrals (above the tables the forces
  are zero and holding them is exact);
* ``force_beyond_load``: the contact or adhesion force exceeded :data:`FORCE_FACTOR` times the
  bearing's load scale ``(k_f + k_r) FH0``, the force that closes the bearing's gap (7.9 mN for the
  paper scene), i.e. orders of magnitude beyond anything a slider of that bearing carries.

:func:`pipeline.model.outcomes.summarize` stores the flags as the scalar ``validity`` (0: valid; declared in
:mod:`pipeline.variables`), and the report refuses a sweep with a flagged scene
(:func:`describe` names them).
"""

from __future__ import annotations

from enum import IntFlag
from typing import Any

import numpy as np

class OutsideValidity(ValueError):
    """A result the report will not draw from: a scene flagged in ``validity`` (one line)."""


#: Forces beyond this multiple of the bearing's load scale ``(k_f + k_r) FH0`` are flagged (two orders
#: of magnitude; the paper's light contact is ~1 mN against 7.9 mN).
FORCE_FACTOR = 100.0


class Validity(IntFlag):
    """Bits of the ``validity`` variable (``flag_masks``); 0: the run stayed inside the model."""

    BEARING_RANGE = 1
    BELOW_TABLES = 2
    FORCE_BEYOND_LOAD = 4


#: Why, in words, per bit (for messages).
REASONS = {
    Validity.BEARING_RANGE: "the slider moved by more than the flying height (outside the air bearing's range)",
    Validity.BELOW_TABLES: "the separation left the interface tables (below their first row)",
    Validity.FORCE_BEYOND_LOAD: f"interface forces beyond {FORCE_FACTOR:g} x the bearing's load (k_f + k_r) FH0",
}


def check_run(*, fh0: float, arms: tuple[float, float], z: np.ndarray, pitch: np.ndarray, d_min: float,
              table_floor: float | None, force: float, load: float) -> Validity:
    """The validity bits of one run (SI units).

    Parameters
    ----------
    fh0 : nominal flying height [m]
    arms : front and rear pad arms ``(l_f, l_r)`` from the centre of gravity [m]
    z, pitch : centre-of-gravity displacement [m] and pitch [rad] over the steady window
    d_min : smallest separation [m] over the steady window
    table_floor : first separation of the interface tables [m] (``None``: no tables)
    force : largest contact or adhesion force magnitude [N] over the steady window
    load : the bearing's load scale ``(k_f + k_r) FH0`` [N]
    """
    flags = Validity(0)
    l_f, l_r = arms
    pad = float(max(np.max(np.abs(z + l_f * pitch)), np.max(np.abs(z - l_r * pitch)))) if z.size else 0.0
    if not pad <= fh0:  # (NaN too)
        flags |= Validity.BEARING_RANGE
    if table_floor is not None and d_min < table_floor - 1e-15:
        flags |= Validity.BELOW_TABLES
    if not force <= FORCE_FACTOR * load:
        flags |= Validity.FORCE_BEYOND_LOAD
    return flags


def reasons(code: Any) -> list[str]:
    """The reasons of a ``validity`` value (empty for 0 or NaN)."""
    try:
        flags = Validity(int(code))
    except (TypeError, ValueError):
        return []
    return [text for bit, text in REASONS.items() if bit in flags]


def describe(codes: np.ndarray, labels: list[str], most: int = 3) -> str | None:
    """One line naming the flagged scenes (``labels[i]`` for ``codes[i] > 0``) and why; ``None``
    when every scene is valid (NaN: not computed, not flagged)."""
    codes = np.asarray(codes, float)
    bad = [i for i, c in enumerate(codes) if np.isfinite(c) and c > 0]
    if not bad:
        return None
    why = sorted({r for i in bad for r in reasons(codes[i])})
    named = ", ".join(labels[i] for i in bad[:most]) + (f" and {len(bad) - most} more" if len(bad) > most else "")
    return f"{len(bad)} of {codes.size} scenes outside the model's validity {named}: {'; '.join(why)}"

"""Heater power as a scene's axis: the actuation the scene states, and the conversions it allows.

A scene may state how its heater's power sets the protrusion, in one of two forms (``[tfc]``, off by
default):

* ``actuation_nm_per_mw``: an actuation efficiency [nm/mW], protrusion = efficiency x power;
* ``actuation_power_mw`` with ``actuation_protrusion_nm``: a table of protrusion [nm] versus power [mW],
  both strictly increasing, interpolated linearly (nothing is extrapolated).

With one of them the touchdown may be given in mW (``touchdown.onset_mw``, ``touchdown.previous_mw``):
validation converts it to the ``onset_nm``/``previous_nm`` every stage reads (:func:`resolve_touchdown`), and
the sweep's datasets carry the heater power [mW] as a coordinate ``heater_power`` on the ``protrusion``
dimension (:func:`power_coordinates`). The conversion itself is :mod:`pipeline.physics.heater`'s, its one
home; this module reads the scene's keys and converts their units (docs/model.md, section "Heater power").
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from ..physics import heater
from ..units import MW, NM, NM_PER_MW
from ..variables import coordinate
from .labels import label, range_grid

if TYPE_CHECKING:  # (the scene's validation imports this module: the kernel's early compile must not load xarray)
    import xarray as xr

#: The touchdown keys given in mW and the keys in nm they set.
TOUCHDOWN_POWER_KEYS = {"onset_mw": "onset_nm", "previous_mw": "previous_nm"}
#: The ``[tfc]`` keys of an actuation.
ACTUATION_KEYS = ("actuation_nm_per_mw", "actuation_power_mw", "actuation_protrusion_nm")
#: The same as scene keys (:func:`pipeline.config.fields.fields`): what :func:`actuation` reads.
ACTUATION_FIELDS = tuple(f"tfc.{key}" for key in ACTUATION_KEYS)


def actuation(config: Mapping[str, Mapping[str, Any]]) -> heater.Actuation | None:
    """The scene's actuation (SI), or ``None`` when it states none.

    Parameters
    ----------
    config : a scene, or its ``section -> key -> value`` configuration

    Returns
    -------
    pipeline.physics.heater.Actuation or None
        From ``tfc.actuation_nm_per_mw`` [nm/mW], or from the table ``tfc.actuation_power_mw`` [mW] /
        ``tfc.actuation_protrusion_nm`` [nm].

    Raises
    ------
    ValueError
        Both forms given, half a table, or numbers :mod:`pipeline.physics.heater` refuses (the message
        names the keys).
    """
    tfc = config["tfc"]
    eff, power, prot = (tfc.get(k) for k in ACTUATION_KEYS)
    if eff is not None and (power is not None or prot is not None):
        raise ValueError("tfc.actuation_nm_per_mw and the table tfc.actuation_power_mw/actuation_protrusion_nm "
                         "are both given: expected one form of the actuation")
    if (power is None) != (prot is None):
        given, missing = (("actuation_power_mw", "actuation_protrusion_nm") if prot is None
                          else ("actuation_protrusion_nm", "actuation_power_mw"))
        raise ValueError(f"tfc.{given} is given without tfc.{missing}: expected both columns of the table")
    if eff is not None:
        return heater.linear(eff * NM_PER_MW)   # (positive: its key's check)
    if power is None:
        return None
    try:
        return heater.tabulated(np.asarray(power) * MW, np.asarray(prot) * NM)
    except ValueError as exc:
        raise ValueError(f"tfc.actuation_power_mw = {list(power)}, tfc.actuation_protrusion_nm = {list(prot)}: "
                         f"{exc}") from None


def power_mw(config: Mapping[str, Mapping[str, Any]], protrusion_nm: Any) -> np.ndarray | None:
    """The heater power [mW] at protrusions [nm] (``None`` without an actuation); NaN at a protrusion outside
    an actuation table's rows (the table covers the sweep's grid, checked at load; an ensemble's target
    protrusion may lie beyond it, and its results are kept)."""
    act = actuation(config)
    if act is None:
        return None
    d = np.asarray(protrusion_nm, dtype=float) * NM
    if act.efficiency is not None:
        return act.power_of(d) / MW
    inside = (d >= act.protrusion[0]) & (d <= act.protrusion[-1])
    out = np.full(d.shape, np.nan)
    out[inside] = act.power_of(d[inside]) / MW
    return out


def power_coordinates(config: Mapping[str, Mapping[str, Any]], protrusion_nm: Any,
                      dim: str = "protrusion") -> dict[str, xr.Variable]:
    """``{"heater_power": power [mW] on dim}`` for a dataset's protrusions [nm], or ``{}`` without an
    actuation (a dataset of a scene without one is as before: no new variable)."""
    p = power_mw(config, protrusion_nm)
    return {} if p is None else {"heater_power": coordinate("heater_power", p, dim)}


def resolve_touchdown(config: dict[str, dict[str, Any]], given: Mapping[str, Any], where: str) -> None:
    """Check the actuation keys and set ``touchdown.onset_nm``/``previous_nm`` from the ones in mW.

    Parameters
    ----------
    config : the validated configuration (defaults filled in); its ``touchdown`` section is updated
    given : the ``[touchdown]`` keys the scene itself states (to tell a given ``onset_nm`` from its default)
    where : the file (or ``--set`` option) the messages name

    Raises
    ------
    ValueError
        An actuation :func:`actuation` refuses; a touchdown in mW without an actuation, without its
        companion key, or beside the same touchdown in nm with another value; a sweep grid outside the
        actuation table.
    """
    try:
        act = actuation(config)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    td = config["touchdown"]
    in_mw = [k for k in TOUCHDOWN_POWER_KEYS if td.get(k) is not None]
    if in_mw and act is None:
        raise ValueError(f"{where}: touchdown.{in_mw[0]} = {td[in_mw[0]]} needs the heater's actuation: expected "
                         "tfc.actuation_nm_per_mw, or the table tfc.actuation_power_mw/actuation_protrusion_nm")
    if len(in_mw) == 1:
        other = next(k for k in TOUCHDOWN_POWER_KEYS if k not in in_mw)
        if TOUCHDOWN_POWER_KEYS[other] not in given:
            raise ValueError(f"{where}: touchdown.{in_mw[0]} is given without touchdown.{other}: expected both "
                             f"steps in mW (or touchdown.{TOUCHDOWN_POWER_KEYS[other]} in nm)")
    tfc = config["tfc"]
    for key in in_mw:
        nm_key = TOUCHDOWN_POWER_KEYS[key]
        if act.efficiency is None and not heater.within(td[key] * MW, act.power):
            raise ValueError(f"{where}: touchdown.{key} = {td[key]} mW lies outside tfc.actuation_power_mw "
                             f"{tfc['actuation_power_mw'][0]:g}-{tfc['actuation_power_mw'][-1]:g} mW: expected a "
                             "power within the table (nothing is extrapolated)")
        value = float(label(float(act.protrusion_of(td[key] * MW)) / NM))
        if nm_key in given and not np.isclose(given[nm_key], value, rtol=1e-9, atol=0.0):
            raise ValueError(f"{where}: touchdown.{key} = {td[key]} mW is {value:.6g} nm, but touchdown.{nm_key} = "
                             f"{given[nm_key]}: expected one of the two (or the same step)")
        td[nm_key] = value
    if act is not None and act.efficiency is None:
        grid = range_grid(config["sweep"]["protrusion_nm"])
        if not heater.within(grid * NM, act.protrusion):
            rows = tfc["actuation_protrusion_nm"]
            raise ValueError(f"{where}: sweep.protrusion_nm {grid[0]:g}-{grid[-1]:g} nm lies outside "
                             f"tfc.actuation_protrusion_nm {rows[0]:g}-{rows[-1]:g} nm: expected the table to cover "
                             "the sweep (nothing is extrapolated)")

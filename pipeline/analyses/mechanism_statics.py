"""Statics maps of the mechanisms that could deepen the 11-nm contact without touching flight: the static
states of the slider at each protrusion with a mechanism set to a value, before any dynamics
(docs/model.md, section "Mechanism statics"; docs/results.md, "Statics of the three mechanisms").

Three mechanisms, each a *case* ``(mechanism, value, model)``:

* ``"penetration-adhesion"``: the model of a scene with ``lubricant.solid_work_of_adhesion_j_m2`` set (the
  value [J/m^2]); its tables carry the mechanism, so its states are those of :func:`pipeline.model.statics.states_at`;
* ``"frictional-heating"``: the protrusion of the frictional heat at its steady state,
  ``delta_f = eta_f Q V`` (the value ``eta_f`` [nm/mW]; ``Q`` the contact's friction force, ``V`` the disk's
  speed): no friction in flight, so the flying states are the model's own, and the contact state at the
  protrusion ``delta`` is the model's at ``delta + delta_f``, the fixed point of
  ``delta_f = eta_f V Q(delta + delta_f)`` (:func:`heated_contact`). Its kernel form,
  ``d(delta_f)/dt = (eta_f Q V - delta_f) / tau_f``, has this as its steady state;
* ``"pitch-compliance"``: the model with another stiffness root or friction arm (the value: the lift of the free
  TFC point per mN of friction [nm/mN], :func:`friction_lift`); the model's forces carry the friction moment
  ``-friction_arm Q`` (:mod:`pipeline.model.forces`), so its states are those of ``states_at``;
* ``"roughness-datum"``: the model of a scene with another contact criterion (the value: ``k sigma`` [nm]).

Per case and protrusion the map gives whether a stable flying state and a stable contact state exist and
both together (the band's precondition: the slider can fly and hold the contact at the same heater step),
the contact state's interference, separation, contact, adhesion and friction forces, real area, friction
coefficient, friction power, the heat's protrusion, and the flash temperature of the contact
(:func:`pipeline.physics.flash_temperature.contact_temperature`, the summits in contact counted from the
interface's ``contact_fraction``) beside the rise of the friction power spread over the nominal area (the
pole tip's bulk heating, whose slider share is what a frictional-heating efficiency ``eta_f`` scales). With a mechanism at zero (``eta_f = 0``; the scene's own model) the
states are today's bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np
import xarray as xr

from ..model import kernel_inputs, running
from ..model import statics as st
from ..model.assembly import Model
from ..model.dmw_record import disk_speed_m_s
from ..model.dynamics import with_values
from ..model.forces import separation_at
from ..model.frictional_heating import HEAT_TOL, MAX_ITER, heat_fixed_point
from ..model.piecewise import ppval, static_table
from ..physics.flash_temperature import Thermal, contact_temperature
from ..units import NM
from ..variables import Variable

#: ``eta_f`` in the map's unit [nm/mW] to SI [m/W].
NM_PER_MW = NM / 1e-3

#: Mechanisms of a case (the ``mechanism`` coordinate).
MECHANISMS = ("none", "penetration-adhesion", "frictional-heating", "pitch-compliance", "roughness-datum")


@dataclass(frozen=True)
class Case:
    """One mechanism at one value: ``mechanism`` (:data:`MECHANISMS`), ``value`` (its unit: J/m^2, nm/mW or
    the label's), ``model`` (the model whose forces carry it; for ``"frictional-heating"`` the scene's own),
    ``heating`` (``eta_f`` [nm/mW], 0 but for ``"frictional-heating"``) and a ``label``."""

    mechanism: str
    value: float
    model: Model
    heating: float = 0.0
    label: str = ""


def friction_lift(model: Model) -> float:
    """The lift of the free TFC point per newton of friction [m/N]: the air bearing's compliance
    ``a K^-1 b`` with ``a = (1, -l_c)`` (the TFC point's height ``z - l_c theta``), ``K`` the pads' stiffness
    and ``b = (0, -friction_arm)`` (the friction's moment about the CG, docs/model.md, section "Slider
    dynamics"); 0 with the pitch locked."""
    s = model.slider
    if model.pitch is None:
        return 0.0
    a = np.array([1.0, -s.l_c])
    return float(a @ np.linalg.solve(s.stiffness_matrix, np.array([0.0, -s.friction_arm])))


def flying_fold(model: Model) -> float:
    """Where the model's stable flying branch ends [m] (NaN: not before twice the flying height): the fold of
    its static start (:func:`pipeline.model.start.start_state`, found once per model and kept in its
    ``statics``), which no mechanism acting only in contact moves."""
    if model.start != "static":
        return np.nan
    running.start(model, float(model.p["FH0"]))
    return float(model.statics.get("fold", np.nan))


def with_friction_arm(model: Model, arm: float) -> Model:
    """A copy of ``model`` whose friction moment has the arm ``arm`` [m] (0: none), its statics its own."""
    return replace(model, p=with_values(model.p, friction_arm=float(arm)),
                   slider=replace(model.slider, friction_arm=float(arm)))


def contact_quantities(model: Model, protrusion: float, state: dict, interface: xr.Dataset | None = None
                       ) -> dict[str, float]:
    """The interface forces of a static state ``state`` (:func:`pipeline.model.statics.states_at`) at
    ``protrusion`` [m]: the tables the kernel reads (:func:`pipeline.model.kernel_inputs.interface_tables`) at
    its separation ``d``, times ``A_n``, the contact ones only under the criterion (the adhesion at rest, the
    continuous lubricant shear at any ``d``, as the static forces take them; SI units; the friction
    coefficient and the count of summits in contact, ``eta A_n contact_fraction(d)`` from ``interface``, [1])."""
    p, _, _ = kernel_inputs.run_parameters(model, protrusion)
    An = float(p["A_n"])
    tabs = kernel_inputs.interface_tables(model, protrusion, An)
    d = float(separation_at(p, state["z"], state["theta"], 0.0))
    x0, h = p["tab_x0"], p["tab_h"]
    on = model.contact is not None and d < model.k_sigma

    def at(table: np.ndarray | None, upper: float = np.inf) -> float:
        if table is None:
            return 0.0
        return An * float(np.clip(ppval(np.ascontiguousarray(table), x0, h, np.array([d]))[0], 0.0, upper))

    friction = 0.0
    if tabs.friction is not None:  # the switched solid part in contact; the continuous lubricant shear beside it
        friction = at(tabs.friction[:, :4]) if on else 0.0
        if tabs.friction.shape[1] == 8:
            friction += at(tabs.friction[:, 4:])
    # (the adhesion at rest: with the meniscus state, its relaxing and immediate tables summed)
    out = {"separation": d, "adhesion_force": at(static_table(tabs.adhesion)),
           "contact_force": at(tabs.contact) if on else 0.0, "friction_force": friction,
           "real_area": at(tabs.area, tabs.area_cap) if on else 0.0, "nominal_area": An}
    out["friction_coefficient"] = out["friction_force"] / out["contact_force"] if out["contact_force"] > 0 else np.nan
    count = np.nan
    if on and interface is not None and "contact_fraction" in interface:
        sep = interface["separation"].values * NM
        frac = float(np.interp(d, sep, interface["contact_fraction"].values))
        count = float(interface["summit_density"]) * 1e12 * An * frac  # (summit_density [um^-2])
    out["contact_count"] = count
    return out


def _stable(states: list[dict], kind: int) -> list[dict]:
    return [s for s in states if s["type"] == kind and s["stable"]]


def contact_state(model: Model, protrusion: float) -> dict | None:
    """The deepest stable contact state of ``model`` at ``protrusion`` [m] (None: there is none)."""
    found = _stable(st.states_at(model, protrusion), st.CONTACT)
    return min(found, key=lambda s: s["clearance"]) if found else None


def heated_contact(model: Model, protrusion: float, eta_f: float, speed: float) -> tuple[float, dict | None, float]:
    """The steady contact state with the frictional heat's protrusion: ``delta_f = eta_f V Q(delta + delta_f)``,
    ``Q`` the friction force of the model's contact state at ``delta + delta_f`` (secant iteration from
    ``delta_f = 0``, to :data:`HEAT_TOL`: :func:`pipeline.model.frictional_heating.heat_fixed_point`).

    Parameters
    ----------
    model : the scene's model; protrusion : ``delta`` [m]; eta_f : [m/W]; speed : ``V`` [m/s]

    Returns
    -------
    delta_f : float
        The heat's protrusion [m] (0 for ``eta_f = 0``; NaN where no contact state continues it).
    state : dict or None
        The contact state at ``delta + delta_f`` (:func:`pipeline.model.statics.states_at`'s entry).
    gain : float
        ``eta_f V dQ/d(delta)`` at the fixed point [1] (secant): below 1 the fixed point is stable
        (a thermal runaway at or above 1).
    """
    state = contact_state(model, protrusion)
    if eta_f == 0.0 or state is None:
        return 0.0, state, 0.0
    last: dict[float, dict | None] = {}

    def steady(x: float) -> float:
        s = state if x == 0.0 else contact_state(model, protrusion + x)
        last[x] = s
        if s is None:
            return np.nan
        return eta_f * speed * contact_quantities(model, protrusion + x, s)["friction_force"]

    x, gain = heat_fixed_point(steady, HEAT_TOL, MAX_ITER)
    return (x, last[x], gain) if np.isfinite(x) else (np.nan, None, gain)


#: The map's variables (dataset units; SI values divided by ``si_unit``).
_CP = ("case", "protrusion")
MAP = {v.name: v for v in (
    Variable("protrusion", "nm", "TFC protrusion", NM, dims=("protrusion",)),
    Variable("case", "", "mechanism case", dims=("case",), dtype="str"),
    Variable("mechanism", "", "mechanism", dims=("case",), dtype="str"),
    Variable("value", "1", "mechanism value", dims=("case",),
             description="the mechanism's value in its own unit (J m-2, nm mW-1, nm mN-1 or nm: see value_units)"),
    Variable("value_units", "", "units of the mechanism value", dims=("case",), dtype="str"),
    Variable("k", "1", "contact criterion k", dims=("case",)),
    Variable("fold", "nm", "end of the flying branch", NM, dims=("case",),
             description="protrusion where the stable flying branch, continued from zero protrusion, ends (the "
                         "saddle-node fold of the static start, bracketed to 1e-3 nm; NaN: not before twice the "
                         "flying height)"),
    Variable("friction_lift", "nm mN-1", "free TFC-point lift per friction", NM / 1e-3, dims=("case",),
             description="lift of the TFC point per mN of friction on the air bearing alone (a K^-1 b)"),
    Variable("flying", "1", "stable flying state", dims=_CP, dtype="int8", flag_values=(0, 1),
             flag_meanings="no yes", description="a stable state above the contact criterion exists"),
    Variable("contact", "1", "stable contact state", dims=_CP, dtype="int8", flag_values=(0, 1),
             flag_meanings="no yes", description="a stable state below the contact criterion exists"),
    Variable("coexist", "1", "flying and contact coexist", dims=_CP, dtype="int8", flag_values=(0, 1),
             flag_meanings="no yes", description="both a stable flying and a stable contact state exist"),
    Variable("flying_clearance", "nm", "flying clearance", NM, dims=_CP,
             description="clearance d - k sigma of the highest stable flying state"),
    Variable("interference", "nm", "static interference", NM, dims=_CP,
             description="interference k sigma - d of the deepest stable contact state"),
    Variable("separation", "nm", "static separation", NM, dims=_CP,
             description="separation d of the contact state to the mean of the summit heights"),
    Variable("contact_force", "mN", "contact force", 1e-3, dims=_CP),
    Variable("adhesion_force", "mN", "adhesion force", 1e-3, dims=_CP),
    Variable("friction_force", "mN", "friction force", 1e-3, dims=_CP),
    Variable("real_area", "um2", "real contact area", 1e-12, dims=_CP),
    Variable("friction_coefficient", "1", "friction coefficient", dims=_CP,
             description="friction force over contact force of the contact state"),
    Variable("friction_power", "mW", "friction power", 1e-3, dims=_CP, description="friction force times disk speed"),
    Variable("thermal_protrusion", "nm", "frictional-heating protrusion", NM, dims=_CP,
             description="steady protrusion of the frictional heat eta_f Q V added to the heater's"),
    Variable("thermal_gain", "1", "frictional-heating loop gain", dims=_CP,
             description="eta_f V dQ/d(delta) at the fixed point: 1 or more is a thermal runaway"),
    Variable("contact_count", "1", "summits in contact", dims=_CP),
    Variable("flash_temperature", "K", "flash temperature rise", dims=_CP,
             description="maximum surface temperature rise of a micro-contact (Tian-Kennedy; Blok's partition)"),
    Variable("heat_partition", "1", "slider's heat share", dims=_CP,
             description="fraction of the friction heat flowing into the slider (Blok's postulate)"),
    Variable("contact_peclet", "1", "micro-contact Peclet number", dims=_CP, description="V a / (2 kappa_disk)"),
    Variable("nominal_temperature", "K", "nominal contact temperature rise", dims=_CP,
             description="maximum surface temperature rise of the friction power spread over the nominal area as "
                         "one circular source (Tian-Kennedy; Blok's partition)"),
    Variable("nominal_heat_partition", "1", "slider's heat share, nominal", dims=_CP,
             description="fraction of the friction heat flowing into the slider at the nominal area's scale"),
)}

VALUE_UNITS = {"none": "1", "penetration-adhesion": "J m-2", "frictional-heating": "nm mW-1",
               "pitch-compliance": "nm mN-1", "roughness-datum": "nm"}


def mechanism_map(cases: Sequence[Case], protrusions, *, interface: xr.Dataset | None = None,
                  thermal: Thermal = Thermal()) -> xr.Dataset:
    """The statics map of ``cases`` (:class:`Case`) at ``protrusions`` [nm] (module docstring): dims
    ``(case, protrusion)``, variables :data:`MAP`.

    Parameters
    ----------
    cases : the mechanisms at their values, each with its model
    protrusions : the heater's protrusions [nm]
    interface : the interface dataset of the scene (``interface.nc``), for the count of summits in contact
        (the flash temperature); None: NaN
    thermal : the contact's thermal properties (:class:`Thermal`)

    Returns
    -------
    xarray.Dataset
        The map (dataset units: nm, mN, um2, mW, K).
    """
    labels = np.asarray(protrusions, dtype=float)
    shape = (len(cases), labels.size)
    names = [n for n, v in MAP.items() if v.dims == _CP]
    tab = {n: np.full(shape, np.nan) for n in names}
    for i, case in enumerate(cases):
        if case.mechanism not in MECHANISMS:
            raise ValueError(f"mechanism_map: mechanism {case.mechanism!r} is not one of {MECHANISMS}")
        m = case.model
        V = disk_speed_m_s(m.scene["dmw"])
        for j, mu in enumerate(labels * NM):
            states = st.states_at(m, mu)
            flying = _stable(states, st.FLYING)
            x, cstate, gain = heated_contact(m, mu, case.heating * NM_PER_MW, V)
            tab["flying"][i, j] = bool(flying)
            tab["contact"][i, j] = cstate is not None
            tab["coexist"][i, j] = bool(flying) and cstate is not None
            tab["flying_clearance"][i, j] = max(s["clearance"] for s in flying) if flying else np.nan
            tab["thermal_protrusion"][i, j] = x
            tab["thermal_gain"][i, j] = gain
            if cstate is None:
                continue
            q = contact_quantities(m, mu + x, cstate, interface)
            tab["interference"][i, j] = -cstate["clearance"]
            for n in ("separation", "contact_force", "adhesion_force", "friction_force", "real_area",
                      "friction_coefficient", "contact_count"):
                tab[n][i, j] = q[n]
            power = q["friction_force"] * V
            tab["friction_power"][i, j] = power
            t = contact_temperature(power, q["real_area"], q["contact_count"], V, thermal.k_slider, thermal.k_disk,
                                    thermal.diffusivity_disk)
            tab["flash_temperature"][i, j] = t["temperature"]
            tab["heat_partition"][i, j] = t["partition"]
            tab["contact_peclet"][i, j] = t["peclet"]
            t = contact_temperature(power, q["nominal_area"], 1.0, V, thermal.k_slider, thermal.k_disk,
                                    thermal.diffusivity_disk)
            tab["nominal_temperature"][i, j] = t["temperature"]
            tab["nominal_heat_partition"][i, j] = t["partition"]
    data: dict[str, Any] = {n: MAP[n].from_si(tab[n], _CP) for n in names}
    data["mechanism"] = MAP["mechanism"].data([c.mechanism for c in cases], ("case",))
    data["value"] = MAP["value"].data([c.value for c in cases], ("case",))
    data["value_units"] = MAP["value_units"].data([VALUE_UNITS[c.mechanism] for c in cases], ("case",))
    data["k"] = MAP["k"].data([c.model.k for c in cases], ("case",))
    data["friction_lift"] = MAP["friction_lift"].from_si([friction_lift(c.model) for c in cases], ("case",))
    data["fold"] = MAP["fold"].from_si([flying_fold(c.model) for c in cases], ("case",))
    ds = xr.Dataset(data, coords={
        "case": MAP["case"].data([c.label or f"{c.mechanism} {c.value:g}" for c in cases], ("case",)),
        "protrusion": MAP["protrusion"].data(labels, ("protrusion",))})
    ds.attrs.update({
        "method": "static states along the relaxed path (pipeline.model.statics.states_at) per mechanism case; the "
                  "frictional heat's protrusion at its steady state eta_f Q V (docs/model.md, section 'Mechanism "
                  "statics')",
        "thermal": f"k_slider {thermal.k_slider:g} W/(m K), k_disk {thermal.k_disk:g} W/(m K), kappa_disk "
                   f"{thermal.diffusivity_disk:g} m2/s (docs/model.md, section 'Flash temperature')",
    })
    return ds

"""The 2-DOF slider model: assemble it from a scene, run it, and summarise a run.

:func:`build_model` turns a scene, its interface tables (``interface.nc`` content) and its DMW
record into the arrays the numba kernel of :mod:`pipeline.model.dynamics` takes; :func:`run_model`
integrates one protrusion; :func:`histories` and :func:`summarize` turn a run into the paper's
time series (Figs 3-5) and the steady-window scalars of the sweep.

The separation ``d`` is measured to the mean of summit heights, ``y_s`` above the mean of surface
heights to which ``FH0`` is measured (docs/model.md, section "Separation datum"; one home: :func:`pipeline.model.forces.separation_at`).
Named model variants (scene keys, one registry each): ``air_bearing.stiffness_root``
(:data:`pipeline.physics.air_bearing.STIFFNESS_ROOTS`), ``air_bearing.rear_law`` (``REAR_LAWS``),
``air_bearing.tfc_stiffening`` (``TFC_STIFFENING``), ``contact.friction_law``
(:data:`pipeline.physics.friction.FRICTION_LAWS`), ``solver.fhm_measure``
(:data:`pipeline.physics.fhm.FHM_MEASURES`), and two deviations from the paper (docs/model.md, section
"Deviations", items 18-19): ``contact.area_model`` (:data:`pipeline.physics.geometry.AREA_MODELS`: the
interface stresses summed over the bulge's gap field, per-protrusion tables of :func:`interface_tables`) and
``slider.friction_arm`` (:data:`pipeline.physics.geometry.FRICTION_ARMS`: the friction moment's arm).

Adding a variant. A friction law, an FHM measure, a stiffness root or an air-bearing force law at the
TFC point is its function in its physics module plus one line in its registry; nothing here or in
the kernel changes (a TFC-point law without a compiled closed form is tabulated per protrusion by
:func:`tfc_table` into the kernel's generic slot, :mod:`pipeline.model.dynamics`). A new scene key whose
laws act at the TFC point (e.g. ``air_bearing.bulge``) adds its registry to :data:`TFC_POINT_LAWS`.

Steady-window definitions (over ``transient_ms <= t <= duration_ms``, sampled every
``output_step_ns``):

* ``fhm_bv`` [%]: peak-to-peak of the separation ``d`` over ``FH0`` (or 3 std, ``solver.fhm_measure``);
  called FHM while flying and BV (bouncing vibration) in contact, as in the paper. The extremes
  are the exact ones tracked by the integrator, not those of the output samples.
* ``clearance``/``min_clearance`` [nm]: mean/minimum of ``c = d - k sigma`` (the minimum exact, as above).
* ``interference`` [nm]: mean of ``-c`` over the samples in contact (NaN if none).
* forces [mN]: time means over the window (zero while out of contact, but for the continuous lubricant
  shear of ``contact.friction_switching = "continuous"``); ``net_force`` is the
  vertical interface force on the slider, contact + contact damping - adhesion.
* ``friction_coefficient`` [1]: mean friction / mean contact force.
* ``mean_pressure``, ``shear_stress`` [MPa]: total contact / friction force over total real area,
  over the samples in contact; ``real_area`` [um2]: mean real area while in contact.
* ``contact_fraction`` [1]: fraction of the window's samples in contact.
* ``contact_switches_per_ms`` [1/ms]: transitions of the contact mode in the window per ms
  (:func:`contact_switch_rate`, counted by the kernel).
* ``regime``: 0 flying (no contact in the steady window, :func:`touched`), 2 surfing (steady
  sliding: in contact in at least 99 % of the samples), 1 bouncing (otherwise, including contacts
  shorter than the output step).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any, Callable, Mapping, NamedTuple, Sequence

import numpy as np
from scipy.interpolate import CubicSpline

from . import dynamics as dyn
from .forces import RearLawRef, rear_law_ref, separation_at
from .piecewise import disk_coefficients, disk_history, piecewise_coefficients, ppval
from .state import (ACCEPTED, MENISCUS, OK, REJECTED, STATUS, STATUS_TEXT, THETA, THETA_RATE, WINDOW_SWITCHES, Z,
                    Z_RATE)
from ..units import KHZ, MS, NM
from ..physics import air_bearing as ab
from ..physics import bulge_bearing as bb
from ..physics.fhm import fhm
from ..physics.friction import friction_parts, friction_stress_table, lubricant_shear_stress
from ..physics.geometry import effective_radius, ellipsoid_table_integral, friction_arm, nominal_area
from ..physics.asperity_statistics import explicit_statistics
from ..config.si import to_si
from ..variables import INTERFACE, Regime
from .bulge_table import from_dataset
from .dmw_record import disk_speed_m_s
from ..validity import check_run
from .start import start_state

#: Regime codes (:class:`pipeline.variables.Regime`, the ``flag_values`` of the ``regime`` variable).
FLYING, BOUNCING, SURFING = Regime.FLYING, Regime.BOUNCING, Regime.SURFING
SURFING_FRACTION = 0.99

#: Absolute tolerance of the meniscus state q, relative to the largest adhesion pressure of the table [1].
MENISCUS_ATOL = 1e-6

#: How many protrusions' integrated interface tables a model keeps (:func:`interface_tables`): a run asks
#: for its own protrusion several times (the kernel, the histories, the meniscus start), the static
#: start's continuation for many once each.
INTEGRATED_CACHE = 8

#: How many protrusions' tabulated TFC-point forces a model keeps (:func:`tfc_table`): the static starts'
#: continuation ladder (about 2 FH0 / 1 nm protrusions) and a batch's runs.
TFC_CACHE = 64

#: Scene keys of ``[air_bearing]`` whose named laws (:class:`pipeline.physics.air_bearing.TfcLaw`) act at
#: the TFC point, each with its registry: the selected laws are summed in the kernel's TFC-point force.
TFC_POINT_LAWS: Mapping[str, Mapping[str, ab.TfcLaw | None]] = {"tfc_stiffening": ab.TFC_STIFFENING,
                                                               "bulge": bb.BULGE_LAWS}


#: How a TFC-point law's table (:attr:`pipeline.physics.air_bearing.TfcLaw.table`) is read from its stage's
#: dataset into the SI object its ``force`` takes.
TABLE_READERS: Mapping[str, Callable[[Any], Any]] = {"bulge": from_dataset}


@dataclass
class Model:
    """Everything one scene needs to run at any protrusion (SI units).

    Attributes
    ----------
    slider : the rigid body and air bearing
    p : the kernel's named parameters (a :data:`pipeline.model.dynamics.PARAMS` record; the
        protrusion-dependent fields are set by :func:`run_model`)
    dmw : DMW coefficients [m] or ``None``; contact, adhesion, friction, area : interface-table
        coefficients [Pa] / [1] versus separation [m], or ``None`` when the effect is off (``friction``
        with ``contact.friction_switching = "continuous"`` and lubricant shear: two tables side by side,
        the switched solid friction and the continuous lubricant shear, :func:`pipeline.physics.friction.friction_parts`)
    pitch : ``None`` when the pitch DOF is locked
    tfc_stiffening : parameters of the compiled gap-power law at the TFC point (a
        :data:`pipeline.model.dynamics.GAP_POWER` record, ``f0`` set per protrusion), ``None`` without it
    rear_law : the rear-bearing law (``air_bearing.rear_law``) as the kernel takes it
        (:func:`pipeline.model.forces.rear_law_ref`)
    tfc_tabulated : the selected TFC-point laws without a compiled form, tabulated per protrusion
        (:func:`tfc_table`); scene : the scene they read
    area_model : ``contact.area_model`` (:data:`pipeline.physics.geometry.AREA_MODELS`). The fields
        ``contact``, ``adhesion``, ``friction`` and ``area`` always hold the stresses at the apex separation
        (the flat-section tables); the kernel and the histories read :func:`interface_tables`, which with
        ``"integrated"`` sums them over the bulge per protrusion
    k_sigma : contact criterion threshold ``k sigma`` [m] (``nan`` without contact)
    """

    slider: ab.Slider
    p: np.record
    dmw: np.ndarray | None
    contact: np.ndarray | None
    adhesion: np.ndarray | None
    friction: np.ndarray | None
    area: np.ndarray | None
    pitch: np.ndarray | None
    sigma: float
    k: float
    section_depth: float
    half_length: float
    half_width: float
    duration: float
    transient: float
    output_step: float
    rtol: float
    atol: np.ndarray
    max_step: float
    fhm_measure: str
    effects: frozenset
    info: dict = field(default_factory=dict)
    tfc_stiffening: np.record | None = None
    rear_law: RearLawRef | None = None
    tfc_tabulated: tuple[ab.TfcLaw, ...] = ()
    scene: Any = None
    start: str = "nominal"
    meniscus: float | None = None
    area_model: str = "flat-section"
    #: the static starts of this model, kept once found: the fold of its flying branch
    #: (:func:`pipeline.model.start.start_state`) and the start state per protrusion (:func:`start`).
    #: Not an init field, so that a copy with other forces (``dataclasses.replace``) finds its own;
    #: copies whose statics are the same share it (:func:`with_solver`, :func:`share_statics`)
    statics: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    #: the integrated interface tables of the last protrusions asked for, by (protrusion, A_n), and the real-area
    #: table capped at 1 they sum ("capped_area"; :func:`interface_tables`)
    integrated: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    #: the tabulated TFC-point force of the last :data:`TFC_CACHE` protrusions asked for, by protrusion
    #: (:func:`tfc_table`): a run and the static starts at one protrusion build it once. Copies with the
    #: same laws share it (:func:`with_criterion`, :func:`with_solver`, :func:`share_statics`)
    tfc_tables: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def k_sigma(self) -> float:
        return self.k * self.sigma if np.isfinite(self.k) else 0.0


def slider_from_scene(scene: Any, damping_ratio: float | None = None) -> tuple[ab.Slider, dict]:
    """The rigid slider and its air bearing from ``[slider]`` and ``[air_bearing]`` (docs/model.md, section "Slider dynamics").

    Stiffnesses by modal inversion of the two natural frequencies (root chosen by the named rule
    ``air_bearing.stiffness_root``, default ``"stiff-rear"``: docs/model.md, section "Air bearing"), pad dampers for the modal
    damping ratio. ``h_cg``, the friction force's moment arm about the CG, by the named rule
    ``slider.friction_arm`` (:func:`pipeline.physics.geometry.friction_arm`): ``T/2`` (``"cg"``, the CG
    height over the air-bearing surface) or ``T`` (``"gimbal"``; docs/model.md, section "Deviations", item 19).
    """
    s, a = scene["slider"], scene["air_bearing"]
    si = to_si(scene)
    ss, sa = si.slider, si.air_bearing
    L, W, T = ss.length, ss.width, ss.thickness
    m, I = ab.mass_properties(L, W, T, s["density_kg_m3"])
    l_f, l_r = ss.front_arm, ss.rear_arm
    l_c = L / 2 - ss.tfc_from_trailing_edge
    f1, f2 = sa.frequencies
    k_f, k_r, info = ab.choose_stiffness(f1, f2, m, I, l_f, l_r, L, a["stiffness_root"])
    zeta = a["damping_ratio"] if damping_ratio is None else damping_ratio
    c_f, c_r = ab.pad_damping(k_f, k_r, m, I, l_f, l_r, zeta) if zeta > 0 else (0.0, 0.0)
    g0 = sa.rear_reference_gap or sa.flying_height
    slider = ab.Slider(m=m, I=I, l_f=l_f, l_r=l_r, l_c=l_c, h_cg=friction_arm(T, s["friction_arm"]), k_f=k_f,
                       k_r=k_r, c_f=c_f, c_r=c_r, g0=g0, n=a["rear_exponent"])
    info["damping_ratio"] = zeta
    info["friction_arm"] = s["friction_arm"]
    return slider, info


def build_model(scene: Any, interface: Any | None, dmw: tuple[np.ndarray, float] | None, k: float | None,
                damping_ratio: float | None = None, bulge: Any | None = None) -> Model:
    """Assemble the model of a scene.

    Parameters
    ----------
    scene : the validated scene
    interface : the interface dataset (``xarray.Dataset`` as written by the interface stage), or
        ``None`` for a scene with neither contact nor adhesion
    dmw : ``(displacement [nm] sampled uniformly from t = 0, sample rate [Hz])`` or ``None``
    k : contact criterion constant [1] (required with the contact effect)
    damping_ratio : overrides ``air_bearing.damping_ratio`` (sweeps)
    bulge : the bulge table (``xarray.Dataset`` as written by the bulge stage, ``bulge.nc``), needed by
        ``air_bearing.bulge = "reynolds"`` (:func:`tfc_point_laws`), else ignored
    """
    eff = scene.effects
    if "air_bearing" not in eff:
        raise ValueError("scene.effects must include 'air_bearing': nothing else holds the slider up")
    slider, info = slider_from_scene(scene, damping_ratio)
    a, sol, dm = scene["air_bearing"], scene["solver"], scene["dmw"]
    si = to_si(scene)
    s_sol = si.solver
    p = dyn.params(m=slider.m, I=slider.I, l_f=slider.l_f, l_r=slider.l_r, l_c=slider.l_c, h_cg=slider.h_cg,
                   k_f=slider.k_f, k_r=slider.k_r, c_f=slider.c_f, c_r=slider.c_r,
                   g0=slider.g0, n=slider.n, F_r0=slider.rear_preload, FH0=si.air_bearing.flying_height)
    gap_power, tabulated = tfc_point_laws(scene, p.FH0, {"bulge": bulge})
    rear_law = rear_law_ref(a["rear_law"])  # (a law that does not compile fails here, one line)
    info.update({"rear_law": a["rear_law"], "tfc_stiffening": a["tfc_stiffening"],
                 "friction_law": scene["contact"]["friction_law"],
                 "friction_coefficient": scene["contact"]["friction_coefficient"]})
    p.c_c = scene["contact"]["damping_n_s_m"]
    p.dwell = s_sol.min_dwell
    p.h_stiff = sol["stiffness_step"]
    # The record gives the disk under the TFC point at time t; the front and rear pads see the same
    # disk point earlier, by the travel time from pad to TFC (the disk moves leading -> trailing edge).
    V = disk_speed_m_s(dm)
    p.off_f = (slider.l_f + slider.l_c) / V
    p.off_r = (slider.l_c - slider.l_r) / V
    p.off_c = 0.0
    order = sol["interpolation_order"]
    duration = s_sol.duration

    dmw_c = None
    if "dmw" in eff:
        if dmw is None:
            raise ValueError("the dmw effect needs a DMW record")
        w_nm, fs = dmw
        need = duration + max(p.off_f, 0.0) + 2.0 / fs
        have = (w_nm.size - 1) / fs
        if have < need:
            raise ValueError(f"DMW record of {have / MS:.4g} ms is shorter than the {need / MS:.4g} ms the "
                             f"simulation needs (duration plus the pad-to-TFC travel time); set "
                             f"dmw.duration_ms >= {np.ceil(need * 1e5) / 1e2:g}")
        dmw_c = disk_coefficients(np.asarray(w_nm, float) * NM, 1.0 / fs, order,
                                      (p.off_c, p.off_f, p.off_r))
        p.dmw_t0, p.dmw_dt = 0.0, 1.0 / fs
        info["disk_speed_m_s"] = V

    tabs = {"contact": None, "adhesion": None, "friction": None, "area": None}
    if interface is not None and "model" in interface.dims:  # both models' tables: the scene's (interface.model)
        interface = interface.sel(model=scene["interface"]["model"])
    if interface is not None and "separation" in interface.coords:
        x = interface["separation"].values * NM
        h = float(x[1] - x[0])
        p.tab_x0, p.tab_h, p.tab_n = x[0], h, x.size - 1
        names = {"contact": ("contact_pressure", "contact"), "adhesion": ("adhesion_pressure", "adhesion"),
                 "friction": ("friction_stress", "friction"), "area": ("real_area_fraction", "contact")}
        for key, (var, effect) in names.items():
            scale = INTERFACE[var].si_unit  # dataset unit -> SI, declared once (pipeline/variables.py)
            if effect in eff:
                if var not in interface:
                    raise ValueError(f"interface tables lack {var!r}, needed by the {effect} effect; "
                                     "re-run `hdi interface`")
                values = interface[var].values * scale
                if key == "friction":  # the named friction law (docs/model.md, section "Friction") acts through the table
                    c = scene["contact"]
                    values = friction_stress_table(c["friction_law"],
                                                   interface["contact_pressure"].values * INTERFACE["contact_pressure"].si_unit,
                                                   values, c["friction_coefficient"])
                    tau_lub, lub = si.lubricant.shear_stress, None
                    if tau_lub > 0.0:  # the lubricant-shear term beside the solid one (docs/model.md, "Lubricant friction")
                        if "wetted_area_fraction" not in interface:
                            raise ValueError("interface tables lack 'wetted_area_fraction', needed by "
                                             "lubricant.shear_stress_mpa > 0; re-run `hdi interface`")
                        lub = lubricant_shear_stress(interface["wetted_area_fraction"].values, tau_lub)
                    # switched with the contact criterion, or the lubricant shear apart: at every separation
                    # (docs/model.md, section "Switched and continuous friction"; two tables side by side)
                    values, always = friction_parts(c["friction_switching"], values, lub)
                    if always is not None:
                        tabs[key] = np.ascontiguousarray(np.hstack([piecewise_coefficients(values, h, order),
                                                                    piecewise_coefficients(always, h, order)]))
                        continue
                tabs[key] = piecewise_coefficients(values, h, order)
    elif eff & {"contact", "adhesion"}:
        raise ValueError("the contact/adhesion effects need interface tables (run `hdi interface`)")
    sigma = float(interface["sigma"]) * NM if interface is not None else np.nan
    # separation datum: d is measured to the mean of summit heights, y_s above the mean of surface
    # heights to which FH0 is measured (docs/model.md, section "Separation datum")
    if interface is not None and "y_s" in interface:
        p.y_s = float(interface["y_s"]) * NM
    elif scene["roughness"]["afm"]:  # y_s is a statistic of the scans: interface.nc has it
        raise ValueError("a scene with roughness.afm needs its interface.nc (y_s of the scans) even without "
                         "contact or adhesion (pipeline.model.scene_inputs.needs_interface)")
    else:  # McCool's y_s of the explicit statistics (docs/model.md, section "Asperity statistics"), what the interface stage would write
        r = scene["roughness"]
        p.y_s = explicit_statistics(r["sigma_nm"], r["summit_radius_um"], r["summit_density_per_um2"])["y_s"]
    info["y_s"] = p.y_s
    if "contact" in eff:
        if k is None or not np.isfinite(k):
            raise ValueError("the contact effect needs the criterion k: set contact.k or run `hdi calibrate`")
    k = float(k) if k is not None else np.nan
    atol_len = s_sol.atol
    w2 = 2 * np.pi * a["frequencies_khz"][1] * KHZ
    atol = np.array([atol_len, atol_len / slider.l_c, atol_len * w2, atol_len / slider.l_c * w2])
    meniscus = si.lubricant.meniscus_time
    if meniscus > 0.0:
        if tabs["adhesion"] is None:
            raise ValueError("lubricant.meniscus_time_us > 0 relaxes the adhesion pressure: it needs the adhesion "
                             "effect in scene.effects")
        if scene["interface"]["adhesion"] == "two-population":
            # the state relaxes towards the menisci around contacts; the bridges act at once (docs/model.md,
            # section "Two adhesion populations"): two tables side by side (pipeline.model.dynamics.Tables)
            parts = [interface[v].values * INTERFACE[v].si_unit
                     for v in ("adhesion_pressure_menisci", "adhesion_pressure_bridges")]
            tabs["adhesion"] = np.ascontiguousarray(np.hstack([piecewise_coefficients(v, p.tab_h, order)
                                                               for v in parts]))
        # the meniscus state q [Pa]: absolute tolerance a millionth of the largest pressure it relaxes towards
        # (the flat-section table's also with contact.area_model = "integrated": a tolerance, of the same order)
        atol = np.append(atol, MENISCUS_ATOL * np.max(np.abs(tabs["adhesion"][:, 3])))
    else:
        meniscus = None
    info.update({"k_f": slider.k_f, "k_r": slider.k_r, "c_f": slider.c_f, "c_r": slider.c_r})
    return Model(slider=slider, p=p, dmw=dmw_c, contact=tabs["contact"], adhesion=tabs["adhesion"],
                 friction=tabs["friction"], area=tabs["area"],
                 pitch=np.ones(1) if "pitch" in eff else None, sigma=sigma, k=k,
                 section_depth=scene["contact"]["section_depth_sigma"] * sigma,
                 half_length=si.tfc.half_length, half_width=si.tfc.half_width,
                 duration=duration, transient=s_sol.transient,
                 output_step=s_sol.output_step, rtol=sol["rtol"], atol=atol,
                 max_step=s_sol.max_step, fhm_measure=sol["fhm_measure"], effects=eff, info=info,
                 tfc_stiffening=gap_power, rear_law=rear_law, tfc_tabulated=tabulated, scene=scene,
                 start=sol["start"], meniscus=meniscus, area_model=scene["contact"]["area_model"])


def tfc_point_laws(scene: Any, fh0: float, tables: Mapping[str, Any] | None = None
                   ) -> tuple[np.record | None, tuple[ab.TfcLaw, ...]]:
    """The scene's air-bearing laws at the TFC point (:data:`TFC_POINT_LAWS`): the parameters of the
    compiled gap-power law (a :data:`pipeline.model.dynamics.GAP_POWER` record, or ``None``) and the laws
    to tabulate (:func:`tfc_table`). ``fh0``: the flying height [m]; ``tables``: the datasets of the stages
    the laws read, by stage name (:attr:`pipeline.physics.air_bearing.TfcLaw.table`); a law that reads one
    gets it bound, in SI (:func:`pipeline.model.bulge_table.from_dataset`)."""
    a = scene["air_bearing"]
    tables = tables or {}
    gap_power, tabulated = None, []
    for key, registry in TFC_POINT_LAWS.items():
        law = registry[a[key]]
        if law is None:
            continue
        if law.closed_form == "gap-power":  # docs/model.md, section "Model variants"
            k_t, q = a["tfc_stiffness_n_m"], a["tfc_stiffening_exponent"]
            gap_power = dyn.params(dyn.GAP_POWER, k_t=k_t, q=q, g0=fh0, g_min=ab.TFC_MIN_GAP * fh0,
                                   k_min=ab.stiffening_stiffness(ab.TFC_MIN_GAP, 1.0, k_t, q))  # at g = g_min
        elif law.closed_form is None:
            if law.table is not None:
                ds = tables.get(law.table)
                if ds is None:
                    raise ValueError(f"air_bearing.{key} = {a[key]!r} needs the {law.table} table "
                                     f"({law.table}.nc: run `hdi {law.table}`)")
                law = replace(law, force=partial(law.force, table=TABLE_READERS[law.table](ds)))
            if law.parameters:
                law = replace(law, force=partial(law.force, **law_parameters(scene, law)))
            if key == "bulge" and a["lift_cap_gap_nm"] is not None:  # hypothesis H8 (off by default)
                g_s = to_si(scene).air_bearing.lift_cap_gap
                law = replace(law, force=partial(capped_lift, force=law.force, gap=g_s))
            tabulated.append(law)
        else:
            raise ValueError(f"air_bearing.{key} = {a[key]!r}: no compiled form {law.closed_form!r} in the kernel")
    return gap_power, tuple(tabulated)


def capped_lift(g: np.ndarray, delta: float, *, force: Callable[..., np.ndarray], gap: float) -> np.ndarray:
    """The bulge lift [N] of ``force`` held at its value at the apex gap ``gap`` [m] for smaller gaps ``g`` [m]
    (``air_bearing.lift_cap_gap_nm``: hypothesis H8, a device without a physical basis; docs/model.md, section
    "Lift cap (hypothesis H8)"); unchanged above it."""
    return force(np.maximum(np.asarray(g, dtype=float), gap), delta)


def law_parameters(scene: Any, law: ab.TfcLaw) -> dict[str, Any]:
    """The numbers a TFC-point law takes (:attr:`pipeline.physics.air_bearing.TfcLaw.parameters`), read from
    the scene in SI units (:func:`pipeline.config.si.to_si`): keyword of its ``force`` -> value."""
    si = to_si(scene)
    return {keyword: si[where.partition(".")[0]][where.partition(".")[2]] for keyword, where in law.parameters}


def tfc_table(model: Model, protrusion: float) -> tuple[np.ndarray, float, float] | None:
    """The tabulated TFC-point force of the model at a protrusion [m]: piecewise-cubic coefficients
    (:func:`pipeline.model.piecewise.piecewise_coefficients`, not-a-knot spline) of the sum of the laws of
    ``model.tfc_tabulated`` [N] on a uniform gap grid, its first gap [m] and step [m]; ``None`` without.

    The kernel takes the force and its stiffness ``-dF/dg`` from the same cubic (linear continuation
    below the grid, constant above). The grid spans the laws' ``gap_range`` times ``FH0`` with their
    largest ``points``. Kept in ``model.tfc_tables`` (the last :data:`TFC_CACHE` protrusions).
    """
    laws = model.tfc_tabulated
    if not laws:
        return None
    cache = model.tfc_tables
    key = float(protrusion)
    found = cache.get(key)
    if found is None:
        found = _tfc_table(laws, model.p.FH0, key)
        while len(cache) >= TFC_CACHE:
            try:  # (oldest first; another thread may have removed it already)
                cache.pop(next(iter(cache)), None)
            except (StopIteration, RuntimeError):
                break
        cache[key] = found
    return found


def _tfc_table(laws: tuple[ab.TfcLaw, ...], fh0: float, protrusion: float) -> tuple[np.ndarray, float, float]:
    """The table of :func:`tfc_table` made anew: the laws' summed force at ``protrusion`` [m] on their gap
    grid over the flying height ``fh0`` [m]."""
    g = np.linspace(min(law.gap_range[0] for law in laws) * fh0, max(law.gap_range[1] for law in laws) * fh0,
                    max(law.points for law in laws))
    force = sum(np.asarray(law.force(g, protrusion), dtype=float) for law in laws)
    h = float(g[1] - g[0])
    return piecewise_coefficients(force, h, 3), float(g[0]), h


@dataclass
class Run:
    """One integrated protrusion: states and contact flags sampled at ``time``.

    ``d_extremes``: exact minimum and maximum of the separation [m] over the steady window, tracked by
    the integrator (step ends and interior extrema), free of aliasing by the output grid.
    ``p``: the parameters the kernel ran with (the model's record with this protrusion, ``A_n``,
    ``k sigma``, ...: :data:`pipeline.model.dynamics.PARAMS`).
    """

    model: Model
    protrusion: float
    p: np.record
    nominal_area: float
    time: np.ndarray
    state: np.ndarray
    contact: np.ndarray
    info: np.ndarray
    d_extremes: tuple[float, float] = (np.nan, np.nan)
    start: str = "given"


class IntegrationError(RuntimeError):
    """The integrator failed (too many steps, step underflow, or a non-finite state)."""


def run_parameters(model: Model, protrusion: float) -> tuple[np.record, dyn.Tables, dyn.Variants]:
    """The kernel's parameters, tables and variants for the model at ``protrusion`` [m]."""
    An = float(nominal_area(protrusion, model.half_length, model.half_width, model.section_depth)) \
        if np.isfinite(model.section_depth) else 0.0
    p = dyn.with_values(model.p, delta=protrusion, A_n=An, k_sigma=model.k_sigma, t_win=model.transient)
    tables, variants = kernel_slots(model, p)
    return p, tables, variants


def start(model: Model, protrusion: float) -> tuple[np.ndarray, str]:
    """The start state of a run at ``protrusion`` [m] by the model's ``solver.start`` rule, and its note
    (:func:`pipeline.model.start.start_state`), kept in the model's ``statics`` once found (a copy is
    returned): the flying runs of a calibration and the realisations of an ensemble ask again."""
    starts = model.statics.setdefault("starts", {})
    key = (model.start, float(protrusion))
    if key not in starts:
        y_s, fh0 = model.p["y_s"], model.p["FH0"]
        # (the fold is searched up to twice the flying height: past FH0 the TFC point is at the disk anyway)
        starts[key] = start_state(lambda mu: run_parameters(model, mu), protrusion, model.start,
                                  contact_start_z=protrusion + y_s - fh0, statics=model.statics, fold_max=2 * fh0)
    y, note = starts[key]
    return y.copy(), note


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


def run_model(model: Model, protrusion: float, y0: np.ndarray | None = None, max_steps: int = 5_000_000) -> Run:
    """Integrate the model at protrusion ``protrusion`` [m] from its start state (``solver.start``:
    :func:`start`), or from ``y0`` when given (the previous heater step, a test)."""
    p, tables, variants = run_parameters(model, protrusion)
    An = p["A_n"]
    n_out = int(round(model.duration / model.output_step)) + 1
    t_out = np.minimum(np.arange(n_out) * model.output_step, model.duration)
    start_note = "given"
    if y0 is None:
        y0, start_note = start(model, protrusion)
    y0 = np.asarray(y0, float)
    if model.meniscus is not None and y0.size == 4:  # the meniscus state starts at its equilibrium
        y0 = np.append(y0, meniscus_equilibrium(model, p, y0))
    Y, C, info, ext = dyn.integrate(y0, dyn.Grid(model.duration, t_out), p, tables, variants,
                                    dyn.Solver(model.rtol, model.atol, model.max_step, max_steps))
    if info[STATUS] != OK:
        raise IntegrationError(f"integration failed at protrusion {protrusion / NM:.3g} nm: "
                               f"{STATUS_TEXT[int(info[STATUS])]} (steps {info[ACCEPTED]}, rejected {info[REJECTED]})")
    return Run(model=model, protrusion=protrusion, p=p, nominal_area=An, time=t_out, state=Y, contact=C, info=info,
               d_extremes=(float(ext[0]), float(ext[1])), start=start_note)


def meniscus_equilibrium(model: Model, p: np.record, y: np.ndarray) -> float:
    """The meniscus state's equilibrium ``q = p_a(d)`` [Pa] at the state ``y`` (z [m], theta [rad], ...)
    at ``t = 0``, the disk under the TFC point where the DMW record puts it (docs/model.md, section
    "Meniscus formation"): the start value of ``q``."""
    w = disk_history(model.dmw, p, np.zeros(1))[0][0] if model.dmw is not None else 0.0
    d = separation_at(p, float(y[Z]), float(y[THETA]), w)
    adhesion = interface_tables(model, p["delta"], p["A_n"]).adhesion
    return float(ppval(adhesion, p.tab_x0, p.tab_h, np.array([d]))[0])


class InterfaceTables(NamedTuple):
    """The interface tables of a model at one protrusion: piecewise cubics versus the separation on the
    grid ``p.tab_x0``, ``p.tab_h`` (``None``: effect off), each to be multiplied by ``A_n``: contact
    pressure, adhesion pressure, friction stress [Pa], real-area fraction [1]; ``area_cap``: the largest
    real area over ``A_n`` [1] (the histories clip the real area to it)."""

    contact: np.ndarray | None
    adhesion: np.ndarray | None
    friction: np.ndarray | None
    area: np.ndarray | None
    area_cap: float = 1.0


def interface_tables(model: Model, protrusion: float, nominal: float) -> InterfaceTables:
    """The interface tables the kernel and the histories use at ``protrusion`` [m], nominal area
    ``nominal`` [m^2] (the ``A_n`` they are multiplied by), by the model's ``contact.area_model``.

    ``"flat-section"`` (the paper's): the model's own tables, the stresses at the apex separation
    ``d`` (``A_n p(d)``), real area capped at ``A_n``. ``"integrated"``: per protrusion, the same stresses
    summed over the bulge's gap field, ``F(d) = 2 pi a b int_0^1 p(d + delta u) (1 - u) du``, tabulated
    at the table's nodes as ``F / A_n`` (exact integral of the tables' cubics,
    :func:`pipeline.physics.geometry.ellipsoid_table_integral`; nothing is taken beyond the table's top,
    :func:`pipeline.physics.geometry.table_truncation`) and splined as the tables are, so the kernel is
    unchanged; the local real-area fraction is capped at 1 before it is summed, so the real area is
    capped at the footprint ``pi a b`` (docs/model.md, section "Deviations", item 18). The last
    :data:`INTEGRATED_CACHE` protrusions' tables are kept on the model.
    """
    flat = InterfaceTables(model.contact, model.adhesion, model.friction, model.area)
    if model.area_model == "flat-section":
        return flat
    if model.area_model != "integrated":
        raise ValueError(f"contact.area_model = {model.area_model!r}: expected 'flat-section' or 'integrated'")
    key = (float(protrusion), float(nominal))
    cache = model.integrated
    found = cache.get(key)
    if found is None:
        found = _integrated_tables(model, flat, *key)
        while len(cache) > INTEGRATED_CACHE:
            try:  # (oldest first, not the capped area table; another thread may have removed it already)
                cache.pop(next(k for k in cache if k != "capped_area"), None)
            except (StopIteration, RuntimeError):
                break
        cache[key] = found
    return found


def _integrated_tables(model: Model, flat: InterfaceTables, protrusion: float, nominal: float) -> InterfaceTables:
    """The ``"integrated"`` tables of :func:`interface_tables` at ``protrusion`` [m], over ``A_n = nominal`` [m^2]."""
    if not nominal > 0:
        raise ValueError(f"contact.area_model = 'integrated' needs a nominal area > 0 (got {nominal} m^2)")
    h = float(model.p["tab_h"])
    order = model.scene["solver"]["interpolation_order"]
    scale = 2.0 * np.pi * model.half_length * model.half_width / nominal  # F / A_n = scale * I
    names = [n for n in InterfaceTables._fields[:4] if getattr(flat, n) is not None]
    if "area" in names and "capped_area" not in model.integrated:
        # a patch of the footprint has at most its own area in contact: the local fraction capped at 1
        c = flat.area
        nodes = np.append(c[:, 3], ppval(c, 0.0, h, np.array([c.shape[0] * h])))
        model.integrated["capped_area"] = c if not np.any(nodes > 1.0) else \
            piecewise_coefficients(np.minimum(nodes, 1.0), h, order)
    tables = [model.integrated["capped_area"] if n == "area" else getattr(flat, n) for n in names]
    # (two tables side by side, dynamics.Tables: the adhesion of the meniscus state, the continuous
    # friction; each integrated on its own)
    split = [n for n in names if getattr(flat, n).shape[1] == 8]
    for n in split:
        j = names.index(n)
        names[j:j + 1] = [n, n + "+"]
        tables[j:j + 1] = [getattr(flat, n)[:, :4], getattr(flat, n)[:, 4:]]
    # the tables at once (one grid): the integral, then the spline through its node values
    integral = scale * ellipsoid_table_integral(np.stack(tables, axis=-1), h, protrusion)
    splines = _splines(integral, h, order)
    for n in split:
        j = names.index(n)
        del names[j + 1]
        splines[j:j + 2] = [np.ascontiguousarray(np.hstack(splines[j:j + 2]))]
    tabs = dict.fromkeys(InterfaceTables._fields[:4])
    tabs.update(zip(names, splines))
    # the whole footprint in contact: 2 pi a b int_0^1 (1 - u) du = pi a b
    return InterfaceTables(**tabs, area_cap=scale / 2.0)


def _splines(values: np.ndarray, h: float, order: int) -> list[np.ndarray]:
    """The piecewise-cubic coefficients of each column of ``values`` (nodes x tables) on a grid of step ``h``,
    as :func:`pipeline.model.piecewise.piecewise_coefficients` makes them (the not-a-knot spline of all the
    columns in one solve for ``order`` 3: a third of the cost of one solve per column)."""
    if order != 3:
        return [piecewise_coefficients(values[:, j], h, order) for j in range(values.shape[1])]
    c = CubicSpline(h * np.arange(values.shape[0]), values, axis=0).c  # (4, pieces, columns)
    return [np.ascontiguousarray(c[:, :, j].T) for j in range(values.shape[1])]


def kernel_slots(model: Model, p: np.record) -> tuple[dyn.Tables, dyn.Variants]:
    """The kernel's tables and variants for the model at the protrusion ``p.delta`` [m]; sets the
    tabulated TFC-point law's grid in ``p`` (``None`` slots: effects off)."""
    gap_power = None
    delta = p["delta"]
    if model.tfc_stiffening is not None:  # the stiffening force is zero at this protrusion's nominal gap
        gp = model.tfc_stiffening
        gap_power = dyn.with_values(gp, f0=_stiffening_potential(p["FH0"] - delta, gp["g0"], gp["q"], gp["g_min"]))
    tfc = tfc_table(model, delta)
    if tfc is not None:
        tfc, p["tfc_x0"], p["tfc_h"] = tfc
    it = interface_tables(model, delta, p["A_n"])
    tables = dyn.Tables(dmw=model.dmw, contact=it.contact, adhesion=it.adhesion, friction=it.friction, tfc=tfc)
    variants = dyn.Variants(pitch=True if model.pitch is not None else None, rear_law=model.rear_law,
                            gap_power=gap_power, meniscus=model.meniscus)
    return tables, variants


def _stiffening_potential(g: float, g0: float, q: float, g_min: float) -> float:
    """``G(max(g, g_min))`` [m] of the stiffening law (:func:`pipeline.physics.air_bearing.tfc_stiffening_force`)."""
    return ab.stiffening_potential(max(g, g_min), g0, q)


def histories(run: Run) -> dict[str, np.ndarray]:
    """Time series of a run [SI]: separation, clearance, forces, friction coefficient, stresses.

    Only the quantities of the scene's effects are returned (no adhesion history without the
    adhesion effect, and so on).
    """
    m, p = run.model, run.p
    Y, t = run.state, run.time
    w = np.zeros_like(t)
    wdot = np.zeros_like(t)
    if m.dmw is not None:
        w, wdot = disk_history(m.dmw, p, t)
    d = separation_at(p, Y[:, Z], Y[:, THETA], w)
    out: dict[str, np.ndarray] = {"separation": d, "disk_displacement": w, "z": Y[:, Z], "pitch": Y[:, THETA]}
    out["clearance"] = d - m.k_sigma
    x0, h, An = p.tab_x0, p.tab_h, run.nominal_area
    tabs = interface_tables(m, run.protrusion, An)  # (those the kernel ran with: contact.area_model)
    net = np.zeros_like(t)
    if tabs.adhesion is not None:  # (the meniscus state q is the adhesion pressure when it is on)
        out["adhesion_force"] = An * (Y[:, MENISCUS] if m.meniscus is not None else ppval(tabs.adhesion, x0, h, d))
        if m.meniscus is not None and tabs.adhesion.shape[1] == 8:  # the part acting at once (dynamics.Tables)
            out["adhesion_force"] += An * ppval(np.ascontiguousarray(tabs.adhesion[:, 4:]), x0, h, d)
        net -= out["adhesion_force"]
    if m.contact is not None:
        c = run.contact

        def on_contact(table: np.ndarray, upper: float = np.inf) -> np.ndarray:
            """``A_n`` times a table at the samples in contact (its laws are off elsewhere: 0)."""
            v = np.zeros_like(t)
            if c.any():
                v[c] = An * np.clip(ppval(table, x0, h, d[c]), 0.0, upper)
            return v

        out["in_contact"] = c
        fc = on_contact(tabs.contact)
        ddot = Y[:, Z_RATE] - m.slider.l_c * Y[:, THETA_RATE] - wdot
        out["contact_force"] = fc
        out["contact_damping_force"] = np.where(c, -p.c_c * ddot, 0.0)
        net += fc + out["contact_damping_force"]
        # (clipped to [0, A_n] (flat section; the footprint when integrated): the spline through the
        # capped table may overshoot by ~1e-6 at the cap)
        area = on_contact(tabs.area, tabs.area_cap)
        out["real_area"] = area
        with np.errstate(invalid="ignore", divide="ignore"):
            out["mean_pressure"] = np.where(c & (area > 0), fc / np.where(area > 0, area, 1.0), np.nan)
            if tabs.friction is not None:
                two = tabs.friction.shape[1] == 8  # the continuous lubricant shear beside (forces.py)
                ff = on_contact(np.ascontiguousarray(tabs.friction[:, :4]) if two else tabs.friction)
                if two:  # ... at every sample
                    ff = ff + An * np.maximum(ppval(np.ascontiguousarray(tabs.friction[:, 4:]), x0, h, d), 0.0)
                out["friction_force"] = ff
                out["friction_coefficient"] = np.where(c & (fc > 0), ff / np.where(fc > 0, fc, 1.0), np.nan)
                out["shear_stress"] = np.where(c & (area > 0), ff / np.where(area > 0, area, 1.0), np.nan)
    if m.adhesion is not None or m.contact is not None:
        out["net_force"] = net
    return out


def summarize(run: Run, hist: dict[str, np.ndarray] | None = None) -> dict[str, float]:
    """Steady-window scalars of a run (SI units; definitions in the module docstring)."""
    m = run.model
    hist = histories(run) if hist is None else hist
    win = run.time >= m.transient - 1e-15
    d = hist["separation"][win]
    c = hist["clearance"][win]
    lo, hi = run.d_extremes
    exact = np.isfinite(lo) and np.isfinite(hi)
    # peak-to-peak of the exact extremes (between samples too) when the kernel found them
    exact_pp = m.fhm_measure == "peak-to-peak" and exact
    fhm_bv = float(fhm(np.array([lo, hi]) if exact_pp else d, m.p.FH0, m.fhm_measure))
    out = {
        "fhm_bv": fhm_bv,
        "clearance": float(np.mean(c)),
        "min_clearance": float(lo - m.k_sigma) if exact else float(np.min(c)),
        "nominal_area": run.nominal_area,
        "protrusion_radius": float(effective_radius(run.protrusion, m.half_length, m.section_depth))
        if np.isfinite(m.section_depth) else np.nan,
    }
    if "adhesion_force" in hist:
        out["adhesion_force"] = float(np.mean(hist["adhesion_force"][win]))
    if "net_force" in hist:
        out["net_force"] = float(np.mean(hist["net_force"][win]))
    if "in_contact" in hist:
        inc = hist["in_contact"][win]
        frac = float(np.mean(inc))
        out["contact_fraction"] = frac
        out["regime"] = FLYING if not touched(run) else (SURFING if frac >= SURFING_FRACTION else BOUNCING)
        out["contact_switches_per_ms"] = contact_switch_rate(run)  # [1/s]; the dataset's unit is 1/ms
        fc = hist["contact_force"][win]
        area = hist["real_area"][win]
        out["contact_force"] = float(np.mean(fc))
        out["interference"] = float(np.mean(-c[inc])) if inc.any() else np.nan
        out["real_area"] = float(np.mean(area[inc])) if inc.any() else np.nan
        out["mean_pressure"] = float(fc.sum() / area.sum()) if area.sum() > 0 else np.nan
        if "friction_force" in hist:
            ff = hist["friction_force"][win]
            out["friction_force"] = float(np.mean(ff))
            out["friction_coefficient"] = float(ff.sum() / fc.sum()) if fc.sum() > 0 else np.nan
            # (the friction in contact: the continuous lubricant shear also acts out of contact)
            out["shear_stress"] = float(np.where(inc, ff, 0.0).sum() / area.sum()) if area.sum() > 0 else np.nan
    out["validity"] = int(_validity(run, hist, win))
    return out


def contact_switch_rate(run: Run) -> float:
    """Transitions of the contact mode (``d < k sigma``) in the steady window per unit time [1/s]: the
    kernel's count (:data:`pipeline.model.state.WINDOW_SWITCHES`, every switch, also those between output
    samples) over the window's length (``contact_switches_per_ms`` in the datasets, [1/ms]). Near 0 for
    a run flying or in steady contact, a few per ms for bouncing, thousands per ms for a sliding mode
    held on the criterion (docs/model.md, section "Switched and continuous friction")."""
    window = run.model.duration - run.model.transient
    return float(run.info[WINDOW_SWITCHES]) / window if window > 0 else np.nan


def touched(run: Run) -> bool:
    """Whether a run touched in the steady window: in contact at an output sample of the window, or
    the exact minimum of the separation below ``k sigma`` (a contact shorter than the output step
    falls between samples but not past the integrator's exact extremes). The one rule of the regime
    (:func:`summarize`) and of the calibration; from a summary, ``min_clearance < 0`` says the same
    whenever the kernel tracked the extremes."""
    win = run.time >= run.model.transient - 1e-15
    return bool(run.contact[win].any() or run.d_extremes[0] < run.model.k_sigma)


def touched_in_summary(min_clearance: Any) -> Any:
    """:func:`touched` read from the steady-window summary: the exact minimum clearance ``d - k sigma``
    (``min_clearance``, any unit) below zero; ``False`` where it is NaN (not evaluated)."""
    with np.errstate(invalid="ignore"):
        return np.asarray(min_clearance) < 0


def _validity(run: Run, hist: dict[str, np.ndarray], win: np.ndarray) -> int:
    """The :class:`pipeline.validity.Validity` bits of a run's steady window."""
    m, s = run.model, run.model.slider
    fh0 = float(m.p["FH0"])
    lo = run.d_extremes[0] if np.isfinite(run.d_extremes[0]) else float(np.min(hist["separation"][win]))
    tables = m.contact is not None or m.adhesion is not None
    forces = [np.max(np.abs(hist[n][win])) for n in ("contact_force", "adhesion_force") if n in hist]
    return check_run(fh0=fh0, arms=(s.l_f, s.l_r), z=hist["z"][win], pitch=hist["pitch"][win], d_min=lo,
                     table_floor=float(m.p["tab_x0"]) if tables else None,
                     force=float(max(forces)) if forces else 0.0, load=(s.k_f + s.k_r) * fh0)


def with_criterion(model: Model, k: float) -> Model:
    """A copy of the model with the contact criterion ``k`` [1] (``d < k sigma``), for a search over k.

    When ``k`` is at or above the model's own and the model's static-start fold is known, the copy
    starts with that fold as an upper bound of its own (:func:`pipeline.model.start.start_state`): on
    the flying branch the contact law is off under either criterion, so the forces agree and a higher
    criterion can only end the branch earlier (where ``d`` reaches ``k sigma``). Starts past the bound
    then go to the contact branch, and starts below it continue the flying branch to their protrusion,
    without a fold search of the copy's own (~0.2 s each): a bisection on k past the touchdown
    (:func:`pipeline.analyses.calibration.k_threshold`) runs many such copies. The start states are
    those of a fresh model with ``k`` (tests/test_start.py).
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

"""Assembling the 2-DOF slider model of a scene: :func:`build_model` and the :class:`Model` it returns.

:func:`build_model` turns a scene, its interface tables (``interface.nc`` content) and its DMW record
into the arrays the numba kernel of :mod:`pipeline.model.dynamics` takes, in named steps: the rigid
body and air bearing (:func:`slider_from_scene`), the kernel's parameter record, the laws at the TFC
point (:func:`tfc_point_laws`), the DMW coefficients, the interface tables, the separation datum, the
contact criterion and the solver tolerances. The per-protrusion inputs of a run are
:mod:`pipeline.model.kernel_inputs`; running is :mod:`pipeline.model.running`, the outcomes of a run
:mod:`pipeline.model.outcomes`, copies of a model :mod:`pipeline.model.copies`.

The separation ``d`` is measured to the mean of summit heights, ``y_s`` above the mean of surface
heights to which ``FH0`` is measured (docs/model.md, section "Separation datum"; one home: :func:`pipeline.model.forces.separation_at`).
Named model variants (scene keys, one registry each, all of one shape:
:class:`pipeline.physics.variants.Registry`; the list: docs/model.md, section "Model variants"), e.g.
``air_bearing.stiffness_root`` (:data:`pipeline.physics.air_bearing.STIFFNESS_ROOTS`), ``air_bearing.rear_law``
(``REAR_LAWS``), ``air_bearing.tfc_stiffening`` (``TFC_STIFFENING``), ``contact.friction_law``
(:data:`pipeline.physics.friction.FRICTION_LAWS`), ``solver.fhm_measure``
(:data:`pipeline.physics.fhm.FHM_MEASURES`), and two deviations from the paper (docs/model.md, section
"Deviations", items 18-19): ``contact.area_model`` (:data:`pipeline.physics.geometry.AREA_MODELS`: the
interface stresses summed over the bulge's gap field by the entry's integral, per-protrusion tables of
:func:`pipeline.model.kernel_inputs.interface_tables`) and ``slider.friction_arm``
(:data:`pipeline.physics.geometry.FRICTION_ARMS`: the friction moment's arm). Each step looks its entry
up (:meth:`pipeline.physics.variants.Registry.lookup`) and uses the entry's behaviour, with the scene
values its ``parameters`` name (:func:`law_parameters`).

Adding a variant. A friction law, an FHM measure, a stiffness root or an air-bearing force law at the
TFC point is its function in its physics module plus one entry in its registry; nothing here or in
the kernel changes (a TFC-point law without a compiled closed form is tabulated per protrusion by
:func:`pipeline.model.kernel_inputs.tfc_table` into the kernel's generic slot, :mod:`pipeline.model.dynamics`).
A new scene key whose laws act at the TFC point (e.g. ``air_bearing.bulge``) adds its registry to
:data:`TFC_POINT_LAWS`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any, Callable, Mapping

import numpy as np

from . import dynamics as dyn
from .dmw_record import check_length, disk_speed_m_s
from .forces import RearLawRef, rear_law_ref
from .piecewise import disk_coefficients, piecewise_coefficients
from ..config.fields import fields, parameter_fields, union
from ..config.si import si_value
from ..physics import air_bearing as ab
from ..physics import bulge_bearing as bb
from ..physics import tfc_laws
from ..physics.asperity_statistics import explicit_statistics
from ..physics.friction import FRICTION_LAWS, friction_parts, friction_stress_table, lubricant_shear_stress
from ..physics.geometry import friction_arm
from ..physics.variants import Entry
from ..units import KHZ
from ..variables import DMW, INTERFACE


#: Absolute tolerance of the meniscus state q, relative to the largest adhesion pressure of the table [1].
MENISCUS_ATOL = 1e-6


#: Scene keys of ``[air_bearing]`` whose named laws (:class:`pipeline.physics.tfc_laws.TfcLaw`) act at
#: the TFC point, each with its registry: the selected laws are summed in the kernel's TFC-point force.
TFC_POINT_LAWS: Mapping[str, Mapping[str, tfc_laws.TfcLaw]] = {"tfc_stiffening": tfc_laws.TFC_STIFFENING,
                                                        "bulge": bb.BULGE_LAWS}


def _bulge_table(ds: Any) -> Any:
    """:func:`pipeline.model.bulge_table.from_dataset`, imported when a table is read (it imports xarray,
    which the first run's early compile process does not import:
    :data:`pipeline.model.ahead.NOT_IMPORTED_EARLY`)."""
    from .bulge_table import from_dataset
    return from_dataset(ds)


#: How a TFC-point law's table (:attr:`pipeline.physics.tfc_laws.TfcLaw.table`) is read from its stage's
#: dataset into the SI object its ``force`` takes.
TABLE_READERS: Mapping[str, Callable[[Any], Any]] = {"bulge": _bulge_table}


#: The scene keys :func:`build_model` reads (:func:`pipeline.config.fields.fields`): its steps' below, and
#: the parameters of every entry of the registries it looks laws up in (:func:`law_parameters`).
MODEL_FIELDS = union(
    fields("scene.effects", "slider.length_mm", "slider.width_mm", "slider.thickness_mm", "slider.density_kg_m3",
           "slider.front_arm_mm", "slider.rear_arm_mm", "slider.tfc_from_trailing_edge_um", "slider.friction_arm",
           "air_bearing.flying_height_nm", "air_bearing.frequencies_khz", "air_bearing.damping_ratio",
           "air_bearing.rear_exponent", "air_bearing.rear_reference_gap_nm", "air_bearing.stiffness_root",
           "air_bearing.rear_law", "air_bearing.tfc_stiffening", "air_bearing.bulge", "air_bearing.lift_cap_gap_nm",
           "tfc.half_length_um", "tfc.half_width_um", "roughness.afm", "roughness.sigma_nm",
           "roughness.summit_radius_um", "roughness.summit_density_per_um2", "lubricant.meniscus_time_us",
           "tfc.frictional_heating_nm_per_mw", "tfc.heating_time_us",
           "lubricant.shear_stress_mpa", "interface.model", "interface.adhesion", "contact.section_depth_sigma",
           "contact.damping_n_s_m", "contact.friction_law", "contact.friction_coefficient",
           "contact.friction_switching", "contact.area_model", "dmw.rpm", "dmw.radius_mm", "solver.rtol",
           "solver.atol_nm", "solver.max_step_ns", "solver.stiffness_step", "solver.min_dwell_ns",
           "solver.duration_ms", "solver.transient_ms", "solver.output_step_ns", "solver.interpolation_order",
           "solver.start", "solver.fhm_measure"),
    *(parameter_fields(registry.values()) for registry in (*TFC_POINT_LAWS.values(), FRICTION_LAWS)))


@dataclass
class Model:
    """Everything one scene needs to run at any protrusion (SI units).

    Attributes
    ----------
    slider : the rigid body and air bearing
    p : the kernel's named parameters (a :data:`pipeline.model.dynamics.PARAMS` record; the
        protrusion-dependent fields are set by :func:`pipeline.model.running.run_model`)
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
        (:func:`pipeline.model.kernel_inputs.tfc_table`); scene : the scene they read
    area_model : ``contact.area_model`` (:data:`pipeline.physics.geometry.AREA_MODELS`). The fields
        ``contact``, ``adhesion``, ``friction`` and ``area`` always hold the stresses at the apex separation
        (the flat-section tables); the kernel and the histories read
        :func:`pipeline.model.kernel_inputs.interface_tables`, which with ``"integrated"`` sums them over the
        bulge per protrusion
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
    tfc_tabulated: tuple[tfc_laws.TfcLaw, ...] = ()
    scene: Any = None
    start: str = "nominal"
    meniscus: float | None = None
    area_model: str = "flat-section"
    #: the frictional heat's protrusion (docs/model.md, section "Frictional heating"): ``(eta_f V, tau_f)``,
    #: its steady rise per friction force [m/N] and its time constant [s] (``None``: off;
    #: :func:`frictional_heating`, the kernel's ``Variants.heating``)
    heating: tuple[float, float] | None = None
    #: the static starts of this model, kept once found: the fold of its flying branch
    #: (:func:`pipeline.model.start.start_state`) and the start state per protrusion
    #: (:func:`pipeline.model.running.start`). Not an init field, so that a copy with other forces
    #: (``dataclasses.replace``) finds its own; copies whose statics are the same share it
    #: (:mod:`pipeline.model.copies`)
    statics: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    #: the integrated interface tables by (protrusion, A_n), and the real-area table capped at 1 they sum
    #: ("capped_area"; :func:`pipeline.model.kernel_inputs.interface_tables`; caching rule:
    #: :mod:`pipeline.model.kernel_inputs`)
    integrated: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    #: the tabulated TFC-point force by protrusion (:func:`pipeline.model.kernel_inputs.tfc_table`): a run
    #: and the static starts at one protrusion build it once; copies with the same laws share it
    #: (:mod:`pipeline.model.copies`; caching rule: :mod:`pipeline.model.kernel_inputs`)
    tfc_tables: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def k_sigma(self) -> float:
        return self.k * self.sigma if np.isfinite(self.k) else 0.0


def in_si(interface: Any, name: str) -> np.ndarray:
    """The values of the ``interface.nc`` variable ``name`` in SI units, from its dataset units by the
    variable schema (:data:`pipeline.variables.INTERFACE`)."""
    return interface[name].values * INTERFACE[name].si_unit


def slider_from_scene(scene: Any, damping_ratio: float | None = None) -> tuple[ab.Slider, dict]:
    """The rigid slider and its air bearing from ``[slider]`` and ``[air_bearing]`` (docs/model.md, section "Slider dynamics").

    Stiffnesses by modal inversion of the two natural frequencies (root chosen by the named rule
    ``air_bearing.stiffness_root``, default ``"stiff-rear"``: docs/model.md, section "Air bearing"), pad dampers for the modal
    damping ratio. ``friction_arm``, the friction force's moment arm about the CG, by the named rule
    ``slider.friction_arm`` (:func:`pipeline.physics.geometry.friction_arm`): ``T/2`` (``"cg"``, the CG
    height over the air-bearing surface) or ``T`` (``"gimbal"``; docs/model.md, section "Deviations", item 19).
    """
    si = scene.si
    ss, sa = si.slider, si.air_bearing
    L, W, T = ss.length, ss.width, ss.thickness
    m, I = ab.mass_properties(L, W, T, ss.density)
    l_f, l_r = ss.front_arm, ss.rear_arm
    l_c = L / 2 - ss.tfc_from_trailing_edge
    f1, f2 = sa.frequencies
    k_f, k_r, info = ab.choose_stiffness(f1, f2, m, I, l_f, l_r, L, sa.stiffness_root)
    zeta = sa.damping_ratio if damping_ratio is None else damping_ratio
    c_f, c_r = ab.pad_damping(k_f, k_r, m, I, l_f, l_r, zeta) if zeta > 0 else (0.0, 0.0)
    g0 = sa.rear_reference_gap or sa.flying_height
    slider = ab.Slider(m=m, I=I, l_f=l_f, l_r=l_r, l_c=l_c, friction_arm=friction_arm(T, ss.friction_arm), k_f=k_f,
                       k_r=k_r, c_f=c_f, c_r=c_r, g0=g0, n=sa.rear_exponent)
    info["damping_ratio"] = zeta
    info["friction_arm"] = ss.friction_arm
    return slider, info


def build_model(scene: Any, interface: Any | None, dmw: tuple[np.ndarray, float] | None, k: float | None,
                damping_ratio: float | None = None, bulge: Any | None = None) -> Model:
    """Assemble the model of a scene, in named steps (each reads the scene through its SI view,
    :func:`pipeline.config.si.to_si`).

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
    si = scene.si
    sa, sc, s_sol = si.air_bearing, si.contact, si.solver
    slider, info = slider_from_scene(scene, damping_ratio)
    p = kernel_record(slider, si)
    gap_power, tabulated = tfc_point_laws(scene, p.FH0, {"bulge": bulge})
    rear_law = rear_law_ref(sa.rear_law)  # (a law that does not compile fails here, one line)
    info.update({"rear_law": sa.rear_law, "tfc_stiffening": sa.tfc_stiffening, "friction_law": sc.friction_law,
                 "friction_coefficient": sc.friction_coefficient})
    dmw_c = disk_record(scene, p, dmw, info)
    interface = scene_interface(scene, interface)
    tabs = flat_tables(scene, p, interface)
    sigma = float(in_si(interface, "sigma")) if interface is not None else np.nan
    p.y_s = summit_datum(scene, interface)
    info["y_s"] = p.y_s
    k = criterion(eff, k)
    atol = tolerances(scene, slider)
    meniscus, tabs["adhesion"], atol = meniscus_state(scene, interface, p, tabs["adhesion"], atol)
    info.update({"k_f": slider.k_f, "k_r": slider.k_r, "c_f": slider.c_f, "c_r": slider.c_r})
    return Model(slider=slider, p=p, dmw=dmw_c, contact=tabs["contact"], adhesion=tabs["adhesion"],
                 friction=tabs["friction"], area=tabs["area"],
                 pitch=np.ones(1) if "pitch" in eff else None, sigma=sigma, k=k,
                 section_depth=sc.section_depth * sigma,
                 half_length=si.tfc.half_length, half_width=si.tfc.half_width,
                 duration=s_sol.duration, transient=s_sol.transient,
                 output_step=s_sol.output_step, rtol=s_sol.rtol, atol=atol,
                 max_step=s_sol.max_step, fhm_measure=s_sol.fhm_measure, effects=eff, info=info,
                 tfc_stiffening=gap_power, rear_law=rear_law, tfc_tabulated=tabulated, scene=scene,
                 start=s_sol.start, meniscus=meniscus, area_model=sc.area_model,
                 heating=frictional_heating(scene))


def frictional_heating(scene: Any) -> tuple[float, float] | None:
    """Step 8: the frictional heat's protrusion ``(eta_f V [m/N], tau_f [s])`` (``tfc.frictional_heating_nm_per_mw``,
    ``tfc.heating_time_us``, the disk speed ``V`` of ``[dmw]``), ``None`` for ``eta_f = 0`` (docs/model.md,
    section "Frictional heating")."""
    st = scene.si.tfc
    if not st.frictional_heating > 0.0:
        return None
    if "friction" not in scene.effects:
        raise ValueError("tfc.frictional_heating_nm_per_mw > 0 heats by the friction force: it needs the friction "
                         "effect in scene.effects")
    return st.frictional_heating * disk_speed_m_s(scene["dmw"]), st.heating_time


def with_record(model: Model, dmw: tuple[np.ndarray, float] | None) -> Model:
    """The model of the same scene on another DMW record ``dmw`` (as :func:`build_model` takes it): the
    model :func:`build_model` gives with that record, bit for bit, its one record-dependent step
    (:func:`disk_record`) made again and the others' results shared (the interface tables, the laws, the
    tolerances: read only). The realisations of a parameter study's candidate (~2 ms instead of ~9 ms:
    docs/performance.md, section "The Python of a pair"). The copy has its own caches (``statics``,
    ``integrated``, ``tfc_tables``: :mod:`pipeline.model.copies` shares them)."""
    p = dyn.with_values(model.p)
    info = dict(model.info)  # (disk_record sets the disk speed again, in its place)
    coefficients = disk_record(model.scene, p, dmw, info)
    return replace(model, p=p, dmw=coefficients, info=info)


def kernel_record(slider: ab.Slider, si: Any) -> np.record:
    """Step 1: the kernel's parameter record (:data:`pipeline.model.dynamics.PARAMS`) with the fields the
    scene fixes: the rigid body and its air bearing (:func:`slider_from_scene`), the flying height, the
    contact damper and the solver's contact thresholds; ``si``: the scene's SI view. The grids are set
    by the later steps, the protrusion-dependent fields per run
    (:func:`pipeline.model.kernel_inputs.run_parameters`)."""
    return dyn.params(m=slider.m, I=slider.I, l_f=slider.l_f, l_r=slider.l_r, l_c=slider.l_c,
                      friction_arm=slider.friction_arm, k_f=slider.k_f, k_r=slider.k_r, c_f=slider.c_f,
                      c_r=slider.c_r, g0=slider.g0, n=slider.n, F_r0=slider.rear_preload,
                      FH0=si.air_bearing.flying_height, c_c=si.contact.damping, dwell=si.solver.min_dwell,
                      h_stiff=si.solver.stiffness_step)


def disk_record(scene: Any, p: np.record, dmw: tuple[np.ndarray, float] | None, info: dict) -> np.ndarray | None:
    """Step 2: the disk travel times from each pad to the TFC point into ``p`` (``off_f``, ``off_r``,
    ``off_c`` [s]) and, with the ``dmw`` effect, the DMW record's coefficients [m] (``None`` without), its
    grid into ``p`` (``dmw_t0``, ``dmw_dt`` [s]) and the disk speed into ``info``."""
    # The record gives the disk under the TFC point at time t; the front and rear pads see the same
    # disk point earlier, by the travel time from pad to TFC (the disk moves leading -> trailing edge).
    V = disk_speed_m_s(scene["dmw"])
    p.off_f = (p.l_f + p.l_c) / V
    p.off_r = (p.l_c - p.l_r) / V
    p.off_c = 0.0
    if "dmw" not in scene.effects:
        return None
    if dmw is None:
        raise ValueError("the dmw effect needs a DMW record")
    s_sol = scene.si.solver
    w_nm, fs = dmw
    check_length(w_nm.size, fs, s_sol.duration, p.off_f, "DMW record")  # (the rule: dmw_record.needed_samples)
    coefficients = disk_coefficients(np.asarray(w_nm, float) * DMW["displacement"].si_unit, 1.0 / fs, s_sol.interpolation_order,
                                     (p.off_c, p.off_f, p.off_r))
    p.dmw_t0, p.dmw_dt = 0.0, 1.0 / fs
    info["disk_speed_m_s"] = V
    return coefficients


def scene_interface(scene: Any, interface: Any | None) -> Any | None:
    """The interface dataset of the scene's ``interface.model`` (a dataset of both models has the
    dimension ``model``), or ``interface`` as it is."""
    if interface is not None and "model" in interface.dims:
        return interface.sel(model=scene.si.interface.model)
    return interface


#: The interface tables of the model: field of :class:`Model` -> (variable of ``interface.nc``, the
#: effect that needs it).
TABLES = {"contact": ("contact_pressure", "contact"), "adhesion": ("adhesion_pressure", "adhesion"),
          "friction": ("friction_stress", "friction"), "area": ("real_area_fraction", "contact")}


def flat_tables(scene: Any, p: np.record, interface: Any | None) -> dict[str, np.ndarray | None]:
    """Step 3: the flat-section interface tables of the scene's effects (piecewise-cubic coefficients in
    SI versus the separation, :data:`TABLES`; ``None``: effect off) and their grid into ``p``
    (``tab_x0``, ``tab_h`` [m], ``tab_n``). The friction table is the named friction law's
    (``contact.friction_law``) with, for ``lubricant.shear_stress_mpa > 0``, the lubricant shear beside
    (two tables side by side, :func:`pipeline.physics.friction.friction_parts`)."""
    eff = scene.effects
    tabs: dict[str, np.ndarray | None] = dict.fromkeys(TABLES)
    if interface is None or "separation" not in interface.coords:
        if eff & {"contact", "adhesion"}:
            raise ValueError("the contact/adhesion effects need interface tables (run `hdi interface`)")
        return tabs
    si = scene.si
    order = si.solver.interpolation_order
    x = in_si(interface, "separation")
    h = float(x[1] - x[0])
    p.tab_x0, p.tab_h, p.tab_n = x[0], h, x.size - 1
    for key, (var, effect) in TABLES.items():
        if effect not in eff:
            continue
        if var not in interface:
            raise ValueError(f"interface tables lack {var!r}, needed by the {effect} effect; re-run `hdi interface`")
        values = in_si(interface, var)
        if key == "friction":  # the named friction law (docs/model.md, section "Friction") acts through the table
            values, always = friction_tables(scene, interface, values)
            if always is not None:
                tabs[key] = np.ascontiguousarray(np.hstack([piecewise_coefficients(values, h, order),
                                                            piecewise_coefficients(always, h, order)]))
                continue
        tabs[key] = piecewise_coefficients(values, h, order)
    return tabs


def friction_tables(scene: Any, interface: Any, stress: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The friction stress [Pa] of the named law (``contact.friction_law``) on the interface's friction
    stress ``stress`` [Pa] (the integral of the law's per-summit form, or of the shear-strength law for a law
    without one: ``interface.nc``'s ``friction_stress_law`` says which), switched with the contact criterion, and the part acting at every separation
    (``contact.friction_switching``, the lubricant shear of ``lubricant.shear_stress_mpa``; ``None``:
    none; docs/model.md, sections "Lubricant friction", "Switched and continuous friction")."""
    si = scene.si
    sc = si.contact
    pressure = in_si(interface, "contact_pressure")
    law = FRICTION_LAWS.lookup(sc.friction_law)
    built = interface.attrs.get("friction_stress_law", "shear-strength")
    if built != (sc.friction_law if law.summit is not None else "shear-strength"):
        raise ValueError(f"the interface tables' friction_stress integrates the {built!r} law, but "
                         f"contact.friction_law = {sc.friction_law!r} reads "
                         f"{'its own per-summit' if law.summit is not None else 'the shear-strength'} table; "
                         "re-run `hdi interface`")
    values = friction_stress_table(sc.friction_law, pressure, stress, **law_parameters(scene, law))
    tau_lub, lub = si.lubricant.shear_stress, None
    if tau_lub > 0.0:
        if "wetted_area_fraction" not in interface:
            raise ValueError("interface tables lack 'wetted_area_fraction', needed by "
                             "lubricant.shear_stress_mpa > 0; re-run `hdi interface`")
        lub = lubricant_shear_stress(interface["wetted_area_fraction"].values, tau_lub)
    return friction_parts(sc.friction_switching, values, lub)


def summit_datum(scene: Any, interface: Any | None) -> float:
    """Step 4: ``y_s`` [m], the mean of summit heights over the mean of surface heights to which
    ``FH0`` is measured (docs/model.md, section "Separation datum"): the interface's (``interface.nc``),
    else McCool's of the explicit statistics (section "Asperity statistics"), what the interface stage
    would write."""
    if interface is not None and "y_s" in interface:
        return float(in_si(interface, "y_s"))
    if scene.si.roughness.afm:  # y_s is a statistic of the scans: interface.nc has it
        raise ValueError("a scene with roughness.afm needs its interface.nc (y_s of the scans) even without "
                         "contact or adhesion (pipeline.model.scene_inputs.needs_interface)")
    sr = scene.si.roughness
    return explicit_statistics(sr.sigma, sr.summit_radius, sr.summit_density)["y_s"]


def criterion(effects: frozenset, k: float | None) -> float:
    """Step 5: the contact criterion ``k`` [1], required with the contact effect (NaN without)."""
    if "contact" in effects and (k is None or not np.isfinite(k)):
        raise ValueError("the contact effect needs the criterion k: set contact.k or run `hdi calibrate`")
    return float(k) if k is not None else np.nan


def tolerances(scene: Any, slider: ab.Slider) -> np.ndarray:
    """Step 6: the absolute tolerances of the state ``(z, theta, z', theta')``: ``solver.atol_nm`` on
    ``z``, over ``l_c`` on ``theta``, times the second natural frequency on the rates."""
    atol_len = scene.si.solver.atol
    # (the hand conversion kept: to_si's frequency [Hz] would round 2 pi f_kHz 1e3 in another order)
    w2 = 2 * np.pi * scene["air_bearing"]["frequencies_khz"][1] * KHZ
    return np.array([atol_len, atol_len / slider.l_c, atol_len * w2, atol_len / slider.l_c * w2])


def meniscus_state(scene: Any, interface: Any | None, p: np.record, adhesion: np.ndarray | None,
                   atol: np.ndarray) -> tuple[float | None, np.ndarray | None, np.ndarray]:
    """Step 7: the meniscus relaxation time [s] (``lubricant.meniscus_time_us``; ``None``: off), the
    adhesion table it relaxes towards, and the tolerances with the meniscus state's appended."""
    meniscus = scene.si.lubricant.meniscus_time
    if not meniscus > 0.0:
        return None, adhesion, atol
    if adhesion is None:
        raise ValueError("lubricant.meniscus_time_us > 0 relaxes the adhesion pressure: it needs the adhesion "
                         "effect in scene.effects")
    if scene.si.interface.adhesion == "two-population":
        # the state relaxes towards the menisci around contacts; the bridges act at once (docs/model.md,
        # section "Two adhesion populations"): two tables side by side (pipeline.model.dynamics.Tables)
        order = scene.si.solver.interpolation_order
        parts = [in_si(interface, v) for v in ("adhesion_pressure_menisci", "adhesion_pressure_bridges")]
        adhesion = np.ascontiguousarray(np.hstack([piecewise_coefficients(v, p.tab_h, order) for v in parts]))
    # the meniscus state q [Pa]: absolute tolerance a millionth of the largest pressure it relaxes towards
    # (the flat-section table's also with contact.area_model = "integrated": a tolerance, of the same order)
    return meniscus, adhesion, np.append(atol, MENISCUS_ATOL * np.max(np.abs(adhesion[:, 3])))


def tfc_point_laws(scene: Any, fh0: float, tables: Mapping[str, Any] | None = None
                   ) -> tuple[np.record | None, tuple[tfc_laws.TfcLaw, ...]]:
    """The scene's air-bearing laws at the TFC point (:data:`TFC_POINT_LAWS`): the parameters of the
    compiled gap-power law (a :data:`pipeline.model.dynamics.GAP_POWER` record, or ``None``) and the laws
    to tabulate (:func:`pipeline.model.kernel_inputs.tfc_table`). ``fh0``: the flying height [m]; ``tables``: the datasets of the stages
    the laws read, by stage name (:attr:`pipeline.physics.tfc_laws.TfcLaw.table`); a law that reads one
    gets it bound, in SI (:func:`pipeline.model.bulge_table.from_dataset`)."""
    a, sa = scene["air_bearing"], scene.si.air_bearing  # (the law names, the numbers in SI)
    tables = tables or {}
    gap_power, tabulated = None, []
    for key, registry in TFC_POINT_LAWS.items():
        law = registry.lookup(a[key])
        if law.force is None:  # ("none": the model without it)
            continue
        if law.closed_form == "gap-power":  # docs/model.md, section "Model variants"
            k_t, q = sa.tfc_stiffness, sa.tfc_stiffening_exponent
            gap_power = dyn.params(dyn.GAP_POWER, k_t=k_t, q=q, g0=fh0, g_min=tfc_laws.TFC_MIN_GAP * fh0,
                                   k_min=tfc_laws.stiffening_stiffness(tfc_laws.TFC_MIN_GAP, 1.0, k_t, q))  # at g = g_min
        elif law.closed_form is None:
            if law.table is not None:
                ds = tables.get(law.table)
                if ds is None:
                    raise ValueError(f"air_bearing.{key} = {a[key]!r} needs the {law.table} table "
                                     f"({law.table}.nc: run `hdi {law.table}`)")
                law = replace(law, force=partial(law.force, table=TABLE_READERS[law.table](ds)))
            if law.parameters:
                law = replace(law, force=partial(law.force, **law_parameters(scene, law)))
            if key == "bulge" and sa.lift_cap_gap is not None:  # hypothesis H8 (off by default)
                law = replace(law, force=partial(capped_lift, force=law.force, gap=sa.lift_cap_gap))
            tabulated.append(law)
        else:
            raise ValueError(f"air_bearing.{key} = {a[key]!r}: no compiled form {law.closed_form!r} in the kernel")
    return gap_power, tuple(tabulated)


def capped_lift(g: np.ndarray, delta: float, *, force: Callable[..., np.ndarray], gap: float) -> np.ndarray:
    """The bulge lift [N] of ``force`` held at its value at the apex gap ``gap`` [m] for smaller gaps ``g`` [m]
    (``air_bearing.lift_cap_gap_nm``: hypothesis H8, a device without a physical basis; docs/model.md, section
    "Lift cap (hypothesis H8)"); unchanged above it."""
    return force(np.maximum(np.asarray(g, dtype=float), gap), delta)


def law_parameters(scene: Any, law: Entry) -> dict[str, Any]:
    """The numbers a registry entry's behaviour takes (:attr:`pipeline.physics.variants.Entry.parameters`: a
    TFC-point law's force, a friction law), read from the scene in SI units (:func:`pipeline.config.si.to_si`):
    keyword -> value."""
    si = scene.si
    return {keyword: si_value(si, where) for keyword, where in law.parameters}

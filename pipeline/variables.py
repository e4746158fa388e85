"""Every output variable of the pipeline, declared once (the variable schema).

Each :class:`~pipeline.cf_variable.Variable` states its name, its dataset units (the paper's units, a UDUNITS string),
the SI value of one dataset unit (``si_unit``; dataset value = SI value / ``si_unit``, i.e. the SI
factor ``si_factor = 1/si_unit``), its ``long_name``, its CF
``standard_name`` where the CF table has one (none here: CF has no standard names for tribology,
and ``time`` is a duration, not CF's calendar time), the dimensions it carries beyond the grid of its dataset, the scene effect that
produces it (absent without that effect), for flag variables their values and missing value, and for a
variable computed from a published formula its sources (CF's ``references``: the keys of docs/model.md and
the section that states the formula; :class:`pipeline.cf_variable.Source`, whose module holds the type).

Groups (:data:`GROUPS`) collect the variables of one kind; :data:`DATASETS` says which groups each
dataset file may hold. Datasets (:mod:`pipeline.stages`), plots (:mod:`pipeline.analyses.plots`), the report's
tables and the optimum finder (:mod:`pipeline.analyses.optimum`) read names, units and flags from here, and
``tests/core/test_variables.py`` checks that every variable every stage writes is declared here with the
units it is written in.

How the datasets meet CF-1.8 (:func:`pipeline.io.cf_encoding`, applied by :func:`pipeline.io.write_dataset`):

* coordinates carry no ``_FillValue`` (CF 2.5.1);
* the simulated time is an elapsed time in seconds, not a date: the coordinate :data:`TIME`
  (``elapsed_time``) in plain ``s``, one name in memory (:func:`pipeline.model.simulation.simulate`) and
  in the files, which CF and xarray read as a number (a coordinate named ``time``, or units
  ``s since <date>``, is a calendar time to both: the compliance checker then asks for a reference date,
  and xarray's default decoding rounded it to microseconds). For the same reason it has no ``axis``
  (CF's ``T`` axis and ``standard_name = "time"`` are a calendar time's); :func:`pipeline.io.read_dataset`
  reads a file written before with ``time`` as ``elapsed_time``;
* ``axis`` where CF has one: ``separation`` of ``interface.nc``, the height of the TFC flat above the
  mean of summit heights, is the vertical axis (``axis = "Z"``, ``positive = "up"``; ``ds.cf["Z"]``);
* labels (string coordinates such as ``roughness`` or ``route``) have no units and are stored as
  character arrays (CF 2.2), which xarray decodes back to strings;
* ``regime`` is a flag variable (:class:`Regime`) whose missing value (-1, a point not computed)
  is declared as ``_FillValue``; xarray reads it as a float with NaN there.
"""

from __future__ import annotations

from enum import IntEnum
from typing import TYPE_CHECKING, Any, Iterable

import numpy as np
from .units import GPA, KHZ, MN, MPA, MS, MW, NM, PER_UM2, UM, UM2, URAD

from .cf_variable import Source, Variable
from .validity import Validity

if TYPE_CHECKING:
    import xarray as xr


class Regime(IntEnum):
    """Regime of a steady window (the ``regime`` variable's ``flag_values``).

    Rule (:func:`pipeline.model.outcomes.summarize`): flying = no contact in the steady window (no sample in
    contact and the integrator's exact minimum of d above k sigma); surfing = in contact in at least
    99 % of the samples (steady sliding); bouncing = otherwise.
    """

    FLYING = 0
    BOUNCING = 1
    SURFING = 2


#: Missing value of ``regime`` (a grid point not computed): declared as ``_FillValue``.
REGIME_FILL = -1


def regime_name(code: Any) -> str:
    """``"flying"``, ``"bouncing"``, ``"surfing"``, or ``"missing"`` for NaN / the fill value."""
    try:
        return Regime(int(code)).name.lower()
    except (TypeError, ValueError):  # NaN (decoded fill) or an unknown code
        return "missing"


def flag_meaning(attrs: dict[str, Any], code: Any) -> str:
    """The meaning of ``code`` in a flag variable's ``flag_values``/``flag_meanings`` (``"missing"``
    for NaN or a code it does not list)."""
    try:
        meanings = attrs["flag_meanings"].split()
        if "flag_masks" in attrs:  # bits: the meanings of those set, "none" for 0
            set_ = [m for bit, m in zip(np.atleast_1d(attrs["flag_masks"]), meanings) if int(code) & int(bit)]
            return "+".join(set_) or "none"
        values = [int(v) for v in np.atleast_1d(attrs["flag_values"])]
        return meanings[values.index(int(code))]
    except (KeyError, TypeError, ValueError, IndexError):
        return "missing"


def _group(*items: Variable) -> dict[str, Variable]:
    return {v.name: v for v in items}


V = Variable

#: The published sources of the variables computed from a published formula (their ``references``; the keys
#: of docs/model.md, section "References", and the section that states the formula).
_STATISTICS = Source(("Nayak71", "McCool86", "GW66"), "Asperity statistics")
_PSI_GW = Source(("GW66",), "Plasticity index")
_PSI_KE = Source(("CEB87", "KE03"), "Plasticity index")
_ASPERITY = Source(("KE02", "Johnson85"), "Single asperity")
_CONTACT = Source(("SP03", "LP04", "SEB90", "GW66", "KE02"), "ISBL interface")
_ADHESION = Source(("SP03", "LP04", "SEB90", "Derjaguin34", "Israelachvili11"), "Adhesion")
_FRICTION = Source(("BT50", "Tabor51", "KE04", "BKE07"), "Friction")
_FHM = Source(("VLP09",), "FHM and BV")
_CRITERION = Source(("VLP09",), "Contact criterion")
_AIR_BEARING = Source(("ZB00",), "Air bearing")
_BULGE = Source(("Gross62", "Burgdorfer59", "FK90"), "Bulge air bearing")
_PH_LIMIT = Source(("Gross62",), "p h = const limit")
_STATICS = Source(("HJJ00", "Filippov88"), "Statics map")
_HEATER = Source(("JB07",), "Heater power")
_FLASH = Source(("TK94", "Blok37"), "Flash temperature")

#: The elapsed simulated time [s]: its coordinate's name in memory and in the files (module docstring).
TIME = "elapsed_time"

#: Coordinates shared by the datasets.
COORDINATES = _group(
    V("protrusion", "nm", "TFC protrusion", NM, dims=("protrusion",)),
    V("roughness", "", "roughness set label", dims=("roughness",), dtype="str"),
    V("damping", "1", "damping ratio", dims=("damping",), description="modal damping ratio of the air bearing"),
    V(TIME, "s", "elapsed time", dims=(TIME,), description="elapsed simulated time"),
    V("hist_protrusion", "nm", "history protrusion", NM, dims=("hist_protrusion",), description="protrusion of the kept histories"),
    # with a scene's heater actuation only (pipeline/config/heater_power.py): the heater power of each protrusion
    V("heater_power", "mW", "heater power", MW, dims=("protrusion",),
      description="heater power that gives the protrusion (the scene's tfc.actuation_*; docs/model.md, section 'Heater power')", references=_HEATER),
    V("direction", "", "stepping pass",
      dims=("direction",), dtype="str", description="pass of a heater-stepping chain (up: increasing protrusion, down: decreasing)"),
    # the statistics each roughness set's interface model used (the given keys, or its AFM scans'), along
    # ``roughness``, so that runs combined on that dimension keep each set's own values
    # (:func:`pipeline.model.interface_tables.used_statistics`)
    V("roughness_sigma", "nm", "set rms roughness", NM, dims=("roughness",), description="combined rms roughness sigma of the roughness set"),
    V("roughness_summit_radius", "um", "set summit radius", UM, dims=("roughness",), description="summit radius of the roughness set", references=_STATISTICS),
    V("roughness_summit_density", "um-2", "set summit density", PER_UM2, dims=("roughness",), description="summit density of the roughness set", references=_STATISTICS),
    V("roughness_plasticity_index", "1", "set plasticity index",
      dims=("roughness",), description="plasticity index (Greenwood-Williamson form) of the roughness set", references=_PSI_GW),
)

#: Values of the whole run, one number each (0-d variables of ``summary.nc``, ``histories.nc``,
#: ``sweep.nc``, ``sweep_histories.nc`` and ``ensemble.nc``; :func:`pipeline.model.simulation.run_values`).
#: Variables, not only global attributes: ``xr.open_mfdataset(..., combine="nested", concat_dim="run")``
#: gives each run its own value, where it keeps the first file's global attributes for all.
#: In ``sweep.nc`` and ``sweep_histories.nc`` those that depend on the grid carry its dimension
#: (:data:`RUN_GRID_DIMS`); the others are one number for all the grid's models.
RUN = _group(
    V("k", "1", "contact criterion k", description="contact criterion k: contact where the separation is below k sigma (NaN: no contact law)", references=_CRITERION),
    V("k_source", "", "source of k", dtype="str", description="where k comes from (the scene, the calibration, a rule)"),
    V("k_sigma", "nm", "contact threshold k sigma", NM, references=_CRITERION),
    V("front_stiffness", "N m-1", "front pad stiffness", description="air-bearing stiffness of the front pad", references=_AIR_BEARING),
    V("rear_stiffness", "N m-1", "rear pad stiffness", description="air-bearing stiffness of the rear pad", references=_AIR_BEARING),
    V("front_damper", "N s m-1", "front pad damping", description="air-bearing damping coefficient of the front pad", references=_AIR_BEARING),
    V("rear_damper", "N s m-1", "rear pad damping", description="air-bearing damping coefficient of the rear pad", references=_AIR_BEARING),
    V("damping_ratio", "1", "damping ratio", description="modal damping ratio of the air bearing of the run's model", references=_AIR_BEARING),
    V("summit_offset", "nm", "summit mean offset y_s", NM, description="mean of summit heights minus mean of surface heights y_s", references=_STATISTICS),
    V("steady_window_start", "ms", "start of the steady window", MS),
    V("steady_window_end", "ms", "steady window end", MS, description="end of the steady window (the simulated duration)"),
    V("tfc_stiffness", "N m-1", "TFC stiffening k_t", description="stiffness k_t of the TFC bulge's stiffening"),
    V("tfc_stiffening_exponent", "1", "TFC stiffening exponent q", description="exponent q of the TFC bulge's stiffening"),
    V("friction_law_coefficient", "1", "friction law coefficient", description="friction coefficient of the coefficient friction law"),
)

#: The run values (:data:`RUN`) that depend on the sweep's grid, and the dimension they take in ``sweep.nc``
#: (:func:`pipeline.model.simulation.grid_run_values`): the contact threshold and the summit offset are
#: the roughness set's, the pad dampers (and the modal damping ratio itself) the damping ratio's.
RUN_GRID_DIMS: dict[str, str] = {"k_sigma": "roughness", "summit_offset": "roughness",
                                 "front_damper": "damping", "rear_damper": "damping", "damping_ratio": "damping"}

#: The run values of :data:`RUN_GRID_DIMS` that are their dimension's coordinate: along the grid they are not a
#: variable of their own (``sweep.nc``'s coordinate ``damping`` holds the modal damping ratio of each model;
#: :func:`pipeline.model.simulation.grid_run_values` checks that they agree); a single run (``summary.nc``) keeps
#: them as 0-d variables.
RUN_GRID_COORDS: frozenset[str] = frozenset({"damping_ratio"})

#: Steady-window scalars of one scene (:func:`pipeline.model.outcomes.summarize`; ``summary.nc``, ``sweep.nc``).
SCALARS = _group(
    V("fhm_bv", "%", "FHM/BV", description="flying-height modulation (flying) / bouncing vibration (contact), peak-to-peak over FH0", references=_FHM),
    V("clearance", "nm", "mean clearance", NM, description="mean clearance d - k sigma over the steady window", references=_CRITERION),
    V("min_clearance", "nm", "minimum clearance", NM, description="minimum clearance over the steady window", references=_CRITERION),
    V("interference", "nm", "mean interference", NM, effect="contact", description="mean interference -(d - k sigma) while in contact", references=_CRITERION),
    V("contact_force", "mN", "mean contact force", MN, effect="contact", description="time-mean asperity contact force", references=_CONTACT),
    V("friction_force", "mN", "mean friction force", MN, effect="friction", description="time-mean friction force", references=_FRICTION),
    V("adhesion_force", "mN", "mean adhesion force", MN, effect="adhesion", description="time-mean adhesion force (attractive)", references=_ADHESION),
    V("net_force", "mN", "mean interface force", MN, description="time-mean vertical interface force on the slider (contact + damping - adhesion)", references=_CONTACT),
    V("friction_coefficient", "1", "friction coefficient", effect="friction", description="friction coefficient: mean friction / mean contact force", references=_FRICTION),
    V("mean_pressure", "MPa", "mean contact pressure", MPA, effect="contact", description="mean contact pressure over the real area while in contact", references=_CONTACT),
    V("shear_stress", "MPa", "mean shear stress", MPA, effect="friction", description="mean shear stress over the real area while in contact", references=_FRICTION),
    V("real_area", "um2", "mean real contact area", UM2, effect="contact", description="mean real contact area while in contact", references=_CONTACT),
    V("nominal_area", "um2", "nominal contact area", UM2, description="nominal contact area of the TFC bulge"),
    V("protrusion_radius", "um", "bulge effective radius", UM, description="effective radius of the bulge in the sliding direction"),
    V("contact_fraction", "1", "time fraction in contact", effect="contact", description="fraction of the steady window spent in contact", references=_CRITERION),
    V("thermal_protrusion", "nm", "mean heat protrusion", NM, effect="friction",
      description="time-mean protrusion delta_f of the frictional heat, d(delta_f)/dt = (eta_f Q V - delta_f) / tau_f "
                  "(only with tfc.frictional_heating_nm_per_mw > 0)"),
    V("friction_power", "mW", "mean friction power", 1e-3, effect="friction",
      description="time-mean friction power Q V (only with tfc.frictional_heating_nm_per_mw > 0)", references=_FRICTION),
    V("flash_temperature", "K", "flash temperature rise", effect="friction",
      description="maximum surface temperature rise of the mean friction power over the mean real area as one circular "
                  "spot, Blok's partition (an upper bound of the micro-contacts'; only with "
                  "tfc.frictional_heating_nm_per_mw > 0)", references=_FLASH),
    V("contact_switches_per_ms", "ms-1", "contact switch rate", KHZ, effect="contact", description="transitions of the contact criterion d < k sigma per unit time over the "
      "steady window (counted by the integrator)"),
    V("regime", "1", "regime", effect="contact", dtype="int8",
      flag_values=tuple(int(r) for r in Regime), flag_meanings=" ".join(r.name.lower() for r in Regime),
      fill_value=REGIME_FILL,
      extra=(("rule", "flying: no contact in the steady window; surfing: in contact >= 99 % of it; "
                      "bouncing: otherwise"),), description="regime of the steady window", references=_FHM),
    V("validity", "1", "validity flags", dtype="int8",
      flag_masks=tuple(int(v) for v in Validity), flag_meanings=" ".join(v.name.lower() for v in Validity),
      fill_value=REGIME_FILL,
      extra=(("rule", "bearing_range: a pad moved by more than FH0; below_tables: separation below the "
                      "interface tables; force_beyond_load: contact or adhesion force above 100 (k_f + k_r) FH0 "
                      "(pipeline/validity.py)"),), description="steady window outside the model's validity (bits; 0: valid)"),
)

#: Time histories of one scene (:func:`pipeline.model.outcomes.histories`; ``histories.nc``,
#: ``sweep_histories.nc``, and ``h_<name>`` in sweep part files).
HISTORIES = _group(
    V("separation", "nm", "separation d", NM, dims=(TIME,), description="separation d of the TFC surface from the mean of summit heights"),
    V("clearance", "nm", "clearance d - k sigma", NM, dims=(TIME,), references=_CRITERION),
    V("disk_displacement", "nm", "disk displacement", NM, dims=(TIME,), description="disk displacement (DMW) under the TFC point"),
    V("contact_force", "mN", "asperity contact force", MN, dims=(TIME,), effect="contact", references=_CONTACT),
    V("contact_damping_force", "mN", "contact damping force", MN, dims=(TIME,), effect="contact"),
    V("friction_force", "mN", "friction force", MN, dims=(TIME,), effect="friction", references=_FRICTION),
    V("adhesion_force", "mN", "adhesion force (attractive)", MN, dims=(TIME,), effect="adhesion", references=_ADHESION),
    V("net_force", "mN", "interface force", MN,
      dims=(TIME,), description="vertical interface force on the slider (contact + damping - adhesion)", references=_CONTACT),
    V("friction_coefficient", "1", "friction coefficient", dims=(TIME,), effect="friction", description="friction coefficient F_friction / F_contact", references=_FRICTION),
    V("mean_pressure", "MPa", "mean contact pressure", MPA, dims=(TIME,), effect="contact", description="mean contact pressure over the real area", references=_CONTACT),
    V("shear_stress", "MPa", "shear stress", MPA, dims=(TIME,), effect="friction", description="shear stress over the real area", references=_FRICTION),
    V("real_area", "um2", "real contact area", UM2, dims=(TIME,), effect="contact", references=_CONTACT),
    V("in_contact", "1", "in contact", dims=(TIME,),
      effect="contact", dtype="int8", flag_values=(0, 1), flag_meanings="not_in_contact in_contact",
      fill_value=-1, description="contact criterion d < k sigma satisfied (1) or not (0)", references=_CRITERION),
    V("z", "nm", "slider displacement z", NM, dims=(TIME,), description="vertical displacement of the centre of gravity (up positive)"),
    V("pitch", "urad", "pitch angle", URAD, dims=(TIME,), description="pitch angle (leading edge up positive)"),  # 0 when locked
    V("steps", "1", "accepted integrator steps", dtype="int64"),
    V("rejected_steps", "1", "rejected integrator steps", dtype="int64"),
    V("contact_switches", "1", "contact switches", dtype="int64", description="contact on/off events located"),
)

#: ``roughness.nc`` (:mod:`pipeline.stages.roughness`): on (surface, route) unless said otherwise.
_SR = ("surface", "route")
ROUGHNESS = _group(
    V("surface", "", "surface",
      dims=("surface",), dtype="str", description="surface (input file stem, 'explicit', or 'combined' = all surfaces combined)"),
    V("route", "", "statistics route", dims=("route",), dtype="str", description="route to the asperity statistics ('spectral': McCool/Nayak from profile moments, "
                   "'summits': direct summit count)"),
    V("sigma", "nm", "rms roughness", NM, dims=_SR, description="rms roughness of the (detrended) surface heights"),
    V("sigma_s", "nm", "summit height std", NM, dims=_SR, description="standard deviation of summit heights", references=_STATISTICS),
    V("y_s", "nm", "summit mean offset y_s", NM, dims=_SR, description="mean of summit heights minus mean of surface heights", references=_STATISTICS),
    V("summit_radius", "um", "summit radius", UM, dims=_SR, description="mean summit radius of curvature", references=_STATISTICS),
    V("summit_density", "um-2", "summit density", PER_UM2, dims=_SR, description="summit density (summits per nominal area)", references=_STATISTICS),
    V("bandwidth_alpha", "1", "Nayak bandwidth parameter", dims=_SR, references=_STATISTICS),
    V("plasticity_index", "1", "plasticity index (GW)", dims=_SR, description="plasticity index, Greenwood-Williamson form", references=_PSI_GW),
    V("plasticity_index_ke", "1", "plasticity index (CEB/KE)", dims=_SR, description="plasticity index, CEB/Kogut-Etsion form", references=_PSI_KE),
    V("pixel_size", "nm", "pixel size", NM,
      dims=("surface",), description="lateral sampling interval of the scan (geometric mean of x and y)"),
    V("m0", "nm2", "spectral moment m0", 1e-18, dims=("surface",), description="profile spectral moment m0 (height variance)", references=_STATISTICS),
    V("m2", "1", "spectral moment m2", dims=("surface",), description="profile spectral moment m2 (slope variance, mean of x and y profiles)", references=_STATISTICS),
    V("m4", "nm-2", "spectral moment m4", 1e18,
      dims=("surface",), description="profile spectral moment m4 (curvature variance, mean of x and y profiles)", references=_STATISTICS),
    V("summit_count", "1", "summit count", dims=("surface",), description="number of summits counted (summit route)", references=_STATISTICS),
)

#: ``dmw.nc`` (:mod:`pipeline.stages.dmw`).
DMW = _group(
    V("frequency", "Hz", "frequency", dims=("frequency",)),
    V("displacement", "nm", "DMW displacement", NM,
      dims=(TIME,), description="disk dynamic microwaviness (vertical displacement under the slider)"),
    V("psd", "nm2 Hz-1", "displacement PSD", 1e-18, dims=("frequency",), description="one-sided power spectral density of the displacement"),
    V("rms", "nm", "rms of the displacement", NM),
    V("band_low", "Hz", "lower edge of the DMW band"),
    V("band_high", "Hz", "upper edge of the DMW band"),
    V("sample_rate", "Hz", "sampling rate", description="sampling rate of the displacement"),
    V("disk_speed", "m s-1", "disk speed", description="disk surface speed under the slider"),
)

#: ``interface.nc`` (:mod:`pipeline.stages.interface`): tables versus separation and their inputs.
_S = ("separation",)
INTERFACE = _group(
    V("separation", "nm", "separation d", NM, dims=_S, extra=(("axis", "Z"), ("positive", "up")),
      description="separation of the TFC surface from the mean of summit heights (the height of the TFC flat "
                  "above the mean plane of summit heights: the vertical axis of the tables)"),
    V("sigma", "nm", "combined rms roughness", NM),
    V("sigma_s", "nm", "summit height std", NM, description="standard deviation of summit heights", references=_STATISTICS),
    V("y_s", "nm", "summit mean offset y_s", NM, description="mean of summit heights above the mean of surface heights", references=_STATISTICS),
    V("summit_radius", "um", "summit radius", UM, references=_STATISTICS),
    V("summit_density", "um-2", "summit density", PER_UM2, references=_STATISTICS),
    V("bandwidth_alpha", "1", "Nayak bandwidth parameter", references=_STATISTICS),
    V("composite_modulus", "GPa", "composite modulus E'", GPA),
    V("hardness", "GPa", "hardness of the softer body", GPA, references=_PSI_GW),
    V("critical_interference", "nm", "critical interference w_c", NM, description="Kogut-Etsion critical interference w_c", references=_ASPERITY),
    V("shear_strength", "MPa", "shear strength tau_y", MPA, description="shear strength tau_y = H/(2.8 sqrt 3)", references=_FRICTION),
    V("plasticity_index_gw", "1", "plasticity index (GW)", description="plasticity index, Greenwood-Williamson form", references=_PSI_GW),
    V("plasticity_index_ke", "1", "plasticity index (CEB/KE)", description="plasticity index, CEB/Kogut-Etsion form", references=_PSI_KE),
    V("lubricant_thickness", "nm", "lubricant thickness", NM),
    V("work_of_adhesion", "J m-2", "work of adhesion", description="work of adhesion (of the menisci around contacts with two populations)"),
    V("bridge_work_of_adhesion", "J m-2", "bridge work of adhesion", description="work of adhesion of the bridges before solid contact"),
    V("solid_work_of_adhesion", "J m-2", "solid work of adhesion", description="work of adhesion at solid contact through the bonded lubricant layer (docs/model.md, section 'Adhesion rising with penetration')"),
    V("intermolecular_distance", "nm", "intermolecular distance", NM),
    V("contact_pressure", "MPa", "contact pressure", MPA, dims=_S, effect="contact", description="contact pressure per nominal area", references=_CONTACT),
    V("elastic_fraction", "1", "elastic summit fraction", dims=_S, effect="contact", description="fraction of summits in elastic contact", references=_CONTACT),
    V("plastic_fraction", "1", "plastic summit fraction", dims=_S, effect="contact", description="fraction of summits in fully plastic contact", references=_CONTACT),
    V("friction_stress", "MPa", "friction stress", MPA, dims=_S, effect="friction", description="friction stress per nominal area", references=_FRICTION),
    V("real_area_fraction", "1", "real area fraction", dims=_S, effect="contact", description="real contact area per nominal area", references=_CONTACT),
    V("adhesion_pressure", "MPa", "adhesion pressure", MPA, dims=_S,
      effect="adhesion", description="adhesion pressure per nominal area (positive: attractive)", references=_ADHESION),
    V("adhesion_pressure_bridges", "MPa", "bridge adhesion pressure", MPA, dims=_S, effect="adhesion", description="adhesion pressure of the bridges before solid contact per nominal area "
      "(Lennard-Jones and menisci of non-touching summits; positive: attractive)", references=_ADHESION),
    V("adhesion_pressure_menisci", "MPa", "meniscus adhesion pressure", MPA, dims=_S, effect="adhesion", description="adhesion pressure of the menisci around solid contacts per nominal area "
      "(positive: attractive)", references=_ADHESION),
    V("wetted_area_fraction", "1", "wetted area fraction", dims=_S, effect="friction", description="summit surface inside the lubricant film and outside solid contact per "
      "nominal area"),
    V("contact_fraction", "1", "summit fraction in contact", dims=_S, effect="contact", description="fraction of summits in contact", references=_CONTACT),
    # interface.model = "deterministic": contact_pressure, real_area_fraction and friction_stress carry the
    # leading dimension `model` (statistical, deterministic), plus the solved series of the FFT
    # boundary-element solution (pipeline.model.deterministic_tables)
    V("model", "", "interface model", dims=("model",), dtype="str", description="interface model of the tables"),
    V("solved_separation", "nm", "solved separation", NM, dims=("solved",), effect="contact", description="separation from the mean of summit heights of a deterministic solve "
                                 "(mean interfacial separation minus y_s)"),
    V("solved_contact_pressure", "MPa", "solved contact pressure", MPA,
      dims=("solved",), effect="contact", description="contact pressure per nominal area of a deterministic solve"),
    V("solved_real_area_fraction", "1", "solved real area fraction",
      dims=("solved",), effect="contact", description="real contact area per nominal area of a deterministic solve"),
    V("solved_iterations", "1", "solver iterations",
      dims=("solved",), effect="contact", dtype="int32", description="constrained conjugate-gradient iterations of a deterministic solve"),
    V("contact_grid_points", "1", "solved grid points", effect="contact", description="grid points of the height map solved deterministically"),
    V("contact_pixel_size", "nm", "solved pixel size", NM, effect="contact", description="pixel size of the height map solved deterministically"),
    V("contact_rms_slope", "1", "solved rms slope", effect="contact", description="rms gradient of the height map solved deterministically"),
)

#: ``calibration.nc`` (:mod:`pipeline.stages.calibrate`).
CALIBRATION = _group(
    V("k", "1", "contact criterion constant", dims=("k",), references=_CRITERION),
    V("touchdown", "nm", "touchdown protrusion", NM, dims=("k",), description="first protrusion of the sweep grid in contact", references=_CRITERION),
    V("k_calibrated", "1", "calibrated k", description="calibrated contact criterion constant k (NaN: none admissible)", references=_CRITERION),
    V("k_low", "1", "k interval low", description="lower (exclusive) end of the admissible k interval", references=_CRITERION),
    V("k_high", "1", "k interval high", description="upper (inclusive) end of the admissible k interval", references=_CRITERION),
    V("k_onset", "1", "onset k", description="smallest k giving contact at the touchdown protrusion", references=_CRITERION),
    V("k_previous", "1", "previous-step k", description="smallest k giving contact at the previous step", references=_CRITERION),
    V("contact_probability_one_sided", "1", "contact probability, 1-sided", description="P(z > k sigma) of the calibrated k", references=_CRITERION),
    V("contact_probability_two_sided", "1", "contact probability, 2-sided", description="P(|z| > k sigma) of the calibrated k", references=_CRITERION),
    V("sigma", "nm", "criterion rms roughness", NM, description="rms roughness of the criterion d < k sigma"),
    # the exact method (touchdown.method = "exact"): one flying run per protrusion of the grid
    V("protrusion", "nm", "TFC protrusion", NM, dims=("protrusion",), description="TFC protrusion of the sweep grid"),
    V("k_threshold", "1", "threshold k", dims=("protrusion",), description="smallest k giving contact at the protrusion (-inf: contact for every k, adhesive "
                          "snap-in)", references=_CRITERION),
    V("min_separation", "nm", "minimum separation", NM, dims=("protrusion",), description="minimum separation over the steady window with the contact law off (-inf: "
                              "separation collapsed)"),
)

#: ``accuracy.nc`` (:mod:`pipeline.stages.accuracy`): errors and costs per operating point, knob and level.
_PKL = ("point", "knob", "level")
ACCURACY = _group(
    V("point", "", "operating point", dims=("point",), dtype="str"),
    V("protrusion", "nm", "TFC protrusion", NM, dims=("point",), description="TFC protrusion of the operating point"),
    V("knob", "", "accuracy knob",
      dims=("knob",), dtype="str", description="accuracy knob (scene key: its suffix is the unit, sample_rate_mhz is in [dmw])"),
    V("level", "1", "setting level", dims=("level",), dtype="int32", description="setting index within a knob, 0 = tightest"),
    V("output", "", "headline output", dims=("output",), dtype="str"),
    V("configuration", "", "configuration",
      dims=("configuration",), dtype="str", description="chosen: all chosen defaults together; scene: the scene's own settings"),
    # the knobs differ in unit: the unit of each row is in setting_units (no common units attribute)
    V("setting", "", "knob setting", dims=("knob", "level"), description="value of the knob at this level (unit: the knob's setting_units; NaN pads knobs with "
                     "fewer settings)"),
    V("setting_units", "", "setting units", dims=("knob",), dtype="str", description="unit of the knob's settings"),
    V("knob_description", "", "knob description", dims=("knob",), dtype="str", description="what the knob sets"),
    V("error", "1", "relative error", dims=_PKL + ("output",), description="relative error of the headline output against the reference"),
    V("max_error", "1", "largest relative error", dims=_PKL, description="largest relative error over the headline outputs"),
    V("wall_time", "s", "wall time", dims=_PKL, description="wall time: setup_time + simulation_time"),
    V("simulation_time", "s", "simulation time", dims=_PKL, description="median wall time of integration + steady-window statistics"),
    V("setup_time", "s", "setup time",
      dims=("knob", "level"), description="wall time of building what the knob changes (tables, DMW record, model)"),
    V("steps", "1", "accepted steps", dims=_PKL, dtype="int32", description="accepted integrator steps"),
    V("rejected_steps", "1", "rejected steps", dims=_PKL, dtype="int32", description="rejected integrator steps"),
    V("contact_switches", "1", "contact switches", dims=_PKL, dtype="int32", description="contact mode switches"),
    V("failed", "1", "failed", dims=_PKL, dtype="int8", flag_values=(0, 1),
      flag_meanings="ok failed", description="integration failed (1) or not (0)"),
    V("is_reference", "1", "is reference", dims=("knob", "level"), dtype="int8", description="this run is the reference configuration (1)"),
    V("passes", "1", "passes",
      dims=("knob", "level"), dtype="int8", description="every headline error below the tolerance at every point (1) or not (0)"),
    V("chosen_level", "1", "chosen level", dims=("knob",), dtype="int32", description="level of the chosen default (-1: no setting passes)"),
    V("chosen_setting", "", "chosen setting", dims=("knob",), description="chosen default of the knob (unit: setting_units)"),
    V("combined_error", "1", "combined error",
      dims=("configuration", "point", "output"), description="relative error of all settings of a configuration together"),
    V("combined_max_error", "1", "combined largest error",
      dims=("configuration", "point"), description="largest relative error over the headline outputs, configuration"),
    V("combined_wall_time", "s", "combined wall time",
      dims=("configuration", "point"), description="wall time of the configuration: tables, record, model and simulation"),
    V("combined_simulation_time", "s", "combined simulation time", dims=("configuration", "point"), description="simulation time of the configuration"),
    # the headline outputs themselves (and their reference values) keep the units of SCALARS
    *(V(n, v.units, v.long_name, v.si_unit, dims=_PKL, description=v.sentence + " (at this setting)", references=v.references)
      for n, v in SCALARS.items()),
    *(V("reference_" + n, v.units, v.long_name + ", reference", v.si_unit, dims=("point",),
        description=v.sentence + " (reference)", references=v.references) for n, v in SCALARS.items()),
)

#: Scalars whose ensemble mean and spread ``sweep.nc`` carries with ``[sweep] realisations`` > 1.
ENSEMBLE_OF = ("fhm_bv", "clearance", "min_clearance", "interference", "contact_force", "friction_force",
               "net_force", "mean_pressure", "contact_fraction", "contact_switches_per_ms", "thermal_protrusion",
               "friction_power", "flash_temperature")

#: ``sweep.nc`` of a DMW ensemble (:func:`pipeline.analyses.ensemble_rules.statistics`).
ENSEMBLE = _group(
    V("realisation", "1", "DMW realisation", dims=("realisation",), dtype="int32", description="DMW realisation (0: the scene's own record)"),
    V("dmw_seed", "1", "DMW seed", dims=("realisation",),
      dtype="float64", description="seed of the synthetic DMW record of the realisation"),  # (32-bit seeds, exact in a double; CF-1.8 allows no int64 or unsigned int)
    *(V(n + "_mean", SCALARS[n].units, SCALARS[n].long_name + ", ensemble mean", SCALARS[n].si_unit,
        effect=SCALARS[n].effect, description="ensemble mean of " + SCALARS[n].sentence, references=SCALARS[n].references)
      for n in ENSEMBLE_OF),
    *(V(n + "_std", SCALARS[n].units, SCALARS[n].long_name + ", ensemble std", SCALARS[n].si_unit,
        effect=SCALARS[n].effect, description="ensemble standard deviation (ddof 1) of " + SCALARS[n].sentence,
        references=SCALARS[n].references)
      for n in ENSEMBLE_OF),
    V("touchdown_probability", "1", "touchdown probability",
      effect="contact", description="fraction of DMW realisations in contact in the steady window", references=_CRITERION),
)

#: ``bulge.nc`` (:mod:`pipeline.model.bulge_table`): the bulge's air-bearing lift on protrusion x apex gap.
_DG = ("protrusion", "apex_gap")
BULGE = _group(
    V("protrusion", "nm", "TFC protrusion", NM, dims=("protrusion",)),
    V("apex_gap", "nm", "apex gap", NM,
      dims=("apex_gap",), description="gap between the bulge apex and the mean of the disk surface heights"),
    V("bulge_lift", "mN", "bulge lift", MN, dims=_DG, description="extra air-bearing lift of the TFC bulge at the TFC point (up positive)", references=_BULGE),
    V("bulge_stiffness", "N m-1", "bulge lift stiffness",
      dims=_DG, description="stiffness of the bulge lift, minus its derivative with respect to the apex gap", references=_BULGE),
    V("bulge_lift_ph_limit", "mN", "bulge lift, p h = const", MN, dims=_DG, description="bulge lift in the high-bearing-number limit p h = const", references=_PH_LIMIT),
    V("bearing_number", "1", "bearing number", dims=_DG, description="bearing number 6 mu U a / (p_pad h_pad^2) of the pad gap h_pad = apex gap + "
                             "protrusion", references=_PH_LIMIT),
    V("pad_pressure", "MPa", "trailing pad pressure", MPA, description="air pressure under the trailing pad around the bulge"),
)

#: Outputs of a heater-stepping chain (``sweep.protocol = "stepping"``, :mod:`pipeline.model.simulation`;
#: docs/model.md, section "Heater stepping"), one value per chain.
STEPPING = _group(
    V("touchdown_protrusion", "nm", "touchdown protrusion", NM,
      effect="contact", description="first protrusion of the upward pass whose steady window touches", references=_CRITERION),
    V("takeoff_protrusion", "nm", "take-off protrusion",
      NM, effect="contact", description="first protrusion of the downward pass whose steady window no longer touches", references=_CRITERION),
    V("hysteresis", "nm", "touchdown hysteresis", NM, effect="contact", description="touchdown minus take-off protrusion of the heater-stepping chain", references=_CRITERION),
)

#: ``statics.nc`` (:mod:`pipeline.stages.statics`, :mod:`pipeline.model.statics`): every static state of the slider
#: versus protrusion (docs/model.md, section "Statics map").
_PS = ("protrusion", "state")
STATICS = _group(
    V("protrusion", "nm", "TFC protrusion", NM, dims=("protrusion",)),
    V("state", "1", "static state", dims=("state",),
      dtype="int32", description="index of a static state at one protrusion, from the highest clearance down"),
    V("mode", "1", "stiffness mode", dims=("mode",), dtype="int32", description="index of an eigenvalue of the static stiffness, ascending"),
    V("clearance", "nm", "static clearance", NM, dims=_PS, description="static clearance d - k sigma of the TFC point in the state", references=_CRITERION),
    V("z", "nm", "static displacement z", NM, dims=_PS, description="vertical displacement of the centre of gravity in the state (up positive)"),
    V("pitch", "urad", "static pitch", URAD, dims=_PS, description="pitch angle in the state (leading edge up positive)"),
    V("state_type", "1", "state type", dims=_PS, dtype="int8", flag_values=(0, 1, 2),
      flag_meanings="flying contact criterion", fill_value=-1, description="where the state lies: above the contact criterion, below it, or on it (held there by "
                         "the jump of the switched contact law)", references=_STATICS),
    V("stable", "1", "stable", dims=_PS, dtype="int8", flag_values=(0, 1),
      flag_meanings="unstable stable", fill_value=-1, description="whether the state is statically stable", references=_STATICS),
    V("barrier", "J", "energy barrier", dims=_PS, description="energy barrier out of a stable state: the rise of the static potential along the relaxed path "
                      "to the lower neighbouring unstable state", references=_STATICS),
    V("potential", "J", "static potential", dims=_PS, description="static potential of the state along the relaxed path, from the deepest state", references=_STATICS),
    V("path_stiffness", "N m-1", "relaxed-path stiffness", dims=_PS, description="stiffness of the state at the TFC point with the pitch relaxed", references=_STATICS),
    V("stiffness_eigenvalue", "N m-1", "stiffness eigenvalue", dims=(*_PS, "mode"), description="eigenvalue (real part) of the static stiffness in the coordinates "
                                       "(z, l_c theta)", references=_STATICS),
    V("state_count", "1", "static states", dims=("protrusion",), dtype="int32", description="number of static states at the protrusion"),
    V("stable_count", "1", "stable states", dims=("protrusion",), dtype="int32", description="number of stable static states at the protrusion"),
    V("dmw_energy", "J", "DMW energy scale", description="DMW energy scale 0.5 k_b sigma_w^2: the air bearing's energy at the TFC point displaced "
                         "by one DMW rms"),
    V("dmw_kinetic_energy", "J", "DMW kinetic energy scale", description="DMW kinetic energy scale 0.5 m_b sigma_v^2: the TFC point's effective mass at "
                                 "the DMW's rms rate"),
    V("bearing_stiffness_tfc", "N m-1", "bearing stiffness at TFC", description="linear air-bearing stiffness at the TFC point", references=_AIR_BEARING),
    V("effective_mass_tfc", "kg", "effective mass at TFC", description="effective mass of the slider at the TFC point"),
)

#: A sweep part file's stacked variables (:func:`pipeline.model.sweep_parts.pack_part`): ``stack__<dims>`` holds the
#: part's variables of dimensions ``<dims>`` along ``stack__<dims>_variable`` (their names), with their units
#: in ``stack__<dims>_units``; :func:`declared` reads ``stack__...`` names as these three.
PART_STACK = "stack"
PART_STACKS = _group(
    V(PART_STACK, "", "part variables",
      description="the part's variables of the dimensions after the first, stacked along the first (float64; "
                  "each variable's own dtype, attributes and missing value in the global attribute part_layout)"),
    V(PART_STACK + "_variable", "", "names of a stack's rows", dtype="str"),
    V(PART_STACK + "_units", "", "units of a stack's rows", dtype="str"),
)


def is_part_stack(name: str) -> bool:
    """Whether ``name`` is a stacked variable of a sweep part file (``stack``, ``stack__protrusion``, ...)."""
    return name == PART_STACK or name.startswith(PART_STACK + "__")


#: Groups by name.
GROUPS: dict[str, dict[str, Variable]] = {
    "coordinates": COORDINATES, "scalars": SCALARS, "histories": HISTORIES, "roughness": ROUGHNESS,
    "dmw": DMW, "interface": INTERFACE, "calibration": CALIBRATION, "accuracy": ACCURACY,
    "ensemble": ENSEMBLE, "bulge": BULGE, "stepping": STEPPING, "run": RUN, "statics": STATICS,
}

#: The groups each dataset file (by stem) may hold, first match wins.
DATASETS: dict[str, tuple[str, ...]] = {
    "roughness": ("roughness",),
    "dmw": ("coordinates", "dmw"),
    "interface": ("interface",),
    "calibration": ("calibration",),
    "summary": ("coordinates", "scalars", "run"),
    "histories": ("coordinates", "histories", "run"),
    "sweep": ("coordinates", "scalars", "ensemble", "stepping", "run"),
    "sweep_histories": ("coordinates", "histories", "run"),
    "sweep-part": ("coordinates", "scalars", "histories", "stepping"),
    "accuracy": ("accuracy",),
    "bulge": ("bulge",),
    "statics": ("statics", "coordinates"),
}


def lookup(name: str, groups: Iterable[str] = ("coordinates", "scalars", "histories")) -> Variable:
    """The declaration of ``name`` in the first of ``groups`` that has it.

    Raises
    ------
    KeyError
        When no group declares it.
    """
    groups = tuple(groups)
    for g in groups:
        if name in GROUPS[g]:
            return GROUPS[g][name]
    raise KeyError(f"variable {name!r} is not declared in pipeline/variables.py groups {list(groups)}")


def declared(dataset: str, name: str) -> Variable:
    """The declaration of variable ``name`` of the dataset file ``<dataset>.nc``.

    Sweep part files prefix history variables with ``h_``; their stacks (:data:`PART_STACKS`) are named
    ``stack__<dims>`` (``stack`` for 0-d variables).
    """
    groups = DATASETS[dataset]
    if dataset == "sweep-part" and name.startswith("h_"):
        return lookup(name[2:], ("histories",))
    if dataset == "sweep-part" and is_part_stack(name.removesuffix("_variable").removesuffix("_units")):
        suffix = next((s for s in ("_variable", "_units") if name.endswith(s)), "")
        return PART_STACKS[PART_STACK + suffix]
    return lookup(name, groups)


def scalar(name: str, values_si: Any, dims: Iterable[str]) -> xr.Variable:
    """A steady-window scalar from SI values (:data:`SCALARS`)."""
    return SCALARS[name].from_si(values_si, dims)


def history(name: str, values_si: Any, dims: Iterable[str]) -> xr.Variable:
    """A time history from SI values (:data:`HISTORIES`)."""
    return HISTORIES[name].from_si(values_si, dims)


def coordinate(name: str, values: Any, dim: str | None = None) -> xr.Variable:
    """A coordinate from values in dataset units (:data:`COORDINATES`)."""
    return COORDINATES[name].data(values, (dim or name,))


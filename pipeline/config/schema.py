"""The scene schema: every section's keys with their kind, default, check and one line of documentation.

A scene key carries its unit in its name (``flying_height_nm``), so a key with the right quantity in
another unit (``flying_height_um``) is reported as a unit error rather than silently misread
(:func:`strip_unit`, :data:`UNIT_SUFFIXES`). Every key has a documented default (the paper scene's value),
so a scene only states what it changes. Beside :data:`SCHEMA`: the effects a scene may ask for, the
sweep's protocols, the free parameters' bounds of ``hdi identify`` and the ``[identify]`` keys generated
from the paper's targets. :func:`describe_keys` is ``hdi --help-keys``. Checking a scene against the
schema is :mod:`pipeline.config.validation`; reading a file is :mod:`pipeline.config.loading`; the
generated table of the model variants the schema's registries choose is :mod:`pipeline.config.variants_table`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Callable

from ..physics import paper
from ..physics.air_bearing import REAR_LAWS, STIFFNESS_ROOTS
from ..physics.tfc_laws import TFC_STIFFENING
from ..physics.bulge_bearing import BULGE_LAWS, PROFILES
from ..physics.reynolds import SLIP_MODELS
from ..physics.equilibrium import STARTS
from ..physics.fhm import FHM_MEASURES
from ..physics.friction import FRICTION_LAWS, FRICTION_SWITCHING
from ..physics.geometry import AREA_MODELS, FRICTION_ARMS
from ..physics.variants import Registry
from ..units import SUFFIX_FACTORS
from .limits import MAX_BOOTSTRAP, MAX_WORK_OF_ADHESION


#: The sweep's protocols (``sweep.protocol``; :func:`pipeline.model.simulation.simulate`, docs/model.md,
#: section "Heater stepping").
PROTOCOLS = ("independent", "stepping")

#: Effects a scene may ask for (docs/cli.md, \"Scenes\").
EFFECTS = ("air_bearing", "pitch", "dmw", "adhesion", "contact", "friction")

#: Unit suffixes that may end a key name (the units table); used to tell "wrong unit" from "unknown key".
UNIT_SUFFIXES = tuple(SUFFIX_FACTORS)


class SceneError(ValueError):
    """A scene file (or an override) is invalid. The message names file, key and expectation."""


@dataclass(frozen=True)
class Key:
    """Schema of one scene key.

    Parameters
    ----------
    kind
        ``"float"``, ``"int"``, ``"str"``, ``"bool"``, ``"floats"`` (list of numbers),
        ``"strs"`` (list of strings), ``"range"`` (table ``{start, stop, step}``),
        ``"float_or_str"`` or ``"tables"`` (list of tables; validated by the stage using it).
    default
        Value when absent (``None``: optional, no default).
    check
        ``(predicate, expectation)``; the expectation text goes into the error message.
    length
        Required list length for ``floats``.
    path
        The value names a file that must exist (relative paths are taken from the scene's folder; in a
        ``--set`` override, from the working directory).
    choices
        The admissible values; a model variant's registry (:class:`pipeline.physics.variants.Registry`)
        is read live, so a registered entry is a choice (and ``--help-keys`` shows its summary).
    doc
        One line with unit and source, shown in errors and ``hdi ... --help-keys``.
    """

    kind: str
    default: Any = None
    check: tuple[Callable[[Any], bool], str] | None = None
    length: int | None = None
    path: bool = False
    choices: tuple[str, ...] | Registry | None = None
    doc: str = ""


def _within(lo: float, hi: float, unit: str, why: str, low_open: bool = True) -> tuple[Callable[[Any], bool], str]:
    """The check of a physical quantity: in ``(lo, hi]`` (``[lo, hi]`` with ``low_open=False``) in the key's
    ``unit``; ``why`` says what the bounds are (in the message of a value beyond them). The bounds are far
    outside any head-disk interface and far inside what the model's numbers survive: a flying height of
    1e90 nm or a density of 1e-90 kg/m^3 gave tables and statistics without a word."""
    shown = f"{'(' if low_open else '['}{lo:g}, {hi:g}] {unit}".rstrip()
    if low_open:
        return (lambda v: lo < v <= hi), f"a number in {shown} ({why})"
    return (lambda v: lo <= v <= hi), f"a number in {shown} ({why})"


#: A length of the slider [mm]: up to 100 mm (a slider is ~1 mm; a disk's diameter is 95 mm).
_slider_mm = _within(0.0, 100.0, "mm", "a slider is about 1 mm; a 3.5-inch disk is 95 mm across")
#: A length of the TFC bulge [um]: 1 nm to 10 mm.
_bulge_um = _within(1e-3, 1e4, "um", "the bulge is microns; the slider a millimetre", low_open=False)
#: A Young's modulus [GPa]: 1 MPa (a soft polymer) to 10,000 GPa (ten times diamond's 1,050 GPa).
_modulus_gpa = _within(1e-3, 1e4, "GPa", "from a soft polymer's 1 MPa to ten times diamond's", low_open=False)
_pos = (lambda v: v > 0, "a positive number")
_nonneg = (lambda v: v >= 0, "a number >= 0")
_frac = (lambda v: 0 <= v < 1, "a number in [0, 1)")
#: A work of adhesion [J/m^2]: >= 0 and at most :data:`pipeline.config.limits.MAX_WORK_OF_ADHESION`.
_adhesion = (lambda v: 0 <= v <= MAX_WORK_OF_ADHESION,
             f"a number in [0, {MAX_WORK_OF_ADHESION:g}] J/m^2 (ten times a lubricated disk's ~0.1; "
             "pipeline/config/limits.py says why)")

#: Free [recon] parameters of ``hdi identify`` and ``hdi sensitivity`` with their bounds (docs/model.md, section "Corrections"): work of
#: adhesion (7.5), DMW rms (5), modal damping, the two frequencies, contact damping. Every corner of the box
#: is a model the study can build (pipeline/analyses/feasibility.py checks it before a study starts): f1 up to
#: 140 kHz, as the paper slider's modal inversion has a real stiffness pair only for f1/f2 <= 0.697 (200/210 kHz,
#: the corner of the first bounds 60-200 kHz, has none; 140/210 = 0.667).
_FREE = [
    {"key": "lubricant.work_of_adhesion_j_m2", "low": 0.03, "high": 0.11},
    {"key": "dmw.rms_nm", "low": 0.08, "high": 0.30},
    {"key": "air_bearing.damping_ratio", "low": 0.01, "high": 0.20},
    {"key": "air_bearing.frequencies_khz[0]", "low": 60.0, "high": 140.0},
    {"key": "air_bearing.frequencies_khz[1]", "low": 210.0, "high": 500.0},
    {"key": "contact.damping_n_s_m", "low": 0.0, "high": 0.05},
]

#: Bounds of the DMW's spectral exponent ``beta`` [1] as a free parameter (docs/model.md, section "DMW as
#: free parameters"). The paper's record is "larger than expected" because its 10-kHz high-pass lets in the
#: long wavelengths: its displacement variance falls with frequency over the 10-500 kHz band, steeper than
#: equal power per decade, so beta < -1 (the upper bound). At beta = -4.5 more than 90 % of the variance lies
#: in the band's first octave (10-20 kHz: 1 - 2^(beta + 1) = 0.91): steeper spectra all look like the
#: high-pass edge and the exponent no longer shapes the record (the lower bound).
DMW_EXPONENT_BOUNDS = (-4.5, -1.0)
#: Bounds of the DMW rms [nm] as a free parameter beside the exponent: above 0 (a record), at most 2.0 nm,
#: where a Gaussian record's peak-to-peak (about 6 rms, 12 nm) passes the flying height (11 nm). A steep
#: spectrum needs a large rms for the paper's flying FHM because the slider tracks the long wavelengths:
#: 1.5-1.8 nm at beta = -4 for 12.4 % (docs/model.md, section "DMW as free parameters").
DMW_RMS_BOUNDS_NM = (0.0, 2.0)
#: The physical range of a free parameter's bounds, checked on ``identify.parameters`` when a scene is
#: loaded: key -> (lowest low, highest high, why). (``hdi sensitivity`` screens keys over any range: its
#: tests use them as dummies of known functions.)
FREE_LIMITS = {
    "dmw.exponent": (*DMW_EXPONENT_BOUNDS, "the DMW's content between the 10-kHz high-pass and 500 kHz"),
    "dmw.rms_nm": (*DMW_RMS_BOUNDS_NM, "a record whose peak-to-peak stays within the flying height"),
}

#: The checks a target's setting names (:attr:`pipeline.physics.paper.Setting.check`).
_SETTING_CHECKS = {"positive": _pos, "nonnegative": _nonneg,
                   "lo <= hi": (lambda v: v[0] <= v[1], "lo <= hi"), "lo < hi": (lambda v: v[0] < v[1], "lo < hi")}


def target_keys() -> dict[str, Key]:
    """The ``[identify]`` keys of the paper's targets, generated from their declarations
    (:data:`pipeline.physics.paper.TARGETS`): per target its value, where it is measured and its
    tolerance (:meth:`pipeline.physics.paper.Target.keys`); a key two targets share (``sliding_at_nm``)
    once."""
    keys: dict[str, Key] = {}
    for t in paper.TARGETS.values():
        for s in t.keys():
            if s.key in keys:
                continue
            pair = isinstance(s.default, tuple)
            keys[s.key] = Key("floats" if pair else "float", list(s.default) if pair else s.default,
                              _SETTING_CHECKS[s.check], length=2 if pair else None, doc=s.doc)
    return keys


def is_folder_name(name: str) -> bool:
    """Whether ``name`` names one folder below another (``results/<name>/``): letters, digits, '.', '_'
    and '-', and not ``.`` or ``..``, which would put the outputs in the results folder's parent."""
    return bool(re.fullmatch(r"[A-Za-z0-9_.-]+", name)) and name not in (".", "..")


#: The schema: section -> key -> Key. Defaults are the paper scene (docs/model.md, section "Parameters").
SCHEMA: dict[str, dict[str, Key]] = {
    "scene": {
        "name": Key("str", None, (lambda v: is_folder_name(v),
                                  "a name of letters, digits, '.', '_' or '-', not '.' or '..'"),
                    doc="scene name; outputs go to results/<name>/"),
        "effects": Key("strs", list(EFFECTS), choices=EFFECTS,
                       doc="effects to simulate; others are not evaluated at all"),
        "description": Key("str", "", doc="free text"),
        "extends": Key("str", None, doc="a base scene file (relative to this one) whose keys this one overrides "
                                        "(the base's relative file paths stay relative to the base)"),
    },
    "slider": {
        "length_mm": Key("float", 0.85, _slider_mm, doc="slider length [mm] (femto, recon)"),
        "width_mm": Key("float", 0.70, _slider_mm, doc="slider width [mm] (recon)"),
        "thickness_mm": Key("float", 0.23, _slider_mm, doc="slider thickness [mm] (recon)"),
        "density_kg_m3": Key("float", 4250.0, _within(1.0, 1e5, "kg/m^3", "from a foam to four times osmium's 22,590", low_open=False), doc="slider density [kg/m^3] (Al2O3-TiC, recon)"),
        "front_arm_mm": Key("float", 0.30, _slider_mm, doc="front air-bearing centre ahead of the CG [mm] (recon)"),
        "rear_arm_mm": Key("float", 0.40, _slider_mm, doc="rear air-bearing centre behind the CG [mm] (recon)"),
        "tfc_from_trailing_edge_um": Key("float", paper.TFC_FROM_TRAILING_EDGE_UM, _nonneg,
                                         doc="TFC bulge centre from the trailing edge [um] (paper)"),
        "friction_arm": Key("str", "cg", choices=FRICTION_ARMS,
                            doc="moment arm of the friction force about the CG [paper-deviation] (docs/model.md, "
                                "section 'Deviations', item 19)"),
    },
    "air_bearing": {
        "flying_height_nm": Key("float", paper.FLYING_HEIGHT_NM, _within(0.0, 1e4, "nm", "sliders fly at 3-50 nm; 10 um is a thousand times the paper's 11 nm"), doc="nominal flying height FH0 [nm] (paper)"),
        "frequencies_khz": Key("floats", [120.0, 300.0], (lambda v: all(0.1 <= x <= 1e4 for x in v) and v[0] < v[1],
                                                          "two increasing frequencies in [0.1, 10000] kHz (air-bearing "
                                                          "modes lie at 50-500 kHz)"), length=2,
                               doc="air-bearing natural frequencies [kHz] (recon)"),
        "damping_ratio": Key("float", 0.05, _frac, doc="modal damping ratio [1] (recon)"),
        "rear_exponent": Key("float", 2.0, _pos, doc="rear bearing nonlinearity exponent n [1] (recon)"),
        "rear_reference_gap_nm": Key("float", None, _pos,
                                     doc="rear bearing reference gap g0 [nm] (recon; default FH0)"),
        "stiffness_root": Key("str", "stiff-rear", choices=STIFFNESS_ROOTS,
                              doc="root of the modal inversion of the two frequencies (docs/model.md, section 'Air "
                                  "bearing')"),
        "rear_law": Key("str", "power", choices=REAR_LAWS,
                        doc="rear bearing law (docs/model.md, section 'Slider dynamics')"),
        "tfc_stiffening": Key("str", "none", choices=TFC_STIFFENING,
                              doc="air-bearing stiffening under the TFC bulge at the TFC gap g (docs/model.md, "
                                  "section 'Gap-power stiffening')"),
        "bulge": Key("str", "none", choices=BULGE_LAWS,
                     doc="the air bearing of the TFC bulge itself (docs/model.md, section 'Bulge air bearing')"),
        "disk_roughness_share": Key("float", 1.0, (lambda v: 0.5 <= v <= 1.0, "a share in [0.5, 1]"),
                                    doc="share of the combined roughness variance on the moving disk [1], for the "
                                        "shear flow factor of the 'rough-reynolds' bulge bearing (recon: 1, the polished "
                                        "TFC pole tip taken as smooth; 0.5 = equal roughness, no shear flow); "
                                        "docs/model.md, section 'Rough-gap bulge bearing'"),
        "lift_cap_gap_nm": Key("float", None, _nonneg,
                               doc="hypothesis H8 (off by default): the bulge lift held at its value at this apex "
                                   "gap g_s [nm] for smaller gaps; no physical basis found (docs/model.md, section "
                                   "'Lift cap (hypothesis H8)')"),
        "pad_pressure_mpa": Key("float", 1.0, (lambda v: 0.1 <= v <= 10.0, "a pressure in [0.1, 10] MPa"),
                                doc="air pressure p_pad under the trailing pad around the bulge [MPa] (recon; "
                                    "about 0.3-3 MPa for a femto trailing pad)"),
        "bulge_profile": Key("str", "ellipsoid", choices=PROFILES,
                             doc="profile of the bulge under its air bearing"),
        "bulge_slip": Key("str", "first-order", choices=SLIP_MODELS,
                          doc="rarefaction of the 'reynolds' bulge bearing (the 'rough-reynolds' law always uses "
                              "'boltzmann'); docs/model.md, section 'Slip-corrected Reynolds equation'"),
        "tfc_stiffness_n_m": Key("float", 1.0e5, _nonneg,
                                 doc="stiffness scale k_t of the TFC stiffening spring [N/m] (recon, to be identified)"),
        "tfc_stiffening_exponent": Key("float", 1.5, (lambda v: 0 <= v <= 4, "a number in [0, 4]"),
                                       doc="exponent p of the TFC stiffening law [1] (recon, docs/model.md, section 'Gap-power stiffening': ~1.5-1.75)"),
    },
    "tfc": {
        "half_length_um": Key("float", paper.TFC_HALF_LENGTH_UM, _bulge_um, doc="ellipsoid semi-axis along sliding a [um] (paper)"),
        "half_width_um": Key("float", paper.TFC_HALF_WIDTH_UM, _bulge_um, doc="ellipsoid semi-axis across b [um] (paper)"),
        "protrusion_nm": Key("float", paper.LIGHT_CONTACT_NM, _nonneg, doc="TFC protrusion delta [nm]"),
        "actuation_nm_per_mw": Key("float", None, _pos,
                                   doc="heater actuation efficiency [nm/mW]: protrusion = efficiency x heater power; "
                                       "datasets then carry heater_power [mW] beside protrusion (docs/model.md, "
                                       "section 'Heater power'); off by default"),
        "actuation_power_mw": Key("floats", None, doc="heater powers [mW] of an actuation table, strictly increasing "
                                                      "(with actuation_protrusion_nm; instead of actuation_nm_per_mw)"),
        "actuation_protrusion_nm": Key("floats", None,
                                       doc="protrusions [nm] at the actuation table's powers, strictly increasing; "
                                           "interpolated linearly, not extrapolated"),
        "frictional_heating_nm_per_mw": Key(
            "float", 0.0, _within(0.0, 0.2, "nm/mW", "the statics' band needs 0.015-0.12 nm/mW (docs/results.md, "
                                  "'Statics of the three mechanisms'); 0.2 nm/mW is ten heater efficiencies",
                                  low_open=False),
            doc="frictional-heating efficiency eta_f [nm/mW]: the contact's friction power Q V raises the TFC point "
                "by eta_f Q V at steady state, relaxing with heating_time_us (docs/model.md, section 'Frictional "
                "heating'); 0: off"),
        "heating_time_us": Key("float", 200.0, _within(10.0, 5000.0, "us", "measured TFC protrusion time constants "
                                                       "are 0.1-1 ms (docs/model.md, section 'Frictional heating')"),
                               doc="thermal time constant tau_f [us] of the frictional heat's protrusion (read "
                                   "with frictional_heating_nm_per_mw > 0)"),
    },
    "roughness": {
        "sigma_nm": Key("float", 0.52, _within(0.0, 1e3, "nm", "disk and slider roughness is 0.1-10 nm; 1 um is a hundred times the flying height"), doc="combined rms roughness sigma [nm] (recon)"),
        "summit_radius_um": Key("float", 5.0, _within(1e-4, 1e4, "um", "from an atom's 0.1 nm to 1 cm", low_open=False), doc="summit radius R [um] (recon)"),
        "summit_density_per_um2": Key("float", 13.3, _within(0.0, 1e6, "um^-2", "at most one summit per nm^2, the atomic scale"),
                                      doc="summit density eta [um^-2] (inferred: y_s = 0.69 nm, docs/model.md, section 'Separation datum')"),
        "afm": Key("strs", None, path=True, doc="AFM scans (any SurfaceTopography format); overrides the statistics"),
        "route": Key("str", "spectral", choices=("spectral", "summits"),
                     doc="which AFM route feeds the interface model"),
        "channel": Key("str", None, doc="AFM channel name (default: the height channel)"),
        "detrend": Key("str", "plane", choices=("center", "height", "plane", "curvature"),
                       doc="detrending of AFM scans (SurfaceTopography detrend_mode)"),
    },
    "materials": {
        "disk_modulus_gpa": Key("float", 150.0, _modulus_gpa, doc="disk Young's modulus [GPa] (recon)"),
        "tfc_modulus_gpa": Key("float", 200.0, _modulus_gpa, doc="TFC/slider Young's modulus [GPa] (recon)"),
        "poisson_ratio": Key("float", 0.3, (lambda v: 0 <= v < 0.5, "a number in [0, 0.5)"),
                             doc="Poisson ratio of both bodies [1] (recon)"),
        "hardness_gpa": Key("float", None, _modulus_gpa, doc="hardness of the softer body H [GPa]"),
        "plasticity_index": Key("float", paper.PLASTICITY_INDEX, _pos,
                                doc="GW plasticity index psi [1] (paper); sets H when hardness_gpa is absent"),
        "composite_modulus_gpa": Key("float", None, _modulus_gpa,
                                     doc="composite modulus E' [GPa]; overrides the one from the two moduli"),
    },
    "lubricant": {
        "thickness_nm": Key("float", paper.LUBRICANT_THICKNESS_NM, _nonneg, doc="bonded lubricant thickness t [nm] (paper)"),
        "work_of_adhesion_j_m2": Key("float", 0.106, _adhesion, doc="work of adhesion dgamma [J/m^2] (recon, CML)"),
        "intermolecular_distance_nm": Key("float", 0.3, _within(0.01, 10.0, "nm", "molecular spacings are 0.1-1 nm", low_open=False), doc="intermolecular distance eps [nm] (recon, CML)"),
        "meniscus_time_us": Key("float", 0.0, _nonneg,
                                doc="meniscus formation time tau_m [us]: the adhesion pressure relaxes towards its "
                                    "ISBL value with this time constant (docs/model.md, section 'Meniscus "
                                    "formation'); 0: at once (the ISBL value). With interface.adhesion = "
                                    "'two-population' it acts on the menisci around solid contacts only"),
        "bridge_work_of_adhesion_j_m2": Key("float", None, _adhesion,
                                            doc="work of adhesion of the bridges before solid contact [J/m^2] "
                                                "(interface.adhesion = 'two-population': Lennard-Jones of the "
                                                "non-wetted summits and menisci of the wetted non-touching ones; "
                                                "recon, bounds 0.002-0.03: van der Waals across the bonded film, "
                                                "A/(12 pi t^2) = 0.0047 for A = 1e-19 J, t = 0.75 nm; docs/model.md, "
                                                "section 'Two adhesion populations')"),
        "solid_work_of_adhesion_j_m2": Key("float", None, _adhesion,
                                           doc="work of adhesion at solid contact through the bonded layer [J/m^2]: "
                                               "a summit's work of adhesion rises linearly from "
                                               "work_of_adhesion_j_m2 at the lubricant surface to this value at "
                                               "solid contact across thickness_nm, then stays there (recon, "
                                               "bounds 0.05-0.10: twice measured carbon-overcoat surface "
                                               "energies, 25-50 mJ/m^2; docs/model.md, section 'Adhesion rising "
                                               "with penetration'); absent: off"),
        "shear_stress_mpa": Key("float", 0.0, (lambda v: 0.0 <= v <= 1000.0, "a number in [0, 1000]"),
                                doc="shear stress of the lubricant on wetted summits [MPa]: the 'lubricant shear' "
                                    "friction term beside the solid shear-strength law (recon, bounds 0-50; "
                                    "docs/model.md, section 'Lubricant friction'); 0: off"),
    },
    "interface": {
        "model": Key("str", "statistical", choices=("statistical", "deterministic"),
                     doc="interface tables the dynamics runs on: 'statistical' (GW/Kogut-Etsion summit "
                         "statistics) or 'deterministic' (FFT boundary elements on the measured roughness.afm "
                         "surface; both are then written to interface.nc)"),
        "adhesion": Key("str", "isbl", choices=("isbl", "two-population"),
                        doc="adhesion model: 'isbl' (the paper's: one work of adhesion for every summit) or "
                            "'two-population' (bridges before contact with lubricant.bridge_work_of_adhesion_j_m2, "
                            "menisci around contacts with lubricant.work_of_adhesion_j_m2; docs/model.md, section "
                            "'Two adhesion populations')"),
    },
    "contact": {
        "k": Key("float", None, doc="contact criterion d < k sigma [1]; absent: from calibration"),
        "section_depth_sigma": Key("float", 3.0, _pos, doc="nominal-area section depth s_n [sigma] (recon)"),
        "damping_n_s_m": Key("float", 0.0, _nonneg, doc="contact damping c_c [N s/m] (recon)"),
        "fallback_probability": Key("float", None, (lambda v: 0 < v < 1, "a probability in (0, 1)"),
                                    doc="when calibration finds no admissible k: use the k of this two-sided "
                                        "contact probability P(|z| > k sigma) = 2 Q(k) [1] (docs/model.md, section 'Contact criterion')"),
        "friction_law": Key("str", "shear-strength", choices=FRICTION_LAWS,
                            doc="friction law (docs/model.md, section 'Friction')"),
        "friction_coefficient": Key("float", None, _nonneg,
                                    doc="friction coefficient mu of the 'coefficient' law [1] (paper: ~1.2)"),
        "friction_switching": Key("str", "criterion", choices=FRICTION_SWITCHING,
                                  doc="how the friction is switched (docs/model.md, section 'Switched and continuous "
                                      "friction')"),
        "area_model": Key("str", "flat-section", choices=AREA_MODELS,
                          doc="how the interface stresses become forces over the bulge [paper-deviation] "
                              "(docs/model.md, section 'Deviations', item 18)"),
    },
    "dmw": {
        "source": Key("str", "synthetic", doc='"synthetic" or a measured record (CSV or NetCDF)'),
        "quantity": Key("str", "displacement", choices=("displacement", "velocity"),
                        doc="what a measured record holds"),
        "column": Key("str", None, doc="column/variable of a measured record"),
        "rms_nm": Key("float", 0.5, _within(0.0, 1e3, "nm", "DMW is 0.1-1 nm; 1 um is a hundred times the flying height", low_open=False), doc="DMW rms [nm] (recon: set for FHM ~12.5 %)"),
        "band_khz": Key("floats", list(paper.DMW_BAND_KHZ), (lambda v: 0 <= v[0] < v[1], "0 <= lo < hi"), length=2,
                        doc="DMW band [kHz] (paper)"),
        "exponent": Key("float", -2.0, doc="power-law exponent of the displacement PSD [1] (recon; as a free "
                                            "parameter within [-4.5, -1], docs/model.md, section 'DMW as free parameters')"),
        "rpm": Key("float", paper.DISK_RPM, _within(0.0, 1e5, "rpm", "disks spin at 3,600-15,000 rpm"), doc="disk speed [rpm] (paper)"),
        "radius_mm": Key("float", paper.TRACK_RADIUS_MM, _within(0.0, 1e3, "mm", "a 3.5-inch disk's tracks lie within 48 mm"), doc="track radius [mm] (paper)"),
        "seed": Key("int", 20090601, (lambda v: 0 <= v < 2**32, "an integer in [0, 2**32 - 1]"),
                    doc="seed of the synthetic record (numpy SeedSequence; 32-bit like the realisations' seeds)"),
        "sample_rate_mhz": Key("float", paper.DMW_SAMPLE_RATE_MHZ, _pos, doc="sampling rate [MS/s] (paper)"),
        "duration_ms": Key("float", None, _pos,
                           doc="record length [ms] (default: the simulated duration plus the disk's travel over the "
                               "slider, in whole periods of the band's lower edge, 2.1 ms for 2 ms; a measured record "
                               "shorter than that is used whole). Any record must hold the simulated duration plus the "
                               "front pad's lead, 0.037 ms in the paper scene, plus 3 samples (docs/my-drive.md)"),
        "sample_rate_hz": Key("float", None, _pos,
                              doc="sampling rate of a measured record [Hz] if it has no time axis (a CSV without a "
                                  "time column, a NetCDF variable on a dimension other than 'time')"),
        "unit": Key("str", None, doc="unit of a measured record's values when the record states none (a CSV "
                                     "without a header or a unit suffix, a NetCDF variable without 'units'): nm, "
                                     "um, mm, m (displacement) or nm/s, um/s, mm/s, m/s (velocity)"),
    },
    "touchdown": {
        "onset_nm": Key("float", paper.TOUCHDOWN_NM, _nonneg, doc="measured touchdown protrusion [nm] (paper)"),
        "previous_nm": Key("float", paper.PREVIOUS_STEP_NM, _nonneg, doc="previous actuation step, no contact [nm] (paper)"),
        "onset_mw": Key("float", None, _nonneg, doc="measured touchdown as a heater power [mW] (with previous_mw); "
                                                    "sets onset_nm through the scene's [tfc] actuation"),
        "previous_mw": Key("float", None, _nonneg, doc="the heater power of the previous step, no contact [mW]; "
                                                       "sets previous_nm through the scene's [tfc] actuation"),
        "k_range": Key("floats", [-3.0, 3.0], (lambda v: v[0] < v[1], "lo < hi"), length=2,
                       doc="physically meaningful k searched by the calibration [1] (contact probability "
                           "0.1 % to 99.9 %)"),
        "k_tolerance": Key("float", 1e-3, _pos, doc="bisection tolerance on k [1]"),
        "k_choice": Key("str", "middle", choices=("middle", "paper"),
                        doc="which admissible k the calibration takes: 'middle' (the largest margin to both touchdown "
                            "conditions) or 'paper' (the k of contact.fallback_probability, the paper's 32.8 %, when "
                            "admissible; else the nearest end); docs/model.md, section 'Contact criterion'"),
        "method": Key("str", "exact", choices=("exact", "bisection"),
                      doc="k* from one flying run per protrusion (exact) or by bisection on k"),
        "curve_points": Key("int", 25, (lambda v: 2 <= v <= 1000, "an integer in [2, 1000]"),
                            doc="k values of the touchdown-versus-k curve"),
    },
    "solver": {
        "rtol": Key("float", 1e-6, _pos, doc="relative error tolerance of the adaptive integrator [1]"),
        "atol_nm": Key("float", 1e-4, _pos, doc="absolute error tolerance on displacements [nm]"),
        "max_step_ns": Key("float", 500.0, _pos, doc="largest time step [ns]"),
        "stiffness_step": Key("float", 1.0, _pos,
                              doc="step cap h <= c / omega of the local interface spring [1] (stiff contact)"),
        "min_dwell_ns": Key("float", 20.0, _nonneg,
                            doc="shortest time a contact mode is held after a switch [ns] (chattering guard)"),
        "duration_ms": Key("float", 2.0, _pos, doc="simulated time [ms]"),
        "transient_ms": Key("float", 0.5, _nonneg, doc="discarded start-up transient [ms]"),
        "output_step_ns": Key("float", 250.0, _pos, doc="sampling of histories and steady-window statistics [ns]"),
        "table_step_nm": Key("float", 0.05, _pos, doc="interface-table separation step [nm]"),
        "table_min_sigma": Key("float", -8.0, (lambda v: v <= -5.0, "a number <= -5 (tables must reach deep "
                                                                   "interference)"),
                               doc="interface table starts at this separation [sigma_s]"),
        "table_max_nm": Key("float", 30.0, _pos, doc="interface table ends at this separation [nm]"),
        "contact_grid_points": Key("int", 256, (lambda v: 16 <= v <= 4096, "an integer in [16, 4096]"),
                                   doc="deterministic interface: at most this many grid points per side of the "
                                       "solved height map (larger scans are Fourier-resampled)"),
        "interpolation_order": Key("int", 3, (lambda v: v in (1, 3), "1 (linear) or 3 (cubic Hermite)"),
                                   doc="interpolation of interface tables in the dynamics"),
        "quadrature_nodes": Key("int", 24, (lambda v: 4 <= v <= 200, "an integer in [4, 200]"),
                                doc="Gauss-Legendre nodes per panel of the ISBL integrals"),
        "quadrature_panels": Key("int", 4, (lambda v: 1 <= v <= 64, "an integer in [1, 64]"),
                                 doc="panels per population range of the ISBL integrals"),
        "bulge_cells_per_a": Key("int", 32, (lambda v: 4 <= v <= 512, "an integer in [4, 512]"),
                                 doc="Reynolds grid of the 'reynolds' bulge table: cells per footprint semi-axis along "
                                     "sliding [1] (docs/model.md, section 'Slip-corrected Reynolds equation')"),
        "bulge_cells_per_b": Key("int", 12, (lambda v: 2 <= v <= 512, "an integer in [2, 512]"),
                                 doc="Reynolds grid of the 'reynolds' bulge table: cells per semi-axis across sliding [1]"),
        "start": Key("str", "static", choices=STARTS,
                     doc="start state of each run (docs/model.md, section 'Start state')"),
        "fhm_measure": Key("str", "peak-to-peak", choices=FHM_MEASURES,
                           doc="FHM/BV measure (docs/model.md, section 'FHM and BV')"),
    },
    "sweep": {
        "protrusion_nm": Key("range", dict(zip(("start", "stop", "step"), paper.PROTRUSION_GRID_NM)),
                             doc="protrusion grid {start, stop, step} [nm] (paper)"),
        "roughness": Key("tables", None, doc="roughness sets, each given or measured: {label=..., sigma_nm=..., summit_radius_um=..., "
                     "summit_density_per_um2=...} (keys left out: the scene's [roughness]) or {label=..., afm=[\"scan\", "
                     "...]} (AFM scans, any [roughness] key such as route); \"scene\": the scene's own [roughness]; "
                     "label optional (made from the values, or afm-<file stems>). sweep.nc holds the statistics each "
                     "set's interface used (roughness_sigma, ...; docs/datasets.md)"),
        "damping_ratio": Key("floats", None, (lambda v: len(v) > 0 and all(0 <= x < 1 for x in v),
                                              "a non-empty list of numbers in [0, 1)"),
                             doc="modal damping ratios [1]"),
        "batch_size": Key("int", 19, (lambda v: v >= 1, "an integer >= 1"),
                          doc="scenes per dask task (19: a quarter of the paper grid; fewer, larger tasks "
                              "amortise the part files and scheduling)"),
        "histories_nm": Key("floats", None, doc="protrusions whose time histories are kept [nm]"),
        "realisations": Key("int", 1, (lambda v: 1 <= v <= 100000, "an integer in [1, 100000]"),
                            doc="DMW realisations (seeds) per grid point; > 1 adds the realisation dimension"),
        "protocol": Key("str", "independent", choices=PROTOCOLS,
                        doc="'independent' (each protrusion from its start state) or 'stepping' (the grid run "
                            "up then down as one chain per roughness x damping x realisation, each step from the "
                            "end state of the previous one; batch_size is then ignored); docs/model.md, "
                            "section 'Heater stepping'"),
    },
    "report": {
        "histories_nm": Key("floats", [5.0, 11.0], doc="protrusions shown in the history figures [nm]"),
        "realisations": Key("int", 8, (lambda v: 1 <= v <= 1000, "an integer in [1, 1000]"),
                            doc="DMW realisations (seeds) over which the comparison judges the paper's targets "
                                "(the ensemble stage); 1: the single-seed comparison of the sweep only"),
    },
    # hdi identify: free parameters with bounds, the paper's targets with tolerances, the optimiser budget
    "identify": {
        "parameters": Key("tables", _FREE, doc="free parameters: [{key = \"section.key\" or \"section.key[i]\", low, high}] (bounds in the key's "
               "unit; docs/model.md, section 'Corrections') [recon]"),
        "targets": Key("strs", list(paper.TARGETS), choices=paper.TARGETS.keys(),  # (live: a declared target is a choice)
                       doc="targets the identification fits (touchdown uses [touchdown] onset_nm/previous_nm)"),
        "realisations": Key("int", 8, (lambda v: 1 <= v <= 1000, "an integer in [1, 1000]"),
                            doc="DMW realisations (seeds) each candidate runs; the targets are judged on their "
                                "ensemble statistics (pipeline/analyses/ensemble_rules.py); 1: the scene's record only"),
        **target_keys(),
        "missing_residual": Key("float", 10.0, _pos,
                                doc="residual of a target a candidate cannot produce (no contact, failed run) [1]"),
        "population": Key("int", 10, (lambda v: v >= 4, "an integer >= 4"),
                          doc="differential evolution: population = population x parameters"),
        "generations": Key("int", 20, (lambda v: v >= 1, "an integer >= 1"),
                           doc="differential evolution: largest number of generations"),
        "seed": Key("int", 20090601, _nonneg, doc="seed of the optimiser"),
        "batch_size": Key("int", 6, (lambda v: v >= 1, "an integer >= 1"), doc="candidates per dask task"),
        "profile_points": Key("int", 11, (lambda v: v >= 3, "an integer >= 3"),
                              doc="points of each parameter profile across its bounds"),
        "profile_method": Key("str", "optimised", choices=("optimised", "slice"),
                              doc="intervals from 'optimised' profiles (the other parameters re-optimised at each "
                                  "point: a compass search warm-started from the neighbouring point, at most "
                                  "profile_evaluations more evaluations per parameter) or 'slice's (the others held "
                                  "at the optimum: narrower where parameters correlate; no evaluations beyond the "
                                  "(profile_points + 1) per parameter both methods make); docs/model.md, section "
                                  "'Identification'"),
        "profile_evaluations": Key("int", 40, (lambda v: v >= 1, "an integer >= 1"),
                                   doc="budget of an 'optimised' profile: evaluations each parameter's profile may spend "
                                       "re-optimising the others (each point 1 + 2 x (parameters - 1) at least; "
                                       "6 parameters: <= 240 per profile round, four generations of the default "
                                       "population)"),
        "polish": Key("bool", True,
                      doc="polish the global search's optimum before the profiles: a compass search over every "
                          "parameter (steps from the profile grid's spacing, halved down to the profile walks' step; "
                          "a fixed budget of evaluations per parameter, raced), so that the profiles start from an optimum "
                          "and are made once rather than again around the better points they find; false: the "
                          "profiles start at the search's optimum, as before; docs/model.md, section "
                          "'Identification'"),
        "racing": Key("bool", True,
                      doc="race the candidates over the DMW records (with realisations > 1): each runs on "
                          "racing_records records first, and more (doubling to all) only while its objective's "
                          "lower confidence bound does not exceed the best point's; false: every candidate on "
                          "every record (the full method); docs/model.md, section 'Identification'"),
        "racing_records": Key("int", 2, (lambda v: v >= 1, "an integer >= 1"),
                              doc="DMW records of a candidate's first racing stage (doubling to realisations); 1: "
                                  "a first stage of one record, bounded by the pooled record-to-record spreads "
                                  "alone; docs/model.md, section 'Identification'"),
        "racing_z": Key("float", 3.0, _pos,
                        doc="racing bound: standard errors of each target's residual (from the record-to-record "
                            "spread) a candidate may lose by and still run on the next records [1]"),
    },
    # hdi sensitivity: [recon] parameters with bounds; Morris screening and Sobol indices (SALib)
    "sensitivity": {
        "parameters": Key("tables", [p for p in _FREE if "frequencies" not in p["key"]] + [
            # frequency bounds with f1/f2 <= 0.54: closer pairs have no real (or no pitch-first) bearing root
            {"key": "air_bearing.frequencies_khz[0]", "low": 90.0, "high": 140.0},
            {"key": "air_bearing.frequencies_khz[1]", "low": 260.0, "high": 400.0},
            {"key": "air_bearing.rear_exponent", "low": 1.0, "high": 3.0},
            # density from 8 um^-2: McCool's relations need alpha = 2412.74 (sigma eta R)^2 > 0.8968, i.e.
            # eta >= 7.42 um^-2 at the paper's sigma 0.52 nm and R 5 um (every sample below it fails)
            {"key": "roughness.summit_density_per_um2", "low": 8.0, "high": 20.0},
        ], doc="[recon] parameters and bounds: [{key = \"section.key\" or \"section.key[i]\", low, high}]; the box "
               "is checked before sampling (every bound and corner a model the study can build: McCool's alpha > "
               "0.8968, so summit_density_per_um2 >= 7.42 at the paper's sigma and R; f1/f2 <= 0.697 for a real "
               "air-bearing root; plasticity limits; the scene's checks)"),
        "methods": Key("strs", ["morris", "sobol"], choices=("morris", "sobol"), doc="methods to run"),
        "morris_trajectories": Key("int", 10, (lambda v: v >= 2, "an integer >= 2"),
                                   doc="Morris trajectories (each parameters + 1 evaluations)"),
        "morris_levels": Key("int", 4, (lambda v: v >= 2 and v % 2 == 0, "an even integer >= 2"),
                             doc="Morris grid levels"),
        "sobol_samples": Key("int", 32, (lambda v: v >= 2 and v & (v - 1) == 0, "a power of 2"),
                             doc="Sobol base samples N (N x (parameters + 2) evaluations)"),
        "confidence_level": Key("float", 0.95, (lambda v: 0 < v < 1, "a number in (0, 1)"),
                                doc="level of the bootstrap confidence intervals [1]"),
        "bootstrap": Key("int", 200, (lambda v: 10 <= v <= MAX_BOOTSTRAP,
                                       f"an integer in [10, {MAX_BOOTSTRAP:,}] (the intervals' resampling error "
                                       "is negligible long before; 1e9 resamples needed 15 GiB)"),
                          doc="bootstrap resamples"),
        "protrusion_nm": Key("range", None, doc="protrusion grid of each evaluation {start, stop, step} [nm] "
                                                "(default: [sweep] protrusion_nm)"),
        "seed": Key("int", 20090601, _nonneg, doc="seed of the samples and the bootstrap"),
        "batch_size": Key("int", 2, (lambda v: v >= 1, "an integer >= 1"), doc="evaluations per dask task"),
    },
}


def describe_keys(section: str | None = None) -> str:
    """The scene schema as text, one key a line: ``key = default  (kind; choices)  doc``, by section
    (``hdi --help-keys [SECTION]``); ``section`` limits it to one.

    Raises
    ------
    SceneError
        For a section the schema does not have (the message lists them).
    """
    if section is not None and section not in SCHEMA:
        raise SceneError(f"--help-keys {section}: no section [{section}]; expected one of {', '.join(SCHEMA)}")
    out = []
    for name, keys in SCHEMA.items():
        if section is not None and name != section:
            continue
        out.append(f"[{name}]")
        for key, spec in keys.items():
            default = "(no default)" if spec.default is None else repr(spec.default)
            if spec.kind == "tables" and spec.default:
                default = f"({len(spec.default)} tables)"
            kind = spec.kind + (f"; one of {', '.join(spec.choices)}" if spec.choices else "")
            out.append(f"  {key} = {default}  ({kind})  {spec.doc}")
            if isinstance(spec.choices, Registry):  # a model variant: each option with its summary
                out.extend(f"      {name}: {entry.summary}" for name, entry in spec.choices.items())
        out.append("")
    return "\n".join(out)


def unit_suffix(key: str) -> str | None:
    """The unit suffix of a key name (``"flying_height_nm"`` -> ``"nm"``; ``None`` without one)."""
    return strip_unit(key)[1]


def strip_unit(key: str) -> tuple[str, str | None]:
    """A key name split into its stem and its unit suffix (``"flying_height_nm"`` -> ``("flying_height",
    "nm")``; ``(key, None)`` without one): the longest suffix of :data:`UNIT_SUFFIXES` that ends it."""
    for suffix in sorted(UNIT_SUFFIXES, key=len, reverse=True):
        if key.endswith("_" + suffix):
            return key[: -len(suffix) - 1], suffix
    return key, None


def scene_key(si_name: str) -> str:
    """The scene key, as a scene file names it, of a value of the SI view (:func:`pipeline.config.si.to_si`):
    ``"air_bearing.flying_height"`` -> ``"air_bearing.flying_height_nm"`` (a key without a unit: itself).

    Raises
    ------
    KeyError
        For a name no key of the schema has.
    """
    section, _, stem = si_name.partition(".")
    for key in SCHEMA.get(section, {}):
        if strip_unit(key)[0] == stem:
            return f"{section}.{key}"
    raise KeyError(f"{si_name}: no scene key of that name (with or without a unit suffix)")

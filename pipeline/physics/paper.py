"""The published values of the paper this project reproduces, in one place.

A. I. Vakis, S.-C. Lee, A. A. Polycarpou, "Dynamic head-disk interface instabilities with friction for
light contact (surfing) recording", IEEE Trans. Magn. 45(11), 4966-4971 (2009),
doi:10.1109/TMAG.2009.2029410 ("the paper").

Only values the paper states ([paper] in docs/model.md) are here; reconstructed defaults ([recon]) stay
with the scene schema (:mod:`pipeline.config.scene`), which takes its [paper] defaults from this module, as do
the report's comparison (:mod:`pipeline.analyses.paper_comparison`), the optimum points
(:mod:`pipeline.analyses.optimum`). The paper's targets are declared here too (:data:`TARGETS`: one
declaration each, from which the schema's ``[identify]`` keys, the identification's residuals and the
report's target tables come). The unit is the suffix of each name. "Source" names where
in the paper the value is stated: the model section (slider, bulge and disk of the simulated drive),
the DMW measurement, or the results (Figs 3-5: the light-contact case at 11 nm protrusion; Fig. 6:
FHM/BV versus protrusion, touchdown and the stable-flying limit; Fig. 7: contact stresses versus
protrusion). The paper's tables did not survive in our copy; values read from them are absent.
"""

from __future__ import annotations

from dataclasses import dataclass

# ----------------------------------------------------------------- the drive (model section)
#: Nominal flying height FH0 [nm] (model section).
FLYING_HEIGHT_NM: float = 11.0
#: Centre of the TFC bulge from the slider's trailing edge [um] (model section).
TFC_FROM_TRAILING_EDGE_UM: float = 8.0
#: Semi-axis a of the ellipsoidal TFC bulge along the sliding direction [um] (model section).
TFC_HALF_LENGTH_UM: float = 3.0
#: Semi-axis b of the bulge across the sliding direction [um]: the bulge is 50 um wide (model section).
TFC_HALF_WIDTH_UM: float = 25.0
#: GW plasticity index psi [1], "purely elastic" (model section).
PLASTICITY_INDEX: float = 0.52
#: Bonded lubricant thickness t [nm] (model section).
LUBRICANT_THICKNESS_NM: float = 0.75
#: Protrusion grid of the study {start, stop, step} [nm]: 0-15 nm in 0.2 nm actuation steps (results, Fig. 6).
PROTRUSION_GRID_NM: tuple[float, float, float] = (0.0, 15.0, 0.2)

# ----------------------------------------------------------------- the DMW measurement
#: Disk speed [rpm]: a 3.5-inch disk (DMW measurement).
DISK_RPM: float = 5425.0
#: Track radius of the measurement, mid-diameter [mm] (DMW measurement; V = 19.5 m/s).
TRACK_RADIUS_MM: float = 34.3
#: Band of the DMW record [kHz]: high-passed at 10 kHz, content up to 500 kHz (DMW measurement).
DMW_BAND_KHZ: tuple[float, float] = (10.0, 500.0)
#: Sampling rate of the laser Doppler vibrometer record [MS/s] (DMW measurement).
DMW_SAMPLE_RATE_MHZ: float = 4.0

# ----------------------------------------------------------------- touchdown and the contact criterion
#: Measured touchdown protrusion [nm]: contact at 9.8 nm (results, Fig. 6).
TOUCHDOWN_NM: float = 9.8
#: The previous actuation step, no contact [nm] (results; actuation resolution 0.2 nm).
PREVIOUS_STEP_NM: float = 9.6
#: Contact probability of the calibrated contact criterion k [1], two-sided P(|z| > k sigma): 32.8 %
#: (model section; two-sided because the paper counts 3 sigma as "0.3 %" = 2 Q(3); k = 0.978).
CONTACT_PROBABILITY: float = 0.328

# ----------------------------------------------------------------- flying (results, Fig. 6)
#: Flying FHM [%], about 12.5 % ...
FHM_FLYING_PERCENT: float = 12.5
#: ... over these protrusions [nm].
FHM_FLYING_RANGE_NM: tuple[float, float] = (4.0, 7.0)
#: FHM just before touchdown [%], about 9 % ...
FHM_TOUCHDOWN_PERCENT: float = 9.0
#: ... at this protrusion [nm].
FHM_TOUCHDOWN_AT_NM: float = 9.0
#: Stable flying needs an FHM below this [%] (criterion; optimum point (a)).
STABLE_FHM_PERCENT: float = 10.0

# ----------------------------------------------------------------- after touchdown (results, Figs 3-7)
#: The BV exceeds this [%] in the bouncing band after touchdown ...
BOUNCING_MIN_PERCENT: float = 20.0
#: ... the band (lo, hi] of protrusions [nm].
BOUNCING_RANGE_NM: tuple[float, float] = (9.8, 10.8)
#: Protrusion of the light-contact (surfing) case of Figs 3-5 [nm].
LIGHT_CONTACT_NM: float = 11.0
#: In steady sliding the BV stays below this [%] (light contact; optimum point (b)).
SLIDING_BV_MAX_PERCENT: float = 2.0
#: Nominal contact area A_n [um^2] ...
NOMINAL_AREA_UM2: float = 62.0
#: ... at this protrusion [nm].
NOMINAL_AREA_AT_NM: float = 11.0
#: Mean interference in light contact [nm] (Figs 3-5, 11 nm).
INTERFERENCE_NM: float = 0.58
#: Contact force in light contact [mN], about 1 mN (Fig. 4, 11 nm).
CONTACT_FORCE_MN: float = 1.0
#: Real contact area in light contact [um^2] (11 nm).
REAL_AREA_UM2: float = 2.7
#: Mean contact pressure in light contact [MPa], about 400 MPa (Figs 5 and 7, 11 nm).
MEAN_PRESSURE_MPA: float = 400.0
#: Friction coefficient in light contact [1], about 1.2 (Fig. 5, 11 nm).
FRICTION_COEFFICIENT: float = 1.2


# ================================================================= the targets of the identification
# One declaration per paper target (:data:`TARGETS`): its published value, its tolerance, how it is
# measured and where the paper states it. Everything that knows the targets reads these declarations:
# the scene schema generates the ``[identify]`` keys from them (the values, tolerances and where each
# target is measured, with the defaults below; ``identify.targets`` chooses among the names),
# :func:`pipeline.analyses.study.targets` interprets the measurements (the residuals of ``hdi identify``,
# ``ensemble.nc``), and the report writes the values and texts those carry. A new target is one
# declaration here, with a measurement of a kind :data:`MEASURES` names.

#: The kinds of measurement :func:`pipeline.analyses.study.targets` interprets (:attr:`Measure.how`):
#: ``touchdown`` (contact at the second of two protrusions, none at the first: the minimum clearance of
#: the steady window); ``flying_mean`` (the mean of ``output`` over the flying points of a range);
#: ``band`` (the graded bouncing band over the steps of an open-low range, each capped at the target);
#: ``at`` (``output`` at one protrusion).
MEASURES: tuple[str, ...] = ("touchdown", "flying_mean", "band", "at")


@dataclass(frozen=True)
class Setting:
    """A key of the scene's ``[identify]`` section that defines a target (generated into the schema).

    Attributes
    ----------
    key : the key; its unit is its suffix (``_nm``, ``_percent``, ...)
    default : a number, or a ``(lo, hi)`` pair (a list of two numbers in the scene)
    doc : one line with unit and source (``hdi --help-keys``)
    check : ``"positive"``, ``"nonnegative"``, ``"lo <= hi"`` or ``"lo < hi"``
    """

    key: str
    default: float | tuple[float, float]
    doc: str
    check: str = "positive"


@dataclass(frozen=True)
class Measure:
    """How a target is measured from a candidate's outputs versus protrusion.

    Attributes
    ----------
    how : one of :data:`MEASURES`
    output : the steady-window output (:data:`pipeline.variables.SCALARS`) measured
    where : the scene key of the protrusion(s) [nm]: an ``[identify]`` key, or ``"section.key"`` of
        another section; a pair of keys for ``touchdown`` (no contact at the first, contact at the second)
    step : the ``[identify]`` key of the protrusion step [nm] over a range (``flying_mean``, ``band``)
    statistic : over DMW realisations, ``"median"`` (with its 10-90 % range) or ``"mean"`` (mean ± 1
        standard deviation: the light-contact state) of an ``at`` measurement
    """

    how: str
    output: str = ""
    where: str | tuple[str, str] = ""
    step: str = ""
    statistic: str = "median"


@dataclass(frozen=True)
class Target:
    """A published target of the paper.

    Attributes
    ----------
    name : the name in ``identify.targets``, datasets (``value_<name>``) and the report
    long_name : the quantity, a :meth:`str.format` template whose fields are the measured protrusions
        (``lo``, ``hi``, ``at``; ``open_lo``: the excluded low end of a band), ``value`` (the published
        value) and the keys the target reads (by their names, e.g. ``previous_nm``)
    units : the unit of the value (the suffix form: ``nm``, ``%``, ``mN``, ``um2``, ``MPa``, ``1``)
    kind : ``"equal"``, ``"above"`` (at least), ``"below"`` (at most) or ``"touchdown"``
    value : the published value: a :class:`Setting` (an ``[identify]`` key with the paper's value as
        default), ``"section.key"`` of a key another section holds, or a fixed number
    tolerance : the ``[identify]`` key of its tolerance (a [recon] default)
    measure : how it is measured (:class:`Measure`)
    paper : what the paper states, a template like ``long_name`` (the report's "paper" column)
    source : where in the paper it is stated
    settings : the other ``[identify]`` keys of its definition (where it is measured), in order
    """

    name: str
    long_name: str
    units: str
    kind: str
    value: Setting | str | float
    tolerance: Setting
    measure: Measure
    paper: str
    source: str
    settings: tuple[Setting, ...] = ()

    def keys(self) -> tuple[Setting, ...]:
        """The ``[identify]`` keys of the target, in schema order: its value, where it is measured, its tolerance.

        Returns
        -------
        tuple of Setting
            The settings [-], each with its key (whose suffix names its unit, ``_nm``, ``_percent``), default
            and check.

        References
        ----------
        [VLP09] (the published values); docs/model.md, section "Paper targets".
        """
        return ((self.value,) if isinstance(self.value, Setting) else ()) + self.settings + (self.tolerance,)


#: Where the light-contact targets are measured (shared by every target at the sliding protrusion).
SLIDING_AT = Setting("sliding_at_nm", LIGHT_CONTACT_NM, "protrusion of the light-contact targets [nm] (paper)",
                     "nonnegative")


def _light_contact(name: str, long_name: str, units: str, value_key: str, value: float, doc: str, tol_key: str,
                   tol: float, tol_doc: str, source: str) -> Target:
    """A light-contact number at :data:`SLIDING_AT`, equal to the paper's, judged by its ensemble mean."""
    return Target(name, f"{long_name} at {{at:g}} nm", units, "equal", Setting(value_key, value, doc),
                  Setting(tol_key, tol, tol_doc), Measure("at", name, SLIDING_AT.key, statistic="mean"),
                  "{value:g}" + ("" if units == "1" else f" {units}"), source, (SLIDING_AT,))


#: The paper's targets, by name, in the order ``hdi identify`` fits and reports them (all by default).
TARGETS: dict[str, Target] = {t.name: t for t in (
    Target("touchdown", "touchdown protrusion", "nm", "touchdown", "touchdown.onset_nm",
           Setting("touchdown_tolerance_nm", 0.1, "tolerance of the touchdown target on the minimum clearance [nm] "
                                                  "(recon: half the 0.2 nm actuation step)"),
           Measure("touchdown", "min_clearance", ("touchdown.previous_nm", "touchdown.onset_nm")),
           "{value:g} nm (none at {previous_nm:g} nm)", "results, Fig. 6: contact at 9.8 nm, none at 9.6 nm"),
    Target("fhm_flying", "flying FHM, mean over {lo:g}-{hi:g} nm", "%", "equal",
           Setting("fhm_flying_percent", FHM_FLYING_PERCENT, "flying FHM over fhm_flying_range_nm [%] (paper)"),
           Setting("fhm_flying_tolerance_percent", 1.0, "tolerance of the flying FHM [%] (recon)"),
           Measure("flying_mean", "fhm_bv", "fhm_flying_range_nm", "flying_step_nm"),
           "about {value:g} %", "results, Fig. 6: about 12.5 % at 4-7 nm",
           (Setting("fhm_flying_range_nm", FHM_FLYING_RANGE_NM, "protrusions of the flying FHM target [nm] (paper)",
                    "lo <= hi"),
            Setting("flying_step_nm", 1.0, "protrusion step over the flying FHM range [nm]"))),
    Target("fhm_touchdown", "FHM at {at:g} nm", "%", "equal",
           Setting("fhm_touchdown_percent", FHM_TOUCHDOWN_PERCENT, "FHM just before touchdown [%] (paper)"),
           Setting("fhm_touchdown_tolerance_percent", 1.0, "its tolerance [%] (recon)"),
           Measure("at", "fhm_bv", "fhm_touchdown_at_nm"), "about {value:g} %",
           "results, Fig. 6: about 9 % at 9 nm, just before touchdown",
           (Setting("fhm_touchdown_at_nm", FHM_TOUCHDOWN_AT_NM, "protrusion of that FHM [nm] (paper)", "nonnegative"),)),
    Target("bouncing", "bouncing BV over ({open_lo:g}, {hi:g}] nm, mean over the steps, each capped at {value:g} %",
           "%", "above",
           Setting("bouncing_min_percent", BOUNCING_MIN_PERCENT, "BV exceeds this after touchdown [%] (paper)"),
           Setting("bouncing_tolerance_percent", 2.0, "tolerance of the bouncing target [%] (recon)"),
           Measure("band", "fhm_bv", "bouncing_range_nm", "band_step_nm"),
           "> {value:g} % at every step ({value:g} %)", "results, Figs 3 and 6: BV above 20 % in (9.8, 10.8] nm",
           (Setting("bouncing_range_nm", BOUNCING_RANGE_NM, "bouncing band (lo, hi] [nm] (paper)", "lo < hi"),
            Setting("band_step_nm", 0.2, "protrusion step over the bouncing band [nm] (paper's step)"))),
    Target("sliding_bv", "BV at {at:g} nm", "%", "below",
           Setting("sliding_bv_max_percent", SLIDING_BV_MAX_PERCENT, "BV in light contact below this [%] (paper)"),
           Setting("sliding_bv_tolerance_percent", 0.5, "its tolerance [%] (recon)"),
           Measure("at", "fhm_bv", SLIDING_AT.key), "< {value:g} %",
           "results, Figs 3-5: steady sliding at 11 nm, BV below 2 %", (SLIDING_AT,)),
    _light_contact("interference", "interference", "nm", "interference_nm", INTERFERENCE_NM,
                   "interference in light contact [nm] (paper)", "interference_tolerance_nm", 0.05,
                   "its tolerance [nm] (recon)", "results, Figs 3-5 (11 nm)"),
    _light_contact("contact_force", "contact force", "mN", "contact_force_mn", CONTACT_FORCE_MN,
                   "contact force in light contact [mN] (paper, ~1 mN)", "contact_force_tolerance_mn", 0.2,
                   "its tolerance [mN] (recon)", "results, Fig. 4 (11 nm)"),
    _light_contact("real_area", "real contact area", "um2", "real_area_um2", REAL_AREA_UM2,
                   "real contact area in light contact [um^2] (paper)", "real_area_tolerance_um2", 0.3,
                   "its tolerance [um^2] (recon)", "results (11 nm)"),
    _light_contact("mean_pressure", "mean contact pressure", "MPa", "mean_pressure_mpa", MEAN_PRESSURE_MPA,
                   "mean contact pressure in light contact [MPa] (paper)", "mean_pressure_tolerance_mpa", 50.0,
                   "its tolerance [MPa] (recon)", "results, Figs 5 and 7 (11 nm)"),
    _light_contact("friction_coefficient", "friction coefficient", "1", "friction_coefficient", FRICTION_COEFFICIENT,
                   "friction coefficient in light contact [1] (paper)", "friction_coefficient_tolerance", 0.15,
                   "its tolerance [1] (recon)", "results, Fig. 5 (11 nm)"),
    Target("net_force", "net interface force at {at:g} nm (negative: attractive)", "mN", "below", 0.0,
           Setting("net_force_tolerance_mn", 0.05, "tolerance of the attractive net force (< 0) in light contact [mN] "
                                                   "(recon)"),
           Measure("at", "net_force", SLIDING_AT.key, statistic="mean"), "attractive (< 0)",
           "results: the light contact at 11 nm is net attractive", (SLIDING_AT,)),
)}

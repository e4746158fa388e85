"""The published values of the paper this project reproduces, in one place.

A. I. Vakis, S.-C. Lee, A. A. Polycarpou, "Dynamic head-disk interface instabilities with friction for
light contact (surfing) recording", IEEE Trans. Magn. 45(11), 4966-4971 (2009),
doi:10.1109/TMAG.2009.2029410 ("the paper").

Only values the paper states ([paper] in docs/model.md) are here; reconstructed defaults ([recon]) stay
with the scene schema (:mod:`pipeline.config.scene`), which takes its [paper] defaults from this module, as do
the report's comparison (:mod:`pipeline.analyses.paper_comparison`), the optimum points
(:mod:`pipeline.analyses.optimum`) and, through the scene defaults of ``[identify]``, the identification
targets (:func:`pipeline.analyses.study.targets`). The unit is the suffix of each name. "Source" names where
in the paper the value is stated: the model section (slider, bulge and disk of the simulated drive),
the DMW measurement, or the results (Figs 3-5: the light-contact case at 11 nm protrusion; Fig. 6:
FHM/BV versus protrusion, touchdown and the stable-flying limit; Fig. 7: contact stresses versus
protrusion). The paper's tables did not survive in our copy; values read from them are absent.
"""

from __future__ import annotations

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

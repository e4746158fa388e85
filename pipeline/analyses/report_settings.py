"""The scene keys the report's analyses read, as one frozen record (taken from the scene once, by the stage)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..config.fields import fields
from ..physics import paper

#: The scene keys the report reads (:meth:`ReportSettings.from_scene`, :func:`wants_ensemble`).
FIELDS = fields("air_bearing.damping_ratio", "solver.transient_ms", "touchdown.onset_nm", "touchdown.previous_nm",
                "report.histories_nm", "report.realisations", "dmw.rms_nm", "dmw.source", "dmw.seed",
                "materials.hardness_gpa", "materials.plasticity_index", "contact.section_depth_sigma",
                "air_bearing.bulge", "air_bearing.lift_cap_gap_nm", "scene.effects")


def _get(scene: Any, section: str, key: str, default: Any = None) -> Any:
    """``scene[section][key]``, ``default`` when the scene, the section or the key is absent or ``None``."""
    if scene is None:
        return default
    try:
        v = scene[section][key]
    except (KeyError, TypeError):
        return default
    return default if v is None else v


@dataclass(frozen=True)
class ReportSettings:
    """What the report uses of the scene (``None``: not set).

    Attributes
    ----------
    damping_ratio : the scene's modal damping ratio [1] (picks the default sweep combination)
    transient_ms : discarded start-up transient [ms] (shaded in the history figures)
    onset_nm, previous_nm : the measured touchdown and the previous actuation step [nm]
    histories_nm : protrusions [nm] of the history figures (``[report] histories_nm``)
    dmw_rms_nm, dmw_source, dmw_seed : the DMW settings, used when ``dmw.nc`` is absent [nm]
    hardness_gpa : the scene's hardness [GPa]; plasticity_index : the scene's psi [1] (H derived from it)
    section_depth_sigma : nominal-area section depth [sigma]
    bulge : the bulge's air-bearing law (``air_bearing.bulge``; ``"none"`` without it)
    lift_cap_nm : the lift cap of hypothesis H8 (``air_bearing.lift_cap_gap_nm``) [nm], ``None`` when off
    """

    damping_ratio: float | None = None
    transient_ms: float | None = None
    onset_nm: float = paper.TOUCHDOWN_NM
    previous_nm: float = paper.PREVIOUS_STEP_NM
    histories_nm: list[float] = field(default_factory=list)
    dmw_rms_nm: float = math.nan
    dmw_source: str | None = None
    dmw_seed: Any = None
    hardness_gpa: float | None = None
    plasticity_index: float | None = None
    section_depth_sigma: float | None = None
    bulge: str = "none"
    lift_cap_nm: float | None = None

    @classmethod
    def from_scene(cls, scene: Any) -> "ReportSettings":
        """The settings of ``scene`` (a scene without a key or section gets the defaults above)."""
        return cls(
            damping_ratio=_get(scene, "air_bearing", "damping_ratio"),
            transient_ms=_get(scene, "solver", "transient_ms"),
            onset_nm=float(_get(scene, "touchdown", "onset_nm", paper.TOUCHDOWN_NM)),
            previous_nm=float(_get(scene, "touchdown", "previous_nm", paper.PREVIOUS_STEP_NM)),
            histories_nm=list(_get(scene, "report", "histories_nm") or []),
            dmw_rms_nm=_get(scene, "dmw", "rms_nm", math.nan),
            dmw_source=_get(scene, "dmw", "source"),
            dmw_seed=_get(scene, "dmw", "seed"),
            hardness_gpa=_get(scene, "materials", "hardness_gpa"),
            plasticity_index=_get(scene, "materials", "plasticity_index"),
            section_depth_sigma=_get(scene, "contact", "section_depth_sigma"),
            bulge=_get(scene, "air_bearing", "bulge", "none"),
            lift_cap_nm=_get(scene, "air_bearing", "lift_cap_gap_nm"),
        )


def wants_ensemble(scene: Any) -> bool:
    """Whether the report judges the paper's targets over DMW realisations (``report.realisations`` > 1)
    and the scene can make them (a synthetic DMW record): the ``ensemble`` stage is then upstream."""
    return bool(_get(scene, "report", "realisations", 1) > 1 and "dmw" in _get(scene, "scene", "effects", [])
                and _get(scene, "dmw", "source") == "synthetic")

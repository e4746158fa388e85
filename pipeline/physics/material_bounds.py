"""Physical bounds of derived material parameters: a warning with the numbers when they are left.

:func:`check_materials` warns (:class:`PhysicsWarning`) when a hardness derived from the plasticity
index, or a plasticity index derived from the hardness, lies outside physical bounds: e.g. an AFM
scan with the paper's fixed psi = 0.52 can imply H = 58.5 GPa. Kept apart from the command line's
checks (:mod:`pipeline.cli_checks`), so that the interface stage's code key
(:mod:`pipeline.code_version`) holds these bounds and not the command line's messages.
"""

from __future__ import annotations

import warnings

from .asperity_statistics import plasticity_index_gw
from ..units import GPA, NM, UM


class PhysicsWarning(UserWarning):
    """A derived material parameter lies outside physical bounds; results may be meaningless."""


#: Hardness over composite modulus H/E' [1]: real solids lie within these bounds (soft metals
#: ~1e-3; diamond and tetrahedral amorphous carbon ~0.1, Tabor's H ~ 3Y with the ideal strength
#: Y ~ E/10 caps it near 0.3).
HARDNESS_RATIO_BOUNDS = (1e-3, 0.3)
#: GW plasticity index [1]: measured engineering surfaces lie within these bounds (Greenwood &
#: Williamson 1966 report 0.1-100; HDI interfaces are near 0.5, the paper's 0.52).
PLASTICITY_BOUNDS = (0.05, 100.0)


def check_materials(E: float, H: float, sigma_s: float, R: float, *, derived: str) -> None:
    """Warn when the hardness or the GW plasticity index of an interface is outside physical bounds.

    Parameters
    ----------
    E, H, sigma_s, R : as :func:`pipeline.physics.asperity_statistics.plasticity_index_gw` [Pa, Pa, m, m]
    derived : ``"hardness"`` (H from the scene's plasticity index) or ``"plasticity_index"`` (psi from the
        scene's hardness): which one was computed, named in the warning

    References
    ----------
    [Tabor51] (H ~ 3Y, the bound on H/E'); [GW66] (the plasticity index); docs/model.md, section
    "Plasticity index".
    """
    psi = float(plasticity_index_gw(E, H, sigma_s, R))
    lo, hi = HARDNESS_RATIO_BOUNDS
    if not lo <= H / E <= hi:
        cause = (f"derived from materials.plasticity_index = {psi:.3g} with sigma_s = {sigma_s / NM:.3g} nm and "
                 f"R = {R / UM:.3g} um" if derived == "hardness" else "materials.hardness_gpa")
        warnings.warn(f"hardness H = {H / GPA:.3g} GPa ({cause}) is {H / E:.3g} E' (E' = {E / GPA:.3g} GPa), outside "
                      f"the physical range {lo:g}-{hi:g} E'; set materials.hardness_gpa for these surfaces",
                      PhysicsWarning, stacklevel=2)
    plo, phi = PLASTICITY_BOUNDS
    if not plo <= psi <= phi:
        warnings.warn(f"GW plasticity index psi = {psi:.3g} (from H = {H / GPA:.3g} GPa, E' = {E / GPA:.3g} GPa, "
                      f"sigma_s = {sigma_s / NM:.3g} nm, R = {R / UM:.3g} um) is outside {plo:g}-{phi:g}, the range "
                      "of measured surfaces", PhysicsWarning, stacklevel=2)

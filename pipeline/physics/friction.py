"""The single-asperity friction law.

The paper computes friction from the asperity stresses, with no assumed coefficient of friction.
Our documented default (docs/model.md, section "Friction") is sliding at the shear strength of the softer body:
``Q = tau_y A`` on every elastic and elastic-plastic summit, with the von Mises shear yield stress
``tau_y = Y / sqrt(3)`` and ``H = 2.8 Y`` (Tabor), i.e. ``tau_y = H / (2.8 sqrt(3))``.
Fully plastic summits carry no friction in the ISBL population table (docs/model.md, section "Friction").

docs/model.md, section "Friction": the paper's mu ~ 1.2 at ~400 MPa implies ~480 MPa of shear stress, more than the
``tau_y`` of a 1.7 GPa hardness, so the law is a named choice (:data:`FRICTION_LAWS`,
``contact.friction_law``): ``"shear-strength"`` as above, or ``"coefficient"``, a constant
coefficient ``Q = mu P`` (Amontons) with ``contact.friction_coefficient``. Both act through the
friction-stress table of the dynamics (:func:`friction_stress_table`), so the choice costs nothing
in the kernel.

References
----------
.. [Tabor51] D. Tabor, The Hardness of Metals, Oxford (1951): ``H ~ 2.8 Y``.
.. [Bowden50] F. P. Bowden, D. Tabor, The Friction and Lubrication of Solids (1950): adhesive
   friction as shear strength times real area.
"""

from __future__ import annotations

import numpy as np



def shear_strength(H: float) -> float:
    """Shear yield stress of the softer body ``tau_y = H / (2.8 sqrt(3))`` [Pa] [Tabor51].

    Parameters
    ----------
    H : hardness [Pa]
    """
    return H / (2.8 * np.sqrt(3.0))


def friction_force(area: np.ndarray, H: float, law: str = "shear-strength") -> np.ndarray:
    """Friction force of one sliding summit [N] by the shear-strength law: ``Q = tau_y A`` [Bowden50].

    Parameters
    ----------
    area : real contact area of the summit [m^2]
    H : hardness [Pa]
    law : must be ``"shear-strength"`` (the coefficient law needs the summit's load, not its area)
    """
    if law != "shear-strength":
        raise ValueError(f"friction law {law!r}: the per-summit area form exists only for 'shear-strength'")
    return shear_strength(H) * np.asarray(area, dtype=float)


def _shear_strength_table(contact_pressure: np.ndarray, shear_strength_stress: np.ndarray, mu: float) -> np.ndarray:
    return shear_strength_stress


def _coefficient_table(contact_pressure: np.ndarray, shear_strength_stress: np.ndarray, mu: float) -> np.ndarray:
    if mu is None or not mu >= 0.0:
        raise ValueError(f"the 'coefficient' friction law needs contact.friction_coefficient >= 0 (got {mu})")
    return mu * np.asarray(contact_pressure, dtype=float)


#: Friction laws a scene may name (``contact.friction_law``): name -> function of the contact pressure
#: table [Pa], the shear-strength friction-stress table of the ISBL integrals [Pa] and ``mu`` [1],
#: returning the friction stress per nominal area [Pa] versus separation.
FRICTION_LAWS = {
    "shear-strength": _shear_strength_table,   # tau = eta int tau_y A phi dz (docs/model.md, section "Friction")
    "coefficient": _coefficient_table,         # tau = mu p_c (docs/model.md, section "Friction")
}


def friction_stress_table(law: str, contact_pressure: np.ndarray, shear_strength_stress: np.ndarray,
                          mu: float | None = None) -> np.ndarray:
    """Friction stress per nominal area [Pa] versus separation for the named law (:data:`FRICTION_LAWS`).

    Parameters
    ----------
    law : ``"shear-strength"`` or ``"coefficient"``
    contact_pressure : contact pressure table ``p_c(d)`` [Pa]
    shear_strength_stress : the ISBL friction-stress table of the shear-strength law [Pa]
    mu : friction coefficient [1] (``"coefficient"`` only)
    """
    if law not in FRICTION_LAWS:
        raise ValueError(f"friction law {law!r} unknown; expected one of {list(FRICTION_LAWS)}")
    return FRICTION_LAWS[law](contact_pressure, shear_strength_stress, mu)

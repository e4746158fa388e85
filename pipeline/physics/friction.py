"""The single-asperity friction law.

The paper computes friction from the asperity stresses, with no assumed coefficient of friction.
Our documented default (SPEC.md section 2) is sliding at the shear strength of the softer body:
``Q = tau_y A`` on every elastic and elastic-plastic summit, with the von Mises shear yield stress
``tau_y = Y / sqrt(3)`` and ``H = 2.8 Y`` (Tabor), i.e. ``tau_y = H / (2.8 sqrt(3))``.
Fully plastic summits carry no friction in the ISBL population table (SPEC.md section 2).

References
----------
.. [Tabor51] D. Tabor, The Hardness of Metals, Oxford (1951): ``H ~ 2.8 Y``.
.. [Bowden50] F. P. Bowden, D. Tabor, The Friction and Lubrication of Solids (1950): adhesive
   friction as shear strength times real area.
"""

from __future__ import annotations

import numpy as np

#: Single-asperity friction laws a scene may name (``[contact] friction_law``).
FRICTION_LAWS = ("shear-strength",)


def shear_strength(H: float) -> float:
    """Shear yield stress of the softer body ``tau_y = H / (2.8 sqrt(3))`` [Pa] [Tabor51].

    Parameters
    ----------
    H : hardness [Pa]
    """
    return H / (2.8 * np.sqrt(3.0))


def friction_force(area: np.ndarray, H: float, law: str = "shear-strength") -> np.ndarray:
    """Friction force of one sliding summit [N]: ``Q = tau_y A`` [Bowden50].

    Parameters
    ----------
    area : real contact area of the summit [m^2]
    H : hardness [Pa]
    law : the friction law (only ``"shear-strength"`` so far)
    """
    if law != "shear-strength":
        raise ValueError(f"friction law {law!r} unknown; expected one of {FRICTION_LAWS}")
    return shear_strength(H) * np.asarray(area, dtype=float)

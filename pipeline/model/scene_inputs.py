"""Scene to model: which inputs a simulation reads, the contact criterion k, and the model itself.

The one home of three rules every caller (the simulate, calibrate, sweep and accuracy stages, the
parameter studies, the benchmarks and the tests) shares:

* :func:`needs_interface`, :func:`input_stages` (and :func:`pipeline.model.contact_rule.needs_calibration`): the inputs a simulation of a scene reads
  (interface tables, DMW record, the calibration for k);
* :func:`contact_k`: the contact criterion constant k and where it came from (docs/model.md, section
  "Contact criterion").

The inputs themselves, read or in memory, are :class:`pipeline.model.inputs.SimulationInputs`; the model
is :func:`pipeline.model.assembly.build_model` of the scene and those inputs
(:meth:`pipeline.model.inputs.SimulationInputs.model`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..config.fields import fields, union
from ..physics.asperity_statistics import contact_probabilities, k_from_probability
from .assembly import MODEL_FIELDS, TFC_POINT_LAWS
from .contact_rule import needs_calibration

if TYPE_CHECKING:
    import xarray as xr

#: The scene keys of the rules of this module: which inputs a simulation reads (:func:`needs_interface`,
#: :func:`table_stages`, :func:`needs_calibration`) and the contact criterion k (:func:`contact_k`).
FIELDS = fields("scene.effects", "roughness.afm", "contact.k", "contact.fallback_probability",
                *(f"air_bearing.{key}" for key in TFC_POINT_LAWS))

#: The scene keys one simulation of a scene reads, besides its protrusion (``tfc.protrusion_nm``) and the
#: datasets of its input stages (their own keys): the model (:data:`pipeline.model.assembly.MODEL_FIELDS`)
#: and the rules of this module.
SIMULATION_FIELDS = union(MODEL_FIELDS, FIELDS)

#: The scene keys a parameter study's simulations may read: every key of the physical sections, since a
#: study varies any of them and then makes the inputs (tables, records) of each candidate itself. The inputs
#: key of the stages that run studies and of their evaluation store.
STUDY_FIELDS = fields("scene.effects", "slider.*", "air_bearing.*", "tfc.*", "roughness.*", "materials.*",
                      "lubricant.*", "interface.*", "contact.*", "dmw.*", "touchdown.*", "solver.*")


def needs_interface(scene: Any) -> bool:
    """Whether a simulation reads interface tables: for contact or adhesion, or, with AFM scans, for the
    summit offset y_s of the separation datum (explicit statistics give y_s without tables)."""
    return bool(scene.effects & {"contact", "adhesion"} or scene["roughness"]["afm"])


def table_stages(scene: Any) -> tuple[str, ...]:
    """The stages whose datasets the scene's air-bearing laws at the TFC point read
    (:data:`pipeline.model.assembly.TFC_POINT_LAWS`, :attr:`pipeline.physics.tfc_laws.TfcLaw.table`:
    ``bulge`` for ``air_bearing.bulge = "reynolds"``)."""
    a = scene["air_bearing"]
    laws = (registry.lookup(a[key]) for key, registry in TFC_POINT_LAWS.items())
    return tuple(dict.fromkeys(law.table for law in laws if law.table))


def input_stages(scene: Any, calibration: bool = True) -> tuple[str, ...]:
    """The inputs (named as the stages that make them) one simulation of the scene reads.

    ``dmw`` with the dmw effect, ``interface`` (:func:`needs_interface`), ``bulge`` with the tabulated
    bulge bearing (:func:`table_stages`), and ``calibrate`` when the contact effect is on and the scene
    fixes no ``contact.k`` (``calibration=False``: a parameter study, which takes k by :func:`contact_k`
    without a calibration).
    """
    up = []
    if scene.has("dmw"):  # (first: a record the simulation cannot use is refused before any dataset is written)
        up.append("dmw")
    if needs_interface(scene):
        up.append("interface")
    up.extend(table_stages(scene))
    if calibration and needs_calibration(scene):
        up.append("calibrate")
    return tuple(up)


def contact_k(scene: Any, calibration: xr.Dataset | None = None, override: float | None = None,
              calibration_name: str = "calibration.nc") -> tuple[float | None, str]:
    """The contact criterion constant k [1] and where it came from, in this order:

    1. ``override`` (an explicit value, e.g. the accuracy stage's ``--k``);
    2. ``contact.k`` when the scene fixes it;
    3. ``k_calibrated`` of the calibration dataset, when one is given;
    4. when there is no admissible calibrated k (or no calibration), ``contact.fallback_probability``:
       the k whose two-sided contact probability ``P(|z| > k sigma) = 2 Q(k)`` equals it (the paper's
       convention, docs/model.md, section "Contact criterion"; said in the source).

    Returns ``(None, "no contact effect")`` without the contact effect. The source names the file, not
    its folder, so datasets of one scene in two folders are identical.

    Raises
    ------
    ValueError
        When none of these gives a k (the message says what to set).
    """
    if not scene.has("contact"):
        return None, "no contact effect"
    if override is not None:
        return float(override), "option k"
    c = scene["contact"]
    if c["k"] is not None:
        return float(c["k"]), "scene (contact.k)"
    fb = c.get("fallback_probability")
    if calibration is not None:
        k = float(calibration["k_calibrated"])
        if np.isfinite(k):
            return k, f"calibration ({calibration_name})"
        if fb is None:
            raise ValueError(f"{calibration_name}: the calibration found no admissible k "
                             f"({calibration.attrs.get('outcome', '')}); set contact.k or contact.fallback_probability")
        k = k_from_probability(fb)
        return k, (f"fallback: no admissible k in {calibration_name}; k = {k:.4f} from contact.fallback_probability "
                   f"= {fb} (two-sided; one-sided {contact_probabilities(k)[1]:.3f})")
    if fb is None:
        raise ValueError("no contact criterion k: set contact.k or contact.fallback_probability (two-sided "
                         "P(|z| > k sigma)), or calibrate the scene (`hdi calibrate`)")
    return k_from_probability(fb), "contact.fallback_probability (two-sided)"


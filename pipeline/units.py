"""The units table: the SI value of every unit a scene key, a dataset or a message uses.

The one place where a unit becomes a number. Scene keys carry their unit in their name
(``flying_height_nm``); :func:`si_factor` maps such a suffix to the factor that turns the key's value
into SI (:func:`pipeline.config.si.to_si` applies it to a whole scene), and datasets divide SI values
by the same constants (:mod:`pipeline.variables`). Physics works in SI only (docs/model.md, section
"Units"); anything else converts at its edge with these names.

This module imports nothing from the package: every layer may use it.
"""

from __future__ import annotations

import math

# lengths [m]
NM = 1e-9
UM = 1e-6
MM = 1e-3
# areas [m^2]
UM2 = UM * UM
# pressures and moduli [Pa]
MPA = 1e6
GPA = 1e9
# forces [N]
MN = 1e-3
# powers [W]: one milliwatt (a heater's power)
MW = 1e-3
# actuation efficiency [m W-1]: one nm of protrusion per mW of heater power
NM_PER_MW = 1e-6
# times [s]
NS = 1e-9
US = 1e-6
MS = 1e-3
# frequencies [Hz]
KHZ = 1e3
MHZ = 1e6
# angles [rad]
URAD = 1e-6
# rotation rate: one revolution per minute [rad/s]
RPM = 2.0 * math.pi / 60.0
# densities: one per square micrometre [m^-2]
PER_UM2 = 1.0 / UM2

# Ratios between two non-SI units, written as exact literals: the quotient of two constants above
# rounds differently (1e-6 / 1e-9 != 1e3 in binary floating point), and results must not change
# with the way a conversion is spelled.
NM_IN_UM = 1e-3             # one nm in um
UM_IN_NM = 1e3              # one um in nm
PER_NM2_IN_PER_UM2 = 1e6    # one nm^-2 in um^-2
PER_UM2_IN_PER_NM2 = 1e-6   # one um^-2 in nm^-2
MHZ_IN_KHZ = 1e3            # one MHz in kHz
S_IN_MS = 1e3               # one s in ms
HZ_IN_KHZ = 1e-3            # one Hz in kHz

#: Unit names of a measured DMW file's columns (pipeline/model/measured_dmw.py) and their factors to
#: [nm] (displacement), [nm/s] (velocity) and [s] (time), exact literals as above.
LENGTH_UNITS = {"nm": 1.0, "um": 1e3, "micron": 1e3, "mm": 1e6, "m": 1e9, "a": 0.1, "angstrom": 0.1}
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "second": 1.0, "seconds": 1.0}
VELOCITY_UNITS = {f"{k}/s": v for k, v in LENGTH_UNITS.items() if k in ("nm", "um", "mm", "m")}

#: SI factor of each unit suffix a scene key may end with (``_nm``, ``_khz``, ...). Dimensionless
#: suffixes (``sigma``: a multiple of the roughness) map to 1.
SUFFIX_FACTORS: dict[str, float] = {
    "nm": NM, "um": UM, "mm": MM, "m": 1.0,
    "gpa": GPA, "mpa": MPA, "pa": 1.0,
    "khz": KHZ, "hz": 1.0, "mhz": MHZ,
    "ms": MS, "us": US, "ns": NS, "s": 1.0,
    "j_m2": 1.0, "n_s_m": 1.0, "n_m": 1.0, "kg_m3": 1.0, "kg": 1.0, "n": 1.0, "mn": MN,
    "mw": MW, "nm_per_mw": NM_PER_MW,
    "per_um2": PER_UM2, "per_m2": 1.0, "rpm": RPM, "sigma": 1.0,
}


#: The CF (UDUNITS) spelling of each unit suffix, for dataset attributes of scene keys (``"j_m2"`` ->
#: ``"J m-2"``); a multiple of the roughness (``sigma``) is dimensionless.
SUFFIX_UNITS: dict[str, str] = {
    "nm": "nm", "um": "um", "mm": "mm", "m": "m",
    "gpa": "GPa", "mpa": "MPa", "pa": "Pa",
    "khz": "kHz", "hz": "Hz", "mhz": "MHz",
    "ms": "ms", "us": "us", "ns": "ns", "s": "s",
    "j_m2": "J m-2", "n_s_m": "N s m-1", "n_m": "N m-1", "kg_m3": "kg m-3", "kg": "kg", "n": "N", "mn": "mN",
    "mw": "mW", "nm_per_mw": "nm mW-1",
    "per_um2": "um-2", "per_m2": "m-2", "rpm": "min-1", "sigma": "1",
}


#: Unit suffixes of an inverse unit, converted to SI by a division by their unit (``x / UM2``: a product by
#: :data:`PER_UM2` rounds otherwise in one value of eight): the one conversion of such a key.
SUFFIX_DIVISORS: dict[str, float] = {"per_um2": UM2}


def to_si_value(value: float, suffix: str) -> float:
    """A number of a scene key with unit suffix ``suffix`` in SI units: times :func:`si_factor`, or divided
    by the unit of an inverse unit (:data:`SUFFIX_DIVISORS`)."""
    divisor = SUFFIX_DIVISORS.get(suffix)
    return value / divisor if divisor is not None else value * si_factor(suffix)


def si_factor(suffix: str) -> float:
    """SI factor of a scene-key unit suffix (``"nm"`` -> 1e-9).

    Raises
    ------
    KeyError
        For a suffix the table does not know (the message lists the known ones).
    """
    try:
        return SUFFIX_FACTORS[suffix]
    except KeyError:
        raise KeyError(f"unit suffix {suffix!r} unknown; expected one of {sorted(SUFFIX_FACTORS)}") from None


def cf_unit(suffix: str | None) -> str:
    """The CF unit of a scene key with this unit suffix (``None``: a key without a unit, ``"1"``)."""
    return "1" if suffix is None else SUFFIX_UNITS[suffix]

"""The declaration of one dataset variable (:class:`Variable`) and the published sources it cites (:class:`Source`).

:mod:`pipeline.variables` declares every output variable with this type (the variable schema); a declaration
gives a variable its CF attributes (:meth:`Variable.attrs`), its NetCDF encoding and the scaling from SI. A
variable computed from a published formula names its sources (:data:`CITATIONS`, by the keys of docs/model.md,
section "References") and the section of docs/model.md that states the formula: its ``references`` attribute
(CF-1.8, section 2.6.2) reads as docs/model.md cites them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Iterable

import numpy as np

if TYPE_CHECKING:
    import xarray as xr

#: The sources datasets cite, by their key in docs/model.md, each as docs/model.md's "References" lists it
#: (``tests/core/test_variables.py`` checks that each is that entry, word for word).
CITATIONS: dict[str, str] = {
    "BKE07": ('V. Brizmer, Y. Kligerman, I. Etsion, "A model for junction growth of a spherical contact under full '
              'stick condition", J. Tribol. 129 (2007) 783-790.'),
    "BT50": "F. P. Bowden, D. Tabor, The Friction and Lubrication of Solids, Clarendon Press, Oxford (1950).",
    "Burgdorfer59": ('A. Burgdorfer, "The influence of the molecular mean free path on the performance of hydrodynamic gas '
                     'lubricated bearings", J. Basic Eng. 81 (1959) 94-100.'),
    "CEB87": ('W. R. Chang, I. Etsion, D. B. Bogy, "An elastic-plastic model for the contact of rough surfaces", J. '
              "Tribol. 109 (1987) 257-263."),
    "Derjaguin34": ('B. V. Derjaguin, "Untersuchungen über die Reibung und Adhäsion, IV", Kolloid-Z. 69 (1934) 155-164 '
                    "(the Derjaguin approximation)."),
    "Filippov88": "A. F. Filippov, Differential Equations with Discontinuous Righthand Sides, Kluwer (1988).",
    "FK90": ('S. Fukui, R. Kaneko, "A database for interpolation of Poiseuille flow rates for high Knudsen number '
             'lubrication problems", J. Tribol. 112 (1990) 78-83.'),
    "Gross62": "W. A. Gross, Gas Film Lubrication, Wiley, New York (1962) (the high-bearing-number limit).",
    "GW66": ('J. A. Greenwood, J. B. P. Williamson, "Contact of nominally flat surfaces", Proc. R. Soc. Lond. A '
             "295 (1966) 300-319."),
    "HJJ00": ('G. Henkelman, G. Jóhannesson, H. Jónsson, "Methods for finding saddle points and minimum energy '
              'paths", in S. D. Schwartz (ed.), Theoretical Methods in Condensed Phase Chemistry, Kluwer (2000) '
              "269-302 (the drag method and where it fails)."),
    "Israelachvili11": "J. N. Israelachvili, Intermolecular and Surface Forces, 3rd ed., Academic Press (2011), ch. 13.",
    "JB07": ('J.-Y. Juang, D. B. Bogy, "Air-bearing effects on actuated thermal pole-tip protrusion for hard disk '
             'drives", J. Tribol. 129 (2007) 570-578 (the actuation efficiency of a thermal protrusion, nm per mW; '
             "the title and pages were not checked against the paper here)."),
    "Johnson85": "K. L. Johnson, Contact Mechanics, Cambridge University Press (1985), eqs. 4.22-4.23.",
    "KE02": ('L. Kogut, I. Etsion, "Elastic-plastic contact analysis of a sphere and a rigid flat", J. Appl. Mech. '
             "69 (2002) 657-662."),
    "KE03": ('L. Kogut, I. Etsion, "A finite element based elastic-plastic model for the contact of rough '
             'surfaces", Tribol. Trans. 46 (2003) 383-390.'),
    "KE04": ('L. Kogut, I. Etsion, "A static friction model for elastic-plastic contacting rough surfaces", J. '
             "Tribol. 126 (2004) 34-40."),
    "LP04": ('S.-C. Lee, A. A. Polycarpou, "Adhesion forces for sub-10 nm flying-height magnetic storage head disk '
             'interfaces", J. Tribol. 126 (2004) 334-341.'),
    "McCool86": 'J. I. McCool, "Comparison of models for the contact of rough surfaces", Wear 107 (1986) 37-60.',
    "Nayak71": 'P. R. Nayak, "Random process model of rough surfaces", J. Lubr. Technol. 93 (1971) 398-407.',
    "SEB90": ('H. M. Stanley, I. Etsion, D. B. Bogy, "Adhesion of contacting rough surfaces in the presence of '
              'sub-boundary lubrication", J. Tribol. 112 (1990) 98-104.'),
    "SP03": ('A. Suh, A. A. Polycarpou, "Adhesion and pull-off forces for polysilicon MEMS surfaces using the '
             'sub-boundary lubrication model", J. Tribol. 125 (2003) 193-199 (cited as the origin of the improved '
             "SBL model; the attribution was not checked against the text here)."),
    "Tabor51": "D. Tabor, The Hardness of Metals, Clarendon Press, Oxford (1951).",
    "Blok37": 'H. Blok, "Theoretical study of temperature rise at surfaces of actual contact under oiliness lubricating conditions", Proc. General Discussion on Lubrication and Lubricants, IMechE, London, 2 (1937) 222-235 (the equal-temperature partition of frictional heat).',
    "TK94": 'X. Tian, F. E. Kennedy, "Maximum and average flash temperatures in sliding contacts", J. Tribol. 116 (1994) 167-174.',
    "VLP09": ('A. I. Vakis, S.-C. Lee, A. A. Polycarpou, "Dynamic head-disk interface instabilities with friction '
              'for light contact (surfing) recording", IEEE Trans. Magn. 45(11) (2009) 4966-4971.'),
    "ZB00": ('Q. H. Zeng, D. B. Bogy, "A simplified 4-DOF suspension model for dynamic load/unload simulation and '
             'its application", J. Tribol. 122 (2000) 274-279 (lumped air-bearing springs).'),
}


@dataclass(frozen=True)
class Source:
    """The published sources of a variable's formula (keys of :data:`CITATIONS`) and the section of
    docs/model.md that states it."""

    keys: tuple[str, ...]
    section: str

    @property
    def text(self) -> str:
        """The ``references`` attribute: each source as docs/model.md lists it, then where docs/model.md uses them."""
        return "; ".join(f"[{k}] {CITATIONS[k].removesuffix('.')}" for k in self.keys) + f' (docs/model.md, section "{self.section}")'


@dataclass(frozen=True)
class Variable:
    """Declaration of one output variable.

    Attributes
    ----------
    name : variable name in the datasets
    units : dataset units (UDUNITS; ``""`` for labels, which have none)
    long_name : CF ``long_name``: a few words, short enough for a plot's axis label (with the units)
    si_unit : SI value of one dataset unit (1e-9 for nm): dataset value = SI value / ``si_unit`` (dividing
        undoes the scene's ``x_nm * 1e-9`` exactly, multiplying by 1e9 would not)
    standard_name : CF standard name, where CF has one
    dims : dimensions beyond the grid of the dataset (e.g. ``(TIME,)`` for histories)
    effect : scene effect producing the variable (``None``: always present)
    dtype : numpy dtype on disk
    flag_values, flag_meanings, flag_masks : for flag variables (values: one code; masks: bits)
    fill_value : declared missing value (``_FillValue``), for integer variables
    extra : further attributes (``rule``, ``formula``, ``axis``, ...)
    description : the ``description`` attribute: the sentence that says what the variable is, where the
        ``long_name`` cannot (``""``: the ``long_name`` says it all)
    references : the published sources of the formula that computes the variable (CF's ``references``
        attribute, :attr:`Source.text`; ``None``: no published formula, e.g. a scene input or a count)
    """

    name: str
    units: str
    long_name: str
    si_unit: float = 1.0
    standard_name: str | None = None
    dims: tuple[str, ...] = ()
    effect: str | None = None
    dtype: str = "float64"
    flag_values: tuple[int, ...] | None = None
    flag_meanings: str | None = None
    flag_masks: tuple[int, ...] | None = None
    fill_value: int | None = None
    extra: tuple[tuple[str, str], ...] = ()
    description: str = ""
    references: Source | None = None

    @property
    def sentence(self) -> str:
        """What the variable is, in full: its :attr:`description`, else its ``long_name``."""
        return self.description or self.long_name

    @property
    def si_factor(self) -> float:
        """Factor from SI to dataset units [dataset unit per SI unit]."""
        return 1.0 / self.si_unit

    def attrs(self) -> dict[str, Any]:
        """CF attributes of the variable (``_FillValue`` goes into the encoding, not here)."""
        a: dict[str, Any] = {"long_name": self.long_name}
        if self.description:
            a["description"] = self.description
        if self.units:
            a["units"] = self.units
        if self.standard_name:
            a["standard_name"] = self.standard_name
        if self.flag_values is not None:
            a["flag_values"] = np.array(self.flag_values, dtype=self.dtype)
            a["flag_meanings"] = self.flag_meanings
        if self.flag_masks is not None:
            a["flag_masks"] = np.array(self.flag_masks, dtype=self.dtype)
            a["flag_meanings"] = self.flag_meanings
        if self.references is not None:
            a["references"] = self.references.text
        a.update(dict(self.extra))
        return a

    def data(self, values: Any, dims: Iterable[str], **attrs: Any) -> xr.Variable:
        """A variable from values already in dataset units (NaN -> fill value for flags)."""
        import xarray as xr  # (here: pipeline.model.ahead.NOT_IMPORTED_EARLY)
        values = self.stored(values)
        if self.dtype == "str":
            return xr.Variable(tuple(dims), values, attrs={**self.attrs(), **attrs})
        return xr.Variable(tuple(dims), values, attrs={**self.attrs(), **attrs}, encoding=self.encoding())

    def from_si(self, values: Any, dims: Iterable[str], **attrs: Any) -> xr.Variable:
        """A variable from SI values (divided by ``si_unit``; flags and labels unscaled)."""
        return self.data(self.scaled(values), dims, **attrs)

    def stored(self, values: Any) -> np.ndarray:
        """The array :meth:`data` holds for ``values`` in dataset units: NaN -> the fill value for flags,
        cast to :attr:`dtype` (``object`` for labels)."""
        values = np.asarray(values)
        if self.fill_value is not None:  # NaN (not computed, or a decoded fill) -> the declared fill
            values = np.where(np.isfinite(values.astype(float)), values, self.fill_value)
        return values.astype(object) if self.dtype == "str" else values.astype(self.dtype)

    def scaled(self, values_si: Any) -> np.ndarray:
        """SI values in dataset units, as :meth:`from_si` takes them (divided by ``si_unit``; flags and
        labels unscaled); :meth:`stored` gives the array a variable then holds."""
        values = np.asarray(values_si)
        if values.dtype.kind in "fiub" and self.si_unit != 1.0:
            values = values / self.si_unit
        return values

    def encoding(self) -> dict[str, Any]:
        """NetCDF encoding of the variable: its declared missing value."""
        return {"_FillValue": np.array(self.fill_value, dtype=self.dtype)} if self.fill_value is not None else {}

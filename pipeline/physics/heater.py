"""The TFC heater's actuation: the bulge's protrusion versus the heater's power, and back.

A drive sets its heater's power, not its protrusion: the thermal actuation raises the pole tip by an amount
close to proportional to the power, the actuation efficiency [JB07], or along a measured (or separately
modelled) curve. This module is the one place where a power becomes a protrusion and a protrusion a power
(docs/model.md, section "Heater power"): a linear law through the origin, or a monotonic table interpolated
piecewise linearly. In SI units: power [W], protrusion [m], efficiency [m W-1].

References
----------
[JB07] J.-Y. Juang, D. B. Bogy, J. Tribol. 129 (2007) 570-578 (the actuation efficiency of a thermal
protrusion, nm per mW); docs/model.md, section "References".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Actuation:
    """Protrusion versus heater power: ``efficiency`` [m W-1] (linear through 0), or the table
    ``power`` [W] -> ``protrusion`` [m] (both strictly increasing; piecewise linear between its rows,
    refused outside them). Build it with :func:`linear` or :func:`tabulated`, which check the numbers.

    References
    ----------
    [JB07] (module docstring).
    """

    efficiency: float | None = None
    power: tuple[float, ...] = ()
    protrusion: tuple[float, ...] = ()

    def protrusion_of(self, power: float | np.ndarray) -> np.ndarray:
        """The protrusion at a heater power.

        Parameters
        ----------
        power : heater power P [W]; within the table's rows for a tabulated actuation

        Returns
        -------
        numpy.ndarray
            Protrusion delta [m]: ``efficiency P``, or the table interpolated linearly.

        Raises
        ------
        ValueError
            A power outside the table's rows (nothing is extrapolated), or a negative power.

        References
        ----------
        [JB07] (module docstring).
        """
        p = np.asarray(power, dtype=float)
        if np.any(p < 0):
            raise ValueError(f"heater power {p.min():g} W is negative: expected a power >= 0")
        if self.efficiency is not None:
            return p * self.efficiency
        _within(p, self.power, "heater power", "W")
        return np.interp(p, self.power, self.protrusion)

    def power_of(self, protrusion: float | np.ndarray) -> np.ndarray:
        """The heater power that gives a protrusion: the inverse of :meth:`protrusion_of`.

        Parameters
        ----------
        protrusion : TFC protrusion delta [m]; within the table's rows for a tabulated actuation

        Returns
        -------
        numpy.ndarray
            Heater power P [W]: ``delta / efficiency``, or the table interpolated linearly the other way.

        Raises
        ------
        ValueError
            A protrusion outside the table's rows, or a negative protrusion.

        References
        ----------
        [JB07] (module docstring).
        """
        d = np.asarray(protrusion, dtype=float)
        if np.any(d < 0):
            raise ValueError(f"protrusion {d.min():g} m is negative: expected a protrusion >= 0")
        if self.efficiency is not None:
            return d / self.efficiency
        _within(d, self.protrusion, "protrusion", "m")
        return np.interp(d, self.protrusion, self.power)


def within(x: float | np.ndarray, rows: tuple[float, ...]) -> bool:
    """Whether every value of ``x`` lies within ``rows[0]``-``rows[-1]`` (a table's column, same unit).

    Parameters
    ----------
    x : values [W] or [m], in the unit of ``rows``
    rows : one column of an actuation table (:attr:`Actuation.power` [W] or :attr:`Actuation.protrusion` [m]),
        increasing

    Returns
    -------
    bool
        Whether no value lies outside the column's first and last rows [-] (an empty ``x``: ``True``).

    References
    ----------
    [JB07] (module docstring): the table is not extrapolated beyond its rows.
    """
    x = np.asarray(x, dtype=float)
    return not x.size or bool(x.min() >= rows[0] and x.max() <= rows[-1])


def _within(x: np.ndarray, rows: tuple[float, ...], what: str, unit: str) -> None:
    """Raise ValueError when a value of ``x`` lies outside ``rows[0]``-``rows[-1]``."""
    if not within(x, rows):
        raise ValueError(f"{what} {x.min():g}-{x.max():g} {unit} lies outside the actuation table's "
                         f"{rows[0]:g}-{rows[-1]:g} {unit}: expected values within its rows (nothing is extrapolated)")


def linear(efficiency: float) -> Actuation:
    """A linear actuation, ``delta = e P``.

    Parameters
    ----------
    efficiency : actuation efficiency e [m W-1] (1 nm/mW = 1e-6 m/W), positive

    Returns
    -------
    Actuation
        The actuation (powers [W], protrusions [m]); its conversions are exact inverses up to rounding.

    Raises
    ------
    ValueError
        A non-positive or non-finite efficiency.

    References
    ----------
    [JB07] (module docstring).
    """
    if not (np.isfinite(efficiency) and efficiency > 0):
        raise ValueError(f"actuation efficiency {efficiency!r} m/W: expected a positive number")
    return Actuation(efficiency=float(efficiency))


def tabulated(power: list[float] | np.ndarray, protrusion: list[float] | np.ndarray) -> Actuation:
    """An actuation from a table of protrusion versus heater power, interpolated linearly.

    Parameters
    ----------
    power : heater powers P [W] of the rows, >= 0 and strictly increasing
    protrusion : protrusions delta [m] at those powers, >= 0 and strictly increasing (a table whose
        protrusion falls or stalls as the power rises has no inverse)

    Returns
    -------
    Actuation
        The tabulated actuation (powers [W], protrusions [m]).

    Raises
    ------
    ValueError
        Fewer than two rows, columns of different lengths, a negative or non-finite value, or a column
        that is not strictly increasing (naming the first row where it is not).

    References
    ----------
    [JB07] (module docstring).
    """
    p, d = np.asarray(power, dtype=float), np.asarray(protrusion, dtype=float)
    if p.ndim != 1 or p.shape != d.shape or p.size < 2:
        raise ValueError(f"actuation table: {p.size} powers and {d.size} protrusions: expected two columns of "
                         "the same length, at least 2 rows")
    for name, col in (("power", p), ("protrusion", d)):
        if not np.all(np.isfinite(col)) or np.any(col < 0):
            raise ValueError(f"actuation table: a {name} is negative or not finite: expected finite numbers >= 0")
        steps = np.flatnonzero(np.diff(col) <= 0)
        if steps.size:
            i = int(steps[0]) + 1
            raise ValueError(f"actuation table: {name} is not strictly increasing at row {i + 1} of {col.size} "
                             "(not above the row before it): expected a monotonic table")
    return Actuation(power=tuple(p.tolist()), protrusion=tuple(d.tolist()))

"""Unit conversion to the internal units: inch, second, pound-force, and back to SI.

The original study worked in in, in/s, in/s^2 and lbf, so every number that leaves
the reader for the analysis is expressed in those units. Campaign files may use any
unit listed in campaign-format.md; this module knows the exact factors. Results are
shown in those units or, with config ``units: si``, in SI (:data:`UNIT_SYSTEMS`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "METRE_IN",
    "STANDARD_GRAVITY_IN_S2",
    "NEWTON_LBF",
    "RESPONSE_QUANTITIES",
    "RESPONSE_UNITS",
    "normalize_unit",
    "known_units",
    "response_quantity_of",
    "factor_to_internal",
    "to_internal",
    "velocity_amplitude_in_s",
    "INCH_M",
    "LBF_N",
    "UnitSystem",
    "INCH_SECOND",
    "SI",
    "UNIT_SYSTEMS",
    "SI_TWIN_COLUMNS",
    "MODEL_PARAMETER_UNITS",
    "response_in_units",
]


METRE_IN: float = 1.0 / 0.0254
"""Inches in one metre (the inch is defined as exactly 0.0254 m)."""

STANDARD_GRAVITY_IN_S2: float = 9.80665 / 0.0254
"""Standard gravity g in in/s^2 (9.80665 m/s^2 exactly; about 386.0886)."""

NEWTON_LBF: float = 1.0 / (0.45359237 * 9.80665)
"""Pound-force in one newton (1 lbf = 0.45359237 kg * 9.80665 m/s^2 exactly)."""

RESPONSE_QUANTITIES: tuple[str, ...] = ("acceleration", "velocity", "displacement")
"""Response quantities a campaign may record."""

_FACTORS_TO_INTERNAL: dict[str, dict[str, float]] = {
    "acceleration": {"g": STANDARD_GRAVITY_IN_S2, "m/s^2": METRE_IN, "in/s^2": 1.0, "mm/s^2": METRE_IN / 1e3},
    # laser vibrometers and displacement probes often record in mm/s, mm or um
    "velocity": {"m/s": METRE_IN, "in/s": 1.0, "mm/s": METRE_IN / 1e3},
    "displacement": {"m": METRE_IN, "in": 1.0, "mm": METRE_IN / 1e3, "um": METRE_IN / 1e6},
    "force": {"lbf": 1.0, "N": NEWTON_LBF},
}

RESPONSE_UNITS: tuple[str, ...] = tuple(
    unit for quantity in RESPONSE_QUANTITIES for unit in _FACTORS_TO_INTERNAL[quantity]
)
"""Canonical units of every response quantity, in the quantities' order."""

# Spellings seen in instrument exports, mapped to the canonical names above.
# Keys are lower-case with spaces removed; "G" for g is an accelerometer convention.
_ALIASES: dict[str, str] = {
    "g": "g",
    "gs": "g",
    "m/s^2": "m/s^2",
    "m/s2": "m/s^2",
    "m/s/s": "m/s^2",
    "ms^-2": "m/s^2",
    "in/s^2": "in/s^2",
    "in/s2": "in/s^2",
    "in/s/s": "in/s^2",
    "mm/s^2": "mm/s^2",
    "mm/s2": "mm/s^2",
    "mm/s/s": "mm/s^2",
    "m/s": "m/s",
    "ms^-1": "m/s",
    "mm/s": "mm/s",
    "in/s": "in/s",
    "ips": "in/s",
    "m": "m",
    "mm": "mm",
    "um": "um",
    "µm": "um",
    "μm": "um",
    "micron": "um",
    "microns": "um",
    "in": "in",
    "inch": "in",
    "lbf": "lbf",
    "lb": "lbf",
    "lbs": "lbf",
    "n": "N",
    "newton": "N",
    "newtons": "N",
}


def normalize_unit(unit: str) -> str:
    """Canonical spelling of a unit name (``"m/s2"`` -> ``"m/s^2"``, ``"N"`` -> ``"N"``).

    Parameters
    ----------
    unit : str
        A unit as written in campaign.yaml or a column name, e.g. ``"m/s²"``.

    Returns
    -------
    str
        The canonical name used by this module, or the input with spaces removed
        when the unit is not known (callers then report it).
    """
    compact = unit.strip().replace(" ", "").replace("²", "^2").replace("**", "^")
    return _ALIASES.get(compact.lower(), compact)


def known_units(quantity: str) -> tuple[str, ...]:
    """Canonical units accepted for ``quantity`` (a response quantity or ``"force"``)."""
    if quantity not in _FACTORS_TO_INTERNAL:
        raise ValueError(f"unknown quantity {quantity!r}; expected one of {', '.join(_FACTORS_TO_INTERNAL)}")
    return tuple(_FACTORS_TO_INTERNAL[quantity])


def response_quantity_of(unit: str) -> str | None:
    """The response quantity whose unit ``unit`` (canonical) is, or None for no response unit.

    >>> response_quantity_of("g"), response_quantity_of("m/s"), response_quantity_of("N")
    ('acceleration', 'velocity', None)
    """
    for quantity in RESPONSE_QUANTITIES:
        if unit in _FACTORS_TO_INTERNAL[quantity]:
            return quantity
    return None


def factor_to_internal(quantity: str, unit: str) -> float:
    """Multiplier taking values of ``quantity`` in ``unit`` to the internal unit.

    Parameters
    ----------
    quantity : str
        ``"acceleration"``, ``"velocity"``, ``"displacement"`` or ``"force"``.
    unit : str
        Unit of the values (any spelling :func:`normalize_unit` understands).

    Returns
    -------
    float
        Factor to in/s^2, in/s, in or lbf.

    Raises
    ------
    ValueError
        For an unknown quantity or a unit that does not belong to the quantity;
        the message names both.
    """
    units = _FACTORS_TO_INTERNAL.get(quantity)
    if units is None:
        raise ValueError(
            f"unknown quantity {quantity!r} (with unit {unit!r}); expected one of "
            f"{', '.join(_FACTORS_TO_INTERNAL)}"
        )
    canonical = normalize_unit(unit)
    if canonical not in units:
        raise ValueError(f"unit {unit!r} is not a unit of {quantity}; expected one of {', '.join(units)}")
    return units[canonical]


def to_internal(values: ArrayLike, quantity: str, unit: str) -> NDArray[np.float64]:
    """Convert values to the internal unit of their quantity.

    Parameters
    ----------
    values : array_like
        Values in ``unit``.
    quantity : str
        ``"acceleration"``, ``"velocity"``, ``"displacement"`` or ``"force"``.
    unit : str
        g, m/s^2, in/s^2, m/s, in/s, m, in, lbf or N.

    Returns
    -------
    ndarray
        Values in in/s^2, in/s, in or lbf.

    Raises
    ------
    ValueError
        Unknown unit/quantity combination (the message names it).
    """
    return np.asarray(values, dtype=np.float64) * factor_to_internal(quantity, unit)


def velocity_amplitude_in_s(
    amplitude: ArrayLike, quantity: str, unit: str, frequency_hz: ArrayLike
) -> NDArray[np.float64]:
    """Velocity amplitude (in/s) of a harmonic with the given response amplitude.

    For a harmonic at angular frequency w = 2 pi f, velocity amplitude is the
    acceleration amplitude / w, or the displacement amplitude * w.

    Parameters
    ----------
    amplitude : array_like
        Amplitude of the response in ``unit``.
    quantity : str
        ``"acceleration"``, ``"velocity"`` or ``"displacement"``.
    unit : str
        Unit of ``amplitude``.
    frequency_hz : array_like
        Frequency of the harmonic in Hz (broadcast against ``amplitude``; must be > 0).

    Returns
    -------
    ndarray
        Velocity amplitude in in/s.

    Raises
    ------
    ValueError
        Unknown quantity/unit, or a frequency that is zero or negative.

    Examples
    --------
    An acceleration amplitude of 1 g at 50 Hz:

    >>> velocity_amplitude_in_s([1.0, 2.0], "acceleration", "g", 50.0).round(4).tolist()
    [1.229, 2.4579]
    """
    if quantity not in RESPONSE_QUANTITIES:
        raise ValueError(
            f"unknown response quantity {quantity!r} (with unit {unit!r}); expected one of "
            f"{', '.join(RESPONSE_QUANTITIES)}"
        )
    internal = to_internal(amplitude, quantity, unit)
    if quantity == "velocity":
        return internal
    frequency = np.asarray(frequency_hz, dtype=np.float64)
    if np.any(frequency <= 0.0):
        raise ValueError(f"frequency must be positive to convert {quantity} to velocity")
    omega_rad_s = 2.0 * math.pi * frequency
    if quantity == "acceleration":
        return internal / omega_rad_s
    return internal * omega_rad_s


INCH_M: float = 0.0254
"""Metres in one inch (exact)."""

LBF_N: float = 0.45359237 * 9.80665
"""Newtons in one pound-force (exact: 0.45359237 kg times standard gravity)."""


@dataclass(frozen=True)
class UnitSystem:
    """The units results are shown in (config ``units``), and the factors from the
    analysis's own inch-pound-second units to them.

    Attributes
    ----------
    name : str
        ``inch-second`` or ``si``.
    velocity, length, area, force : str
        Unit labels for axes and sentences (``in/s``, ``in``, ``in²``, ``lbf`` or
        ``m/s``, ``m``, ``m²``, ``N``).
    per_in_s, per_in, per_in2, per_lbf : float
        Value in this system of 1 in/s, 1 in, 1 in², 1 lbf.
    """

    name: str
    velocity: str
    length: str
    area: str
    force: str
    per_in_s: float
    per_in: float
    per_in2: float
    per_lbf: float


INCH_SECOND = UnitSystem("inch-second", "in/s", "in", "in²", "lbf", 1.0, 1.0, 1.0, 1.0)
"""The paper's units, in which the analysis works and the contract's columns are written."""

SI = UnitSystem("si", "m/s", "m", "m²", "N", INCH_M, INCH_M, INCH_M**2, LBF_N)
"""SI: m/s, m, m², N (frequencies stay in Hz)."""

UNIT_SYSTEMS: dict[str, UnitSystem] = {system.name: system for system in (INCH_SECOND, SI)}
"""Config ``units`` value -> unit system."""

SI_TWIN_COLUMNS: dict[str, tuple[str, str, float]] = {
    "velocity_amplitude_in_s": ("velocity_amplitude_m_s", "m/s", INCH_M),
    "amplitude_low_in_s": ("amplitude_low_m_s", "m/s", INCH_M),
    "amplitude_high_in_s": ("amplitude_high_m_s", "m/s", INCH_M),
    "bearing_area_in2": ("bearing_area_m2", "m^2", INCH_M**2),
}
"""Inch-second table column -> (its SI twin's name, the twin's unit, factor to it)."""

MODEL_PARAMETER_UNITS: dict[str, tuple[str, str, float]] = {
    "sigma": ("lbf/in", "N/m", LBF_N / INCH_M),
    "sigma0": ("lbf/in", "N/m", LBF_N / INCH_M),
    "fc": ("lbf", "N", LBF_N),
    "alpha0": ("lbf", "N", LBF_N),
    "alpha1": ("lbf", "N", LBF_N),
    "sigma1": ("lbf s/in", "N s/m", LBF_N / INCH_M),
    "alpha2": ("lbf s/in", "N s/m", LBF_N / INCH_M),
    "v0": ("in/s", "m/s", INCH_M),
    "vd": ("in/s", "m/s", INCH_M),
    "zeta0": ("1", "1", 1.0),
    "omega_rad_s": ("rad/s", "rad/s", 1.0),
    "f_linear_hz": ("Hz", "Hz", 1.0),
}
"""Dahl / LuGre parameter (results/tables/model_fits.parquet) -> (unit as fitted, SI
unit, factor to SI)."""


_SI_RESPONSE_UNITS: dict[str, str] = {"acceleration": "m/s²", "velocity": "m/s", "displacement": "m"}


def response_in_units(
    values: ArrayLike, quantity: str, unit: str, units: UnitSystem
) -> tuple[NDArray[np.float64], str]:
    """A recorded response as shown in ``units``: SI converts it (g -> m/s², in/s -> m/s,
    in -> m); the inch-second system keeps the campaign's own unit.

    Returns
    -------
    (ndarray, str)
        The values and their unit label.

    Examples
    --------
    >>> values, label = response_in_units([1.0], "acceleration", "g", SI)
    >>> round(float(values[0]), 5), label
    (9.80665, 'm/s²')
    >>> response_in_units([2.0], "acceleration", "g", INCH_SECOND)[1]
    'g'
    """
    if units.name != "si":
        return np.asarray(values, dtype=np.float64), unit
    return to_internal(values, quantity, unit) * INCH_M, _SI_RESPONSE_UNITS[quantity]

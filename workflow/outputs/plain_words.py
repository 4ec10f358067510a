"""Numbers a reader can act on: fractions as percentages, fitted parameters by what they
mean, which of them the data do not determine, and when a number says little.

Pure functions shared by the verdict page, its first page in the report and the figures.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping

from workflow.io.units import INCH_SECOND, UnitSystem

__all__ = [
    "percent_of",
    "PARAMETER_WORDS",
    "parameter_words",
    "unidentified_parameters",
    "unidentified_sentence",
    "uncertainty_note",
    "LEFT_OUT_SAYS_LITTLE",
    "left_out_caveat",
]


def percent_of(fraction: float) -> str:
    """A fraction (0-1) as a percentage a reader reads at once: ``1.0`` -> ``100 %``,
    ``0.987`` -> ``98.7 %``, ``0.004`` -> ``0.4 %``.

    Examples
    --------
    >>> percent_of(1.0), percent_of(0.987), percent_of(0.5), percent_of(0.004)
    ('100 %', '98.7 %', '50 %', '0.4 %')
    """
    value = 100 * float(fraction)
    if not math.isfinite(value):
        return "–"
    text = f"{value:.1f}".rstrip("0").rstrip(".") if abs(value) >= 1 else f"{value:.2g}"
    return f"{text} %"


#: The averaged models' parameters (workflow.models.averaged) in words.
PARAMETER_WORDS: dict[str, str] = {
    "f_lin_hz": "the small-amplitude natural frequency",
    "zeta0": "the linear viscous damping",
    "joint_stiffness_fraction": "the joint's share of the modal stiffness",
    "slip_velocity_in_s": "the amplitude at which the joint slips",
    "stiction_ratio": "the stiction-to-friction ratio (LuGre α1/α0)",
    "stribeck_velocity_in_s": "the Stribeck velocity (LuGre v0)",
    "micro_damping_ratio": "the bristle damping (LuGre σ1) relative to the linear damping",
    "chi": "the power-law exponent of the slip thresholds",
    "macro_ratio": "the macro-slip stiffness ratio",
    "quadratic_zeta_per_in_s": "the quadratic (velocity-squared) damping",
    "stiffness_shift": "the amplitude-dependent stiffness change",
    "stiffness_exponent": "the power of amplitude of the stiffness change",
    "drift": "the drift of the friction limit with run order",
}


def parameter_words(name: str) -> str:
    """A fitted parameter's name in words (its own name when it is not a known one).

    Examples
    --------
    >>> parameter_words("micro_damping_ratio")
    'the bristle damping (LuGre σ1) relative to the linear damping'
    >>> parameter_words("stiffness_fraction_cell_1")
    'the stiffness share of slip-threshold cell 1 (cell 1 = the lowest thresholds)'
    """
    cell = re.fullmatch(r"stiffness_fraction_cell_(\d+)", name)
    if cell:
        return f"the stiffness share of slip-threshold cell {cell[1]} (cell 1 = the lowest thresholds)"
    return PARAMETER_WORDS.get(name, name)


_FLAG = re.compile(
    r"^(?P<name>\w+) = (?P<value>\S+) at (?:the (?P<side>lower|upper) edge of its fit range|its physical limit)"
)


def _value_text(name: str, value: float, units: UnitSystem) -> str:
    """A parameter's value with its unit: amplitudes in ``units``, ratios bare."""
    if name.endswith("_in_s") and not name.startswith("quadratic"):
        return f"{value * units.per_in_s:.3g} {units.velocity}"
    if name == "quadratic_zeta_per_in_s":
        return f"{value / units.per_in_s:.3g} per {units.velocity}"
    if name == "f_lin_hz":
        return f"{value:.5g} Hz"
    return f"{value:.3g}"


def unidentified_parameters(
    fits: Iterable[tuple[str, Mapping | None]], units: UnitSystem = INCH_SECOND
) -> list[dict]:
    """The fitted parameters the data do not determine, each once.

    Parameters
    ----------
    fits : iterable of (role, fit)
        ``("the baseline", entry["baseline"])``, ``("the extended model",
        entry["extended_model"])``: each fit's ``flags`` (diagnosis.json) name the
        parameters that ended on an edge of their fit range or at their physical limit.
    units : UnitSystem
        Units of the values shown.

    Returns
    -------
    list of dict
        ``name``, ``words`` (:func:`parameter_words`), ``value`` (text with unit),
        ``where`` ("lower edge", "upper edge", "physical limit"), ``roles`` (the fits
        flagging it, in order); flags of another form are kept whole as ``words``.
    """
    found: dict[tuple[str, str], dict] = {}
    for role, fit in fits:
        for flag in (fit or {}).get("flags") or []:
            match = _FLAG.match(flag)
            if not match:
                key = (flag, "")
                found.setdefault(key, {"name": flag, "words": flag, "value": "", "where": "", "roles": []})
            else:
                name = match["name"]
                where = f"{match['side']} edge" if match["side"] else "physical limit"
                key = (name, where)
                value = _value_text(name, float(match["value"]), units)
                found.setdefault(
                    key,
                    {
                        "name": name,
                        "words": parameter_words(name),
                        "value": value,
                        "where": where,
                        "roles": [],
                    },
                )
            if role not in found[key]["roles"]:
                found[key]["roles"].append(role)
    return list(found.values())


def unidentified_sentence(parameters: list[dict]) -> str | None:
    """One sentence naming every parameter the data do not determine, or None.

    Examples
    --------
    >>> unidentified_sentence([{"name": "stiction_ratio", "words": "the stiction ratio",
    ...     "value": "3", "where": "upper edge", "roles": ["the baseline", "the extended model"]}])
    'Not determined by these data: the stiction ratio (the baseline and the extended model: 3, the upper edge of the range the fit may take). The fit stopped at that edge: the value is a bound, not a measurement.'
    """
    if not parameters:
        return None
    parts = []
    physical = False
    for p in parameters:
        if not p["where"]:
            parts.append(p["words"])
            continue
        physical |= p["where"] == "physical limit"
        roles = " and ".join(p["roles"])
        edge = (
            "its physical limit"
            if p["where"] == "physical limit"
            else f"the {p['where']} of the range the fit may take"
        )
        parts.append(f"{p['words']} ({roles}: {p['value']}, {edge})")
    text = "Not determined by these data: " + "; ".join(parts) + "."
    text += (
        " The fit stopped at that edge: the value is a bound, not a measurement."
        if len(parts) == 1
        else " The fits stopped at those edges: the values are bounds, not measurements."
    )
    if physical:
        text += (
            " At a physical limit the data ask for more than a lap joint's contact can give "
            "(docs/discovery.md, fit ranges)."
        )
    return text


def uncertainty_note(value: float, std: float) -> str:
    """What a linearised uncertainty says of its value, in words ('' when it is ordinary).

    Examples
    --------
    >>> uncertainty_note(0.3504, 27.0)
    'not determined: the uncertainty exceeds the value'
    >>> uncertainty_note(5.382, 0.0)
    'not determined: the fit does not change with it (zero sensitivity)'
    >>> uncertainty_note(39.5, 0.4)
    ''
    """
    if std is None or not math.isfinite(std) or value is None or not math.isfinite(value):
        return ""
    if std == 0:
        return "not determined: the fit does not change with it (zero sensitivity)"
    if std >= abs(value):
        return "not determined: the uncertainty exceeds the value"
    return ""


LEFT_OUT_SAYS_LITTLE = 10.0
"""A left-out bearing area predicted worse than this many scatters by both models: neither
predicts it, and the ratio of their errors says little."""


def left_out_caveat(errors: Iterable[float | None]) -> str | None:
    """The caveat on the across-configuration prediction when both models miss every
    left-out configuration by more than :data:`LEFT_OUT_SAYS_LITTLE` scatters.

    ``errors``: both models' errors on each left-out configuration (scatters).

    Examples
    --------
    >>> left_out_caveat([1730.0, 1142.0, 25.0, 30.0])
    'Both predictions miss every left-out configuration by more than 25 times the measured scatter: neither model predicts a new bearing area, and the ratio of their errors says little.'
    >>> left_out_caveat([1.2, 3.0]) is None
    True
    """
    finite = [float(e) for e in errors if e is not None and math.isfinite(float(e))]
    if not finite or min(finite) <= LEFT_OUT_SAYS_LITTLE:
        return None
    return (
        f"Both predictions miss every left-out configuration by more than {min(finite):.3g} "
        "times the measured scatter: neither model predicts a new bearing area, and the "
        "ratio of their errors says little."
    )

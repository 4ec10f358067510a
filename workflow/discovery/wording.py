"""Wording of the diagnosis: sizes in scatters (as the residual figure draws them) and as
percentages, and the sentence that says where and by how much the baseline is wrong (or
why it is not)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from workflow.discovery.misfit import EXPLAINS_LIMIT
from workflow.io.units import INCH_SECOND, UnitSystem

__all__ = [
    "two_digits",
    "format_percent",
    "scatters_words",
    "runs_words",
    "statistic_words",
    "discrepancy_sentence",
]


def _span(low_in_s: float, high_in_s: float, units: UnitSystem, joiner: str = "-") -> str:
    """``0.465-1.47 in/s``: amplitudes given in in/s, shown in ``units``."""
    return f"{units.per_in_s * low_in_s:.3g}{joiner}{units.per_in_s * high_in_s:.3g} {units.velocity}"


def two_digits(value: float) -> str:
    """A number to two significant digits without exponent, never rounded to zero.

    Examples
    --------
    >>> two_digits(-0.0042), two_digits(31.4), two_digits(1234.0), two_digits(0.0)
    ('-0.0042', '31', '1200', '0')
    """
    if value == 0 or not np.isfinite(value):
        return f"{value:g}"
    rounded = float(f"{value:.2g}")
    decimals = max(0, 1 - int(np.floor(np.log10(abs(rounded)))))
    return f"{rounded:.{decimals}f}"


def format_percent(value_percent: float) -> str:
    """A signed percentage to two significant digits, never rounded to zero.

    ``-0.0042`` gives ``"-0.0042 %"``, ``31.4`` gives ``"+31 %"``; exactly zero gives ``"0 %"``.

    Examples
    --------
    >>> format_percent(-0.0042), format_percent(31.4), format_percent(0.0)
    ('-0.0042 %', '+31 %', '0 %')
    """
    if value_percent == 0 or not np.isfinite(value_percent):
        return f"{value_percent:g} %"
    text = two_digits(value_percent)
    return f"{text if text.startswith('-') else '+' + text} %"


def scatters_words(value: float, signed: bool = False) -> str:
    """A binned mean residual in units of the measured scatter, as the residual figure
    draws it: ``2.6 scatters`` (``+2.6 scatters`` when ``signed``).

    Examples
    --------
    >>> scatters_words(-7.46), scatters_words(2.61, signed=True), scatters_words(1.0)
    ('7.5 scatters', '+2.6 scatters', '1.0 scatters')
    """
    text = two_digits(value if signed else abs(value))
    if signed and value > 0:
        text = "+" + text
    return f"{text} scatters"


def _misfit_percent(curve: str, mean: float) -> float:
    """A bin's mean residual as a percentage of the model: damping residuals are in
    ln zeta, frequency residuals relative."""
    return 100 * float(np.expm1(mean)) if curve == "damping" else 100 * float(mean)


def _misfit_words(model_name: str, row: Mapping, units: UnitSystem) -> str:
    """``the measured damping lies 2.6 scatters (4.7 %) below the lugre fit at 1-3.2 in/s``:
    the bin's mean as the residual figure draws it (in scatters, its side), then as a
    percentage of the model."""
    scaled = row["mean_over_scatter"]
    side = "above" if scaled > 0 else "below" if scaled < 0 else "on"
    size = format_percent(_misfit_percent(row["curve"], row["mean"])).lstrip("+-")
    return (
        f"the measured {row['curve']} lies {scatters_words(scaled)} ({size}) {side} the "
        f"{model_name} fit at {_span(row['v_low_in_s'], row['v_high_in_s'], units)}"
    )


def runs_words(n_runs: int) -> str:
    """``1 run``, ``8 runs``."""
    return f"{n_runs} run{'' if n_runs == 1 else 's'}"


def statistic_words(row: Mapping) -> str:
    """The t test behind a bin's verdict: ``|t|``, over what, ``p`` and its corrected limit.

    ``|t|`` is quoted with its ``p``, which decides (:func:`~workflow.discovery.misfit.misfit_significant`):
    the same ``|t|`` is clearer over many runs than over three. With one run the
    segments are the observations.

    Examples
    --------
    >>> statistic_words({"t": -6.49, "n_runs": 3, "p": 0.0013, "p_limit": 0.00083})
    '|t| = 6.5 over 3 runs, p = 0.0013 against 0.00083 after correction'
    >>> statistic_words({"t": 11.0, "n_runs": 1, "n_segments": 40, "p": 1e-9, "p_limit": 1e-3})
    '|t| = 11.0 over the 40 segments of the one run, p = 1e-09 against 0.001 after correction'
    """
    over = (
        f"the {row.get('n_segments', '?')} segments of the one run"
        if row["n_runs"] == 1
        else runs_words(row["n_runs"])
    )
    return f"|t| = {abs(row['t']):.1f} over {over}, p = {row['p']:.2g} against {row['p_limit']:.2g} after correction"


def _judgement(row: Mapping) -> str:
    """Why a bin is not a misfit: which half of
    :func:`~workflow.discovery.misfit.misfit_significant` it fails."""
    tolerance = _misfit_percent(row["curve"], row["tolerance"])
    clear = row["p"] < row["p_limit"]
    small = abs(row["mean"]) <= row["tolerance"]
    statistic = statistic_words(row)
    accuracy = f"the {abs(tolerance):.2g} % in {row['curve']} the models are accurate to"
    if clear and small:
        return (
            f"statistically clear ({statistic}) but physically negligible: smaller than {accuracy} "
            f"({abs(row['mean']) / row['tolerance']:.2g} of it)"
        )
    if small:
        return f"neither statistically significant ({statistic}) nor larger than {accuracy}"
    return f"larger than {accuracy} but not statistically significant ({statistic})"


def _negligible_misfit_words(model_name: str, row: Mapping, lead: str, units: UnitSystem) -> str:
    """``LEAD, where the measured damping lies ... , is JUDGEMENT``."""
    return f"{lead}, where {_misfit_words(model_name, row, units)}, is {_judgement(row)}"


def _largest(rows: list[Mapping]) -> Mapping:
    """The bin the residual figure shows furthest from zero (its binned mean in scatters)."""
    return max(rows, key=lambda b: abs(b["mean_over_scatter"]))


def _significant_words(model_name: str, curve: str, significant: list[Mapping], units: UnitSystem) -> str:
    """``the measured damping differs from the lugre fit between A and B, by up to ... at ...``:
    the bin furthest from zero on each side the significant bins lie (the figure's
    markers above and below zero), the larger first."""
    lo = min(b["v_low_in_s"] for b in significant)
    hi = max(b["v_high_in_s"] for b in significant)
    sides = [
        _largest(side)
        for side in (
            [b for b in significant if b["mean_over_scatter"] > 0],
            [b for b in significant if b["mean_over_scatter"] <= 0],
        )
        if side
    ]
    sides.sort(key=lambda b: -abs(b["mean_over_scatter"]))

    def size(row: Mapping) -> str:
        return (
            f"{scatters_words(row['mean_over_scatter'], signed=True)} "
            f"({format_percent(_misfit_percent(curve, row['mean']))}; {statistic_words(row)})"
        )

    if len(significant) == 1:
        where = f"at {_span(lo, hi, units)}, by {size(sides[0])}"
    else:
        where = f"between {_span(lo, hi, units, ' and ')}, by up to " + " and ".join(
            f"{size(row)} at {_span(row['v_low_in_s'], row['v_high_in_s'], units)}" for row in sides
        )
    return f"the measured {curve} differs from the {model_name} fit {where}"


def discrepancy_sentence(
    model_name: str,
    bins: list[dict],
    trend: dict | None,
    n_runs: int,
    units: UnitSystem = INCH_SECOND,
) -> str:
    """Plain sentence: where and by how much the model is wrong (or that it is not), in
    damping and in frequency, in the numbers the residual figure draws.

    Every bin is quoted by its binned mean in units of the measured scatter
    (``mean_over_scatter``, the mean the residual figure draws for that half decade) and
    as a percentage of the model (two significant digits, so that a misfit that is not
    zero never reads as ``0.00 %``), with its side in words. A misfit is significant by
    :func:`~workflow.discovery.misfit.misfit_significant` (statistically clear and larger
    than the models' accuracy). Each curve is named: where it has significant bins, their
    range and the one furthest from zero (on each side of zero where they lie on both), then the furthest of its other bins when that
    one lies outside the figure's ±2 scatter band (:data:`~workflow.discovery.misfit.EXPLAINS_LIMIT`),
    said not significant and why; where it has none, its bin furthest from zero and
    which half of the rule that bin fails. So the figure's largest excursion of each
    curve is always named, significant or not. Amplitudes (``v_low_in_s``,
    ``v_high_in_s`` of the bins, in/s) are shown in ``units``.

    Examples
    --------
    >>> discrepancy_sentence("dahl", [], None, 8)
    "No misfit of the dahl baseline is significant (statistically clear and larger than the models' accuracy) in damping or in frequency (8 runs)."
    """
    parts, quiet = [], []
    for curve in ("damping", "frequency"):
        rows = [b for b in bins if b["curve"] == curve]
        significant = [b for b in rows if b["significant"]]
        if not significant:
            if rows:
                quiet.append(_largest(rows))
            continue
        parts.append(_significant_words(model_name, curve, significant, units))
        off_band = [b for b in rows if not b["significant"] and abs(b["mean_over_scatter"]) > EXPLAINS_LIMIT]
        if off_band:
            parts.append(
                _negligible_misfit_words(
                    model_name,
                    _largest(off_band),
                    f"the largest {curve} misfit that is not significant",
                    units,
                )
            )
    if trend is not None and trend["significant"]:
        parts.append(
            f"the runs' damping curve shifts with run order ({trend['order']}) by "
            f"{format_percent(_misfit_percent('damping', trend['change_over_sequence']))} from the "
            f"first to the last run where the shift is largest (t = {trend['t']:.1f})"
        )
    if not parts:
        tail = "".join(
            "; " + _negligible_misfit_words(model_name, row, f"its largest {row['curve']} misfit", units)
            for row in quiet
        )
        return (
            f"No misfit of the {model_name} baseline is significant (statistically clear and larger "
            f"than the models' accuracy) in damping or in frequency ({runs_words(n_runs)}){tail}."
        )
    parts += [
        _negligible_misfit_words(model_name, row, f"its largest {row['curve']} misfit", units)
        for row in quiet
    ]
    text = "; ".join(parts)
    return text[0].upper() + text[1:] + "."

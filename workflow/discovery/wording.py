"""Wording of the diagnosis: sizes as percentages, and the sentence that says where and by
how much the baseline is wrong (or why it is not)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from workflow.io.units import INCH_SECOND, UnitSystem

__all__ = ["format_percent", "runs_words", "statistic_words", "discrepancy_sentence"]


def _span(low_in_s: float, high_in_s: float, units: UnitSystem, joiner: str = "-") -> str:
    """``0.465-1.47 in/s``: amplitudes given in in/s, shown in ``units``."""
    return f"{units.per_in_s * low_in_s:.3g}{joiner}{units.per_in_s * high_in_s:.3g} {units.velocity}"


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
    rounded = float(f"{value_percent:.2g}")
    decimals = max(0, 1 - int(np.floor(np.log10(abs(rounded)))))
    return f"{rounded:+.{decimals}f} %"


def _misfit_percent(curve: str, mean: float) -> float:
    """A bin's mean residual as a percentage of the model: damping residuals are in
    ln zeta, frequency residuals relative."""
    return 100 * float(np.expm1(mean)) if curve == "damping" else 100 * float(mean)


def _misfit_words(model_name: str, row: Mapping, units: UnitSystem) -> str:
    """``the measured damping lies 4.2 % above the lugre fit at 1-3.2 in/s``."""
    size = _misfit_percent(row["curve"], row["mean"])
    side = "above" if size > 0 else "below" if size < 0 else "on"
    return (
        f"the measured {row['curve']} lies {format_percent(size).lstrip('+-')} {side} the "
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


def discrepancy_sentence(
    model_name: str,
    bins: list[dict],
    trend: dict | None,
    n_runs: int,
    units: UnitSystem = INCH_SECOND,
) -> str:
    """Plain sentence: where and by how much the model is wrong (or that it is not), in
    damping and in frequency.

    Sizes are percentages of the model (two significant digits, so that a misfit that
    is not zero never reads as ``0.00 %``), with their direction in words. A misfit is
    significant by :func:`~workflow.discovery.misfit.misfit_significant` (statistically
    clear and larger than the models' accuracy). Each curve is named: where it has
    significant bins, their range and the largest, then the largest bin outside that range
    that exceeds the models' accuracy without being significant (so that a residual figure
    showing a large misfit there is not contradicted); where it has none, its largest bin by
    ``|t|`` and which half of the rule that bin fails, so that a large but uncertain
    misfit in one curve is not left out beside a significant one in the other.
    Amplitudes (``v_low_in_s``, ``v_high_in_s`` of the bins, in/s) are shown in ``units``.

    Examples
    --------
    >>> discrepancy_sentence("dahl", [], None, 8)
    "The dahl baseline fits damping and frequency at every amplitude to within the run-to-run scatter or the models' accuracy (8 runs)."
    """
    parts, quiet = [], []
    for curve in ("damping", "frequency"):
        rows = [b for b in bins if b["curve"] == curve]
        sig = [b for b in rows if b["significant"]]
        if not sig:
            if rows:
                quiet.append(max(rows, key=lambda b: abs(b["t"])))
            continue
        lo = min(b["v_low_in_s"] for b in sig)
        hi = max(b["v_high_in_s"] for b in sig)
        worst = max(sig, key=lambda b: abs(b["mean"]))
        size = f"{format_percent(_misfit_percent(curve, worst['mean']))} ({statistic_words(worst)})"
        if len(sig) == 1:
            where = f"at {_span(lo, hi, units)}, by {size}"
        else:
            where = (
                f"between {_span(lo, hi, units, ' and ')}, by up to {size} "
                f"at {_span(worst['v_low_in_s'], worst['v_high_in_s'], units)}"
            )
        parts.append(f"the measured {curve} differs from the {model_name} fit {where}")
        outside = [
            b
            for b in rows
            if (b["v_high_in_s"] <= lo or b["v_low_in_s"] >= hi) and abs(b["mean"]) > b["tolerance"]
        ]
        if outside:
            parts.append(
                _negligible_misfit_words(
                    model_name,
                    max(outside, key=lambda b: abs(b["mean"])),
                    f"the largest {curve} misfit outside that range",
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
            "; " + _negligible_misfit_words(model_name, row, f"the largest {row['curve']} misfit", units)
            for row in quiet
        )
        return (
            f"The {model_name} baseline fits damping and frequency at every amplitude to "
            f"within the run-to-run scatter or the models' accuracy ({runs_words(n_runs)}){tail}."
        )
    parts += [
        _negligible_misfit_words(model_name, row, f"its largest {row['curve']} misfit", units)
        for row in quiet
    ]
    text = "; ".join(parts)
    return text[0].upper() + text[1:] + "."

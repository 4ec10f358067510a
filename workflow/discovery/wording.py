"""Wording of the diagnosis: sizes as percentages, and the sentence that says where and by
how much the baseline is wrong (or why it is not)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

__all__ = ["format_percent", "discrepancy_sentence"]


def _fmt_v(v: float) -> str:
    return f"{v:.3g}"


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


def _misfit_words(model_name: str, row: Mapping) -> str:
    """``the measured damping lies 4.2 % above the lugre fit at 1-3.2 in/s``."""
    size = _misfit_percent(row["curve"], row["mean"])
    side = "above" if size > 0 else "below" if size < 0 else "on"
    return (
        f"the measured {row['curve']} lies {format_percent(size).lstrip('+-')} {side} the "
        f"{model_name} fit at {_fmt_v(row['v_low_in_s'])}-{_fmt_v(row['v_high_in_s'])} in/s"
    )


def _negligible_misfit_words(model_name: str, row: Mapping) -> str:
    """Why the bin with the largest |t| is not a misfit: not significant after the
    Bonferroni correction, or smaller than the models' accuracy, or both."""
    tolerance = _misfit_percent(row["curve"], row["tolerance"])
    clear = row["p"] < row["p_limit"]
    small = abs(row["mean"]) <= row["tolerance"]
    statistic = f"|t| = {abs(row['t']):.1f}, p = {row['p']:.2g} against {row['p_limit']:.2g} after correction"
    accuracy = f"the {abs(tolerance):.2g} % in {row['curve']} the models are accurate to"
    if clear and small:
        judgement = (
            f"statistically clear ({statistic}) but physically negligible: smaller than {accuracy} "
            f"({abs(row['mean']) / row['tolerance']:.2g} of it)"
        )
    elif small:
        judgement = f"neither statistically significant ({statistic}) nor larger than {accuracy}"
    else:
        judgement = f"larger than {accuracy} but not statistically significant ({statistic})"
    return f"the largest binned misfit, where {_misfit_words(model_name, row)}, is {judgement}"


def discrepancy_sentence(model_name: str, bins: list[dict], trend: dict | None, n_runs: int) -> str:
    """Plain sentence: where and by how much the model is wrong (or that it is not).

    Sizes are percentages of the model (two significant digits, so that a misfit that
    is not zero never reads as ``0.00 %``), with their direction in words. A misfit is
    called significant only when it is both statistically clear (``p`` below the
    corrected limit) and larger than the models' accuracy (``tolerance``); when no bin
    is, the sentence says which of the two the largest one (by ``|t|``) fails.

    Examples
    --------
    >>> discrepancy_sentence("dahl", [], None, 8)
    "The dahl baseline fits damping and frequency at every amplitude to within the run-to-run scatter or the models' accuracy (8 runs)."
    """
    sig = [b for b in bins if b["significant"]]
    parts = []
    for curve in ("damping", "frequency"):
        rows = [b for b in sig if b["curve"] == curve]
        if not rows:
            continue
        lo = min(b["v_low_in_s"] for b in rows)
        hi = max(b["v_high_in_s"] for b in rows)
        worst = max(rows, key=lambda b: abs(b["mean"]))
        parts.append(
            f"the measured {curve} differs from the {model_name} fit between "
            f"{_fmt_v(lo)} and {_fmt_v(hi)} in/s, by up to "
            f"{format_percent(_misfit_percent(curve, worst['mean']))} "
            f"(|t| = {abs(worst['t']):.1f} over {worst['n_runs']} runs) at "
            f"{_fmt_v(worst['v_low_in_s'])}-{_fmt_v(worst['v_high_in_s'])} in/s"
        )
    if trend is not None and trend["significant"]:
        parts.append(
            f"the runs' damping curve shifts with run order ({trend['order']}) by "
            f"{format_percent(_misfit_percent('damping', trend['change_over_sequence']))} from the "
            f"first to the last run where the shift is largest (t = {trend['t']:.1f})"
        )
    if not parts:
        worst = max(bins, key=lambda b: abs(b["t"]), default=None)
        tail = "" if worst is None else "; " + _negligible_misfit_words(model_name, worst)
        return (
            f"The {model_name} baseline fits damping and frequency at every amplitude to "
            f"within the run-to-run scatter or the models' accuracy ({n_runs} runs){tail}."
        )
    text = "; ".join(parts)
    return text[0].upper() + text[1:] + "."

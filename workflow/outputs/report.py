"""The report's first page and its tables, as self-contained HTML.

Pure functions: they take ``results/diagnosis.json`` (output contract) and the
Parquet tables as Python objects and return text. ``scripts/report_summary.py``
writes them to ``results/report/`` and ``rules/report.smk`` marks them for
``snakemake --report``, whose HTML viewer shows them beside the figures.

* :func:`verdict_html`: the verdict in plain words - what the paper's model gets
  wrong, the cause per configuration and for the campaign, the extended model and
  its held-out gain, how sure we are, the hypotheses and the excluded runs.
* :func:`hypotheses_html`, :func:`runs_html`, :func:`damping_fits_html`,
  :func:`model_fits_html`, :func:`candidates_html`, :func:`rejected_segments_html`:
  the key tables, readable (units in the headers, numbers rounded).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from workflow.discovery.confidence import verdict_key
from workflow.discovery.wording import discrepancy_sentence, runs_words
from workflow.io.recording_time import run_order
from workflow.io.units import INCH_SECOND, MODEL_PARAMETER_UNITS, UnitSystem
from workflow.outputs.escape import display_text, html_text, rst_strong, rst_text
from workflow.outputs.plain_words import (
    left_out_caveat,
    percent_of,
    uncertainty_note,
    unidentified_parameters,
    unidentified_sentence,
)

__all__ = [
    "CAUSE_WORDS",
    "CLEAR_MARGIN",
    "CLEAR_CONFIDENCE",
    "FLAT_CHANGE",
    "CAUSE_NAMES",
    "MODEL_NAMES",
    "ERROR_UNIT",
    "ONE_RUN_ERROR_UNIT",
    "CSS",
    "fmt",
    "ratio",
    "esc",
    "model_name",
    "cause_name",
    "candidate_name",
    "tag",
    "page",
    "html_table",
    "amplitude_range",
    "candidate_margin",
    "signature_sentences",
    "explains_sentences",
    "threshold_sentences",
    "margin_words",
    "gain_words",
    "END_SEGMENTS",
    "measured_trends",
    "trend_sentence",
    "campaign_headline",
    "discrepancy_text",
    "hypotheses_in_units",
    "hypothesis_summary",
    "excluded_runs",
    "modes_section",
    "verdict_html",
    "hypotheses_html",
    "runs_in_recorded_order",
    "runs_html",
    "damping_fits_html",
    "model_fits_html",
    "candidates_html",
    "rejected_segments_html",
    "verdict_rst",
    "landing_rst",
    "quality_html",
]


#: What each cause of the output contract means, in plain words.
CAUSE_WORDS: dict[str, str] = {
    "none": "none — the paper's friction model explains the data within the run-to-run scatter",
    "microslip_power_law": "micro-slip — slip spreads gradually over the contact "
    "(Iwan-type, many slip thresholds)",
    "quadratic_damping": "quadratic damping — a velocity-squared loss (air or fluid drag, radiation)",
    "stiffness_nonlinearity": "stiffness nonlinearity — an amplitude-dependent stiffness that dissipates "
    "nothing (contact opening, geometry)",
    "run_drift": "run drift — the joint changed between runs (preload relaxation, settling)",
    "unknown": "unknown — the paper's model fails, but none of the candidate causes fixes it",
}
"""The physical mechanism of each cause. What the data show is said from the numbers
(:func:`trend_sentence`), never from the cause's textbook signature."""

CLEAR_MARGIN = 1.5
"""The verdict is called *clearly* ahead of the next candidate only when that candidate's
held-out error is at least this many times the verdict's ..."""

CLEAR_CONFIDENCE = 0.8
"""... and the verdict's confidence (its probability over reweightings of the runs) is at
least this."""

FLAT_CHANGE = 0.05
"""A measured trend smaller than this relative change (5 %) over the amplitude range is
called flat."""

#: Short names of the causes, for tables and headlines.
CAUSE_NAMES: dict[str, str] = {
    "none": "none (paper's model suffices)",
    "microslip_power_law": "micro-slip (power law)",
    "quadratic_damping": "quadratic damping",
    "stiffness_nonlinearity": "stiffness nonlinearity",
    "run_drift": "run-to-run drift",
    "unknown": "unknown",
}

#: Display names of the model ids of the diagnosis.
MODEL_NAMES: dict[str, str] = {
    "dahl": "Dahl",
    "lugre": "LuGre",
    "iwan": "Iwan micro-slip",
    "dahl_quadratic": "Dahl + quadratic damping",
    "dahl_stiffness": "Dahl + nonlinear stiffness",
    "dahl_drift": "Dahl + run drift",
}

ERROR_UNIT = (
    "held-out error: RMS of the residuals on runs left out of the fit, divided by "
    "the measured run-to-run scatter (1 = the model predicts a new run as well as the "
    "runs repeat each other)"
)

ONE_RUN_ERROR_UNIT = (
    "; with one run, amplitude ranges of that run are left out and the scatter is the segments' own"
)

CSS = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; font-size: 15px;
       line-height: 1.45; color: #1d1d1f; margin: 0 auto; padding: 0.5em 1.2em 2em 1.2em;
       max-width: 1100px; }
h1 { font-size: 1.6em; margin: 0.4em 0 0.3em 0; }
h2 { font-size: 1.25em; margin: 1.4em 0 0.4em 0; border-bottom: 1px solid #ddd;
     padding-bottom: 0.15em; }
h3 { font-size: 1.05em; margin: 1em 0 0.3em 0; }
p, li { max-width: 60em; }
.headline { background: #f3f6fb; border-left: 5px solid #2b6cb0; padding: 0.7em 1em;
            margin: 0.8em 0; font-size: 1.08em; }
.headline.none { border-left-color: #2f855a; background: #f0f8f3; }
.headline.unknown { border-left-color: #c05621; background: #fdf5ee; }
.note { color: #555; font-size: 0.92em; }
table { border-collapse: collapse; margin: 0.5em 0 1em 0; font-size: 0.92em; }
th, td { border: 1px solid #d5d5d5; padding: 0.3em 0.55em; vertical-align: top;
         text-align: left; }
th { background: #f2f2f2; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
tr.excluded td { background: #fff3f0; }
.tag { display: inline-block; padding: 0.05em 0.45em; border-radius: 0.6em;
       font-size: 0.85em; white-space: nowrap; }
.tag.supported, .tag.used, .tag.none { background: #d9f2e3; color: #22543d; }
.tag.contradicted, .tag.excluded { background: #fde2dd; color: #822727; }
.tag.inconclusive, .tag.skipped, .tag.not-applicable { background: #eee; color: #444; }
.tag.flag { background: #fdf0c8; color: #744210; }
.tag.cause { background: #dbe7f7; color: #1a365d; }
"""


# ------------------------------------------------------------------ formatting
def _number(value: Any) -> float | str:
    """``value`` as a float (nan when missing), or as text when it is no number."""
    if value is None:
        return math.nan
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


def fmt(value: Any, digits: int = 3) -> str:
    """A number with ``digits`` significant digits; '-' for missing or non-finite.

    Plain below ``10**(digits + 2)`` (``100``, never ``1e+02``), in exponent form above
    it and below 0.001.

    Examples
    --------
    >>> fmt(100.0, 2), fmt(1234.0), fmt(0.0795), fmt(2.5e-4), fmt(None)
    ('100', '1230', '0.0795', '2.50e-04', '–')
    """
    number = _number(value)
    if isinstance(number, str):
        return number
    if not math.isfinite(number):
        return "–"
    if number != 0 and (abs(number) >= 10 ** (digits + 2) or abs(number) < 1e-3):
        return f"{number:.{digits - 1}e}"
    if abs(number) >= 10**digits:
        # the g format would write 100 as 1e+02 at two digits
        return f"{round(number, digits - 1 - int(math.floor(math.log10(abs(number))))):.0f}"
    return f"{number:.{digits}g}"


def ratio(value: Any) -> str:
    """A ratio with two decimals ('-' when missing)."""
    number = _number(value)
    if isinstance(number, str):
        return number
    return f"{number:.2f}" if math.isfinite(number) else "–"


def esc(text: Any) -> str:
    """Text (the campaign's or ours) as HTML (:func:`workflow.outputs.escape.html_text`)."""
    return html_text(text)


def model_name(model_id: str | None) -> str:
    if model_id and model_id.startswith("iwan_cells_"):
        return "Iwan micro-slip with slip thresholds from the data"
    return MODEL_NAMES.get(model_id or "", model_id or "?")


def cause_name(cause: str | None) -> str:
    return CAUSE_NAMES.get(cause or "", cause or "?")


def candidate_name(cause: str | None) -> str:
    """A candidate cause as the model it stands for ('none' is the baseline itself)."""
    return "the baseline itself (no extension)" if cause == "none" else cause_name(cause)


def tag(text: str, kind: str) -> str:
    return f'<span class="tag {esc(kind.replace(" ", "-"))}">{esc(text)}</span>'


def page(title: str, body: str) -> str:
    """A complete HTML page (inline style, no external resources)."""
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{esc(title)}</title><style>{CSS}</style></head>\n"
        f"<body>\n{body}\n</body></html>\n"
    )


def html_table(
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    *,
    numeric: Sequence[int] = (),
    row_classes: Sequence[str] | None = None,
) -> str:
    """A table from already-escaped cell HTML; ``numeric`` columns right-aligned."""
    head = "".join(f"<th>{cell}</th>" for cell in header)
    lines = [f"<table><thead><tr>{head}</tr></thead><tbody>"]
    for index, row in enumerate(rows):
        cls = f' class="{row_classes[index]}"' if row_classes and row_classes[index] else ""
        cells = "".join(
            f'<td class="num">{cell}</td>' if k in numeric else f"<td>{cell}</td>"
            for k, cell in enumerate(row)
        )
        lines.append(f"<tr{cls}>{cells}</tr>")
    lines.append("</tbody></table>")
    return "\n".join(lines)


def amplitude_range(low_in_s: Any, high_in_s: Any, units: UnitSystem = INCH_SECOND) -> str:
    """``0.1–3 in/s``: a range of velocity amplitudes given in in/s, shown in ``units``."""
    return (
        f"{fmt(_scaled(low_in_s, units.per_in_s))}–{fmt(_scaled(high_in_s, units.per_in_s))} {units.velocity}"
    )


def _scaled(value: Any, factor: float) -> Any:
    """``value`` times ``factor`` when it is a number; as it is otherwise (None, text)."""
    return value * factor if isinstance(value, (int, float)) and not isinstance(value, bool) else value


# ------------------------------------------------------------------ the verdict
def candidate_margin(entry: Mapping) -> dict | None:
    """How far the chosen cause is from the next candidate, by held-out error.

    Returns
    -------
    dict or None
        ``chosen``/``chosen_score`` (the verdict's held-out error), ``next``/
        ``next_score`` (the best other candidate) and ``ratio`` = next / chosen
        (above 1: the verdict predicts held-out runs better by that factor; below 1:
        the other candidate scored lower but was not accepted, see ``decision_rule``).
    """
    ranking = [r for r in entry.get("ranking", []) if r.get("score") is not None]
    chosen = entry.get("cause")
    if chosen == "unknown":
        chosen = "none"  # unknown keeps the baseline: compare it with the best candidate
    mine = [r for r in ranking if r["cause"] == chosen]
    others = [r for r in ranking if r["cause"] != chosen]
    if not mine or not others:
        return None
    best_other = min(others, key=lambda r: r["score"])
    chosen_score = float(mine[0]["score"])
    next_score = float(best_other["score"])
    ratio = next_score / chosen_score if chosen_score > 0 else None
    return {
        "chosen": entry.get("cause"),
        "chosen_score": chosen_score,
        "next": best_other["cause"],
        "next_score": next_score,
        "ratio": ratio,
    }


def signature_sentences(entry: Mapping) -> list[str]:
    """Why the stiffness candidate was set aside when its fit lacks the stiffness
    signature (``evidence.candidates.stiffness_nonlinearity.signature``)."""
    candidate = ((entry.get("evidence") or {}).get("candidates") or {}).get("stiffness_nonlinearity") or {}
    signature = candidate.get("signature") or {}
    if signature.get("shows_signature", True):
        return []
    whole = signature.get("relative_frequency_change")
    friction = signature.get("friction_relative_frequency_change")
    return [
        f"{cause_name('stiffness_nonlinearity')} is not eligible: over the measured amplitudes its fit "
        f"changes the frequency by {fmt(100 * whole, 2)} %, less than its friction alone "
        f"({fmt(100 * friction, 2)} %); its stiffness term cancels the friction's frequency change "
        "instead of showing one the friction cannot explain (the contract's signature)."
    ]


def explains_sentences(entry: dict, units: UnitSystem = INCH_SECOND) -> list[str]:
    """Whether the model the verdict rests on explains the data, and where it does not
    (``explains_data`` and ``evidence.explains_data`` of diagnosis.json)."""
    explained = (entry.get("evidence") or {}).get("explains_data") or {}
    if entry.get("explains_data") is None:
        return []
    model = model_name((entry.get("extended_model") or {}).get("model"))
    limit = fmt(explained.get("limit", 2))
    if entry["explains_data"]:
        return [f"{model} explains the data: every half decade of amplitude is within {limit} scatters."]
    failing = explained.get("failing_bins") or []
    where = "; ".join(
        f"{b['curve']} at {amplitude_range(b['v_low_in_s'], b['v_high_in_s'], units)} "
        f"({fmt(b['mean_over_scatter'])} scatters)"
        for b in failing[:4]
    )
    more = f" and {len(failing) - 4} more" if len(failing) > 4 else ""
    return [
        f"{model} does not explain all the data: it misses by more than {limit} scatters in {where}{more}."
    ]


def threshold_sentences(entry: Mapping, units: UnitSystem = INCH_SECOND) -> list[str]:
    """The slip-threshold distribution recovered from the data, when the power law did not
    explain a micro-slip joint (``evidence.threshold_distribution`` of diagnosis.json)."""
    refinement = (entry.get("evidence") or {}).get("threshold_distribution")
    if not refinement:
        return []
    cells = refinement.get("cells") or []
    head = (
        f"The power law does not explain the data, so the spread of slip thresholds was recovered "
        f"from the data in {len(cells)} half-decade cells: held-out error "
        f"{fmt(refinement.get('heldout_error'))} against the power law's "
        f"{fmt(refinement.get('iwan_heldout_error'))}, BIC {fmt(refinement.get('bic'))} against "
        f"{fmt(refinement.get('iwan_bic'))}; "
    )
    head += (
        "it is the extended model."
        if refinement.get("adopted")
        else "it does not lower both, so the power law stays the extended model."
    )
    shares = []
    for cell in cells:
        error = cell.get("standard_error")
        share = fmt(100 * cell["stiffness_fraction"], 2)
        share = f"{share} ± {fmt(100 * error, 2)} %" if error is not None else f"{share} % (not identified)"
        shares.append(
            f"{amplitude_range(cell['threshold_low_in_s'], cell['threshold_high_in_s'], units)}: {share}"
        )
    return [
        head,
        "Share of the modal stiffness released by the slip thresholds of each cell (± one "
        "standard error): " + "; ".join(shares) + ".",
    ]


def margin_words(margin_ratio: float | None, confidence: float | None) -> str:
    """How far ahead of the next candidate the verdict is, in words that scale with it.

    ``clearly ahead`` needs a margin of :data:`CLEAR_MARGIN` and a confidence of
    :data:`CLEAR_CONFIDENCE`; ``ahead`` a margin of 1.2; below that ``only marginally
    ahead``; below 1 (the other candidate predicts better) ``behind``.
    """
    if margin_ratio is None or not math.isfinite(margin_ratio):
        return "not compared with"
    if margin_ratio < 1.0:
        return "behind"
    if margin_ratio >= CLEAR_MARGIN and (confidence or 0.0) >= CLEAR_CONFIDENCE:
        return "clearly ahead of"
    if margin_ratio >= 1.2:
        return "ahead of"
    return "only marginally ahead of"


def gain_words(gain_ratio: float | None, margin_ratio: float | None, confidence: float | None) -> str:
    """'clearly better' / 'better' / 'no better': the extended model's held-out prediction
    against the baseline's. 'clearly' only when the gain is at least a halving of the
    error and the verdict is clearly ahead of the next candidate (:func:`margin_words`)."""
    if gain_ratio is None or not math.isfinite(gain_ratio) or gain_ratio >= 1.0:
        return "no better"
    if gain_ratio <= 0.5 and margin_words(margin_ratio, confidence) == "clearly ahead of":
        return "clearly better"
    return "better"


END_SEGMENTS = 3
"""Fewest segments whose median stands for an end of the measured range: an end bin with
fewer is widened inward by quarter decades until it has them."""


def _end_bin(codes: np.ndarray, counts: np.ndarray, from_top: bool) -> np.ndarray:
    """The quarter-decade codes making up one end of the range (at least :data:`END_SEGMENTS`)."""
    order = codes[::-1] if from_top else codes
    taken, total = [], 0
    for code, count in zip(order, counts[::-1] if from_top else counts):
        taken.append(code)
        total += count
        if total >= END_SEGMENTS:
            break
    return np.asarray(taken)


def measured_trends(segments: pd.DataFrame, per_decade: int = 4) -> dict[str, dict]:
    """What the measured damping and frequency do over each configuration's full range of
    amplitudes, from the segments figures 10-12 and the backbones plot.

    The range is that of every kept segment (the figures' horizontal extent). Each end's
    damping and frequency are the medians of the segments in its ``1/per_decade`` decade
    (widened inward until it holds :data:`END_SEGMENTS`), so that a few runs reaching
    further than the others set the top end as they do on the figure; the medians of
    the bins between give the lowest and highest damping on the way.

    Parameters
    ----------
    segments : DataFrame
        results/tables/segments.parquet (``configuration``, ``run``,
        ``velocity_amplitude_in_s``, ``zeta``, ``frequency_hz``).
    per_decade : int
        Amplitude bins per decade.

    Returns
    -------
    dict
        Configuration -> ``amplitude_low_in_s``, ``amplitude_high_in_s`` (the smallest and
        largest segment amplitude), ``n_segments``, ``n_runs``; per end (``low``/``high``)
        ``end_<end>_low_in_s``/``end_<end>_high_in_s`` (its amplitudes), ``runs_<end>``,
        ``zeta_<end>`` (fraction of critical) and ``frequency_<end>_hz``; ``zeta_min``,
        ``zeta_max`` and ``zeta_min_in_s``/``zeta_max_in_s`` over the bins' medians.
        Configurations with fewer than ``2 * END_SEGMENTS`` segments are left out.

    Examples
    --------
    >>> frame = pd.DataFrame({"configuration": "a", "run": ["r1"] * 6 + ["r2"] * 2,
    ...     "velocity_amplitude_in_s": [0.1, 0.11, 0.12, 0.5, 0.6, 1.0, 4.0, 4.4],
    ...     "zeta": [1e-3] * 6 + [2e-3] * 2, "frequency_hz": 100.0})
    >>> trend = measured_trends(frame)["a"]
    >>> trend["amplitude_high_in_s"], trend["zeta_high"], trend["runs_high"]
    (4.4, 0.002, 2)
    """
    trends = {}
    if segments is None or segments.empty:
        return trends
    for name, part in segments.groupby("configuration", sort=False):
        part = part[part["velocity_amplitude_in_s"] > 0]
        if len(part) < 2 * END_SEGMENTS:
            continue
        velocity = part["velocity_amplitude_in_s"].to_numpy(float)
        code = np.floor(per_decade * np.log10(velocity)).astype(int)
        codes, counts = np.unique(code, return_counts=True)
        trend = {
            "amplitude_low_in_s": float(velocity.min()),
            "amplitude_high_in_s": float(velocity.max()),
            "n_segments": len(part),
            "n_runs": int(part["run"].nunique()) if "run" in part else 1,
        }
        for end, from_top in (("low", False), ("high", True)):
            inside = np.isin(code, _end_bin(codes, counts, from_top))
            chosen = part[inside]
            trend[f"end_{end}_low_in_s"] = float(velocity[inside].min())
            trend[f"end_{end}_high_in_s"] = float(velocity[inside].max())
            trend[f"runs_{end}"] = int(chosen["run"].nunique()) if "run" in chosen else 1
            trend[f"zeta_{end}"] = float(chosen["zeta"].median())
            trend[f"frequency_{end}_hz"] = float(chosen["frequency_hz"].median())
        by_bin = part.groupby(code)
        medians = by_bin["zeta"].median()[by_bin.size() >= END_SEGMENTS]
        at = by_bin["velocity_amplitude_in_s"].median()
        if medians.empty:
            medians = pd.Series([trend["zeta_low"], trend["zeta_high"]])
            at = pd.Series([trend["amplitude_low_in_s"], trend["amplitude_high_in_s"]])
        trend["zeta_min"], trend["zeta_min_in_s"] = float(medians.min()), float(at[medians.idxmin()])
        trend["zeta_max"], trend["zeta_max_in_s"] = float(medians.max()), float(at[medians.idxmax()])
        trends[str(name)] = trend
    return trends


def _direction(low: float, high: float, flat: float) -> str:
    change = high / low - 1.0 if low else math.inf
    if abs(change) < flat:
        return "stays level"
    return "rises" if change > 0 else "falls"


def _end_words(trend: Mapping, end: str, units: UnitSystem) -> str:
    """``the median of 12 segments at 0.05-0.07 in/s`` (and how many runs reach the top)."""
    where = amplitude_range(trend[f"end_{end}_low_in_s"], trend[f"end_{end}_high_in_s"], units)
    runs = trend[f"runs_{end}"]
    verb = "reaches" if runs == 1 else "reach"
    reach = (
        f", {runs} of {trend['n_runs']} runs {verb} it" if end == "high" and runs < trend["n_runs"] else ""
    )
    return f"at {where}{reach}"


def trend_sentence(trend: Mapping, units: UnitSystem = INCH_SECOND) -> str:
    """What the measured damping and frequency do over the full measured range, in words
    taken from the numbers of :func:`measured_trends` (direction, both ends, the damping's
    low or high point on the way when it lies beyond both ends, said as a turn: "rises
    from A to a high of M near V, then falls to B"; the frequency's relative change)."""
    zeta = _direction(trend["zeta_low"], trend["zeta_high"], FLAT_CHANGE)
    frequency_change = trend["frequency_high_hz"] / trend["frequency_low_hz"] - 1.0
    # a joint's frequency moves by a fraction of a percent: 0.1 % is already a trend
    frequency = _direction(trend["frequency_low_hz"], trend["frequency_high_hz"], 1e-3)
    ends = (trend["zeta_low"], trend["zeta_high"])
    low_end = f"{fmt(100 * trend['zeta_low'])} % {_end_words(trend, 'low', units)}"
    high_end = f"{fmt(100 * trend['zeta_high'])} % {_end_words(trend, 'high', units)}"
    # a low or high point beyond both ends is a turn the figure shows: said as one
    if trend["zeta_min"] < (1 - FLAT_CHANGE) * min(ends):
        turn = ("falls", "a low", trend["zeta_min"], trend["zeta_min_in_s"], "rises")
    elif trend["zeta_max"] > (1 + FLAT_CHANGE) * max(ends):
        turn = ("rises", "a high", trend["zeta_max"], trend["zeta_max_in_s"], "falls")
    else:
        turn = None
    if turn is None:
        damping = f"the damping {zeta} from {low_end} to {high_end}"
    else:
        first, point, value, at_in_s, then = turn
        damping = (
            f"the damping {first} from {low_end} to {point} of {fmt(100 * value)} % near "
            f"{fmt(units.per_in_s * at_in_s)} {units.velocity}, then {then} to {high_end}"
        )
    return (
        f"Measured from {fmt(units.per_in_s * trend['amplitude_low_in_s'])} to "
        f"{fmt(units.per_in_s * trend['amplitude_high_in_s'])} {units.velocity} "
        f"({trend['n_segments']} segments, {runs_words(trend['n_runs'])}), {damping} "
        f"(medians of the segments there), and the frequency {frequency} from "
        f"{fmt(trend['frequency_low_hz'], 5)} Hz to {fmt(trend['frequency_high_hz'], 5)} Hz "
        f"({100 * frequency_change:+.2f} %)."
    )


def discrepancy_text(entry: Mapping, units: UnitSystem = INCH_SECOND) -> str:
    """A configuration's discrepancy sentence (diagnosis.json, amplitudes in in/s) with its
    amplitudes in ``units``: rebuilt from the binned residuals and the run-order trend
    the diagnosis keeps as evidence, so that the page speaks one unit. Kept as written
    when the evidence does not rebuild it (the sentence is then in in/s)."""
    text = entry.get("discrepancy", "")
    evidence = entry.get("evidence") or {}
    bins = evidence.get("binned_residuals")
    model = (entry.get("baseline") or {}).get("model")
    if units.velocity == INCH_SECOND.velocity or bins is None or not model:
        return text
    trend = evidence.get("run_order_trend")
    runs = evidence.get("n_runs", 0)
    as_written = discrepancy_sentence(model, bins, trend, runs)
    if not text.endswith(as_written):
        return text
    return text[: len(text) - len(as_written)] + discrepancy_sentence(model, bins, trend, runs, units)


def _unidentified(entry: Mapping, units: UnitSystem = INCH_SECOND) -> list[dict]:
    """The parameters of the baseline and the extended model that the data do not
    determine (their ``flags``), each once (:func:`~workflow.outputs.plain_words.unidentified_parameters`)."""
    return unidentified_parameters(
        (("the baseline", entry.get("baseline")), ("the extended model", entry.get("extended_model"))),
        units,
    )


def _unidentified_tag(entry: Mapping) -> str:
    """A short tag pointing to the sentence on the parameters the data do not determine."""
    count = len(_unidentified(entry))
    if not count:
        return ""
    return " " + tag(
        f"{count} fitted parameter{'s' if count > 1 else ''} not determined by the data (see How sure we are)",
        "flag",
    )


def _n_runs(entry: Mapping) -> int:
    """Runs behind a configuration's diagnosis (2 when the document does not say)."""
    runs = (entry.get("evidence") or {}).get("n_runs")
    return int(runs) if runs is not None else 2


def campaign_headline(document: Mapping) -> str:
    """One or two plain sentences: the campaign's verdict."""
    entries = document.get("configurations", {})
    names = list(entries)
    cause = document.get("cause", "unknown")
    failing = [n for n in names if entries[n].get("cause") != "none"]
    if not names:
        return "No configuration had enough usable segments to be diagnosed; see the excluded runs below."
    if cause == "none":
        return (
            f"The paper's friction model explains all {len(names)} configuration"
            f"{'s' if len(names) != 1 else ''} within the run-to-run scatter: "
            "no missing physics was found."
        )
    which = ", ".join(failing)
    if cause == "unknown":
        return (
            f"The paper's friction model (the better of Dahl and LuGre) does not explain the "
            f"measured damping and frequency in {len(failing)} of {len(names)} configuration"
            f"{'s' if len(names) != 1 else ''} ({which}), and none of the candidate causes "
            "fixes it: the cause is unknown."
        )
    words = []
    for n in failing:
        margin = candidate_margin(entries[n]) or {}
        confidence = (entries[n].get("confidence") or {}).get(entries[n].get("cause"))
        words.append(gain_words((entries[n].get("gain") or {}).get("ratio"), margin.get("ratio"), confidence))
    word = "clearly better" if words and all(w == "clearly better" for w in words) else "better"
    text = (
        f"The paper's friction model (the better of Dahl and LuGre) falls short in "
        f"{len(failing)} of {len(names)} configuration{'s' if len(names) != 1 else ''} "
        f"({which}): a model with the missing physics predicts "
        f"{'runs' if all(_n_runs(entries[n]) > 1 for n in failing) else 'data'} held out of the fit "
        f"{word}. "
    )
    ratios = [
        entries[n]["gain"].get("ratio")
        for n in failing
        if entries[n].get("cause") == cause and entries[n].get("gain")
    ]
    ratios = [r for r in ratios if r is not None]
    extended = [entries[n]["extended_model"]["model"] for n in failing if entries[n].get("cause") == cause]
    text += f"The cause: {CAUSE_WORDS.get(cause, cause)}."
    if extended and ratios:
        best = min(ratios)
        held_out = (
            "predicts runs it was not fitted to"
            if all(_n_runs(entries[n]) > 1 for n in failing)
            else "predicts amplitude ranges held out of the fit (with one run, no run could be held out)"
        )
        text += (
            f" The extended model, {model_name(extended[0])}, {held_out} with {ratio(best)} of "
            "the baseline's error" + (f" ({fmt(1 / best, 2)} times better)" if best > 0 else "") + "."
        )
    return text


def _configuration_row(name: str, entry: Mapping, area_in2: float | None, units: UnitSystem) -> list[str]:
    gain = entry.get("gain") or {}
    margin = candidate_margin(entry)
    if margin and margin["ratio"] is not None:
        next_text = esc(cause_name(margin["next"]))
        margin_text = f"{fmt(margin['next_score'])} (×{ratio(margin['ratio'])})"
        if margin["ratio"] < 1:
            margin_text += " lower, but not a clear gain"
    else:
        next_text, margin_text = "–", "–"
    return [
        esc(name),
        fmt(_scaled(area_in2, units.per_in2)),
        esc(model_name(entry.get("baseline", {}).get("model"))),
        tag(cause_name(entry.get("cause")), "none" if entry.get("cause") == "none" else "cause"),
        esc(model_name(entry.get("extended_model", {}).get("model"))),
        fmt(gain.get("baseline")),
        fmt(gain.get("extended")),
        ratio(gain.get("ratio")),
        next_text,
        margin_text,
    ]


def _sureness_items(name: str, entry: Mapping, units: UnitSystem = INCH_SECOND) -> list[str]:
    """Plain-sentence evidence for one configuration (escaped HTML list items)."""
    evidence = entry.get("evidence") or {}
    gain = entry.get("gain") or {}
    cause = entry.get("cause")
    items = []
    runs, segments = evidence.get("n_runs"), evidence.get("n_segments")
    if runs is not None:
        text = (
            f"Based on {runs_words(runs)} and {segments} segments "
            f"({evidence.get('effective_observations', '?')} effectively independent)."
        )
        if runs == 1:
            text += (
                " With one run, held out means a range of amplitudes of that run held out of the "
                "fit, and the scatter is the segments' own: nothing here says how a second run of "
                "the joint would differ."
            )
        items.append(text)
    baselines = evidence.get("baselines") or {}
    if baselines:
        parts = [f"{model_name(m)} {fmt(b.get('heldout_error'))}" for m, b in baselines.items()]
        items.append(
            "Held-out error of the paper's models: "
            + ", ".join(parts)
            + f"; the better one, {model_name(entry.get('baseline', {}).get('model'))}, "
            "is the baseline."
        )
    if cause not in ("none", "unknown"):
        candidate = (evidence.get("candidates") or {}).get(cause, {})
        text = (
            f"{model_name(candidate.get('model') or entry.get('extended_model', {}).get('model'))} "
            f"lowers the held-out error from {fmt(gain.get('baseline'))} to "
            f"{fmt(candidate.get('heldout_error', gain.get('extended')))} "
            f"(ratio {ratio(candidate.get('ratio_to_baseline', gain.get('ratio')))}; a clear gain "
            f"needs a ratio below {ratio(evidence.get('clear_gain_threshold'))})"
        )
        if candidate.get("delta_bic") is not None:
            text += (
                f" and the information criterion by {fmt(-candidate['delta_bic'])} "
                f"(ΔBIC {fmt(candidate['delta_bic'])})"
            )
        items.append(text + ".")
        if candidate.get("residual_significant"):
            items.append(
                f"Some misfit remains after the extension ({candidate.get('significant_bins', '?')} "
                "amplitude bin(s) still significant): the extended model is better, "
                "not perfect."
            )
    items.extend(signature_sentences(entry))
    margin = candidate_margin(entry)
    if margin and margin["ratio"] is not None:
        if margin["ratio"] >= 1 and cause in ("none", "unknown"):
            items.append(
                f"No candidate predicts held-out runs better than the baseline; the "
                f"closest, {cause_name(margin['next'])}, has {ratio(margin['ratio'])} "
                f"times its held-out error ({fmt(margin['next_score'])})."
            )
        elif margin["ratio"] >= 1:
            confidence = (entry.get("confidence") or {}).get(verdict_key(entry.get("causes") or [cause]))
            sure = f"; its confidence is {percent_of(confidence)}" if confidence is not None else ""
            items.append(
                f"The verdict is {margin_words(margin['ratio'], confidence)} the next-best candidate, "
                f"{candidate_name(margin['next'])}: its held-out error ({fmt(margin['next_score'])}) is "
                f"{ratio(margin['ratio'])} times the verdict's{sure} (clearly ahead needs "
                f"{CLEAR_MARGIN:g} times and {100 * CLEAR_CONFIDENCE:.0f} %)."
            )
        else:
            items.append(
                f"{cause_name(margin['next'])} scored a lower held-out error "
                f"({fmt(margin['next_score'])} against {fmt(margin['chosen_score'])}, "
                f"ratio {ratio(margin['ratio'])}) but was not accepted: "
                f"{evidence.get('decision_rule', 'see the decision rule')}."
            )
    items.extend(threshold_sentences(entry, units))
    unidentified = unidentified_sentence(_unidentified(entry, units))
    if unidentified:
        items.append(unidentified)
    items.extend(explains_sentences(entry, units))
    trend = evidence.get("run_order_trend") or {}
    if trend.get("p") is not None:
        # the order the runs were taken in: timestamps when the diagnosis found them
        order = trend.get("order") or "file-name order, which may not be the order the runs were taken in"
        items.append(
            f"Run-order trend of the damping ({order}): "
            f"{fmt(100 * (trend.get('change_over_sequence') or 0), 2)} % "
            f"from the first run to the last where the shift is largest, p = {fmt(trend['p'], 2)} "
            f"({'significant' if trend.get('significant') else 'not significant'})."
        )
    if evidence.get("decision_rule"):
        items.append(f"Decision rule: {evidence['decision_rule']}.")
    return [esc(item) for item in items]


_NUMBER = r"\d+(?:\.\d+)?(?:e[+-]?\d+)?"
_IN_S = re.compile(rf"({_NUMBER})(?:-({_NUMBER}))? in/s")


def hypotheses_in_units(hypotheses: pd.DataFrame, units: UnitSystem = INCH_SECOND) -> pd.DataFrame:
    """The hypotheses table (results/tables/hypotheses.parquet, in/s and in²) as shown in
    ``units``: the amplitudes in each ``statistic`` converted, and the estimates and
    intervals of a slope per in² (H2, ``1/in^2``) per ``units.area``.

    Examples
    --------
    >>> from workflow.io.units import SI
    >>> table = pd.DataFrame({"statistic": ["slope of fitted zeta vs bearing area at velocity "
    ...     "amplitude 0.63 in/s, 1/in^2"], "estimate": [0.00064516], "ci_low": [0.0], "ci_high": [0.0]})
    >>> row = hypotheses_in_units(table, SI).iloc[0]
    >>> row["statistic"], round(float(row["estimate"]), 6)
    ('slope of fitted zeta vs bearing area at velocity amplitude 0.016 m/s, 1/m²', 1.0)
    """
    if units.velocity == INCH_SECOND.velocity or hypotheses is None or hypotheses.empty:
        return hypotheses

    def amplitudes(match: re.Match) -> str:
        low = f"{float(match[1]) * units.per_in_s:.3g}"
        high = f"-{float(match[2]) * units.per_in_s:.3g}" if match[2] else ""
        return f"{low}{high} {units.velocity}"

    shown = hypotheses.copy()
    per_area = shown["statistic"].astype(str).str.contains("1/in^2", regex=False)
    for column in ("estimate", "ci_low", "ci_high"):
        shown[column] = shown[column].where(~per_area, shown[column] / units.per_in2)
    shown["statistic"] = (
        shown["statistic"]
        .astype(str)
        .str.replace(_IN_S, amplitudes, regex=True)
        .str.replace("1/in^2", f"1/{units.area}", regex=False)
    )
    return shown


def hypothesis_summary(hypotheses: pd.DataFrame, units: UnitSystem = INCH_SECOND) -> list[list[str]]:
    """One row per hypothesis and configuration: verdicts over the amplitudes tested, in ``units``."""
    rows = []
    if hypotheses is None or hypotheses.empty:
        return rows
    hypotheses = hypotheses_in_units(hypotheses, units)
    for (hypothesis, configuration), part in hypotheses.groupby(["hypothesis", "configuration"], sort=False):
        counts = part["verdict"].value_counts()
        if len(part) == 1:
            verdicts = tag(part["verdict"].iloc[0], part["verdict"].iloc[0])
        else:
            verdicts = " ".join(
                tag(f"{verdict} at {count} of {len(part)}", verdict) for verdict, count in counts.items()
            )
        if (part["verdict"] == "not applicable").all():
            note = str(part["note"].iloc[0]) if "note" in part and part["note"].iloc[0] else "cannot run here"
            rows.append(
                [
                    esc(hypothesis),
                    esc(configuration),
                    verdicts,
                    "not applicable",
                    esc(part["statistic"].iloc[0]),
                    esc(f"not applicable: {note}"),
                ]
            )
            continue
        if len(part) == 1:
            r = part.iloc[0]
            estimates = f"{fmt(r.estimate)} [{fmt(r.ci_low)}, {fmt(r.ci_high)}]"
        else:
            estimates = (
                f"{fmt(part['estimate'].min())} to {fmt(part['estimate'].max())}; "
                f"intervals within [{fmt(part['ci_low'].min())}, {fmt(part['ci_high'].max())}]"
            )
        statistic = (
            re.sub(
                rf" at velocity amplitude [0-9.eE+-]+ {re.escape(units.velocity)}",
                " at each amplitude",
                str(part["statistic"].iloc[0]),
            )
            if len(part) > 1
            else part["statistic"].iloc[0]
        )
        rows.append(
            [
                esc(hypothesis),
                esc(configuration),
                verdicts,
                esc(
                    amplitude_range(
                        part["amplitude_low_in_s"].min(), part["amplitude_high_in_s"].max(), units
                    )
                ),
                esc(statistic),
                esc(estimates),
            ]
        )
    return rows


def excluded_runs(runs: pd.DataFrame) -> pd.DataFrame:
    if runs is None or runs.empty:
        return pd.DataFrame(columns=["configuration", "run", "path", "reason"])
    return runs[runs["status"] == "excluded"]


def _confidence_text(confidence: Mapping | None) -> str:
    """``microslip (power law) 0.93, none 0.05``: the largest shares, escaped."""
    shares = sorted((confidence or {}).items(), key=lambda item: -item[1])[:3]
    return esc(", ".join(f"{cause_name(cause)} {share:.2f}" for cause, share in shares))


def modes_section(document: Mapping) -> list[str]:
    """The verdict page's section on every mode and channel (diagnosis.json ``modes`` and
    ``channels``): a verdict per mode, and per configuration each channel's own; nothing
    for a campaign of one mode and one channel."""
    modes = document.get("modes") or []
    several_channels = any(
        entry.get("channels") for mode in modes for entry in mode.get("configurations", {}).values()
    )
    if len(modes) < 2 and not several_channels:
        return []
    parts = ["<h2>Every mode</h2>"]
    for mode in modes:
        mode_hz = mode.get("mode_hz")
        heading = f"mode {mode_hz:.5g} Hz" if isinstance(mode_hz, int | float) else "mode not found"
        parts.append(
            f"<h3>{esc(heading)}: {esc(cause_name(mode.get('cause')))}</h3>"
            f"<p>confidence: {_confidence_text(mode.get('confidence'))}</p>"
        )
        rows = []
        for name, entry in mode.get("configurations", {}).items():
            channels = entry.get("channels") or {}
            seen = "; ".join(
                f"{channel}: {cause_name(own.get('cause'))}" for channel, own in channels.items()
            )
            rows.append(
                [
                    esc(name),
                    esc(cause_name(entry.get("cause"))),
                    _confidence_text(entry.get("confidence")),
                    esc(fmt(entry.get("gain", {}).get("ratio"))),
                    esc(seen),
                ]
            )
        parts.append(
            html_table(
                ["configuration", "cause", "confidence", "ratio", "each channel's own verdict"],
                rows,
                numeric=(3,),
            )
        )
    parts.append(
        '<p class="note">Each mode is diagnosed on its own. With several channels a '
        "configuration's verdict is one joint analysis of every channel (each on one amplitude "
        "scale, in its own scatter, the same runs held out on all); each channel's own verdict is "
        "a consistency check. The paper's figures and models are the first mode's, on the first channel.</p>"
    )
    return parts


def verdict_html(
    document: Mapping,
    *,
    runs: pd.DataFrame | None = None,
    hypotheses: pd.DataFrame | None = None,
    areas: Mapping[str, float] | None = None,
    segments: pd.DataFrame | None = None,
    units: UnitSystem = INCH_SECOND,
) -> str:
    """The report's first page: the verdict of ``results/diagnosis.json`` in plain words.

    Parameters
    ----------
    document : mapping
        The diagnosis document (output contract).
    runs : DataFrame, optional
        ``results/tables/runs.parquet`` (for the excluded runs and their reasons).
    hypotheses : DataFrame, optional
        ``results/tables/hypotheses.parquet``.
    areas : mapping, optional
        Configuration -> bearing area (in²), for the table.
    segments : DataFrame, optional
        ``results/tables/segments.parquet``: the measured trends are said from it.
    units : UnitSystem
        Config ``units``: the page's amplitudes and areas are shown in it (the quoted
        discrepancy sentences of diagnosis.json keep its in/s).

    Returns
    -------
    str
        A complete HTML page.
    """
    entries = document.get("configurations", {})
    cause = document.get("cause", "unknown")
    trends = measured_trends(segments) if segments is not None else {}
    areas = dict(areas or {})
    across = document.get("across_configurations") or {}
    if not areas:
        areas = {n: c.get("bearing_area_in2") for n, c in (across.get("configurations") or {}).items()}
    one_run = any(_n_runs(entry) == 1 for entry in entries.values())
    parts = [f"<h1>Verdict: campaign {esc(document.get('campaign', '?'))}</h1>"]
    kind = "none" if cause == "none" else ("unknown" if cause == "unknown" else "")
    parts.append(
        f'<div class="headline {kind}"><b>Campaign verdict: '
        f"{esc(cause_name(cause))}.</b> {esc(campaign_headline(document))}</div>"
    )

    # what the paper's model gets wrong
    parts.append("<h2>What the paper's model gets wrong</h2>")
    if entries:
        parts.append(
            "<ul>"
            + "".join(
                f"<li><b>{esc(n)}</b> ({tag(cause_name(e.get('cause')), 'none' if e.get('cause') == 'none' else 'cause')}): "
                f"{esc(discrepancy_text(e, units))}"
                + (f" {esc(trend_sentence(trends[n], units))}" if n in trends else "")
                + _unidentified_tag(e)
                + "</li>"
                for n, e in entries.items()
            )
            + "</ul>"
        )
    if entries and units.velocity != INCH_SECOND.velocity:
        parts.append(
            f'<p class="note">Shown in {units.velocity} and {units.area}; diagnosis.json and the '
            f"tables keep in/s and in² (1 in/s = {INCH_SECOND.per_in_s * units.per_in_s:g} "
            f"{units.velocity}).</p>"
        )
    skipped = document.get("skipped_configurations") or {}
    if skipped:
        parts.append(
            "<p>Not diagnosed: "
            + "; ".join(f"<b>{esc(n)}</b> ({esc(reason)})" for n, reason in skipped.items())
            + ".</p>"
        )

    # cause and gain per configuration
    parts.append("<h2>Cause and extended model per configuration</h2>")
    parts.append(
        html_table(
            [
                "configuration",
                f"area ({units.area})",
                "baseline",
                "cause",
                "extended model",
                "held-out error: baseline",
                "extended",
                "ratio",
                "next-best candidate",
                "its error (× verdict's)",
            ],
            [_configuration_row(n, e, areas.get(n), units) for n, e in entries.items()],
            numeric=(1, 5, 6, 7, 9),
        )
    )
    parts.append(
        f'<p class="note">{esc(ERROR_UNIT)}{esc(ONE_RUN_ERROR_UNIT) if one_run else ""}. Ratio: extended / baseline held-out error; below 1 '
        "the extended model predicts better; with cause none the extended model is the "
        "baseline and the ratio is 1. Last column: the best other candidate's held-out error "
        "and how many times the verdict's it is.</p>"
    )
    for name, entry in entries.items():
        if entry.get("cause") not in ("none", "unknown"):
            parts.append(
                f"<p><b>{esc(name)}</b>, the cause: {esc(CAUSE_WORDS.get(entry['cause'], entry['cause']))}.</p>"
            )

    parts.extend(modes_section(document))

    # how sure
    parts.append("<h2>How sure we are</h2>")
    for name, entry in entries.items():
        parts.append(
            f"<h3>{esc(name)}</h3><ul>"
            + "".join(f"<li>{item}</li>" for item in _sureness_items(name, entry, units))
            + "</ul>"
        )
    if across:
        parts.append("<h3>Across configurations (predicting a left-out bearing area)</h3>")
        if across.get("applicable"):
            models = across.get("models") or {}
            parts.append(
                f"<p>With parameters linear in ln(bearing area) fitted to the other configurations, "
                f"the mean error predicting a left-out configuration is "
                f"{fmt(across.get('baseline_mean_error'))} for {esc(model_name(models.get('baseline')))} "
                f"and {fmt(across.get('extended_mean_error'))} for "
                f"{esc(model_name(models.get('extended')))} (ratio {ratio(across.get('ratio'))}), "
                "in units of the run-to-run scatter.</p>"
            )
            caveat = left_out_caveat(
                error
                for c in (across.get("configurations") or {}).values()
                for error in (c.get("baseline_error"), c.get("extended_error"))
            )
            if caveat:
                parts.append(f"<p>{esc(caveat)}</p>")
        else:
            parts.append(f"<p>Not applicable: {esc(across.get('reason', 'no reason given'))}.</p>")

    # hypotheses
    parts.append("<h2>The paper's hypotheses</h2>")
    rows = hypothesis_summary(hypotheses, units) if hypotheses is not None else []
    if rows:
        parts.append(
            html_table(
                [
                    "hypothesis",
                    "configuration",
                    "verdict",
                    "amplitudes tested",
                    "statistic",
                    "estimate [95 % CI]",
                ],
                rows,
            )
        )
    else:
        parts.append("<p>No hypothesis could be tested.</p>")

    # excluded runs
    parts.append("<h2>Runs</h2>")
    if runs is not None and not runs.empty:
        excluded = excluded_runs(runs)
        used = int((runs["status"] == "used").sum())
        parts.append(f"<p>{used} of {len(runs)} run files used, {len(excluded)} excluded.</p>")
        if len(excluded):
            parts.append(
                html_table(
                    ["configuration", "run", "file", "reason"],
                    [
                        [esc(r.configuration), esc(r.run), esc(r.path), esc(r.reason)]
                        for r in excluded.itertuples()
                    ],
                    row_classes=["excluded"] * len(excluded),
                )
            )
    parts.append(
        '<p class="note">The figures and tables behind this page are in the other '
        "categories of the report: measured data, damping and area fits, friction models, "
        "diagnosis (residuals, candidates, held-out prediction) and quality.</p>"
    )
    return page(f"Verdict: {document.get('campaign', '')}", "\n".join(parts))


# ------------------------------------------------------------------ tables
def hypotheses_html(hypotheses: pd.DataFrame, units: UnitSystem = INCH_SECOND) -> str:
    """Every hypothesis test, one row per configuration and amplitude, in ``units``."""
    hypotheses = hypotheses_in_units(hypotheses, units)
    rows = [
        [
            esc(r.hypothesis),
            esc(r.configuration),
            tag(r.verdict, r.verdict),
            esc(r.statistic),
            fmt(r.estimate),
            f"{fmt(r.ci_low)} – {fmt(r.ci_high)}",
            fmt(100 * r.confidence, 3),
            esc(amplitude_range(r.amplitude_low_in_s, r.amplitude_high_in_s, units)),
            str(r.n_runs),
            esc(r.note or ""),
        ]
        for r in hypotheses.itertuples()
    ]
    body = (
        "<h1>The paper's hypotheses</h1>"
        "<p>H1: damping rises with amplitude at low amplitude (per configuration). "
        "H2: damping rises with bearing area (across configurations, at amplitudes all "
        "reach). Supported: the confidence interval excludes zero on the predicted side; "
        "contradicted: it excludes zero on the other side; inconclusive: it contains zero.</p>"
        + html_table(
            [
                "hypothesis",
                "configuration",
                "verdict",
                "statistic",
                "estimate",
                "confidence interval",
                "confidence (%)",
                "amplitudes",
                "runs",
                "note",
            ],
            rows,
            numeric=(4, 5, 6, 8),
        )
    )
    return page("Hypotheses", body)


def runs_in_recorded_order(runs: pd.DataFrame) -> tuple[pd.DataFrame, dict[str, str]]:
    """The runs table with each configuration's rows in run order, and which order that is.

    Run order is the order of the recording start times (``record_start``) when every
    file of the configuration states one, else of the file names
    (:func:`workflow.io.recording_time.run_order`); rows that are not run files (a glob
    that matched nothing) keep their place after the runs.
    """
    starts = runs["record_start"] if "record_start" in runs else pd.Series("", index=runs.index)
    parts, orders = [], {}
    for name, part in runs.groupby("configuration", sort=False):
        names = part["run"].astype(str)
        ordered, orders[name] = run_order(list(names), dict(zip(names, starts[part.index].fillna(""))))
        rank = {run: i for i, run in enumerate(ordered)}
        parts.append(part.iloc[np.argsort(names.map(rank).to_numpy(), kind="stable")])
    return (pd.concat(parts) if parts else runs), orders


def runs_html(runs: pd.DataFrame) -> str:
    """Every run file: used or excluded, and why; each configuration's runs in run order."""
    runs, orders = runs_in_recorded_order(runs)
    counts = runs.groupby("configuration", sort=False)["status"].value_counts().unstack(fill_value=0)
    summary = html_table(
        ["configuration", "used", "excluded"],
        [
            [esc(name), str(int(row.get("used", 0))), str(int(row.get("excluded", 0)))]
            for name, row in counts.iterrows()
        ],
        numeric=(1, 2),
    )
    recorded = runs["record_start"].fillna("") if "record_start" in runs else pd.Series("", index=runs.index)
    rows = [
        [
            esc(r.configuration),
            esc(r.run),
            esc(r.path),
            esc(recorded[r.Index]),
            tag(r.status, r.status),
            esc(r.reason),
        ]
        for r in runs.itertuples()
    ]
    order_notes = "".join(f"<li>{esc(name)}: run order: {esc(order)}</li>" for name, order in orders.items())
    body = (
        "<h1>Runs and quality checks</h1>"
        + summary
        + f"<ul>{order_notes}</ul>"
        + html_table(
            ["configuration", "run", "file", "recording start", "status", "reason"],
            rows,
            row_classes=["excluded" if r.status == "excluded" else "" for r in runs.itertuples()],
        )
    )
    return page("Runs", body)


def damping_fits_html(fits: pd.DataFrame) -> str:
    """Polynomial damping fits per configuration."""
    rows = []
    for r in fits.itertuples():
        coefficients = ", ".join(fmt(c, 4) for c in (r.coefficients if r.coefficients is not None else []))
        rows.append(
            [
                esc(r.configuration),
                fmt(r.bearing_area_in2),
                str(r.degree),
                esc(coefficients),
                esc(r.x_transform),
                fmt(r.cv_rmse_at_degree),
                str(r.n_runs),
                str(r.n_segments),
                esc(amplitude_range(r.amplitude_low_in_s, r.amplitude_high_in_s)),
                esc(r.cv_scheme),
            ]
        )
    body = (
        "<h1>Damping fits</h1><p>ζ (fraction of critical) as a polynomial in "
        "x = log10(velocity amplitude / 1 in/s), coefficients from the constant term up; "
        "degree chosen by cross-validation.</p>"
        + html_table(
            [
                "configuration",
                "bearing area (in²)",
                "degree",
                "coefficients (ζ, constant first)",
                "x",
                "CV RMSE of ζ",
                "runs",
                "segments",
                "amplitude range",
                "degree chosen by",
            ],
            rows,
            numeric=(1, 2, 5, 6, 7),
        )
    )
    return page("Damping fits", body)


def _parameter_line(name: str, value: float, std: float, units: UnitSystem) -> str:
    """``sigma = 2891 ± 61 lbf/in`` (HTML), in ``units``, with a word when the uncertainty
    leaves the value undetermined (:func:`~workflow.outputs.plain_words.uncertainty_note`)."""
    unit, unit_si, factor_si = MODEL_PARAMETER_UNITS.get(name, ("", "", 1.0))
    if units.name == "si":
        unit, value, std = unit_si, value * factor_si, std * factor_si
    unit = "" if unit in ("", "1") else f" {unit}"
    note = uncertainty_note(value, std)
    return f"{esc(name)} = {fmt(value, 4)} ± {fmt(std, 2)}{esc(unit)}" + (
        f" <i>({esc(note)})</i>" if note else ""
    )


def model_fits_html(fits: pd.DataFrame, units: UnitSystem = INCH_SECOND) -> str:
    """Dahl and LuGre parameters per configuration, value ± one sigma with its unit (in
    ``units``), fit quality."""
    rows = []
    for (configuration, model), part in fits.groupby(["configuration", "model"], sort=False):
        first = part.iloc[0]
        params = "<br>".join(_parameter_line(p.parameter, p.value, p.std, units) for p in part.itertuples())
        rows.append(
            [
                esc(configuration),
                esc(model_name(model)),
                params,
                fmt(first["rms_log_zeta"]),
                fmt(100 * first["rms_rel_frequency"]),
                esc(first.get("modal_coordinate", "")),
            ]
        )
    body = (
        "<h1>Friction model fits</h1><p>Each model simulated through the same band-pass, "
        "envelope and log decrement as the data; parameters ± one sigma from the Jacobian.</p>"
        + html_table(
            [
                "configuration",
                "model",
                "parameters (± 1σ)",
                "RMS error of ln ζ",
                "RMS error of frequency (%)",
                "modal coordinate",
            ],
            rows,
            numeric=(3, 4),
        )
    )
    return page("Friction model fits", body)


def candidates_html(document: Mapping) -> str:
    """Every model tried by the diagnosis, per configuration: held-out errors, BIC, params."""
    parts = [
        "<h1>Diagnosis: every candidate</h1>",
        f'<p class="note">{esc(ERROR_UNIT)}. ΔBIC is against the baseline (negative: better '
        "after paying for the extra parameters).</p>",
    ]
    for name, entry in (document.get("configurations") or {}).items():
        evidence = entry.get("evidence") or {}
        parts.append(f"<h2>{esc(name)}: {tag(cause_name(entry.get('cause')), 'cause')}</h2>")
        rows = []
        for model, b in (evidence.get("baselines") or {}).items():
            rows.append(
                [
                    esc(
                        f"paper's model ({'baseline' if model == entry['baseline']['model'] else 'not used'})"
                    ),
                    esc(model_name(model)),
                    fmt(b.get("heldout_error")),
                    fmt(b.get("heldout_error_zeta")),
                    fmt(b.get("heldout_error_frequency")),
                    "–",
                    fmt(b.get("bic")),
                    "–",
                    "",
                ]
            )
        for cause, c in (evidence.get("candidates") or {}).items():
            params = ", ".join(f"{esc(k)} = {fmt(v)}" for k, v in (c.get("params") or {}).items())
            rows.append(
                [
                    esc(cause_name(cause)),
                    esc(model_name(c.get("model"))),
                    fmt(c.get("heldout_error")),
                    fmt(c.get("heldout_error_zeta")),
                    fmt(c.get("heldout_error_frequency")),
                    ratio(c.get("ratio_to_baseline")),
                    fmt(c.get("bic")),
                    fmt(c.get("delta_bic")),
                    params,
                ]
            )
        parts.append(
            html_table(
                [
                    "cause",
                    "model",
                    "held-out error",
                    "… damping",
                    "… frequency",
                    "ratio to baseline",
                    "BIC",
                    "ΔBIC",
                    "parameters",
                ],
                rows,
                numeric=(2, 3, 4, 5, 6, 7),
            )
        )
        parts.append(f"<p>{esc(entry.get('discrepancy', ''))}</p>")
    return page("Diagnosis candidates", "\n".join(parts))


def rejected_segments_html(rejected: pd.DataFrame) -> str:
    """Count of dropped segments per configuration and rule."""
    if rejected is None or rejected.empty:
        return page("Rejected segments", "<h1>Rejected segments</h1><p>No segment was dropped.</p>")
    frame = rejected[~rejected["kept"].astype(bool)] if "kept" in rejected else rejected
    exploded = frame.assign(rule=frame["reject_reason"].astype(str).str.split(",")).explode("rule")
    table = exploded.groupby(["configuration", "rule"], sort=False).size().unstack(fill_value=0)
    header = ["configuration", *[esc(c) for c in table.columns], "segments dropped"]
    totals = frame.groupby("configuration", sort=False).size()
    rows = [
        [esc(name), *[str(int(v)) for v in row.values], str(int(totals.get(name, 0)))]
        for name, row in table.iterrows()
    ]
    body = (
        "<h1>Rejected segments</h1><p>Segments dropped by each rule "
        "(a segment can be dropped by several; see docs/decay_analysis.md).</p>"
        + html_table(header, rows, numeric=tuple(range(1, len(header))))
    )
    return page("Rejected segments", body)


# ------------------------------------------------------------------ the first page (rst)
def verdict_rst(
    document: Mapping,
    *,
    runs: pd.DataFrame | None = None,
    hypotheses: pd.DataFrame | None = None,
    segments: pd.DataFrame | None = None,
    units: UnitSystem = INCH_SECOND,
) -> str:
    """The verdict in a few short paragraphs of reStructuredText (the report's first page).

    Narrow enough for the column Snakemake's report gives its workflow description:
    no tables, one bullet per configuration. The full page with the evidence is
    :func:`verdict_html`.
    """
    entries = document.get("configurations", {})
    cause = document.get("cause", "unknown")
    trends = measured_trends(segments) if segments is not None else {}
    title = rst_text(f"Verdict: {cause_name(cause)}")
    lines = [title, "=" * len(title), ""]
    if document.get("campaign"):
        lines += [f"Campaign {rst_strong(document['campaign'])}.", ""]
    # whole sentences are not shortened: only the campaign's text in them is (display_text)
    lines += [rst_text(campaign_headline(document), limit=None), ""]
    for name, entry in entries.items():
        gain = entry.get("gain") or {}
        base = model_name(entry.get("baseline", {}).get("model"))
        if entry.get("cause") == "none":
            text = f"{base} fits within the run-to-run scatter (held-out error {fmt(gain.get('baseline'))})."
        else:
            text = discrepancy_text(entry, units)
            if entry.get("cause") != "unknown":
                text += (
                    f" {model_name(entry.get('extended_model', {}).get('model'))} predicts "
                    f"{'held-out runs' if _n_runs(entry) > 1 else 'held-out amplitude ranges of the one run'} "
                    f"with {ratio(gain.get('ratio'))} of {base}'s error "
                    f"({fmt(gain.get('extended'))} against {fmt(gain.get('baseline'))})."
                )
                margin = candidate_margin(entry)
                if margin and margin["ratio"] is not None and margin["ratio"] >= 1:
                    confidence = (entry.get("confidence") or {}).get(entry.get("cause"))
                    text += (
                        f" It is {margin_words(margin['ratio'], confidence)} the next best, "
                        f"{candidate_name(margin['next'])}, which has {ratio(margin['ratio'])} times "
                        "its error."
                    )
        if name in trends:
            text += " " + trend_sentence(trends[name], units)
        unidentified = unidentified_sentence(_unidentified(entry, units))
        if unidentified:
            text += " " + unidentified
        lines += [
            f"* {rst_strong(name)}: *{rst_text(cause_name(entry.get('cause')))}*. "
            + rst_text(text, limit=None),
            "",
        ]
    skipped = document.get("skipped_configurations") or {}
    for name, reason in skipped.items():
        lines += [f"* {rst_strong(name)}: not diagnosed ({rst_text(reason)}).", ""]
    if hypotheses is not None and not hypotheses.empty:
        parts = []
        for hypothesis, part in hypotheses.groupby("hypothesis", sort=False):
            verdicts = []
            for configuration, sub in part.groupby("configuration", sort=False):
                counts = sub["verdict"].value_counts()
                if len(sub) == 1:
                    verdicts.append(f"{sub['verdict'].iloc[0]} for {configuration}")
                else:
                    verdicts.append(
                        ", ".join(f"{v} at {c} of {len(sub)} amplitudes" for v, c in counts.items())
                    )
            parts.append(f"{hypothesis}: {'; '.join(verdicts)}.")
        lines += ["**The paper's hypotheses.** " + rst_text(" ".join(parts), limit=None), ""]
    if runs is not None and not runs.empty:
        excluded = excluded_runs(runs)
        text = f"{int((runs['status'] == 'used').sum())} of {len(runs)} run files used"
        if len(excluded):
            text += "; excluded: " + "; ".join(
                f"{display_text(r.configuration)}/{display_text(r.run)} ({display_text(r.reason)})"
                for r in excluded.itertuples()
            )
        lines += ["**Runs.** " + rst_text(text + ".", limit=None), ""]
    lines += [
        "The evidence (held-out errors of every candidate, margins, residual tests) is on "
        "the page verdict.html_ in category `1 Verdict`_; the figures and tables are in "
        "the categories listed under *Results*.",
        "",
    ]
    return "\n".join(lines)


def landing_rst(verdict: str, description: str) -> str:
    """The report's first page: the verdict, then the workflow description.

    ``verdict`` (:func:`verdict_rst`) holds the campaign's text only as
    :func:`~workflow.outputs.escape.rst_text`, in which no Jinja tag can form, so it goes
    through Snakemake's Jinja rendering of the page as it is; ``description``
    (report/workflow.rst) keeps its Jinja expressions.
    """
    heading = "About this study"
    return verdict + "\n\n" + heading + "\n" + "=" * len(heading) + "\n\n" + description


def quality_html(quality: pd.DataFrame) -> str:
    """The quality checks of every run: one row per run, one column per check.

    ``quality`` is ``results/tables/quality.parquet``: ``configuration``, ``run`` and
    one row per check with ``check``, ``applied``, ``passed``, ``value``,
    ``threshold``, ``unit``, ``reason``. A failed check is shaded and its reason
    shown on hover; a check that does not apply shows '-'.
    """
    if quality is None or quality.empty:
        return page("Quality checks", "<h1>Quality checks</h1><p>No quality check was recorded.</p>")
    checks = list(dict.fromkeys(quality["check"]))
    header = ["configuration", "run"]
    for check in checks:
        rows = quality[quality["check"] == check]
        unit = str(rows["unit"].iloc[0]) if "unit" in rows else ""
        threshold = rows["threshold"].iloc[0] if "threshold" in rows else None
        detail = "; ".join(
            part for part in (esc(unit), f"limit {fmt(threshold)}" if fmt(threshold) != "–" else "") if part
        )
        header.append(f'{esc(check)}<br><span class="note">{detail}</span>' if detail else esc(check))
    body_rows, classes = [], []
    for (configuration, run), part in quality.groupby(["configuration", "run"], sort=False):
        by_check = {r.check: r for r in part.itertuples()}
        cells, failed_any = [esc(configuration), esc(run)], False
        for check in checks:
            r = by_check.get(check)
            if r is None or not bool(r.applied):
                cells.append("–")
            elif bool(r.passed):
                cells.append(fmt(r.value))
            else:
                failed_any = True
                cells.append(f'<span class="tag excluded" title="{esc(r.reason)}">{fmt(r.value)} ✗</span>')
        body_rows.append(cells)
        classes.append("excluded" if failed_any else "")
    failed = quality[quality["applied"].astype(bool) & ~quality["passed"].astype(bool)]
    reasons = ""
    if len(failed):
        reasons = "<h2>Failed checks</h2>" + html_table(
            ["configuration", "run", "check", "value", "limit", "reason"],
            [
                [
                    esc(r.configuration),
                    esc(r.run),
                    esc(r.check),
                    fmt(r.value),
                    fmt(r.threshold),
                    esc(r.reason),
                ]
                for r in failed.itertuples()
            ],
            numeric=(3, 4),
        )
    body = (
        "<h1>Quality checks</h1><p>The measured value of every check for every run, with "
        "the limit from config.yaml (quality). Shaded: a check failed and the run was "
        "excluded; '–': the check does not apply (no force column, pre-trigger not stated, "
        "...).</p>"
        + html_table(header, body_rows, numeric=tuple(range(2, len(header))), row_classes=classes)
        + reasons
    )
    return page("Quality checks", body)

"""The report's shared wording: names of models and causes, and the sentences of the
verdict (headline, margins, gains, measured trends, signatures, thresholds) that the
verdict page (:mod:`workflow.outputs.verdict_page`) and the first page
(:mod:`workflow.outputs.landing_page`) both say.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from workflow.discovery.confidence import verdict_key
from workflow.discovery.misfit import MIN_BIN_RUNS, MIN_BIN_SEGMENTS_ONE_RUN
from workflow.discovery.wording import discrepancy_sentence, runs_words
from workflow.io.units import INCH_SECOND, UnitSystem
from workflow.outputs.plain_words import unidentified_parameters
from workflow.outputs.report_html import amplitude_range, fmt, ratio
from workflow.outputs.run_levels import within_run_change

__all__ = [
    "CAUSE_WORDS",
    "CLEAR_MARGIN",
    "CLEAR_CONFIDENCE",
    "FLAT_CHANGE",
    "CAUSE_NAMES",
    "MODEL_NAMES",
    "ERROR_UNIT",
    "ONE_RUN_ERROR_UNIT",
    "model_name",
    "cause_name",
    "entry_causes",
    "verdict_name",
    "verdict_confidence",
    "candidate_name",
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
    "unidentified_parameters_of",
    "n_runs_of",
    "hypothesis_verdicts",
    "excluded_runs",
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


def model_name(model_id: str | None) -> str:
    """Display name of a model id; a combined model (``iwan_cells_<n>_quadratic``,
    ``iwan_cells_<n>_stiffness``) names its added term.

    >>> model_name("iwan_cells_4_quadratic")
    'Iwan micro-slip with slip thresholds from the data + quadratic damping'
    """
    if model_id and model_id.startswith("iwan_cells_"):
        added = {"quadratic": " + quadratic damping", "stiffness": " + nonlinear stiffness"}
        term = added.get(model_id.rsplit("_", 1)[-1], "")
        return f"Iwan micro-slip with slip thresholds from the data{term}"
    return MODEL_NAMES.get(model_id or "", model_id or "?")


def cause_name(cause: str | None) -> str:
    """Short name of a cause, or of a combination by its ``confidence`` key.

    >>> cause_name("microslip_power_law+quadratic_damping")
    'micro-slip (power law) + quadratic damping'
    """
    if cause and "+" in cause:
        return " + ".join(CAUSE_NAMES.get(part, part) for part in cause.split("+"))
    return CAUSE_NAMES.get(cause or "", cause or "?")


def entry_causes(entry: Mapping) -> list[str]:
    """The mechanisms of a verdict of diagnosis.json, of one of its modes or configurations:
    ``causes``, the largest share of the gain first, or ``cause`` alone where a document
    has no ``causes`` (``unknown`` where it has neither)."""
    return list(entry.get("causes") or [entry.get("cause") or "unknown"])


def verdict_name(entry: Mapping) -> str:
    """The verdict of diagnosis.json, of one of its modes or configurations: every
    mechanism of ``causes`` named, the largest share of the gain first (``cause`` alone is
    only the first).

    >>> verdict_name({"cause": "stiffness_nonlinearity",
    ...               "causes": ["stiffness_nonlinearity", "microslip_power_law"]})
    'stiffness nonlinearity + micro-slip (power law)'
    """
    return " + ".join(cause_name(cause) for cause in entry_causes(entry))


def verdict_confidence(entry: Mapping) -> float | None:
    """The verdict's share of ``confidence`` (a combination's under its key,
    :func:`~workflow.discovery.confidence.verdict_key`); None where there is none.

    >>> verdict_confidence({"cause": "quadratic_damping", "causes": ["quadratic_damping", "microslip_power_law"],
    ...                     "confidence": {"microslip_power_law+quadratic_damping": 0.9, "quadratic_damping": 0.1}})
    0.9
    """
    share = (entry.get("confidence") or {}).get(verdict_key(entry_causes(entry)))
    return None if share is None else float(share)


def candidate_name(cause: str | None) -> str:
    """A candidate cause as the model it stands for ('none' is the baseline itself)."""
    return "the baseline itself (no extension)" if cause == "none" else cause_name(cause)


# ------------------------------------------------------------------ the verdict
def candidate_margin(entry: Mapping) -> dict | None:
    """How far the chosen cause is from the next candidate, by held-out error.

    The verdict's error is that of its extended model (``gain.extended``, the error the
    table and the candidates figure give it: the slip thresholds recovered from the data
    where they replaced the power law); the next candidate is the best of the other
    causes of the ranking (a combination counts as its own cause, keyed as in
    :func:`~workflow.discovery.confidence.verdict_key`).

    Returns
    -------
    dict or None
        ``chosen``/``chosen_score`` (the verdict's held-out error), ``next``/
        ``next_score`` (the best other candidate) and ``ratio`` = next / chosen
        (above 1: the verdict predicts held-out runs better by that factor; below 1:
        the other candidate scored lower but was not accepted, see ``decision_rule``).
    """
    ranking = [r for r in entry.get("ranking", []) if r.get("score") is not None]
    cause = entry.get("cause")
    # unknown keeps the baseline: compare it with the best candidate
    chosen = "none" if cause in ("none", "unknown") else verdict_key(entry_causes(entry))
    mine = [r for r in ranking if r["cause"] == chosen]
    others = [r for r in ranking if r["cause"] != chosen]
    if not mine or not others:
        return None
    best_other = min(others, key=lambda r: r["score"])
    extended = (entry.get("gain") or {}).get("extended")
    chosen_score = float(extended if chosen != "none" and extended is not None else mine[0]["score"])
    next_score = float(best_other["score"])
    ratio = next_score / chosen_score if chosen_score > 0 else None
    return {
        "chosen": cause,
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
    own = signature.get("own_shape_share")
    own_words = (
        ""
        if own is None
        else f", and only {fmt(own, 2)} of its term's change is not proportional to the friction's softening"
    )
    return [
        f"{cause_name('stiffness_nonlinearity')} is not eligible: over the measured amplitudes its fit "
        f"changes the frequency by {fmt(100 * whole, 2)} %, less than its friction alone "
        f"({fmt(100 * friction, 2)} %), never raises it with amplitude{own_words}; its stiffness term "
        "cancels part of the friction's frequency change instead of showing one the friction cannot "
        "explain (the contract's signature)."
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
        return [
            f"{model} explains the data: every half decade of amplitude with {MIN_BIN_RUNS} runs or more "
            f"(one run: {MIN_BIN_SEGMENTS_ONE_RUN} segments) is within {limit} scatters."
        ]
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
        f"from the data in {len(cells)} quarter-decade cells: held-out error "
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
        end_bins = {
            end: _end_bin(codes, counts, from_top) for end, from_top in (("low", False), ("high", True))
        }
        runs = part["run"].to_numpy() if "run" in part else np.zeros(len(part))
        trend["zeta_change_within_runs"], trend["zeta_change_error"] = within_run_change(
            runs, code, np.log(part["zeta"].to_numpy(float)), end_bins["low"], end_bins["high"]
        )
        for end in ("low", "high"):
            inside = np.isin(code, end_bins[end])
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
    within = trend.get("zeta_change_within_runs", math.nan)
    # a difference of the ends that each run's own change does not show is the runs' levels
    levels_differ = zeta != "stays level" and abs(within) < max(
        2 * trend["zeta_change_error"], math.log1p(FLAT_CHANGE)
    )
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
    if turn is None and levels_differ:
        damping = (
            f"the damping stays level within each run ({100 * math.expm1(within):+.1f} % from end to end, "
            f"runs' own levels removed), the runs reaching each end sitting at levels of their own: "
            f"{low_end} and {high_end}"
        )
    elif turn is None:
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


def unidentified_parameters_of(entry: Mapping, units: UnitSystem = INCH_SECOND) -> list[dict]:
    """The parameters of the baseline and the extended model that the data do not
    determine (their ``flags``), each once (:func:`~workflow.outputs.plain_words.unidentified_parameters`)."""
    return unidentified_parameters(
        (("the baseline", entry.get("baseline")), ("the extended model", entry.get("extended_model"))),
        units,
    )


def n_runs_of(entry: Mapping) -> int:
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
        words.append(
            gain_words(
                (entries[n].get("gain") or {}).get("ratio"),
                margin.get("ratio"),
                verdict_confidence(entries[n]),
            )
        )
    word = "clearly better" if words and all(w == "clearly better" for w in words) else "better"
    text = (
        f"The paper's friction model (the better of Dahl and LuGre) falls short in "
        f"{len(failing)} of {len(names)} configuration{'s' if len(names) != 1 else ''} "
        f"({which}): a model with the missing physics predicts "
        f"{'runs' if all(n_runs_of(entries[n]) > 1 for n in failing) else 'data'} held out of the fit "
        f"{word}. "
    )
    ratios = [
        entries[n]["gain"].get("ratio")
        for n in failing
        if entries[n].get("cause") == cause and entries[n].get("gain")
    ]
    ratios = [r for r in ratios if r is not None]
    extended = [entries[n]["extended_model"]["model"] for n in failing if entries[n].get("cause") == cause]
    causes = entry_causes(document)
    if len(causes) == 1:
        text += f"The cause: {CAUSE_WORDS.get(cause, cause)}."
    else:
        text += (
            "The causes, the largest share of the gain first: "
            + "; and ".join(CAUSE_WORDS.get(c, c) for c in causes)
            + "."
        )
    if extended and ratios:
        best = min(ratios)
        held_out = (
            "predicts runs it was not fitted to"
            if all(n_runs_of(entries[n]) > 1 for n in failing)
            else "predicts amplitude ranges held out of the fit (with one run, no run could be held out)"
        )
        text += (
            f" The extended model, {model_name(extended[0])}, {held_out} with {ratio(best)} of "
            "the baseline's error" + (f" ({fmt(1 / best, 2)} times better)" if best > 0 else "") + "."
        )
    return text


def hypothesis_verdicts(part: pd.DataFrame) -> list[tuple[str, str]]:
    """The verdicts of one hypothesis in one configuration, as ``(verdict, where)``.

    A test at one amplitude (``amplitude_low_in_s == amplitude_high_in_s``, one point of
    figure 13's right panel) counts as an amplitude: ``("supported", "at 5 of 5
    amplitudes")`` per verdict; a test over their span (the mean of the slopes) is
    ``(verdict, "over their mean")``, never an amplitude more. A single test: ``(verdict, "")``.

    Examples
    --------
    >>> part = pd.DataFrame({"verdict": ["supported"] * 3, "amplitude_low_in_s": [0.6, 1.0, 0.6],
    ...                      "amplitude_high_in_s": [0.6, 1.0, 1.0]})
    >>> hypothesis_verdicts(part)
    [('supported', 'at 2 of 2 amplitudes'), ('supported', 'over their mean')]
    """
    if len(part) == 1:
        return [(str(part["verdict"].iloc[0]), "")]
    single = part["amplitude_low_in_s"] == part["amplitude_high_in_s"]
    at = part[single]
    verdicts = [(str(v), f"at {c} of {len(at)} amplitudes") for v, c in at["verdict"].value_counts().items()]
    return verdicts + [(str(v), "over their mean") for v in part.loc[~single, "verdict"]]


def excluded_runs(runs: pd.DataFrame) -> pd.DataFrame:
    if runs is None or runs.empty:
        return pd.DataFrame(columns=["configuration", "run", "path", "reason"])
    return runs[runs["status"] == "excluded"]

"""The verdict page (:func:`verdict_html`), self-contained HTML.

Pure functions: they take ``results/diagnosis.json`` (output contract) and the Parquet
tables as Python objects and return text; ``scripts/report_summary.py`` writes the page
to ``results/report/``. The verdict in plain words: what the paper's model gets wrong,
the cause per configuration and for the campaign, the extended model and its held-out
gain, how sure we are, the hypotheses and the excluded runs.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

import pandas as pd

from workflow.discovery.wording import runs_words
from workflow.io.units import INCH_SECOND, UnitSystem
from workflow.outputs.plain_words import (
    left_out_caveat,
    percent_of,
    unidentified_sentence,
)
from workflow.outputs.report_html import (
    amplitude_range,
    esc,
    fmt,
    html_table,
    page,
    ratio,
    scaled_number,
    tag,
)
from workflow.outputs.report_tables import hypotheses_in_units
from workflow.outputs.report_wording import (
    CAUSE_WORDS,
    CLEAR_CONFIDENCE,
    CLEAR_MARGIN,
    ERROR_UNIT,
    ONE_RUN_ERROR_UNIT,
    campaign_headline,
    candidate_margin,
    candidate_name,
    cause_name,
    discrepancy_text,
    excluded_runs,
    explains_sentences,
    hypothesis_verdicts,
    margin_words,
    measured_trends,
    model_name,
    n_runs_of,
    signature_sentences,
    threshold_sentences,
    trend_sentence,
    unidentified_parameters_of,
    verdict_confidence,
    verdict_name,
)

__all__ = [
    "gain_route",
    "hypothesis_summary",
    "modes_section",
    "verdict_html",
]


def _unidentified_tag(entry: Mapping) -> str:
    """A short tag pointing to the sentence on the parameters the data do not determine."""
    count = len(unidentified_parameters_of(entry))
    if not count:
        return ""
    return " " + tag(
        f"{count} fitted parameter{'s' if count > 1 else ''} not determined by the data (see How sure we are)",
        "flag",
    )


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
        fmt(scaled_number(area_in2, units.per_in2)),
        esc(model_name(entry.get("baseline", {}).get("model"))),
        tag(verdict_name(entry), "none" if entry.get("cause") == "none" else "cause"),
        esc(model_name(entry.get("extended_model", {}).get("model"))),
        fmt(gain.get("baseline")),
        fmt(gain.get("extended")),
        ratio(gain.get("ratio")),
        next_text,
        margin_text,
    ]


def gain_route(gain_ratio: float | None, candidate: Mapping, evidence: Mapping) -> str:
    """Why a named candidate's gain was enough, by the decision rule's own routes
    (:func:`workflow.discovery.decision.decide`): the baseline's misfit is significant
    (then any candidate lowering the held-out error and the BIC may be named), or the
    ratio is below the clear-gain threshold, or the candidate removes more held-out
    misfit than the models' accuracy.

    >>> gain_route(0.713, {}, {"clear_gain_threshold": 0.7, "baseline_misfit_significant": True})
    "ratio 0.71; the baseline's misfit is significant, so a lower held-out error and information criterion suffice"
    >>> gain_route(0.698, {}, {"clear_gain_threshold": 0.7, "baseline_misfit_significant": False})
    'ratio 0.698, below the clear-gain ratio 0.70'
    """
    threshold = evidence.get("clear_gain_threshold")
    text = f"ratio {ratio(gain_ratio)}"
    if gain_ratio is not None and threshold is not None and ratio(gain_ratio) == ratio(threshold):
        text = f"ratio {gain_ratio:.3f}"  # two decimals would read as the threshold itself
    if evidence.get("baseline_misfit_significant"):
        return (
            text + "; the baseline's misfit is significant, so a lower held-out error and "
            "information criterion suffice"
        )
    if gain_ratio is not None and threshold is not None and gain_ratio < threshold:
        return text + f", below the clear-gain ratio {ratio(threshold)}"
    if candidate.get("beyond_accuracy"):
        return (
            text + f", not below the clear-gain ratio {ratio(threshold)}, but it removes more "
            "held-out misfit than the models' accuracy"
        )
    return text + f"; a clear gain needs a ratio below {ratio(threshold)}"


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
            f"({gain_route(candidate.get('ratio_to_baseline', gain.get('ratio')), candidate, evidence)})"
        )
        if candidate.get("delta_bic") is not None:
            text += (
                f" and the information criterion by {fmt(-candidate['delta_bic'])} "
                f"(ΔBIC {fmt(candidate['delta_bic'])})"
            )
        items.append(text + ".")
        if candidate.get("residual_significant"):
            # the candidate's, which may not be the extended model the residual figure draws
            items.append(
                f"{model_name(candidate.get('model'))} leaves some misfit "
                f"({candidate.get('significant_bins', '?')} amplitude bin(s) still significant): "
                "it is better, not perfect."
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
            confidence = verdict_confidence(entry)
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
    unidentified = unidentified_sentence(unidentified_parameters_of(entry, units))
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


def hypothesis_summary(hypotheses: pd.DataFrame, units: UnitSystem = INCH_SECOND) -> list[list[str]]:
    """One row per hypothesis and configuration: verdicts over the amplitudes tested, in ``units``."""
    rows = []
    if hypotheses is None or hypotheses.empty:
        return rows
    hypotheses = hypotheses_in_units(hypotheses, units)
    for (hypothesis, configuration), part in hypotheses.groupby(["hypothesis", "configuration"], sort=False):
        verdicts = " ".join(
            tag(f"{verdict} {where}".strip(), verdict) for verdict, where in hypothesis_verdicts(part)
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
            f"<h3>{esc(heading)}: {esc(verdict_name(mode))}</h3>"
            f"<p>confidence: {_confidence_text(mode.get('confidence'))}</p>"
        )
        rows = []
        for name, entry in mode.get("configurations", {}).items():
            channels = entry.get("channels") or {}
            seen = "; ".join(f"{channel}: {verdict_name(own)}" for channel, own in channels.items())
            rows.append(
                [
                    esc(name),
                    esc(verdict_name(entry)),
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
        "a consistency check. The paper's figures and models are the first mode's, on the first "
        "channel listed that the runs kept (the tables' <code>channel</code>).</p>"
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

    Examples
    --------
    The campaign's text reaches the page only escaped:

    >>> page = verdict_html({"campaign": "<b>washers</b>", "cause": "none", "configurations": {}})
    >>> page.startswith("<!DOCTYPE html>"), "<title>Verdict: &lt;b&gt;washers&lt;/b&gt;</title>" in page
    (True, True)
    """
    entries = document.get("configurations", {})
    cause = document.get("cause", "unknown")
    trends = measured_trends(segments) if segments is not None else {}
    areas = dict(areas or {})
    across = document.get("across_configurations") or {}
    if not areas:
        areas = {n: c.get("bearing_area_in2") for n, c in (across.get("configurations") or {}).items()}
    one_run = any(n_runs_of(entry) == 1 for entry in entries.values())
    parts = [f"<h1>Verdict: campaign {esc(document.get('campaign', '?'))}</h1>"]
    kind = "none" if cause == "none" else ("unknown" if cause == "unknown" else "")
    parts.append(
        f'<div class="headline {kind}"><b>Campaign verdict: '
        f"{esc(verdict_name(document))}.</b> {esc(campaign_headline(document))}</div>"
    )

    # what the paper's model gets wrong
    parts.append("<h2>What the paper's model gets wrong</h2>")
    if entries:
        parts.append(
            "<ul>"
            + "".join(
                f"<li><b>{esc(n)}</b> ({tag(verdict_name(e), 'none' if e.get('cause') == 'none' else 'cause')}): "
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
        partial = (
            runs[(runs["status"] == "used") & (runs["left_out"].fillna("") != "")]
            if "left_out" in runs
            else []
        )
        if len(partial):
            parts.append(
                f"<p>{len(partial)} used run(s) with a channel or mode left out (it failed a "
                "check of that channel or mode; the run's other channels and modes are used):</p>"
            )
            parts.append(
                html_table(
                    ["configuration", "run", "file", "left out"],
                    [
                        [esc(r.configuration), esc(r.run), esc(r.path), esc(r.left_out)]
                        for r in partial.itertuples()
                    ],
                )
            )
    parts.append(
        '<p class="note">The figures and tables behind this page are in the other '
        "categories of the report: measured data, damping and area fits, friction models, "
        "diagnosis (residuals, candidates, held-out prediction) and quality.</p>"
    )
    return page(f"Verdict: {document.get('campaign', '')}", "\n".join(parts))

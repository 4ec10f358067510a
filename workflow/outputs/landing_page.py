"""The report's first page, reStructuredText for ``snakemake --report`` (its landing page):
the verdict in short (:func:`verdict_rst`) in the page frame (:func:`landing_rst`).
"""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from workflow.io.escape import display_text, rst_strong, rst_text
from workflow.io.units import INCH_SECOND, UnitSystem
from workflow.outputs.plain_words import unidentified_sentence
from workflow.outputs.report_html import fmt, ratio
from workflow.outputs.report_wording import (
    campaign_headline,
    candidate_margin,
    candidate_name,
    discrepancy_text,
    excluded_runs,
    explains_sentences,
    hypothesis_verdicts,
    margin_words,
    measured_trends,
    model_name,
    n_runs_of,
    trend_sentence,
    unidentified_parameters_of,
    verdict_confidence,
    verdict_name,
)

__all__ = [
    "verdict_rst",
    "landing_rst",
]


# ------------------------------------------------------------------ the first page (rst)
def verdict_rst(
    document: Mapping,
    *,
    runs: pd.DataFrame | None = None,
    hypotheses: pd.DataFrame | None = None,
    segments: pd.DataFrame | None = None,
    units: UnitSystem = INCH_SECOND,
) -> str:
    r"""The verdict in a few short paragraphs of reStructuredText (the report's first page).

    Narrow enough for the column Snakemake's report gives its workflow description:
    no tables, one bullet per configuration. The full page with the evidence is
    :func:`workflow.outputs.verdict_page.verdict_html`.

    Examples
    --------
    reStructuredText's markup in the campaign's name is escaped:

    >>> print("\n".join(verdict_rst({"campaign": "washers_*2*", "cause": "none", "configurations": {}}).splitlines()[:4]))
    Verdict\: none \(paper\'s model suffices\)
    ==========================================
    <BLANKLINE>
    Campaign **washers\_\*2\***.
    """
    entries = document.get("configurations", {})
    trends = measured_trends(segments) if segments is not None else {}
    title = rst_text(f"Verdict: {verdict_name(document)}")
    lines = [title, "=" * len(title), ""]
    if document.get("campaign"):
        lines += [f"Campaign {rst_strong(document['campaign'])}.", ""]
    # whole sentences are not shortened: only the campaign's text in them is (display_text)
    lines += [rst_text(campaign_headline(document), limit=None), ""]
    for name, entry in entries.items():
        gain = entry.get("gain") or {}
        base = model_name(entry.get("baseline", {}).get("model"))
        if entry.get("cause") == "none":
            # what the residual figure shows: no significant misfit, and whether every
            # half decade's mean lies within the ±2 band
            text = " ".join(
                [
                    f"{base} leaves no significant misfit (held-out error {fmt(gain.get('baseline'))}).",
                    *explains_sentences(entry, units),
                ]
            )
        else:
            text = discrepancy_text(entry, units)
            if entry.get("cause") != "unknown":
                text += (
                    f" {model_name(entry.get('extended_model', {}).get('model'))} predicts "
                    f"{'held-out runs' if n_runs_of(entry) > 1 else 'held-out amplitude ranges of the one run'} "
                    f"with {ratio(gain.get('ratio'))} of {base}'s error "
                    f"({fmt(gain.get('extended'))} against {fmt(gain.get('baseline'))})."
                )
                margin = candidate_margin(entry)
                if margin and margin["ratio"] is not None and margin["ratio"] >= 1:
                    confidence = verdict_confidence(entry)
                    text += (
                        f" It is {margin_words(margin['ratio'], confidence)} the next best, "
                        f"{candidate_name(margin['next'])}, which has {ratio(margin['ratio'])} times "
                        "its error."
                    )
        if name in trends:
            text += " " + trend_sentence(trends[name], units)
        unidentified = unidentified_sentence(unidentified_parameters_of(entry, units))
        if unidentified:
            text += " " + unidentified
        lines += [
            f"* {rst_strong(name)}: *{rst_text(verdict_name(entry))}*. " + rst_text(text, limit=None),
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
                verdicts.append(
                    ", ".join(
                        f"{v} {where}" if where else f"{v} for {configuration}"
                        for v, where in hypothesis_verdicts(sub)
                    )
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
    :func:`~workflow.io.escape.rst_text`, in which no Jinja tag can form, so it goes
    through Snakemake's Jinja rendering of the page as it is; ``description``
    (report/workflow.rst) keeps its Jinja expressions.

    Examples
    --------
    >>> print(landing_rst("Verdict\\n=======\\n\\nNone.", "The workflow of {{ snakemake.config['campaign'] }}."))
    Verdict
    =======
    <BLANKLINE>
    None.
    <BLANKLINE>
    About this study
    ================
    <BLANKLINE>
    The workflow of {{ snakemake.config['campaign'] }}.
    """
    heading = "About this study"
    return verdict + "\n\n" + heading + "\n" + "=" * len(heading) + "\n\n" + description

"""The few lines a person reads when a run ends (console and results/summary.txt): the
verdict and how sure it is, every mode's, how many runs were used, why the others were
excluded and what was left out of the used ones, and where the report is.
"""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from workflow.discovery.confidence import verdict_key
from workflow.io.escape import terminal_text
from workflow.outputs.report_command import REPORT_COMMAND_FILE
from workflow.outputs.report_wording import entry_causes, verdict_confidence, verdict_name

__all__ = [
    "REASONS_SHOWN",
    "run_summary",
]


REASONS_SHOWN = 3
"""Excluded runs whose reason is printed; the rest are counted (runs.csv has them all)."""


def _verdict_text(entry: Mapping, key: str | None = None) -> str:
    """``micro-slip (power law) (microslip_power_law), confidence 0.97``: the verdict (every
    mechanism of a combination), its ``confidence`` key when given, and its share of
    ``confidence`` where there is one."""
    confidence = verdict_confidence(entry)
    named = terminal_text(verdict_name(entry)) + (f" ({terminal_text(key)})" if key else "")
    return named + (f", confidence {confidence:.2f}" if confidence is not None else "")


def _within(line: str, width: int) -> str:
    """``line`` cut to ``width`` characters, an ellipsis marking the cut."""
    return line if len(line) <= width else line[: width - 1] + "…"


def run_summary(document: Mapping, runs: pd.DataFrame, *, width: int = 100) -> str:
    """Plain-text summary of a finished analysis.

    Parameters
    ----------
    document : mapping
        results/diagnosis.json.
    runs : DataFrame
        results/tables/runs.parquet (``configuration``, ``run``, ``path``, ``status``,
        ``reason``).
    width : int
        Longest line, characters (a reason is cut there, with an ellipsis).

    Returns
    -------
    str
        Lines ending in a newline.

    Examples
    --------
    The campaign's name reaches the terminal with its control characters shown, not run:

    >>> runs = pd.DataFrame({"configuration": ["no_washer", "no_washer"], "run": ["run01", "run02"],
    ...     "path": ["no_washer/run01.txt", "no_washer/run02.txt"], "status": ["used", "excluded"],
    ...     "reason": ["", "no_washer/run02.txt: line 40: '1.2.3' is not a number"]})
    >>> document = {"campaign": "washers\\x1b[2J", "cause": "none", "configurations": {}}
    >>> print("\\n".join(run_summary(document, runs).splitlines()[:4]))
    lapjoint: campaign washers\\x1b[2J
    Verdict: none (paper's model suffices) (none)
    Runs: 1 used, 1 excluded (of 2 files)
      excluded no_washer/run02.txt: no_washer/run02.txt: line 40: '1.2.3' is not a number
    """
    # the campaign's text reaches the console only through terminal_text; a reason's
    # whitespace runs are folded to one space first (its line breaks are layout, not content)
    lines = [f"lapjoint: campaign {terminal_text(document.get('campaign', '?'))}"]
    key = verdict_key(entry_causes(document))
    modes = document.get("modes") or []
    first_hz = modes[0].get("mode_hz") if len(modes) > 1 else None
    at = f" (mode {first_hz:.5g} Hz)" if isinstance(first_hz, int | float) else ""
    lines.append(f"Verdict{at}: {_verdict_text(document, key)}")
    for name, entry in document.get("configurations", {}).items():
        gain = (entry.get("gain") or {}).get("ratio")
        gain_text = f", held-out error ratio {gain:.2f}" if isinstance(gain, int | float) else ""
        explained = entry.get("explains_data")
        explained_text = (
            "" if explained is None else ", explains the data" if explained else ", does not explain the data"
        )
        lines.append(f"  {terminal_text(name)}: {_verdict_text(entry)}{gain_text}{explained_text}")
    for name, reason in (document.get("skipped_configurations") or {}).items():
        reason = terminal_text(" ".join(str(reason).split()))
        lines.append(_within(f"  {terminal_text(name)}: not diagnosed ({reason})", width))
    for mode in modes[1:]:
        mode_hz = mode.get("mode_hz")
        heading = f"mode {mode_hz:.5g} Hz" if isinstance(mode_hz, int | float) else "mode not found"
        lines.append(f"Verdict ({heading}): {_verdict_text(mode)}")
    used = runs[runs["status"] == "used"]
    excluded = runs[runs["status"] != "used"]
    lines.append(f"Runs: {len(used)} used, {len(excluded)} excluded (of {len(runs)} files)")
    for row in excluded.head(REASONS_SHOWN).itertuples():
        reason = terminal_text(" ".join(str(row.reason).split()))
        lines.append(_within(f"  excluded {terminal_text(row.path)}: {reason}", width))
    if len(excluded) > REASONS_SHOWN:
        lines.append(f"  ... and {len(excluded) - REASONS_SHOWN} more")
    left_out = used[used["left_out"].fillna("") != ""] if "left_out" in used else used.iloc[:0]
    for row in left_out.head(REASONS_SHOWN).itertuples():
        reason = terminal_text(" ".join(str(row.left_out).split()))
        lines.append(_within(f"  left out: {reason}", width))
    if len(left_out) > REASONS_SHOWN:
        lines.append(f"  ... and {len(left_out) - REASONS_SHOWN} more used runs with a part left out")
    if len(excluded) or len(left_out):
        lines.append("  every run and its reason: results/tables/runs.csv")
    lines.append("Report: results/report/verdict.html (verdict page)")
    lines.append(f"  one-file report: the command in {REPORT_COMMAND_FILE} (works from any folder)")
    return "\n".join(lines) + "\n"

"""The few lines a person reads when a run ends (console and results/summary.txt): the
verdict, how many runs were used and why the others were excluded, and where the report is.
"""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from workflow.io.escape import terminal_text
from workflow.outputs.report_command import REPORT_COMMAND_FILE
from workflow.outputs.report_wording import cause_name

__all__ = [
    "REASONS_SHOWN",
    "run_summary",
]


REASONS_SHOWN = 3
"""Excluded runs whose reason is printed; the rest are counted (runs.csv has them all)."""


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
    cause = document.get("cause")
    lines.append(f"Verdict: {terminal_text(cause_name(cause))} ({terminal_text(cause)})")
    for name, entry in document.get("configurations", {}).items():
        gain = (entry.get("gain") or {}).get("ratio")
        gain_text = f", held-out error ratio {gain:.2f}" if isinstance(gain, int | float) else ""
        lines.append(f"  {terminal_text(name)}: {terminal_text(cause_name(entry.get('cause')))}{gain_text}")
    for name, reason in (document.get("skipped_configurations") or {}).items():
        reason = terminal_text(" ".join(str(reason).split()))
        lines.append(_within(f"  {terminal_text(name)}: not diagnosed ({reason})", width))
    used = runs[runs["status"] == "used"]
    excluded = runs[runs["status"] != "used"]
    lines.append(f"Runs: {len(used)} used, {len(excluded)} excluded (of {len(runs)} files)")
    for row in excluded.head(REASONS_SHOWN).itertuples():
        reason = terminal_text(" ".join(str(row.reason).split()))
        lines.append(_within(f"  excluded {terminal_text(row.path)}: {reason}", width))
    if len(excluded) > REASONS_SHOWN:
        lines.append(f"  ... and {len(excluded) - REASONS_SHOWN} more")
    if len(excluded):
        lines.append("  every run and its reason: results/tables/runs.csv")
    lines.append("Report: results/report/verdict.html (verdict page)")
    lines.append(f"  one-file report: the command in {REPORT_COMMAND_FILE} (works from any folder)")
    return "\n".join(lines) + "\n"

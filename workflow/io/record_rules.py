"""Rules every run reader applies, whatever the file's format: which column a name is
(campaign-format.md), and when two sample rates agree.

Shared by the ASCII reader (:mod:`workflow.io.campaign`) and the system-format readers
(:mod:`workflow.io.readers`).
"""

from __future__ import annotations

import re

__all__ = ["SAMPLE_RATE_REL_TOLERANCE", "NAME_WITH_UNIT", "split_name_unit", "column_role", "rates_agree"]

SAMPLE_RATE_REL_TOLERANCE: float = 1e-3
"""Sample rates from two sources (campaign.yaml, header, time column) agree when they
differ by less than this fraction (plus the time column's print resolution over the
record length)."""

NAME_WITH_UNIT = re.compile(r"(.*?)\s*(?:\(([^)]*)\)|\[([^\]]*)\])\s*")
"""A column name with its unit in parentheses or brackets: ``Force (lbf)``, ``a [g]``."""


def split_name_unit(name: str) -> tuple[str, str | None]:
    """``"Force (lbf)"`` -> ``("Force", "lbf")``; ``"Force"`` -> ``("Force", None)``."""
    match = NAME_WITH_UNIT.fullmatch(name.strip())
    if match and match.group(1):
        return match.group(1), (match.group(2) if match.group(2) is not None else match.group(3)).strip()
    return name.strip(), None


def column_role(name: str) -> str | None:
    """time, force or response from a column name (campaign-format.md rules).

    Examples
    --------
    >>> [column_role(name) for name in ("Time (s)", "Force (lbf)", "Accel [g]", "Temperature")]
    ['time', 'force', 'response', None]
    """
    base = split_name_unit(name)[0].lower()
    if base.startswith("time"):
        return "time"
    if "force" in base or "hammer" in base:
        return "force"
    if any(key in base for key in ("acc", "vel", "resp", "disp")):
        return "response"
    return None


def rates_agree(a_hz: float, b_hz: float, extra_rel: float = 0.0) -> bool:
    """Whether two sample rates (Hz) agree within :data:`SAMPLE_RATE_REL_TOLERANCE` plus
    ``extra_rel`` (a fraction) of the larger.

    Examples
    --------
    >>> rates_agree(10000.0, 10005.0), rates_agree(10000.0, 10020.0)
    (True, False)
    """
    return abs(a_hz - b_hz) <= (SAMPLE_RATE_REL_TOLERANCE + extra_rel) * max(a_hz, b_hz)

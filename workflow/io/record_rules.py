"""Rules every run reader applies, whatever the file's format: which column a name is
(campaign-format.md), when two sample rates agree, and which step of a time vector breaks
its uniform steps.

Shared by the ASCII reader (:mod:`workflow.io.campaign`) and the system-format readers
(:mod:`workflow.io.readers`).
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "SAMPLE_RATE_REL_TOLERANCE",
    "TIME_STEP_REL_TOLERANCE",
    "NAME_WITH_UNIT",
    "split_name_unit",
    "column_role",
    "rates_agree",
    "first_bad_time_step",
]

SAMPLE_RATE_REL_TOLERANCE: float = 1e-3
"""Sample rates from two sources (campaign.yaml, header, time column) agree when they
differ by less than this fraction (plus the time column's print resolution over the
record length)."""

TIME_STEP_REL_TOLERANCE: float = 0.01
"""A time step may differ from the record's typical (median) step by this fraction of it, plus
the resolution with which the time column is printed (rounding of the last digit)."""

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


def first_bad_time_step(steps_s: NDArray[np.float64], resolution_s: float = 0.0) -> tuple[int, float] | None:
    """The first step of a time column that goes backwards or differs from the record's
    typical step, or None when the steps are uniform.

    The typical step is the median, not the mean: one jump shifts the mean away from
    every other step, and the first step of the record would be blamed for it.

    Parameters
    ----------
    steps_s : ndarray
        Differences of successive time stamps, s.
    resolution_s : float, optional
        Resolution with which the time stamps are printed, s (added to the tolerance of
        :data:`TIME_STEP_REL_TOLERANCE` times the typical step).

    Returns
    -------
    (index, typical_step_s) or None
        0-based index of the bad step (from sample ``index`` to ``index + 1``) and the
        typical step, s.

    Examples
    --------
    >>> steps_s = np.full(9, 0.001)
    >>> steps_s[4] = 0.5  # a jump between samples 4 and 5
    >>> first_bad_time_step(steps_s)
    (4, 0.001)
    """
    typical_s = float(np.median(steps_s))
    tolerance_s = TIME_STEP_REL_TOLERANCE * abs(typical_s) + resolution_s
    bad = np.flatnonzero((steps_s <= 0.0) | ~(np.abs(steps_s - typical_s) <= tolerance_s))
    return None if bad.size == 0 else (int(bad[0]), typical_s)

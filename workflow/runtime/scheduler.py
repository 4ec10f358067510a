"""Scheduling: which configuration's diagnosis starts first, and ending the Snakemake
process as soon as its last job is done.

Snakemake's job scheduler rate-limits submissions (``--max-jobs-per-timespan``,
100 jobs a second by default) and, after each scheduling round, starts a
``threading.Timer`` that wakes the scheduler again one timespan later. The timer of
the last round is still pending when the workflow has finished, and the interpreter
waits for it before exiting: a second of idle wall time at the end of every run
that executed jobs. No setting avoids it: Snakemake 9 reads a timespan of ``100ms`` as
100 minutes (its pattern tries ``m`` before ``ms``), and the limiter cannot be switched
off from the command line.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping

__all__ = [
    "largest_area_first",
    "cancel_scheduler_timers",
]


def largest_area_first(areas_in2: Mapping[str, float | None], base: int = 1) -> dict[str, int]:
    """Job priorities that start the configurations' diagnoses in order of bearing area,
    the largest first.

    The larger a lap joint's bearing area, the more of its contact slips over the
    measured amplitudes and the more models its diagnosis fits (the slip thresholds from
    the data, the combinations): on the demo the no-washer joint's takes 4 s, the
    washers' 2 s. Started last of three on two cores, the longest runs alone at the end.
    Snakemake fixes priorities before any segment exists, and the bearing area is what
    is known of a configuration then.

    Parameters
    ----------
    areas_in2 : mapping
        Configuration -> bearing area (in^2), None where campaign.yaml states none.
    base : int
        The priority of a configuration without an area (and of the smallest).

    Returns
    -------
    dict
        Configuration -> priority: ``base`` plus the number of configurations of a stated
        area smaller than its own.

    Examples
    --------
    >>> largest_area_first({"no_washer": 1.36, "large_washer": 0.66, "small_washer": 0.17, "x": None})
    {'no_washer': 3, 'large_washer': 2, 'small_washer': 1, 'x': 1}
    """
    stated = sorted(area for area in areas_in2.values() if area is not None)
    return {
        name: base + (0 if area is None else sum(other < area for other in stated))
        for name, area in areas_in2.items()
    }


def cancel_scheduler_timers() -> int:
    """Cancel the Snakemake job scheduler's pending wake-up timers.

    Call only once the scheduler has finished (an ``onsuccess`` or ``onerror``
    handler): the timers then have nothing left to wake. Timers of any other origin
    are left alone.

    Returns
    -------
    int
        The number of timers cancelled.
    """
    cancelled = 0
    for thread in threading.enumerate():
        function = getattr(thread, "function", None)
        if (
            isinstance(thread, threading.Timer)
            and getattr(function, "__module__", "") == "snakemake.scheduling.job_scheduler"
            and getattr(function, "__qualname__", "").startswith("JobScheduler.")
        ):
            thread.cancel()
            cancelled += 1
    return cancelled

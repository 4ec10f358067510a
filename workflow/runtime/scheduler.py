"""Ending the Snakemake process as soon as its last job is done.

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

__all__ = [
    "cancel_scheduler_timers",
]


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

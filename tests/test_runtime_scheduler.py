"""The Snakemake process ends with its last job: the scheduler's wake-up timer is cancelled."""

import threading

from snakemake.scheduling.job_scheduler import JobScheduler

from workflow.runtime.scheduler import cancel_scheduler_timers


class _SchedulerState:
    """The one attribute of a JobScheduler that its wake-up timer touches."""

    def __init__(self):
        self._open_jobs = threading.Semaphore(0)


def test_the_schedulers_pending_wake_up_is_cancelled_and_other_timers_are_not():
    scheduler = _SchedulerState()
    # Snakemake's own method starts the timer, so a rename or a move in Snakemake fails here
    JobScheduler._schedule_reevalutation(scheduler, 60)
    woken = threading.Event()
    other = threading.Timer(60, woken.set)
    other.start()
    try:
        (wake_up,) = [t for t in threading.enumerate() if isinstance(t, threading.Timer) and t is not other]
        assert cancel_scheduler_timers() == 1
        wake_up.join(timeout=5)
        assert not wake_up.is_alive()
        assert other.is_alive()
        # cancelled, not fired: the scheduler's semaphore was never released
        assert not scheduler._open_jobs.acquire(blocking=False)
    finally:
        other.cancel()
    assert not woken.is_set()

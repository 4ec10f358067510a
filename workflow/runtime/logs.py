"""Logging for workflow scripts: every script writes to its rule's ``log:`` file."""

from __future__ import annotations

import atexit
import gc
import logging
import os
import resource
import sys
import time
from pathlib import Path
from types import TracebackType

from workflow.io.escape import terminal_lines

__all__ = [
    "COST_LINE",
    "ScriptStop",
    "peak_resident_mb",
    "setup_script_logging",
    "exit_without_teardown",
    "TerminalSafeFormatter",
]


COST_LINE = "cost: start-up {start_up:.3f} s CPU, work {work:.3f} s CPU, peak memory {peak_mb:.0f} MB"
"""Last line of every script's log (bench/bench_workflow.py reads it): CPU seconds spent
before logging was set up (interpreter, Snakemake's preamble, imports) and after it
(the rule's work), and the process's peak resident memory."""


class ScriptStop(Exception):
    """A script's deliberate stop (strict mode, nothing to show): logged as
    ``stopped: <message>`` without a traceback, exit status 1.

    Scripts raise it instead of ``SystemExit``, whose exit status the end of
    :func:`setup_script_logging` cannot see.
    """


def peak_resident_mb() -> float:
    """Peak resident memory of this process, MB (MiB).

    Linux: the high-water mark of the process's own memory (``VmHWM``). Not
    ``getrusage``'s ``ru_maxrss``, which Linux carries over through ``exec`` from the
    forking parent, so that a script started by Snakemake would report Snakemake's
    size. Elsewhere ``ru_maxrss`` (bytes on macOS).
    """
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 2**10  # kB
    except OSError:
        pass
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 2**10


class TerminalSafeFormatter(logging.Formatter):
    """Log lines with every character a terminal acts on written out as its escape
    (:func:`workflow.io.escape.terminal_lines`): messages name the campaign's runs,
    channels and paths, and the job's log is echoed to the console."""

    def format(self, record: logging.LogRecord) -> str:
        return terminal_lines(super().format(record))


def setup_script_logging(log_path: str | Path | None, name: str) -> logging.Logger:
    """Send log records (and any uncaught exception) to ``log_path`` and stderr;
    at exit, log the script's cost (:data:`COST_LINE`) and end the process.

    Call it right after the script's imports: the CPU time used until then counts as
    start-up.

    The process ends right after the cost line (:func:`exit_without_teardown`): its
    outputs are written and closed by then, and the interpreter's teardown of SciPy,
    pandas, Numba or matplotlib (0.1-0.4 s of CPU a job) would change nothing. The exit
    status is 1 after an uncaught exception (:class:`ScriptStop` included), else 0; a
    script therefore never raises ``SystemExit``, whose status would be lost.

    Parameters
    ----------
    log_path : path or None
        The rule's log file; None logs to stderr only (a script run by hand).
    name : str
        Logger name, usually the script's rule.
    """
    handlers: list[logging.Handler] = [logging.StreamHandler(sys.stderr)]
    if log_path:
        Path(log_path).parent.mkdir(parents=True, exist_ok=True)
        handlers.append(logging.FileHandler(log_path, mode="w"))
    logging.basicConfig(level=logging.INFO, handlers=handlers, force=True)
    for handler in handlers:
        handler.setFormatter(TerminalSafeFormatter("%(asctime)s %(name)s %(levelname)s %(message)s"))
    logger = logging.getLogger(name)
    failed = False

    def log_uncaught(kind: type[BaseException], value: BaseException, trace: TracebackType | None) -> None:
        nonlocal failed
        failed = True
        if isinstance(value, ScriptStop):
            logger.error("stopped: %s", value)
        else:
            logger.error("stopped: %s", value, exc_info=(kind, value, trace))

    sys.excepthook = log_uncaught
    # the imports' objects out of the collector's sweeps, and collection on again (a job's
    # script collects nothing while it imports: workflow/__init__.py)
    gc.freeze()
    gc.enable()
    start_up_cpu_s = time.process_time()

    def log_cost_and_exit() -> None:
        logger.info(
            COST_LINE.format(
                start_up=start_up_cpu_s, work=time.process_time() - start_up_cpu_s, peak_mb=peak_resident_mb()
            )
        )
        exit_without_teardown(1 if failed else 0)

    atexit.register(log_cost_and_exit)
    return logger


def exit_without_teardown(status: int) -> None:
    """End the process now with ``status``, after flushing the standard streams and
    closing the log handlers. The exit handlers not yet run (those registered before
    the caller's) and the interpreter's teardown (freeing every module) are skipped.

    Only for the end of a script whose files are all written and closed.
    """
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (AttributeError, OSError, ValueError):
            pass
    logging.shutdown()
    os._exit(status)

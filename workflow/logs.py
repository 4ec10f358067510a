"""Logging for workflow scripts: every script writes to its rule's ``log:`` file."""

from __future__ import annotations

import logging
import sys
from pathlib import Path
from types import TracebackType


def setup_script_logging(log_path: str | Path | None, name: str) -> logging.Logger:
    """Send log records (and any uncaught exception) to ``log_path`` and stderr.

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
    logging.basicConfig(
        level=logging.INFO,
        format="%(asctime)s %(name)s %(levelname)s %(message)s",
        handlers=handlers,
        force=True,
    )
    logger = logging.getLogger(name)

    def log_uncaught(kind: type[BaseException], value: BaseException, trace: TracebackType | None) -> None:
        logger.error("stopped: %s", value, exc_info=(kind, value, trace))

    sys.excepthook = log_uncaught
    return logger

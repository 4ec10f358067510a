"""When a run was recorded, as its file states it, and the order of runs that follows.

The run files of acquisition systems carry the wall-clock time their recording started:
TDMS ``wf_start_time`` (UTC), the UFF58 header's date line, Test.Lab's
``function_record.creation_time`` (local clock time: the file names no time zone). The
runs table keeps it as ISO 8601 text (``record_start``); the run-order drift test and
the report order a configuration's runs by it when every run has one, and by file name
otherwise (campaign-format.md: files sorted by name are the run order).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from datetime import UTC, datetime

import numpy as np

__all__ = [
    "FILE_NAME_ORDER",
    "RECORD_START_ORDER",
    "parse_clock_time",
    "utc_from_datetime64",
    "iso_text",
    "run_order",
]


FILE_NAME_ORDER = "file-name order"
"""How the order of runs is named when it is the order of their file names."""

RECORD_START_ORDER = "recording start times in the files"
"""How the order of runs is named when it is the order of their recording start times."""

_CLOCK_FORMATS = (
    "%d-%b-%y %H:%M:%S",  # UFF58 ID line 3: DD-MMM-YY HH:MM:SS
    "%d-%b-%Y %H:%M:%S",
    "%Y/%m/%d %H:%M:%S",  # Test.Lab creation_time
    "%Y-%m-%d %H:%M:%S",
    "%Y-%m-%dT%H:%M:%S",
    "%Y-%m-%dT%H:%M:%S.%f",
)

_LABVIEW_EPOCH = np.datetime64("1904-01-01T00:00:00")
"""TDMS time stamps count from here: a zero time stamp means "not set"."""


def parse_clock_time(text: object) -> datetime | None:
    """A date and time written as text (no time zone), or None when the text is not one.

    Accepts the UFF58 form ``DD-MMM-YY HH:MM:SS`` (and a four-digit year), Test.Lab's
    ``YYYY/MM/DD HH:MM:SS`` and ISO 8601 without a zone. Anything else (ID lines are free
    text in many exports) is not an error: the file then has no start time.
    """
    if not isinstance(text, str):
        return None
    stripped = " ".join(text.split())
    for pattern in _CLOCK_FORMATS:
        try:
            return datetime.strptime(stripped, pattern)
        except ValueError:
            continue
    return None


def utc_from_datetime64(value: object) -> datetime | None:
    """A TDMS time stamp (``numpy.datetime64``, UTC) as an aware datetime; None when unset."""
    if not isinstance(value, np.datetime64) or np.isnat(value):
        return None
    microseconds = value.astype("datetime64[us]")
    if microseconds == _LABVIEW_EPOCH:
        return None
    return microseconds.astype(datetime).replace(tzinfo=UTC)


def iso_text(moment: datetime | None) -> str:
    """ISO 8601 text of a start time (``+00:00`` when the file gave UTC); empty for None."""
    return "" if moment is None else moment.isoformat()


def run_order(run_names: Sequence[str], record_start: Mapping[str, str]) -> tuple[list[str], str]:
    """The runs of one configuration in the order they were recorded.

    Parameters
    ----------
    run_names : sequence of str
        The configuration's runs (file names without extension).
    record_start : mapping
        Run name -> ISO 8601 recording start (the runs table's ``record_start``); runs
        missing or empty have none.

    Returns
    -------
    runs : list of str
        By recording start when every run has one, all of one kind (with or without a
        time zone) and no two equal; else by file name.
    order : str
        Which order that is, in words (:data:`RECORD_START_ORDER`, or
        :data:`FILE_NAME_ORDER`, a colon and the reason the start times could not be used).

    Examples
    --------
    >>> run_order(["run02", "run01"], {"run01": "2026-05-12T14:03:10", "run02": "2026-05-12T13:58:02"})
    (['run02', 'run01'], 'recording start times in the files')
    >>> run_order(["run02", "run01"], {"run01": "2026-05-12T14:03:10"})
    (['run01', 'run02'], 'file-name order: 1 of 2 runs carry no recording start time')
    """
    by_name = sorted(run_names)
    starts = {name: record_start.get(name) or "" for name in by_name}
    missing = [name for name in by_name if not starts[name]]
    if missing:
        if len(missing) == len(by_name):
            return by_name, f"{FILE_NAME_ORDER}: the files carry no recording start time"
        return by_name, (
            f"{FILE_NAME_ORDER}: {len(missing)} of {len(by_name)} runs carry no recording start time"
        )
    moments = {name: datetime.fromisoformat(text) for name, text in starts.items()}
    if len({moment.tzinfo is None for moment in moments.values()}) > 1:
        return by_name, f"{FILE_NAME_ORDER}: some recording start times name a time zone, others do not"
    if len(set(moments.values())) < len(moments):
        return by_name, f"{FILE_NAME_ORDER}: two runs carry the same recording start time"
    return sorted(by_name, key=moments.__getitem__), RECORD_START_ORDER

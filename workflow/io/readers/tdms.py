"""NI TDMS files (LabVIEW, NI DAQ), read by npTDMS.

Every channel of numbers is a channel named ``group/channel`` (its bare name also selects
it when no other group has one of that name). Sample interval, start time and unit are the
waveform properties ``wf_increment`` (s), ``wf_start_offset`` (s) and ``unit_string``; the
recording's wall-clock start is the channel's ``wf_start_time`` (UTC), else a ``DateTime``
property of its group or of the file.
"""

from __future__ import annotations

import logging
from datetime import datetime
from pathlib import Path

import numpy as np

from workflow.io.limits import quoted
from workflow.io.readers.channels import Channel, FileChannels
from workflow.io.recording_time import utc_from_datetime64
from workflow.io.records import CampaignFormatError

__all__ = [
    "read_tdms_channels",
]


class _WarningRecords(logging.Handler):
    """Keeps the messages of the warnings logged while a file is read."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


def _date_time_property(properties: dict) -> datetime | None:
    """The ``DateTime`` property (any case) of a TDMS group or file as an aware datetime, or None."""
    for key, value in properties.items():
        if key.lower() == "datetime":
            return utc_from_datetime64(value)
    return None


def _stated_number(properties: dict, key: str, channel: str, shown: str) -> float | None:
    """A channel's numeric property, None when absent; any other value is an error
    naming the channel (never silently replaced)."""
    value = properties.get(key)
    if value is None:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = None
    if number is None or isinstance(value, (str, bytes)) or not np.isfinite(number):
        raise CampaignFormatError(
            shown, None, f"channel {quoted(channel)}: {key} is {quoted(str(value))}, not a finite number"
        )
    return number


def read_tdms_channels(path: Path, shown: str) -> FileChannels:
    """Channels of a TDMS file.

    Raises
    ------
    CampaignFormatError
        Not a readable TDMS file (truncated, corrupt) or no channels of numbers.
    """
    from nptdms import TdmsFile

    # npTDMS reads what it can of a truncated last segment and only logs a warning.
    warnings = _WarningRecords()
    logger = logging.getLogger("nptdms")
    logger.addHandler(warnings)
    try:
        # From an open file, npTDMS does not look for a '.tdms_index' file beside it
        # (which could be a link out of the campaign folder).
        with open(path, "rb") as handle:  # read-only: raw files are never modified
            tdms = TdmsFile.read(handle)
            groups = [(group, group.channels()) for group in tdms.groups()]
            arrays = [[channel[:] for channel in group_channels] for _, group_channels in groups]
    except Exception as error:  # npTDMS raises ValueError, EOFError, struct.error, ...
        raise CampaignFormatError(
            shown, None, f"cannot read as a TDMS file ({type(error).__name__}: {error})"
        ) from None
    finally:
        logger.removeHandler(warnings)
    truncated = [message for message in warnings.messages if "less data than expected" in message]
    if truncated:
        raise CampaignFormatError(shown, None, f"truncated TDMS file: {truncated[0]}")
    channels = []
    for (group, group_channels), group_arrays in zip(groups, arrays, strict=True):
        group_start = _date_time_property(group.properties) or _date_time_property(tdms.properties)
        for channel, values in zip(group_channels, group_arrays, strict=True):
            if not (isinstance(values, np.ndarray) and np.issubdtype(values.dtype, np.number)):
                continue  # strings and timestamps are not samples
            properties = channel.properties
            name = f"{group.name}/{channel.name}"
            increment = _stated_number(properties, "wf_increment", name, shown)
            start = _stated_number(properties, "wf_start_offset", name, shown)
            channels.append(
                Channel(
                    name=name,
                    values=values,
                    record=f"channel {name!r}",
                    unit=properties.get("unit_string"),
                    sample_interval_s=increment,
                    interval_source="wf_increment",
                    start_s=start,
                    aliases=(channel.name,),
                    record_start=utc_from_datetime64(properties.get("wf_start_time")) or group_start,
                )
            )
    return FileChannels("TDMS", channels)

"""Universal File Format dataset 58 time records (ASCII and binary 58b), read by pyuff.

Every dataset 58 with function type 1 (time response) is a channel, named by its first ID
line. The role comes from the ordinate's specific data type (8 displacement, 11 velocity,
12 acceleration: response; 9 reaction force, 13 excitation force: force), the unit from
the ordinate's units label, the sample interval and start time from the abscissa
increment and minimum. Other datasets (geometry, units, FRFs) are skipped. The recording's
date and time is ID line 3, where the format puts it (``DD-MMM-YY HH:MM:SS``), else ID
line 2 when that holds one; local clock time, as the format names no time zone.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from workflow.io.readers.channels import Channel, FileChannels, unit_label
from workflow.io.recording_time import parse_clock_time
from workflow.io.records import CampaignFormatError

__all__ = [
    "TIME_RESPONSE_FUNCTION",
    "read_uff_channels",
]


TIME_RESPONSE_FUNCTION: int = 1
"""Dataset 58 function type of a time response."""

_ROLE_OF_DATA_TYPE = {8: "response", 11: "response", 12: "response", 9: "force", 13: "force"}
_TIME_UNITS_S = {"s": 1.0, "sec": 1.0, "ms": 1e-3}


_DELIMITER_LINE = re.compile(rb"^    -1[ \t]*\r?$", re.MULTILINE)


def _unclosed_dataset_line(path: Path) -> int | None:
    """1-based line of a dataset whose closing ``-1`` line is missing (a cut-off file), or None.

    Datasets are enclosed in pairs of ``    -1`` lines; pyuff silently skips an unclosed
    last one, which would turn a truncated file into a file with a channel missing.
    """
    with open(path, "rb") as handle:  # read-only: raw files are never modified
        data = handle.read()
    delimiters = [match.start() for match in _DELIMITER_LINE.finditer(data)]
    if len(delimiters) % 2 == 0:
        return None
    return data.count(b"\n", 0, delimiters[-1]) + 1


def _read_sets(path: Path, shown: str) -> list[dict[str, Any]]:
    import pyuff

    unclosed = _unclosed_dataset_line(path)
    if unclosed is not None:
        raise CampaignFormatError(
            shown,
            unclosed,
            "truncated or corrupt UFF file: the dataset that starts on this line is not closed by a '    -1' line",
        )
    try:
        uff = pyuff.UFF(str(path))
        if 58 not in [int(t) for t in uff.get_set_types()]:
            raise CampaignFormatError(shown, None, "no dataset 58 (function at nodal DOF) in the UFF file")
        sets = uff.read_sets()
    except CampaignFormatError:
        raise
    except Exception as error:  # pyuff raises bare Exception, ValueError, IndexError, ...
        raise CampaignFormatError(
            shown, None, f"cannot read as a UFF file ({type(error).__name__}: {error})"
        ) from None
    return sets if isinstance(sets, list) else [sets]


def read_uff_channels(path: Path, shown: str) -> FileChannels:
    """Channels of a UFF file's dataset 58 time records.

    Raises
    ------
    CampaignFormatError
        Not a readable UFF file, no time records, or a record whose sample count, abscissa
        or values are wrong (the record is named by its position and ID line).
    """
    sets = _read_sets(path, shown)
    channels = []
    binary = False
    for position, dataset in enumerate(sets, start=1):
        if int(dataset.get("type", -1)) != 58 or int(dataset.get("func_type", -1)) != TIME_RESPONSE_FUNCTION:
            continue
        binary = binary or bool(dataset.get("binary"))
        name = str(dataset.get("id1", "")).strip()
        where = f"dataset {position} (58, ID {name!r})"
        values = np.asarray(dataset.get("data", []))
        declared = int(dataset.get("num_pts", -1))
        if values.size != declared:
            raise CampaignFormatError(
                shown,
                None,
                f"{where}: the header declares {declared} samples but {values.size} were read "
                "(truncated or corrupt record)",
            )
        if np.iscomplexobj(values):
            raise CampaignFormatError(shown, None, f"{where}: complex values, not a time record")
        abscissa_unit = (unit_label(dataset.get("abscissa_axis_units_lab")) or "s").lower()
        factor_s = _TIME_UNITS_S.get(abscissa_unit)
        if factor_s is None:
            raise CampaignFormatError(
                shown, None, f"{where}: abscissa unit {abscissa_unit!r}: expected s or ms"
            )
        interval_s = start_s = None
        if int(dataset.get("abscissa_spacing", 1)) == 1:
            interval_s = float(dataset.get("abscissa_inc")) * factor_s
            start_s = float(dataset.get("abscissa_min", 0.0)) * factor_s
        else:  # uneven abscissa: the time values are in the record; they must be uniform anyway
            abscissa = np.asarray(dataset.get("x", []), dtype=np.float64) * factor_s
            steps = np.diff(abscissa)
            if abscissa.size != values.size or steps.size == 0 or np.ptp(steps) > 0.01 * np.mean(steps):
                raise CampaignFormatError(
                    shown, None, f"{where}: uneven abscissa; a run needs uniformly spaced samples"
                )
            interval_s = float(np.mean(steps))
            start_s = float(abscissa[0])
        channels.append(
            Channel(
                name=name,
                values=values,
                record=where,
                unit=dataset.get("ordinate_axis_units_lab"),
                sample_interval_s=interval_s,
                interval_source="abscissa increment",
                start_s=start_s,
                role=_ROLE_OF_DATA_TYPE.get(int(dataset.get("ordinate_spec_data_type", 0))),
                record_start=parse_clock_time(dataset.get("id3")) or parse_clock_time(dataset.get("id2")),
            )
        )
    if not channels:
        raise CampaignFormatError(
            shown, None, "no time records in the UFF file (dataset 58 with function type 1)"
        )
    return FileChannels("UFF58b" if binary else "UFF58", channels)

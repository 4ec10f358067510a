"""Recording start times as files state them, and the run order that follows."""

from datetime import UTC, datetime

import numpy as np
import pytest

from workflow.io.recording_time import (
    FILE_NAME_ORDER,
    RECORD_START_ORDER,
    parse_clock_time,
    run_order,
    utc_from_datetime64,
)


@pytest.mark.parametrize(
    "text",
    [
        "05-Mar-26 14:07:09",
        "05-Mar-2026 14:07:09",
        "2026/03/05 14:07:09",
        "2026-03-05T14:07:09",
        " 05-Mar-26  14:07:09 ",
    ],
)
def test_clock_times_of_the_formats(text):
    assert parse_clock_time(text) == datetime(2026, 3, 5, 14, 7, 9)


@pytest.mark.parametrize("text", ["", "Record 1", "NONE", "05-Mar-26", None, 3.0])
def test_text_that_is_not_a_date_is_no_start_time(text):
    assert parse_clock_time(text) is None


def test_tdms_time_stamps_are_utc_and_zero_is_unset():
    stamp = np.datetime64("2026-03-05T14:07:09.250000")
    assert utc_from_datetime64(stamp) == datetime(2026, 3, 5, 14, 7, 9, 250000, tzinfo=UTC)
    assert utc_from_datetime64(np.datetime64("1904-01-01T00:00:00")) is None
    assert utc_from_datetime64(np.datetime64("NaT")) is None


def test_runs_in_recording_order_only_when_every_run_has_a_distinct_start():
    names = ["a", "b", "c"]
    starts = {"a": "2026-03-05T14:09:00", "b": "2026-03-05T14:07:00", "c": "2026-03-05T14:08:00"}
    assert run_order(names, starts) == (["b", "c", "a"], RECORD_START_ORDER)
    missing = run_order(names, {**starts, "c": ""})
    assert missing == (names, f"{FILE_NAME_ORDER}: 1 of 3 runs carry no recording start time")
    same = run_order(names, {**starts, "c": starts["a"]})
    assert same[0] == names and "the same recording start" in same[1]
    mixed = run_order(names, {**starts, "c": "2026-03-05T14:08:00+00:00"})
    assert mixed[0] == names and "time zone" in mixed[1]
    assert run_order(["b", "a"], {}) == (
        ["a", "b"],
        f"{FILE_NAME_ORDER}: the files carry no recording start time",
    )

"""Reader of ASCII run files (campaign-format.md): one file read and checked against
campaign.yaml (:func:`read_ascii_run`), and the sample rate a file's head declares
(:func:`declared_sample_rate_hz`, for planning).

The text and its numbers are read by :mod:`workflow.io.readers.ascii_rows`, the header
and columns by :mod:`workflow.io.readers.ascii_columns`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from workflow.io.campaign import Campaign, frequency_problem
from workflow.io.readers.ascii_columns import (
    check_magnitude,
    check_time,
    column_unit_factors,
    find_columns,
    read_header_values,
    response_column_units,
)
from workflow.io.readers.ascii_rows import (
    DECIMAL_COMMA_HINT,
    SPACES,
    decimal_commas_to_points,
    is_decimal_comma_row,
    line_delimiter,
    locate_numbers,
    most_common,
    parse_block_careful,
    parse_text_fast,
    print_resolution,
    read_run_text,
    split_row,
    wide_encoding,
)
from workflow.io.record_rules import rates_agree
from workflow.io.records import (
    MIN_SAMPLES,
    CampaignFormatError,
    ResponseChannel,
    RunFile,
    RunRecord,
)

__all__ = [
    "HEAD_ROWS",
    "HEAD_BYTES",
    "declared_sample_rate_hz",
    "read_ascii_run",
]


HEAD_ROWS: int = 11
"""Numeric rows whose majority decides the delimiter and the column count, so that a
single bad first row is reported as bad instead of setting the format."""


HEAD_BYTES: int = 65536
"""Bytes of a run file that :func:`declared_sample_rate_hz` reads: enough for any header
and the first rows of the numbers."""


def declared_sample_rate_hz(campaign_dir: str | Path, run_file: RunFile, campaign: Campaign) -> float | None:
    """The sample rate (Hz) a run file declares, from its first :data:`HEAD_BYTES` only:
    campaign.yaml's ``sample_rate_hz``, else the header's, else the step of the first
    rows of the time column; None when the head does not tell (or cannot be read: the
    full read then reports why).

    Planning checks campaign.yaml's band and mode against it before any job runs,
    without reading whole records.
    """
    if campaign.sample_rate_hz is not None:
        return campaign.sample_rate_hz
    path = Path(campaign_dir) / run_file.path
    shown = path.as_posix()
    try:
        with open(path, "rb") as handle:
            raw = handle.read(HEAD_BYTES)
        if wide_encoding(raw) is not None or b"\x00" in raw:
            return None
        text = raw.decode("utf-8-sig", errors="replace").replace("\r\n", "\n").replace("\r", "\n")
        header, offset, first_line = locate_numbers(text)
        if offset < 0:
            return None
        header_values = read_header_values(header, shown)
        if header_values.sample_rate_hz is not None:
            return header_values.sample_rate_hz
        rows = [row for row in text[offset:].split("\n")[:HEAD_ROWS] if row.strip()]
        delimiter = most_common([line_delimiter(row) for row in rows], SPACES)
        n_columns = most_common([len(split_row(row, delimiter)) for row in rows], 1)
        columns = find_columns(header, first_line, delimiter, n_columns, campaign, shown)
        if "time" not in columns.roles:
            return None
        time_factor_s = column_unit_factors(columns, campaign, shown)[0]
        time_s = np.array([float(split_row(row, delimiter)[columns.roles["time"]]) for row in rows[:-1]])
    except (OSError, ValueError, IndexError):  # CampaignFormatError is a ValueError
        return None
    steps_s = np.diff(time_s) * time_factor_s
    if steps_s.size == 0 or not np.all(steps_s > 0):
        return None
    return float(1.0 / np.mean(steps_s))


def read_ascii_run(full_path: Path, relative: str, shown: str, campaign: Campaign) -> RunRecord:
    """Read one ASCII run file and check it against the input contract.

    The file is found and checked readable by :func:`workflow.io.run_files.read_run`;
    ``relative`` and ``shown`` are as :func:`workflow.io.readers.read_system_run` takes
    them, and the record and errors as ``read_run`` gives them.
    """
    text = read_run_text(full_path, shown)
    if campaign.decimal == ",":
        text = decimal_commas_to_points(text, shown)
    if not text.strip():
        raise CampaignFormatError(shown, 1, "the file is empty")
    header, offset, first_line = locate_numbers(text)
    if offset < 0:
        comma_line = next(
            (number for number, line in header if line.strip() and is_decimal_comma_row(line)), None
        )
        if comma_line is not None:
            raise CampaignFormatError(
                shown, comma_line, f"{DECIMAL_COMMA_HINT}: {header[comma_line - 1][1].strip()[:60]!r}"
            )
        last_line = len(text.rstrip("\n").split("\n"))
        raise CampaignFormatError(
            shown,
            last_line,
            f"no numeric rows: all {last_line} line(s) are header text (expected numbers "
            "after the header, one sample per line)",
        )

    # The numbers are text[offset:end]; no copy of them is made (a long record's text
    # is the largest thing a run-analysis job holds).
    end = len(text)
    while end > offset and text[end - 1].isspace():
        end -= 1
    head_end = offset
    for _ in range(HEAD_ROWS):
        head_end = text.find("\n", head_end + 1, end)
        if head_end < 0:
            head_end = end
            break
    rows_head = [row for row in text[offset:head_end].split("\n") if row.strip()]
    delimiter = most_common([line_delimiter(row) for row in rows_head], SPACES)
    n_columns = most_common([len(split_row(row, delimiter)) for row in rows_head], 1)
    n_rows = text.count("\n", offset, end) + 1

    header_values = read_header_values(header, shown)
    columns = find_columns(header, first_line, delimiter, n_columns, campaign, shown)
    time_factor_s, force_factor_lbf = column_unit_factors(columns, campaign, shown)
    response_units, refusals = response_column_units(columns, campaign, shown)

    values = parse_text_fast(text, offset, end, delimiter, n_rows, n_columns)
    if values is None:
        values = parse_block_careful(text[offset:end].split("\n"), first_line, delimiter, n_columns, shown)
    last_data_line = first_line + n_rows - 1
    if n_rows < MIN_SAMPLES:
        raise CampaignFormatError(
            shown,
            last_data_line,
            f"only {n_rows} samples; a run needs at least {MIN_SAMPLES}",
        )

    # Sample rate: campaign.yaml, then the header, then the time column; any two
    # sources that are present must agree.
    sources: list[tuple[str, float, int | None, float]] = []
    if campaign.sample_rate_hz is not None:
        sources.append(("campaign.yaml sample_rate_hz", campaign.sample_rate_hz, None, 0.0))
    if header_values.sample_rate_hz is not None:
        sources.append(("header", header_values.sample_rate_hz, header_values.sample_rate_line, 0.0))
    time_s = None
    if "time" in columns.roles:
        time_s = values[:, columns.roles["time"]] * time_factor_s
        first_row, last_row = rows_head[0], text[max(text.rfind("\n", offset, end), offset - 1) + 1 : end]
        resolution_s = time_factor_s * print_resolution(
            [split_row(row, delimiter)[columns.roles["time"]] for row in (first_row, last_row)]
        )
        rate_hz = check_time(time_s, resolution_s, first_line, shown)
        duration_s = time_s[-1] - time_s[0]
        sources.append(("time column", rate_hz, first_line, 2.0 * resolution_s / duration_s))
    if not sources:
        raise CampaignFormatError(
            shown,
            None,
            "sample rate missing: no time column, no 'Sample rate: ... Hz' header line "
            "and no sample_rate_hz in campaign.yaml",
        )
    for i, (name_a, rate_a, line_a, slack_a) in enumerate(sources):
        for name_b, rate_b, line_b, slack_b in sources[i + 1 :]:
            if not rates_agree(rate_a, rate_b, slack_a + slack_b):
                raise CampaignFormatError(
                    shown,
                    line_b if line_b is not None else line_a,
                    f"sample rate {rate_b:.9g} Hz from the {name_b} disagrees with "
                    f"{rate_a:.9g} Hz from the {name_a}",
                )
    source_name, sample_rate_hz = sources[0][0], sources[0][1]
    rate_line = sources[0][2]
    rate_source = source_name if rate_line is None else f"{source_name}, line {rate_line}"
    problem = frequency_problem(campaign, sample_rate_hz, rate_source)
    if problem is not None:
        raise CampaignFormatError(shown, rate_line, f"campaign.yaml {problem}")
    sample_rate_source = "campaign.yaml" if source_name.startswith("campaign") else source_name

    pretrigger_samples, pretrigger_source = campaign.pretrigger_samples, "default"
    if header_values.pretrigger_line is not None:
        header_pre = header_values.pretrigger_samples
        if header_pre is None:
            header_pre = int(round(header_values.pretrigger_s * sample_rate_hz))
        if campaign.pretrigger_given and header_pre != campaign.pretrigger_samples:
            raise CampaignFormatError(
                shown,
                header_values.pretrigger_line,
                f"pre-trigger {header_pre} samples in the header disagrees with "
                f"campaign.yaml pretrigger_samples {campaign.pretrigger_samples}",
            )
        pretrigger_samples, pretrigger_source = header_pre, "header"
    if time_s is not None and time_s[0] * sample_rate_hz <= -0.5:
        # a time column that starts before 0 counts the samples before the trigger
        time_pre = int(round(-time_s[0] * sample_rate_hz))
        stated = {
            "header": (header_values.pretrigger_line is not None, pretrigger_samples),
            "campaign.yaml pretrigger_samples": (campaign.pretrigger_given, campaign.pretrigger_samples),
        }
        for where, (given, samples) in stated.items():
            if given and samples != time_pre:
                raise CampaignFormatError(
                    shown,
                    first_line,
                    f"the time column starts at {time_s[0]:.9g} s, a pre-trigger of {time_pre} samples, "
                    f"but the {where} says {samples} samples",
                )
        pretrigger_samples, pretrigger_source = time_pre, "time column"
    if campaign.pretrigger_given:
        pretrigger_source = "campaign.yaml"
    if pretrigger_samples >= n_rows:
        raise CampaignFormatError(
            shown,
            header_values.pretrigger_line,
            f"pre-trigger of {pretrigger_samples} samples is not shorter than the record ({n_rows} samples)",
        )

    checked = [("force", columns.roles["force"])] if "force" in columns.roles else []
    for role, index in checked + [("response", index) for index in columns.responses]:
        check_magnitude(values[:, index], role, index, columns, first_line, shown)
    force_lbf = None
    if "force" in columns.roles:
        force_lbf = values[:, columns.roles["force"]] * force_factor_lbf
    names = campaign.response.channel_names()
    responses = tuple(
        ResponseChannel(
            name, np.ascontiguousarray(values[:, index]), unit, columns.names[index] if columns.names else ""
        )
        for name, index, unit in zip(names, columns.responses, response_units)
        if unit is not None
    )
    response = responses[0].values
    return RunRecord(
        path=relative,
        sample_rate_hz=float(sample_rate_hz),
        pretrigger_samples=int(pretrigger_samples),
        time_s=None if time_s is None else np.ascontiguousarray(time_s),
        force_lbf=None if force_lbf is None else np.ascontiguousarray(force_lbf),
        response=response,
        response_quantity=responses[0].quantity,
        response_unit=responses[0].unit,
        header=dict(header_values.entries),
        n_samples=int(n_rows),
        column_names=columns.names,
        sample_rate_source=sample_rate_source,
        pretrigger_source=pretrigger_source,
        responses=responses,
        refused_channels=tuple((name, why) for name, why in zip(names, refusals) if why is not None),
    )

"""ASCII run files, header level: the header's ``key: value`` lines, the line of names and
units, and which column is time, force and each response, in which unit.

- A response column whose unit (in parentheses) differs from campaign.yaml's response
  unit is an error naming both, not a silent conversion: the contract makes any
  file/campaign.yaml disagreement an error, and one of the two labels is then wrong.
  The same holds for a force unit that contradicts campaign.yaml's ``force.unit``.
  A force column's own unit (lbf or N) is always converted to lbf; a force column with
  no unit anywhere is taken to be in lbf (the original lab's unit).
- Columns whose names match no role are ignored; two columns with the same role are
  an error.
- Without a line of names, a single text line directly before one-column numbers is
  indistinguishable from a header line and is treated as header.
- ``Pre-trigger`` in the header may be given in samples (``25 samples`` or ``25``) or
  in seconds (``0.01 s``, ``10 ms``), converted with the sample rate.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from workflow.io import units
from workflow.io.campaign import force_unit, response_units
from workflow.io.limits import MAX_QUOTED_PROBLEMS, magnitude_problem, name_length_problem, quoted, shortened
from workflow.io.readers.ascii_rows import (
    KEY_VALUE,
    SPACES,
    VALUE_WITH_UNIT,
    is_data_like,
    row_problem,
    split_row,
)
from workflow.io.record_rules import (
    TIME_STEP_REL_TOLERANCE,
    column_role,
    first_bad_time_step,
    split_name_unit,
)
from workflow.io.records import CampaignFormatError

if TYPE_CHECKING:
    from workflow.io.campaign import Campaign

__all__ = [
    "HeaderValues",
    "read_header_values",
    "find_columns",
    "response_column_units",
    "column_unit_factors",
    "check_magnitude",
    "check_time",
]


# --------------------------------------------------------------------------------------
# Run files: header


def _merge_unit_tokens(tokens: list[str]) -> list[str]:
    """Re-join whitespace tokens so that ``Time (s)`` stays one name."""
    merged: list[str] = []
    for token in tokens:
        open_unit = merged and merged[-1].count("(") > merged[-1].count(")")
        if merged and (token.startswith(("(", "[")) or open_unit):
            merged[-1] += " " + token
        else:
            merged.append(token)
    return merged


def _split_names(line: str, delimiter: str, n_columns: int) -> list[str] | None:
    """The line's cells when some reading of it gives exactly ``n_columns`` names."""
    stripped = line.strip()
    candidates = []
    if delimiter != SPACES:
        candidates.append(split_row(stripped, delimiter))
    candidates += [[cell.strip() for cell in stripped.split(d)] for d in ("\t", ",", ";")]
    candidates.append(re.split(r"\s{2,}", stripped))
    candidates.append(_merge_unit_tokens(stripped.split()))
    for names in candidates:
        names = [_unquoted(name) for name in names]
        if len(names) == n_columns and all(names):
            return names
    return None


def _unquoted(cell: str) -> str:
    """A cell without the quotes a CSV writer puts around text: ``"Force (N)"``."""
    cell = cell.strip()
    if len(cell) >= 2 and cell[0] == cell[-1] and cell[0] in "\"'":
        return cell[1:-1].strip()
    return cell


def _names_of(line: str, delimiter: str, n_columns: int) -> list[str] | None:
    names = _split_names(line, delimiter, n_columns)
    if names is None:
        return None
    roles = {column_role(name) for name in names} - {None}
    if not roles:
        return None
    # Split otherwise than the numbers are, a title ("Ring-down acceleration record") can
    # give as many words as there are columns: names must then name two roles at least.
    if n_columns >= 2 and len(roles) < 2 and not _splits_as_data(line, delimiter, n_columns):
        return None
    return names


def _splits_as_data(line: str, delimiter: str, n_columns: int) -> bool:
    """Whether ``line`` splits at the numbers' own delimiter into ``n_columns`` cells."""
    return delimiter != SPACES and len(split_row(line, delimiter)) == n_columns


def _is_key_value(line: str, delimiter: str, n_columns: int) -> bool:
    """A ``key: value`` header line, not a line of names that holds a colon
    (``Time (s)<TAB>Ch1: Acceleration (g)<TAB>Ch2: Force (lbf)``)."""
    if not KEY_VALUE.fullmatch(line):
        return False
    if n_columns < 2 or not _splits_as_data(line, delimiter, n_columns):
        return True
    cells = [_unquoted(cell) for cell in split_row(line, delimiter)]
    return len({column_role(cell) for cell in cells} - {None}) < 2


_KNOWN_UNIT_WORDS = {
    "s",
    "ms",
    "sec",
    *units.RESPONSE_UNITS,
    *units.known_units("force"),
}


def _is_units_row(line: str, delimiter: str, n_columns: int) -> list[str] | None:
    """Cells of a line of bare units under the names (``s  lbf  g``), else None."""
    cells = _split_names(line, delimiter, n_columns)
    if cells is None:
        return None
    bare = [cell.strip("()[] ") for cell in cells]
    if all(units.normalize_unit(cell) in _KNOWN_UNIT_WORDS for cell in bare):
        return bare
    return None


def _canonical_header_key(key: str) -> tuple[str, str | None]:
    """``"Sample rate (Hz)"`` -> ``("sample rate", "Hz")``."""
    name, unit = split_name_unit(key)
    return re.sub(r"[\s_\-]+", " ", name.lower()).strip(), unit


_SAMPLE_RATE_KEYS = {
    "sample rate",
    "sampling rate",
    "sample frequency",
    "sampling frequency",
    "sampling freq",
    "sample freq",
    "fs",
}


_PRETRIGGER_KEYS = {
    "pre trigger",
    "pretrigger",
    "pre trigger samples",
    "pretrigger samples",
    "pre trigger length",
    "pretrigger length",
}


_RATE_FACTORS_HZ = {"": 1.0, "hz": 1.0, "khz": 1e3, "sps": 1.0, "samples/s": 1.0, "s/s": 1.0}


_PRETRIGGER_SAMPLE_UNITS = {"", "samples", "sample", "points", "pts"}


_PRETRIGGER_TIME_UNITS_S = {"s": 1.0, "sec": 1.0, "ms": 1e-3}


@dataclass(frozen=True)
class HeaderValues:
    """What a run file's header says: its sample rate (Hz) and pre-trigger length (samples
    or seconds), each with the line it is on, and every ``key: value`` entry."""

    sample_rate_hz: float | None = None
    sample_rate_line: int | None = None
    pretrigger_samples: int | None = None
    pretrigger_s: float | None = None
    pretrigger_line: int | None = None
    entries: dict[str, str] = field(default_factory=dict)


def read_header_values(lines: list[tuple[int, str]], path: str) -> HeaderValues:
    """``key: value`` lines of the header, with sample rate and pre-trigger understood."""
    entries: dict[str, str] = {}
    rate = rate_line = pre_samples = pre_s = pre_line = None
    for number, line in lines:
        match = KEY_VALUE.fullmatch(line)
        if not match:
            continue
        # a spreadsheet pads the line with empty cells: "Sample rate: 2560 Hz,,"
        key, value = match.group(1), match.group(2).rstrip(",;\t ")
        entries.setdefault(key, value)
        name, key_unit = _canonical_header_key(key)
        if name in _SAMPLE_RATE_KEYS and rate is None:
            parsed = VALUE_WITH_UNIT.fullmatch(value)
            unit = (parsed.group(2) if parsed and parsed.group(2) else key_unit or "").lower()
            if not parsed or unit not in _RATE_FACTORS_HZ or not 0 < float(parsed.group(1)) < math.inf:
                raise CampaignFormatError(
                    path, number, f"cannot read a positive sample rate in Hz from {quoted(line.strip())}"
                )
            rate, rate_line = float(parsed.group(1)) * _RATE_FACTORS_HZ[unit], number
        elif name in _PRETRIGGER_KEYS and pre_line is None:
            parsed = VALUE_WITH_UNIT.fullmatch(value)
            unit = (parsed.group(2) if parsed and parsed.group(2) else key_unit or "").lower()
            amount = float(parsed.group(1)) if parsed else -1.0
            amount = amount if math.isfinite(amount) else -1.0
            if parsed and amount >= 0 and unit in _PRETRIGGER_SAMPLE_UNITS and amount == round(amount):
                pre_samples, pre_line = int(round(amount)), number
            elif parsed and amount >= 0 and unit in _PRETRIGGER_TIME_UNITS_S:
                pre_s, pre_line = amount * _PRETRIGGER_TIME_UNITS_S[unit], number
            else:
                raise CampaignFormatError(
                    path,
                    number,
                    f"cannot read the pre-trigger from {quoted(line.strip())} "
                    "(expected a whole number of samples, e.g. 'Pre-trigger: 25 samples')",
                )
    return HeaderValues(rate, rate_line, pre_samples, pre_s, pre_line, entries)


@dataclass(frozen=True)
class _Columns:
    roles: dict[str, int]
    units: dict[str, str | None]
    names: tuple[str, ...]
    line: int | None
    responses: tuple[int, ...] = ()
    """The response columns, one per campaign.yaml channel (``roles["response"]`` is the first)."""
    response_units: tuple[str | None, ...] = ()
    """Each response column's unit as written (None: none given)."""


def find_columns(
    header: list[tuple[int, str]],
    first_line: int,
    delimiter: str,
    n_columns: int,
    campaign: Campaign,
    path: str,
) -> _Columns:
    """Column roles and units from the line of names, or the positional rules."""
    text_lines = [
        (number, line)
        for number, line in header
        if line.strip() and not _is_key_value(line, delimiter, n_columns)
    ]
    # A first data row with a bad cell is not numeric and so lands in the header:
    # recognise it by its shape so that it is reported instead of silently dropped.
    if text_lines and text_lines[-1][0] == first_line - 1:
        number, line = text_lines[-1]
        tokens = [t for t in re.split(r"[\t,;\s]+", line.strip()) if t]
        # With several columns a bad row may also have lost or gained a cell; with one
        # column only an exact match is taken, so that a title line stays a title.
        counts = (n_columns,) if n_columns == 1 else (n_columns - 1, n_columns, n_columns + 1)
        if len(tokens) in counts and any(is_data_like(t) for t in tokens):
            problem = row_problem(line, delimiter, n_columns, first_line) or "not a numeric row"
            raise CampaignFormatError(path, number, problem)

    names, names_line, units_cells = None, None, None
    if text_lines:
        last_number, last_line = text_lines[-1]
        names = _names_of(last_line, delimiter, n_columns)
        names_line = last_number if names else None
        if names is None and len(text_lines) >= 2:
            above_number, above_line = text_lines[-2]
            above = _names_of(above_line, delimiter, n_columns)
            if above is not None:
                units_cells = _is_units_row(last_line, delimiter, n_columns)
                if units_cells is None:
                    raise CampaignFormatError(
                        path,
                        last_number,
                        f"unexpected text {quoted(last_line.strip())} between the column names "
                        f"(line {above_number}) and the numbers",
                    )
                names, names_line = above, above_number
        if names is None:
            roles_in_line = {column_role(t) for t in _merge_unit_tokens(last_line.split())} - {None}
            if len(roles_in_line) >= 2:
                raise CampaignFormatError(
                    path,
                    last_number,
                    f"the column names do not match the {n_columns} column(s) of numbers",
                )

    references = campaign.response.references()
    if references != (None,):
        return _named_response_columns(names, names_line, units_cells, n_columns, first_line, campaign, path)
    if names is None:
        order = _positional_roles(n_columns, 0, campaign)
        if order is None:
            raise CampaignFormatError(
                path,
                first_line,
                f"{n_columns} columns and no line of column names: cannot tell which is "
                "the response (name the columns, e.g. 'Time (s)  Force (lbf)  Acceleration (g)')",
            )
        roles = {role: i for i, role in enumerate(order)}
        return _Columns(roles, {}, (), None, (roles["response"],), (None,))

    for name in names:
        long_name = name_length_problem("column name", name)
        if long_name is not None:
            raise CampaignFormatError(path, names_line, long_name)
    roles: dict[str, int] = {}
    column_units: dict[str, str | None] = {}
    for index, name in enumerate(names):
        role = column_role(name)
        if role is None:
            continue  # columns with other names (extra channels) are not used
        if role in roles:
            raise CampaignFormatError(
                path,
                names_line,
                f"two {role} columns: {quoted(names[roles[role]])} and {quoted(name)}",
            )
        roles[role] = index
        unit = split_name_unit(name)[1]
        if unit is None and any(bracket in name for bracket in "()[]"):
            raise CampaignFormatError(
                path,
                names_line,
                f"the unit of the {role} column {quoted(name)} cannot be read: write one unit in "
                "parentheses or brackets after the name, e.g. 'Acceleration (m/s^2)' or 'Force [N]'",
            )
        if units_cells is not None:
            unit = units_cells[index]
        column_units[role] = unit
    if "response" not in roles:
        raise CampaignFormatError(
            path,
            names_line,
            f"no response column among {[shortened(name) for name in names][:MAX_QUOTED_PROBLEMS]} (a response column's name contains acc, vel, resp or disp)",
        )
    _check_named_quantity(
        names[roles["response"]],
        split_name_unit(names[roles["response"]])[0].lower(),
        campaign,
        path,
        names_line,
    )
    return _Columns(
        roles, column_units, tuple(names), names_line, (roles["response"],), (column_units["response"],)
    )


def _positional_roles(n_columns: int, n_responses: int, campaign: Campaign) -> tuple[str, ...] | None:
    """Roles of a file's columns without a line of names (the contract's positional rules),
    or None when they do not decide. With ``n_responses`` > 0 the responses are already
    picked by index and the roles are those of the other columns, in order."""
    if n_responses == 0:
        if n_columns == 3:
            return ("time", "force", "response")
        if n_columns == 2:
            return ("force", "response") if campaign.force is not None else ("time", "response")
        return ("response",) if n_columns == 1 else None
    others = n_columns - n_responses
    if others == 2:
        return ("time", "force")
    if others == 1:
        return ("force",) if campaign.force is not None else ("time",)
    return () if others == 0 else None


def _named_response_columns(
    names: list[str] | None,
    names_line: int | None,
    units_cells: list[str] | None,
    n_columns: int,
    first_line: int,
    campaign: Campaign,
    path: str,
) -> _Columns:
    """Columns of a file whose response channels campaign.yaml names (``channel`` or
    ``channels``): a name is a column's name without its unit (case ignored), an index
    counts the columns from 0; the time and force columns keep the contract's rules."""
    references = campaign.response.references()
    key = "response.channels" if campaign.response.channels is not None else "response.channel"
    for name in names or ():
        long_name = name_length_problem("column name", name)
        if long_name is not None:
            raise CampaignFormatError(path, names_line, long_name)
    listing = ", ".join(f"[{i}] {quoted(name)}" for i, name in enumerate(names)) if names else ""
    bare = [split_name_unit(name)[0].strip().lower() for name in names] if names else []
    responses = []
    for reference in references:
        if isinstance(reference, int):
            if reference >= n_columns:
                raise CampaignFormatError(
                    path,
                    names_line,
                    f"campaign.yaml {key}: {reference} but the file has {n_columns} column(s)",
                )
            responses.append(reference)
            continue
        if names is None:
            raise CampaignFormatError(
                path,
                first_line,
                f"campaign.yaml {key}: {quoted(reference)} names a column but the file has no line of column names",
            )
        matches = [i for i, name in enumerate(names) if name == reference]
        matches = matches or [i for i, name in enumerate(bare) if name == reference.strip().lower()]
        if len(matches) != 1:
            found = "several columns" if matches else "no column"
            raise CampaignFormatError(
                path,
                names_line,
                f"campaign.yaml {key}: {quoted(reference)} matches {found}; the columns: {listing}",
            )
        responses.append(matches[0])
    roles: dict[str, int] = {}
    column_units: dict[str, str | None] = {}
    others = [index for index in range(n_columns) if index not in responses]
    if names is None:
        order = _positional_roles(n_columns, len(responses), campaign)
        if order is None:
            raise CampaignFormatError(
                path,
                first_line,
                f"{n_columns} columns and no line of column names: cannot tell which are the time "
                "and force columns (name the columns)",
            )
        roles = {role: index for role, index in zip(order, others)}
    else:
        for index in others:
            role = column_role(names[index])
            if role in ("time", "force"):
                if role in roles:
                    raise CampaignFormatError(
                        path,
                        names_line,
                        f"two {role} columns: {quoted(names[roles[role]])} and {quoted(names[index])}",
                    )
                roles[role] = index
                column_units[role] = (
                    units_cells[index] if units_cells is not None else split_name_unit(names[index])[1]
                )
        for index in responses:
            _check_named_quantity(names[index], bare[index], campaign, path, names_line)
    response_units = tuple(
        None
        if names is None
        else (units_cells[i] if units_cells is not None else split_name_unit(names[i])[1])
        for i in responses
    )
    roles["response"] = responses[0]
    column_units["response"] = response_units[0]
    return _Columns(roles, column_units, tuple(names or ()), names_line, tuple(responses), response_units)


def _check_named_quantity(name: str, bare: str, campaign: Campaign, path: str, line: int | None) -> None:
    """Refuse a response column whose name says another quantity than campaign.yaml's
    (``bare``: the name without its unit, lower-case); without a quantity in campaign.yaml
    each column's unit says what it records."""
    if campaign.response.quantity is None:
        return
    for word, quantity in (("acc", "acceleration"), ("vel", "velocity"), ("disp", "displacement")):
        if word in bare and quantity != campaign.response.quantity:
            raise CampaignFormatError(
                path,
                line,
                f"response column {quoted(name)} is {quantity} but campaign.yaml says "
                f"response quantity {campaign.response.quantity}",
            )


def response_column_units(
    columns: _Columns, campaign: Campaign, path: str
) -> tuple[tuple[str | None, ...], tuple[str | None, ...]]:
    """Each response column's canonical unit, or None with why it is refused
    (:func:`workflow.io.campaign.response_units`); every column refused is an error."""
    whats = [
        f"response column {quoted(columns.names[index])}" if columns.names else f"response column {index + 1}"
        for index in columns.responses
    ]
    try:
        return response_units(columns.response_units, campaign, whats)
    except ValueError as error:
        raise CampaignFormatError(path, columns.line, str(error)) from None


_TIME_UNIT_FACTORS_S = {
    **dict.fromkeys(("s", "sec", "secs", "second", "seconds"), 1.0),
    **dict.fromkeys(("ms", "msec", "millisecond", "milliseconds"), 1e-3),
}
"""Spellings of a time column's unit, and the factor to seconds."""


def column_unit_factors(columns: _Columns, campaign: Campaign, path: str) -> tuple[float, float]:
    """Factors taking the time column to s and the force column to lbf; checks units."""
    line = columns.line
    time_factor_s = 1.0
    time_unit = columns.units.get("time")
    if time_unit:
        time_factor_s = _TIME_UNIT_FACTORS_S.get(time_unit.strip().lower(), 0.0)
        if time_factor_s == 0.0:
            raise CampaignFormatError(path, line, f"time column unit {quoted(time_unit)}: expected s or ms")
    force_factor_lbf = 1.0
    if "force" in columns.roles:
        try:
            unit = force_unit(columns.units.get("force") or None, campaign, "force column")
        except ValueError as error:
            raise CampaignFormatError(path, line, str(error)) from None
        force_factor_lbf = units.factor_to_internal("force", unit)
    return time_factor_s, force_factor_lbf


def check_magnitude(
    column: NDArray[np.float64], role: str, index: int, columns: _Columns, first_line: int, path: str
) -> None:
    """Refuse a force or response column (0-based ``index``) the analysis cannot square
    (:mod:`workflow.io.limits`), naming the line of the first such value."""
    name = f" {quoted(columns.names[index])}" if columns.names else ""
    problem = magnitude_problem(column, f"{role} column {index + 1}{name}")
    if problem is not None:
        raise CampaignFormatError(path, first_line + problem[0], problem[1])


def check_time(time_s: NDArray[np.float64], resolution_s: float, first_line: int, path: str) -> float:
    """Sample rate (Hz) from a time column that must increase in uniform steps."""
    steps = np.diff(time_s)
    bad = first_bad_time_step(steps, resolution_s)
    if bad is not None:
        i, typical_s = bad
        if steps[i] <= 0.0:
            problem = f"time column not increasing: {time_s[i + 1]:.9g} s follows {time_s[i]:.9g} s"
        elif i + 1 < steps.size and steps[i + 1] <= 0.0:
            # a stamp ahead of its neighbours (a spike, two rows swapped): this line is the wrong one
            problem = (
                f"time column out of order: {time_s[i + 1]:.9g} s is followed by {time_s[i + 2]:.9g} s "
                "on the next line"
            )
        else:
            tolerance_s = TIME_STEP_REL_TOLERANCE * typical_s + resolution_s
            problem = (
                f"time column not uniform: step {steps[i]:.6g} s (from {time_s[i]:.9g} s on the line "
                f"before) differs from the record's typical step {typical_s:.6g} s by "
                f"{100 * abs(steps[i] / typical_s - 1):.3g} % (tolerance {100 * tolerance_s / typical_s:.3g} %)"
            )
        raise CampaignFormatError(path, first_line + i + 1, problem)
    return (time_s.size - 1) / (time_s[-1] - time_s[0])

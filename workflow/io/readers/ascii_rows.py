"""ASCII run files, text level: encodings, decimal commas, delimiters, where the numbers
start, and the numeric block parsed in two passes.

The fast pass hands the numeric block (everything after the header) to NumPy's C reader
(``np.loadtxt``). Whenever it fails or its result is suspicious, a careful line-by-line
pass re-reads the block to find and name the first bad line, so speed never costs an
exact error message.

- A trailing delimiter at the end of every row (some exporters write one) is accepted.
  Blank lines are accepted after the numbers, not among them.
"""

from __future__ import annotations

import io
import math
import re
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workflow.io.limits import quoted
from workflow.io.records import CampaignFormatError

__all__ = [
    "DECIMAL_COMMA_HINT",
    "CAREFUL_CHUNK_ROWS",
    "FAST_CHUNK_CHARS",
    "KEY_VALUE",
    "VALUE_WITH_UNIT",
    "SPACES",
    "line_delimiter",
    "split_row",
    "is_data_like",
    "is_decimal_comma_row",
    "row_problem",
    "parse_block_careful",
    "parse_text_fast",
    "print_resolution",
    "wide_encoding",
    "read_run_text",
    "decimal_commas_to_points",
    "locate_numbers",
    "most_common",
]


# --------------------------------------------------------------------------------------
# Run files: tokens and rows

_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)


KEY_VALUE = re.compile(r"\s*([^:]*[^:\s])\s*:\s*(.*?)\s*")
"""A header line ``key: value`` (the key, the value)."""


VALUE_WITH_UNIT = re.compile(r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*?)\s*")
"""A header value: a number and what follows it (its unit)."""


SPACES = " "
"""Delimiter marker: columns separated by runs of spaces."""


_DELIMITER_NAMES = {"\t": "tab", ",": "comma", ";": "semicolon", SPACES: "spaces"}


# Characters a numeric block may hold; anything else sends it to the careful pass.
_FOREIGN = {
    "\t": re.compile(r"[^0-9eE+\-. \t\n]"),
    ",": re.compile(r"[^0-9eE+\-. ,\n]"),
    ";": re.compile(r"[^0-9eE+\-. ;\n]"),
    SPACES: re.compile(r"[^0-9eE+\-. \n]"),
}


def line_delimiter(line: str) -> str:
    """The delimiter a single row appears to use (tab, comma, semicolon, else spaces)."""
    for delimiter in ("\t", ",", ";"):
        if delimiter in line:
            return delimiter
    return SPACES


def split_row(line: str, delimiter: str) -> list[str]:
    """Cells of one row; a single trailing comma/semicolon is tolerated."""
    if delimiter == SPACES:
        return line.split()
    cells = [cell.strip() for cell in line.strip().split(delimiter)]
    if len(cells) > 1 and cells[-1] == "":
        cells.pop()
    return cells


def _is_numeric_row(line: str) -> bool:
    cells = split_row(line, line_delimiter(line))
    return bool(cells) and all(_NUMBER.fullmatch(cell) for cell in cells)


def is_data_like(cell: str) -> bool:
    """A token that looks like a measured value (decimal, exponent, NaN or inf)."""
    if _NON_FINITE.fullmatch(cell):
        return True
    return bool(_NUMBER.fullmatch(cell)) and ("." in cell or "e" in cell.lower())


_DECIMAL_COMMA_NUMBER = re.compile(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?")


DECIMAL_COMMA_HINT = (
    "numbers written with decimal commas; the decimal point of run files is '.' "
    'unless campaign.yaml says decimal: "," (campaign-format.md)'
)


def is_decimal_comma_row(line: str) -> bool:
    """A row of numbers written with decimal commas (``0,0021<TAB>-0,00037``)."""
    cells = [cell for cell in re.split(r"[\t; ]+", line.strip()) if cell]
    return (
        bool(cells)
        and all(_NUMBER.fullmatch(cell) or _DECIMAL_COMMA_NUMBER.fullmatch(cell) for cell in cells)
        and any(_DECIMAL_COMMA_NUMBER.fullmatch(cell) for cell in cells)
    )


def row_problem(line: str, delimiter: str, n_columns: int, format_line: int) -> str | None:
    """What is wrong with one row of the numeric block, or None if it is fine."""
    stripped = line.strip()
    if not stripped:
        return "blank line among the numbers"
    if delimiter != "," and is_decimal_comma_row(stripped):
        return f"{DECIMAL_COMMA_HINT}: {stripped[:60]!r}"
    for other in ("\t", ",", ";"):
        if other != delimiter and other in stripped:
            return (
                f"mixed delimiters: {_DELIMITER_NAMES[other]} in a row separated by "
                f"{_DELIMITER_NAMES[delimiter]} (as set by the numbers from line {format_line})"
                + ("; note that '.' is the decimal point" if other == "," else "")
            )
    cells = split_row(stripped, delimiter)
    if delimiter != SPACES and any(re.search(r"\s", cell) for cell in cells):
        return f"mixed delimiters: spaces inside a cell of a row separated by {_DELIMITER_NAMES[delimiter]}"
    if len(cells) != n_columns:
        return (
            f"ragged row: {len(cells)} value{'s' if len(cells) != 1 else ''}, expected "
            f"{n_columns} like the rows from line {format_line}"
        )
    for column, cell in enumerate(cells, start=1):
        if cell == "":
            return f"empty cell in column {column}"
        if _NON_FINITE.fullmatch(cell):
            return f"NaN/inf value {quoted(cell)} in column {column}"
        if not _NUMBER.fullmatch(cell):
            return f"non-numeric cell {quoted(cell)} in column {column}"
        if not math.isfinite(float(cell)):
            return f"value {quoted(cell)} in column {column} overflows a float"
    return None


CAREFUL_CHUNK_ROWS: int = 2048
"""Rows per chunk when hunting for a bad line: clean chunks still go through the C
parser, so only the chunk holding the bad line is read line by line."""


def parse_block_careful(
    rows: list[str], first_line: int, delimiter: str, n_columns: int, path: str
) -> NDArray[np.float64]:
    """Parse that names the first bad line (chunked; line by line where needed)."""
    values = np.empty((len(rows), n_columns))
    for start in range(0, len(rows), CAREFUL_CHUNK_ROWS):
        chunk = rows[start : start + CAREFUL_CHUNK_ROWS]
        fast = _parse_block_fast("\n".join(chunk), delimiter, len(chunk), n_columns)
        if fast is not None:
            values[start : start + len(chunk)] = fast
            continue
        for index, row in enumerate(chunk, start=start):
            problem = row_problem(row, delimiter, n_columns, first_line)
            if problem is not None:
                raise CampaignFormatError(path, first_line + index, problem)
            values[index] = [float(cell) for cell in split_row(row, delimiter)]
    return values


FAST_CHUNK_CHARS: int = 1 << 20
"""Characters of the numeric block handed to the C reader at a time: the reader's working
copy of the text (4 bytes a character) then stays small however long the record."""


def parse_text_fast(
    text: str, start: int, end: int, delimiter: str, n_rows: int, n_columns: int
) -> NDArray[np.float64] | None:
    """:func:`_parse_block_fast` of ``text[start:end]``, in chunks of whole rows (no copy
    of the whole block); None whenever the careful pass must decide."""
    if _FOREIGN[delimiter].search(text, start, end):
        return None
    values = np.empty((n_rows, n_columns))
    row, position = 0, start
    while position <= end:
        stop = end
        if position + FAST_CHUNK_CHARS < end:
            stop = text.rfind("\n", position, position + FAST_CHUNK_CHARS)
            if stop < 0:
                stop = text.find("\n", position + FAST_CHUNK_CHARS, end)
                stop = end if stop < 0 else stop
        chunk = text[position:stop]
        chunk_rows = chunk.count("\n") + 1
        if row + chunk_rows > n_rows:
            return None
        parsed = _parse_block_fast(chunk, delimiter, chunk_rows, n_columns)
        if parsed is None:
            return None
        values[row : row + chunk_rows] = parsed
        row, position = row + chunk_rows, stop + 1
    return values if row == n_rows else None


def _parse_block_fast(block: str, delimiter: str, n_rows: int, n_columns: int) -> NDArray[np.float64] | None:
    """C-parser read of the numeric block; None whenever the careful pass must decide."""
    if _FOREIGN[delimiter].search(block):
        return None
    if (
        delimiter != SPACES
        and block.count(delimiter + "\n") == n_rows - 1
        and block.rstrip().endswith(delimiter)
    ):
        block = block.replace(delimiter + "\n", "\n").rstrip()[:-1]  # one trailing delimiter per row
    try:
        # NumPy's C reader (not pandas): the run-analysis jobs then start without pandas.
        values = np.loadtxt(
            io.StringIO(block),
            delimiter=None if delimiter == SPACES else delimiter,
            comments=None,
            ndmin=2,
            dtype=np.float64,
        )
    except ValueError:
        return None
    if values.shape != (n_rows, n_columns) or not np.isfinite(values).all():
        return None
    return np.ascontiguousarray(values)


def print_resolution(tokens: list[str]) -> float:
    """Spacing of the last printed digit of the coarsest of some numbers.

    ``'0.0000195'`` -> 1e-7, ``'1.28e+01'`` -> 0.1. Bare integers (such as a first
    time stamp written ``0``) say nothing about the precision and are skipped unless
    all tokens are integers.
    """
    resolutions = []
    for token in tokens:
        mantissa, marker, exponent = token.lower().partition("e")
        if "." in mantissa or marker:
            decimals = len(mantissa.partition(".")[2])
            resolutions.append(10.0 ** (int(exponent or 0) - decimals))
    return max(resolutions) if resolutions else 1.0


_WIDE_ENCODINGS = (
    (b"\xff\xfe\x00\x00", "UTF-32 (little-endian)"),
    (b"\x00\x00\xfe\xff", "UTF-32 (big-endian)"),
    (b"\xff\xfe", "UTF-16 (little-endian)"),
    (b"\xfe\xff", "UTF-16 (big-endian)"),
)


def wide_encoding(raw: bytes) -> str | None:
    """The name of a UTF-16/UTF-32 encoding the bytes are written in, from the byte-order
    mark or, without one, from NUL bytes alternating with ASCII text; else None."""
    for mark, name in _WIDE_ENCODINGS:
        if raw.startswith(mark):
            return name
    head = raw[:4096]
    if len(head) >= 8:
        even_nul = head[0::2].count(0) / len(head[0::2])
        odd_nul = head[1::2].count(0) / len(head[1::2])
        if odd_nul > 0.9 and even_nul < 0.1:
            return "UTF-16 (little-endian)"
        if even_nul > 0.9 and odd_nul < 0.1:
            return "UTF-16 (big-endian)"
    return None


def read_run_text(path: Path, shown: str) -> str:
    """File text with LF line ends (UTF-8, else Windows-1252 for old exports)."""
    try:
        with open(path, "rb") as handle:  # read-only: raw files are never modified
            raw = handle.read()
    except OSError as error:
        raise CampaignFormatError(shown, None, f"cannot be read: {error.strerror or error}") from None
    encoding = wide_encoding(raw)
    if encoding is not None:
        raise CampaignFormatError(
            shown,
            None,
            f"text encoded as {encoding}: run files must be ASCII or UTF-8 text "
            "(save the export as ASCII/UTF-8, or convert it, e.g. with iconv)",
        )
    nul = raw.find(b"\x00")
    if nul >= 0:
        # lines end in LF, CRLF or a lone CR, as the text is read below
        line_ends = raw.count(b"\n", 0, nul) + raw.count(b"\r", 0, nul) - raw.count(b"\r\n", 0, nul)
        raise CampaignFormatError(shown, line_ends + 1, "binary data (NUL byte): not a text export")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("cp1252", errors="replace")
    del raw  # a long record: hold one copy of its text at a time
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text


_COMMA_SEPARATED_CELL = re.compile(r"[^\t; \n]*,[^\t; \n]*[,.]|[^\t; \n]*\.[^\t; \n]*,")


_NUMERIC_CHARACTERS = re.compile(r"[0-9eE+\-.,;\t ]+")


def decimal_commas_to_points(text: str, shown: str) -> str:
    """Text of a file written with decimal commas, with decimal points instead.

    In a row of numbers, a cell holding two commas, or a comma and a point, means commas
    also separate the columns (or mark thousands), which cannot be told apart from
    decimal commas. A header line of text with such a cell (a date: ``12.05.2004, 14:03``)
    is left as it is.
    """
    lines = text.split("\n")
    for number, line in enumerate(lines, start=1):
        clash = _COMMA_SEPARATED_CELL.search(line)
        if clash is None:
            lines[number - 1] = line.replace(",", ".")
        elif _NUMERIC_CHARACTERS.fullmatch(line.strip()):
            raise CampaignFormatError(
                shown,
                number,
                f"campaign.yaml says decimal: ',' but {quoted(clash.group(0))} holds more than one separator; "
                "with decimal commas the columns must be separated by tabs, semicolons or spaces",
            )
    return "\n".join(lines)


def locate_numbers(text: str) -> tuple[list[tuple[int, str]], int, int]:
    """Header lines, character offset and 1-based line of the first numeric row."""
    header: list[tuple[int, str]] = []
    position, number = 0, 0
    while position < len(text):
        end = text.find("\n", position)
        end = len(text) if end < 0 else end
        line = text[position:end]
        number += 1
        if line.strip() and _is_numeric_row(line):
            return header, position, number
        header.append((number, line))
        position = end + 1
    return header, -1, number


def most_common(items: list[Any], fallback: Any) -> Any:
    """The item that occurs most often (the first of them on a tie); ``fallback`` when
    there is none."""
    if not items:
        return fallback
    counts = Counter(items)
    best = max(counts.values())
    return next(item for item in items if counts[item] == best)

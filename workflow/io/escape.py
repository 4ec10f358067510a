"""Text from a campaign made safe for each place the workflow writes it.

Every name, path, channel, unit, header text and reason that comes from a campaign is
untrusted (docs/input-safety.md). It reaches an output only through the function of its
destination:

* :func:`html_text`: HTML element content or a quoted attribute value.
* :func:`rst_text`: reStructuredText, after the Jinja pass Snakemake applies to report
  captions and to the report's first page (no inline markup, no Jinja tag survives).
* :func:`plot_text`: matplotlib text (no mathtext: ``$`` stays a dollar sign).
* :func:`terminal_text`: the console and plain-text files (no escape sequence reaches
  the terminal); :func:`terminal_lines` for a message of several lines (a log record).
* :func:`spreadsheet_text`: a cell of a CSV file a spreadsheet opens (no formula).

Each one first makes invisible characters visible (:func:`visible_controls`), so that a
name reads the same everywhere and no line break, terminal escape or bidirectional
override can hide or rearrange text, then shortens very long text (:func:`shortened`).
"""

from __future__ import annotations

import html
import string
import unicodedata
from typing import Any

__all__ = [
    "visible_controls",
    "shortened",
    "display_text",
    "html_text",
    "rst_text",
    "rst_strong",
    "plot_text",
    "terminal_text",
    "terminal_lines",
    "spreadsheet_text",
]

DISPLAY_LIMIT = 2000
"""Longest text shown in a page, a report or a terminal line, characters (a name is
bounded when read; a sentence holding one stays far below this)."""

PLOT_LIMIT = 120
"""Longest campaign text drawn in a figure, characters: a title or a legend entry
wider than the figure helps nobody and costs layout time."""

_NAMED_CONTROLS = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}
_INVISIBLE_CATEGORIES = {"Cc", "Cf", "Cs", "Zl", "Zp"}
_RST_PUNCTUATION = frozenset(string.punctuation)


def _visible(character: str) -> str:
    if character in _NAMED_CONTROLS:
        return _NAMED_CONTROLS[character]
    code = ord(character)
    if code < 0x100:
        return f"\\x{code:02x}"
    if code < 0x10000:
        return f"\\u{code:04x}"
    return f"\\U{code:08x}"


def visible_controls(text: Any) -> str:
    """``text`` with every control, format, line-separator and lone-surrogate character
    written as its Python escape (``\\n``, ``\\x1b``, ``\\u202e``, ``\\udcff``).

    Control characters (C0, DEL, C1) drive terminals and break lines; format characters
    (bidirectional overrides, zero-width) reorder or hide text; lone surrogates come from
    file names that are not UTF-8 and cannot be written out as UTF-8."""
    text = str(text)
    if text.isprintable():  # holds none of those characters: the common case, fast
        return text
    return "".join(
        _visible(character) if unicodedata.category(character) in _INVISIBLE_CATEGORIES else character
        for character in text
    )


def shortened(text: str, limit: int | None = DISPLAY_LIMIT) -> str:
    """``text`` cut to about ``limit`` characters: its start and its end, and between them
    how many characters were cut (``abc … [12345 characters cut] … xyz``); ``None``: as
    it is (a sentence made of pieces already shortened)."""
    if limit is None or len(text) <= limit:
        return text
    keep = max(limit - 40, 2)
    head, tail = text[: (keep + 1) // 2], text[len(text) - keep // 2 :]
    return f"{head} … [{len(text) - len(head) - len(tail)} characters cut] … {tail}"


def display_text(text: Any, limit: int | None = DISPLAY_LIMIT) -> str:
    """``text`` with invisible characters visible, then shortened to ``limit``: what every
    destination shows of a campaign's text before its own escaping."""
    return shortened(visible_controls(text), limit)


def html_text(text: Any, limit: int | None = DISPLAY_LIMIT) -> str:
    """``text`` as HTML element content or a double-quoted attribute value.

    Examples
    --------
    >>> html_text('<script>alert("x")</script>')
    '&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt;'
    """
    return html.escape(display_text(text, limit), quote=True)


def rst_text(text: Any, limit: int | None = DISPLAY_LIMIT) -> str:
    """``text`` as plain reStructuredText inside a paragraph, after Jinja.

    Every ASCII punctuation character is backslash-escaped: in reStructuredText an
    escaped character stands for itself, so no inline markup, role, reference, standalone
    link (``javascript:...``) or directive can start inside the text, and since each of
    ``{ % # }`` is preceded by a backslash, no Jinja tag (``{{``, ``{%``, ``{#``) can
    form. Line breaks are shown as ``\\n`` (:func:`visible_controls`), so the text stays
    inside its paragraph."""
    return "".join(
        f"\\{character}" if character in _RST_PUNCTUATION else character
        for character in display_text(text, limit)
    )


def rst_strong(text: Any, limit: int | None = DISPLAY_LIMIT) -> str:
    """``text`` in bold (``**...**``); text that is empty or only spaces is shown as
    ``(empty)``, since bold markup around nothing is a markup error."""
    escaped = rst_text(text, limit).strip()
    return f"**{escaped if escaped else '(empty)'}**"


def plot_text(text: Any, limit: int | None = PLOT_LIMIT) -> str:
    """``text`` for a matplotlib title, label or legend entry: ``$`` is escaped so that
    no mathtext is parsed (a stray ``$\\frac{`` would stop the figure)."""
    return display_text(text, limit).replace("$", r"\$")


def terminal_text(text: Any, limit: int | None = DISPLAY_LIMIT) -> str:
    """``text`` for the console or a plain-text file: no character that a terminal
    interprets (escape sequences, carriage returns, line breaks) is left raw."""
    return display_text(text, limit)


def terminal_lines(text: Any) -> str:
    """Lines of a message for the console (a log record, a traceback): each line as
    :func:`terminal_text`, the line breaks between them kept, nothing shortened."""
    return "\n".join(visible_controls(line) for line in str(text).split("\n"))


_FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def spreadsheet_text(text: Any) -> str:
    """``text`` for a cell of a CSV file that a spreadsheet opens: a cell that starts like
    a formula (``=``, ``+``, ``-``, ``@``, tab, carriage return) gets a leading ``'``, which
    spreadsheets read as "text, not a formula" (a run file named ``=HYPERLINK(...)``
    would otherwise be evaluated when the table is opened). Nothing else changes: the CSV
    writer quotes separators and line breaks."""
    text = str(text)
    return "'" + text if text.startswith(_FORMULA_STARTS) else text

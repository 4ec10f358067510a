"""The report pages' HTML: the style sheet, page and table frames, tags, and how numbers
and amplitude ranges are written.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from workflow.io.escape import html_text
from workflow.io.units import INCH_SECOND, UnitSystem

__all__ = [
    "CSS",
    "fmt",
    "ratio",
    "esc",
    "tag",
    "page",
    "html_table",
    "amplitude_range",
    "scaled_number",
]


CSS = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; font-size: 15px;
       line-height: 1.45; color: #1d1d1f; margin: 0 auto; padding: 0.5em 1.2em 2em 1.2em;
       max-width: 1100px; }
h1 { font-size: 1.6em; margin: 0.4em 0 0.3em 0; }
h2 { font-size: 1.25em; margin: 1.4em 0 0.4em 0; border-bottom: 1px solid #ddd;
     padding-bottom: 0.15em; }
h3 { font-size: 1.05em; margin: 1em 0 0.3em 0; }
p, li { max-width: 60em; }
.headline { background: #f3f6fb; border-left: 5px solid #2b6cb0; padding: 0.7em 1em;
            margin: 0.8em 0; font-size: 1.08em; }
.headline.none { border-left-color: #2f855a; background: #f0f8f3; }
.headline.unknown { border-left-color: #c05621; background: #fdf5ee; }
.note { color: #555; font-size: 0.92em; }
table { border-collapse: collapse; margin: 0.5em 0 1em 0; font-size: 0.92em; }
th, td { border: 1px solid #d5d5d5; padding: 0.3em 0.55em; vertical-align: top;
         text-align: left; }
th { background: #f2f2f2; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
tr.excluded td { background: #fff3f0; }
.tag { display: inline-block; padding: 0.05em 0.45em; border-radius: 0.6em;
       font-size: 0.85em; white-space: nowrap; }
.tag.supported, .tag.used, .tag.none { background: #d9f2e3; color: #22543d; }
.tag.contradicted, .tag.excluded { background: #fde2dd; color: #822727; }
.tag.inconclusive, .tag.skipped, .tag.not-applicable { background: #eee; color: #444; }
.tag.flag { background: #fdf0c8; color: #744210; }
.tag.cause { background: #dbe7f7; color: #1a365d; }
"""


# ------------------------------------------------------------------ formatting
def _number(value: Any) -> float | str:
    """``value`` as a float (nan when missing), or as text when it is no number."""
    if value is None:
        return math.nan
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


def fmt(value: Any, digits: int = 3) -> str:
    """A number with ``digits`` significant digits; '-' for missing or non-finite.

    Plain below ``10**(digits + 2)`` (``100``, never ``1e+02``), in exponent form above
    it and below 0.001.

    Examples
    --------
    >>> fmt(100.0, 2), fmt(1234.0), fmt(0.0795), fmt(2.5e-4), fmt(None)
    ('100', '1230', '0.0795', '2.50e-04', '–')
    """
    number = _number(value)
    if isinstance(number, str):
        return number
    if not math.isfinite(number):
        return "–"
    if number != 0 and (abs(number) >= 10 ** (digits + 2) or abs(number) < 1e-3):
        return f"{number:.{digits - 1}e}"
    if abs(number) >= 10**digits:
        # the g format would write 100 as 1e+02 at two digits
        return f"{round(number, digits - 1 - int(math.floor(math.log10(abs(number))))):.0f}"
    return f"{number:.{digits}g}"


def ratio(value: Any) -> str:
    """A ratio with two decimals ('-' when missing)."""
    number = _number(value)
    if isinstance(number, str):
        return number
    return f"{number:.2f}" if math.isfinite(number) else "–"


def esc(text: Any) -> str:
    """Text (the campaign's or ours) as HTML (:func:`workflow.io.escape.html_text`)."""
    return html_text(text)


def tag(text: str, kind: str) -> str:
    return f'<span class="tag {esc(kind.replace(" ", "-"))}">{esc(text)}</span>'


def page(title: str, body: str) -> str:
    """A complete HTML page (inline style, no external resources)."""
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{esc(title)}</title><style>{CSS}</style></head>\n"
        f"<body>\n{body}\n</body></html>\n"
    )


def html_table(
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    *,
    numeric: Sequence[int] = (),
    row_classes: Sequence[str] | None = None,
) -> str:
    """A table from already-escaped cell HTML; ``numeric`` columns right-aligned."""
    head = "".join(f"<th>{cell}</th>" for cell in header)
    lines = [f"<table><thead><tr>{head}</tr></thead><tbody>"]
    for index, row in enumerate(rows):
        cls = f' class="{row_classes[index]}"' if row_classes and row_classes[index] else ""
        cells = "".join(
            f'<td class="num">{cell}</td>' if k in numeric else f"<td>{cell}</td>"
            for k, cell in enumerate(row)
        )
        lines.append(f"<tr{cls}>{cells}</tr>")
    lines.append("</tbody></table>")
    return "\n".join(lines)


def amplitude_range(low_in_s: Any, high_in_s: Any, units: UnitSystem = INCH_SECOND) -> str:
    """``0.1–3 in/s``: a range of velocity amplitudes given in in/s, shown in ``units``."""
    return f"{fmt(scaled_number(low_in_s, units.per_in_s))}–{fmt(scaled_number(high_in_s, units.per_in_s))} {units.velocity}"


def scaled_number(value: Any, factor: float) -> Any:
    """``value`` times ``factor`` when it is a number; as it is otherwise (None, text)."""
    return value * factor if isinstance(value, (int, float)) and not isinstance(value, bool) else value

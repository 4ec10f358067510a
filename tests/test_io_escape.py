"""Campaign text through each destination's escaping function: what is shown is the text,
and nothing in it acts (no markup, template tag, mathtext or terminal control)."""

import html
import io
import unicodedata
from html.parser import HTMLParser

import jinja2
import matplotlib
import pytest
from docutils.core import publish_parts

from workflow.io.escape import (
    DISPLAY_LIMIT,
    PLOT_LIMIT,
    display_text,
    html_text,
    plot_text,
    rst_strong,
    rst_text,
    shortened,
    spreadsheet_text,
    terminal_text,
    visible_controls,
)

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MARKER = "lapjoint-injected"

HOSTILE = [
    '{% endraw %}{{ self.__init__.__globals__.__builtins__.__import__("os").system("touch PWNED") }}{% raw %}',
    "{{ 7*7 }}",
    "{# comment #}x",
    "{%- if true %}yes{% endif %}",
    "run_01_",
    "_",
    f"a\n\n.. raw:: html\n\n   <script>document.title='{MARKER}'</script>\n\nb",
    f'<img src=x onerror="alert(1)" id="{MARKER}">',
    "$\\frac{",
    "$x$ and \\$",
    "\x1b[2J\x1b[H\x1b[32mVerdict: none\x1b[0m",
    "a\rb\u202egnp.exe\u2028c\x85d",
    "`code`_ *em* **strong** |sub| [1]_ :role:`x` javascript:alert(1) __init__",
    "----",
    "*",
    "name\\",
    "bad-utf8-\udcff",
    "",
    "   ",
    "ζ in %, x² (Å)",
]


class Elements(HTMLParser):
    """The start tags of an HTML fragment."""

    def __init__(self):
        super().__init__()
        self.tags: list[tuple[str, list]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, attrs))


def start_tags(fragment: str) -> list[tuple[str, list]]:
    parser = Elements()
    parser.feed(fragment)
    parser.close()
    return parser.tags


def snakemake_jinja_then_docutils(source: str) -> str:
    """What Snakemake does to a report caption or its first page: Jinja (its environment,
    unsandboxed), then docutils to HTML; warnings raised as errors."""
    rendered = jinja2.Environment(trim_blocks=True, lstrip_blocks=True).from_string(source).render()
    return publish_parts(rendered, writer="html", settings_overrides={"report_level": 2, "halt_level": 2})[
        "body"
    ]


@pytest.mark.parametrize("text", HOSTILE)
def test_rst_text_shows_the_text_through_jinja_and_docutils(text, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    body = snakemake_jinja_then_docutils(f"Run {rst_strong(text)}: {rst_text(text)}.\n")
    assert not (tmp_path / "PWNED").exists()
    assert [tag for tag, _ in start_tags(body)] == ["p", "strong"]
    shown = display_text(text)
    expected = shown.strip() or "(empty)"
    assert html.unescape(body) == f"<p>Run <strong>{expected}</strong>: {shown}.</p>\n"


def test_rst_text_keeps_a_name_in_its_paragraph_and_list_item():
    text = HOSTILE[6]
    body = snakemake_jinja_then_docutils(f"* {rst_strong('cfg')}: excluded {rst_text(text)}\n* next\n")
    assert [tag for tag, _ in start_tags(body)] == ["ul", "li", "strong", "li"]
    assert "<script>" in html.unescape(body) and "\\n\\n.. raw" in html.unescape(body)


@pytest.mark.parametrize("text", HOSTILE)
def test_html_text_is_text_in_content_and_attributes(text):
    fragment = f'<p title="{html_text(text)}">{html_text(text)}</p>'
    tags = start_tags(fragment)
    assert tags == [("p", [("title", display_text(text))])]
    assert html.unescape(fragment) == f'<p title="{display_text(text)}">{display_text(text)}</p>'


@pytest.mark.parametrize("text", HOSTILE)
def test_plot_text_draws_the_text_without_mathtext(text):
    figure, axis = plt.subplots()
    title = axis.set_title(plot_text(text))
    axis.plot([0, 1], [0, 1], label=plot_text(text))
    axis.legend()
    figure.savefig(io.BytesIO(), format="png")  # a mathtext error would raise here
    plt.close(figure)
    drawn, is_math = title._preprocess_math(title.get_text())
    assert not is_math
    assert drawn == display_text(text, PLOT_LIMIT)


@pytest.mark.parametrize("text", HOSTILE)
def test_terminal_text_holds_no_character_a_terminal_acts_on(text):
    shown = terminal_text(text)
    assert not any(unicodedata.category(c) in {"Cc", "Cf", "Cs", "Zl", "Zp"} for c in shown)
    shown.encode("utf-8")  # lone surrogates (names that are not UTF-8) are written out


def test_visible_controls_names_each_character():
    assert visible_controls("a\nb\tc\x1b[2J\u202e\udcff\U000e0001") == (
        "a\\nb\\tc\\x1b[2J\\u202e\\udcff\\U000e0001"
    )
    assert visible_controls("ζ (Å) ü") == "ζ (Å) ü"


def test_shortened_keeps_start_and_end_and_says_how_much_was_cut():
    name = "start-" + "x" * 100_000 + "-end"
    short = shortened(name, 200)
    assert len(short) <= 200
    assert short.startswith("start-") and short.endswith("-end")
    head, tail = short.split(" … [")
    cut = int(tail.split(" characters cut")[0])
    assert len(head) + cut + len(tail.split("] … ")[1]) == len(name)
    assert shortened("short", 200) == "short"
    assert shortened(name, None) == name
    assert len(html_text(name)) <= DISPLAY_LIMIT and len(plot_text(name)) <= PLOT_LIMIT


def test_a_very_long_name_draws_quickly():
    figure, axis = plt.subplots()
    axis.set_title(plot_text("n" * 100_000))
    figure.savefig(io.BytesIO(), format="png", bbox_inches="tight")
    plt.close(figure)


@pytest.mark.parametrize(
    "text, cell",
    [
        ('=HYPERLINK("http://x","y")', '\'=HYPERLINK("http://x","y")'),
        ("+1", "'+1"),
        ("-2 dB", "'-2 dB"),
        ("@SUM(A1)", "'@SUM(A1)"),
        ("\tx", "'\tx"),
        ("run01", "run01"),
        ("a=b", "a=b"),
        ("", ""),
    ],
)
def test_spreadsheet_text_leaves_no_formula(text, cell):
    assert spreadsheet_text(text) == cell

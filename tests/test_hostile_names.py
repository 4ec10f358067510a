"""A campaign whose names attack every place they are written (issue 36): `snakemake all`
and `snakemake --report` on it run no command, inject no element into any page, stop no
job, print no terminal escape and raise no reStructuredText warning.

One small campaign (2 configurations x 3 runs, cheap fits) is analysed and reported once;
each test checks one destination. The names: a Jinja payload that runs a command (as a run
file name, a TDMS channel name and the campaign's name), ``{{ 7*7 }}``, underscores, an
rst ``.. raw:: html`` block behind line breaks, HTML tags, ``$\\frac{``, terminal escapes
(screen clear, colours, cursor home) and a name past any display width.
"""

import base64
import functools
import html
import json
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from browser import audit_page, chromium
from helpers import CHEAP, REPO, run_snakemake
from system_format_files import write_tdms

MARKER = "lapjoint-marker"
"""In every injected element's id: no element of any page may carry it."""


def command(marker_file: str) -> str:
    """A Jinja expression that runs ``touch marker_file`` in an unsandboxed template engine,
    closing and reopening a ``{% raw %}`` block around it."""
    return (
        '{% endraw %}{{ self.__init__.__globals__.__builtins__.__import__("os").system('
        f'"touch {marker_file}") }}}}{{% raw %}}'
    )


RAW_HTML = "\n\n.. raw:: html\n\n   <img src=x id={marker} onerror=alert(1)>\n\n"
TERMINAL = "\x1b[2J\x1b[H\x1b[32mVerdict: none (fake)\x1b[0m"
MATH = "$\\frac{"

CAMPAIGN_NAME = (
    f"{command('PWNED-campaign')} {{{{ 7*7 }}}} {MATH} {TERMINAL} <script>document.title='{MARKER}'</script>"
    + RAW_HTML.format(marker=f"{MARKER}-campaign")
    + "end_of_name_"
)
USED_RUN = f"run04 {{{{ 7*7 }}}} {MATH} _x_ <b id={MARKER}-run>"
"""A run that is analysed: its name is in legends, tables and pages."""
EXCLUDED_RUNS = [
    command("PWNED-file"),
    "short" + RAW_HTML.format(marker=f"{MARKER}-file"),
    "long-" + "n" * 200 + "-end",
    f"ansi {TERMINAL}",
]
"""Run files that are too short (so excluded, their names in the exclusion reasons); one
whose name holds terminal escapes is excluded for its name before it is read."""
FOLDER = "camp<"
SUBFOLDER = f"script><img src=x id={MARKER}-folder>{{{{ 7*7 }}}} _x_"
"""The campaign folder is ``FOLDER/SUBFOLDER``: its path holds ``</script>``."""
TDMS_CHANNELS = [f"</script><img src=x id={MARKER}-tdms>", command("PWNED-tdms")]

snakemake = functools.partial(run_snakemake, timeout=900)


def short_run_text() -> str:
    return "Sample rate: 2560 Hz\nTime (s)\tForce (lbf)\tAcceleration (g)\n0\t0\t0\n0.0004\t1\t1\n"


@pytest.fixture(scope="module")
def hostile(tmp_path_factory):
    """The campaign analysed (``all``) and reported (``--report``): workdir, both results."""
    from workflow.lab.virtual_lab import generate_campaign

    root = tmp_path_factory.mktemp("hostile_names")
    campaign = root / FOLDER / SUBFOLDER
    generate_campaign(
        campaign, seed=11, runs_per_configuration=3, configurations={"no_washer": 1.36, "small_washer": 0.17}
    )
    (campaign / "no_washer" / "run03.txt").rename(campaign / "no_washer" / f"{USED_RUN}.txt")
    for name in EXCLUDED_RUNS:
        (campaign / "small_washer" / f"{name}.txt").write_text(short_run_text())
    samples = np.sin(np.arange(4096) / 3.0)
    write_tdms(
        campaign / "no_washer" / "channels.tdms",
        "Impact",
        {name: (samples, {"wf_increment": 1 / 2560, "unit_string": "g"}) for name in TDMS_CHANNELS},
    )
    text = (campaign / "campaign.yaml").read_text()
    text = re.sub(r"^name: .*$", lambda _: "name: " + json.dumps(CAMPAIGN_NAME), text, count=1, flags=re.M)
    text = text.replace('files: "no_washer/*.txt"', 'files: "no_washer/*"')
    (campaign / "campaign.yaml").write_text(text)
    workdir = root / "work"
    workdir.mkdir()
    configfile = root / "hostile.yaml"
    configfile.write_text(f"campaign: {json.dumps(str(campaign))}\n")
    options = ["--configfile", str(configfile), "--config", *CHEAP]
    analysed = snakemake(workdir, "-c2", "all", *options)
    reported = snakemake(
        workdir,
        "--report",
        "results/report.html",
        "--report-html-stylesheet-path",
        str(REPO / "report" / "report.css"),
        *options,
    )
    return root, workdir, analysed, reported


def test_every_job_ends_and_the_report_is_built(hostile):
    _, workdir, analysed, reported = hostile
    assert analysed.returncode == 0, analysed.stderr[-6000:]
    assert reported.returncode == 0, reported.stderr[-6000:]
    assert "Report created" in reported.stderr


def test_no_name_runs_a_command(hostile):
    root, workdir, _, _ = hostile
    found = [path for path in [*root.rglob("PWNED*"), *Path.cwd().glob("PWNED*"), *REPO.glob("PWNED*")]]
    assert found == []


class Elements(HTMLParser):
    """Every start tag of a page, with its attributes."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))


def elements(page: str) -> list[tuple[str, dict]]:
    parser = Elements()
    parser.feed(page)
    parser.close()
    return parser.tags


def injected(page: str) -> list[tuple[str, dict]]:
    """Elements a name put into ``page``: any carrying the marker, any script."""
    return [
        (tag, attrs)
        for tag, attrs in elements(page)
        if tag == "script" or MARKER in (attrs.get("id") or "") or any(key.startswith("on") for key in attrs)
    ]


def report_parts(workdir: Path) -> tuple[str, dict, str]:
    """report.html, its results (captions, embedded pages) and its first page's HTML."""
    text = (workdir / "results" / "report.html").read_text()
    results = json.loads(re.search(r"var results = (\{.*\});\n", text).group(1))
    description = json.loads(re.search(r"var workflow_desc = (\".*\");\n", text).group(1))
    return text, results, description


def test_report_html_holds_only_the_reports_own_scripts(hostile):
    _, workdir, _, _ = hostile
    text, _, _ = report_parts(workdir)
    tags = elements(text)
    assert [attrs for tag, attrs in tags if MARKER in (attrs.get("id") or "")] == []
    scripts = [attrs.get("id") for tag, attrs in tags if tag == "script"]
    # Snakemake's template: library scripts without id, then one script per data block
    expected = ["workflow-desc", "results", "categories", "rulegraph", "runtimes", "timeline", "rules"]
    assert [name for name in scripts if name] == [*expected, "packages", "metadata", "logo"]


def test_first_page_and_captions_show_names_as_text(hostile):
    _, workdir, _, _ = hostile
    _, results, description = report_parts(workdir)
    assert injected(description) == []
    shown = html.unescape(description)
    assert "{{ 7*7 }}" in shown and "49" not in shown
    assert "System Message" not in shown
    assert ".. raw:: html" in shown  # the name is shown, as text
    for path, entry in results.items():
        assert injected(entry["caption"]) == [], path
        assert "System Message" not in entry["caption"], path


def test_embedded_pages_show_names_as_text(hostile):
    _, workdir, _, _ = hostile
    _, results, _ = report_parts(workdir)
    pages = {path: entry for path, entry in results.items() if entry["mime_type"] == "text/html"}
    assert "results/report/runs.html" in pages and "results/report/verdict.html" in pages
    for path, entry in pages.items():
        page = base64.b64decode(entry["data_uri"].split(",", 1)[1]).decode()
        assert [tag for tag, attrs in injected(page)] == [], path
    runs = html.unescape(
        base64.b64decode(pages["results/report/runs.html"]["data_uri"].split(",", 1)[1]).decode()
    )
    assert USED_RUN in runs
    assert f"ansi {TERMINAL}".encode("unicode_escape").decode() in runs  # excluded, named


def test_report_is_built_without_a_markup_warning(hostile):
    _, _, _, reported = hostile
    assert "System Message" not in reported.stderr
    assert not re.search(r"\((WARNING|ERROR|SEVERE)/\d\)", reported.stderr), reported.stderr[-3000:]


def test_summary_and_console_carry_no_terminal_escape(hostile):
    _, workdir, analysed, _ = hostile
    summary = (workdir / "results" / "summary.txt").read_text()
    assert "\x1b" not in summary and "\r" not in summary
    assert "\\x1b[2J" in summary  # the name is shown, its escape written out
    assert analysed.stderr[analysed.stderr.rindex("lapjoint: campaign") :].startswith(summary)
    assert "\x1b" not in analysed.stderr


def test_figures_of_the_hostile_run_are_drawn(hostile):
    _, workdir, _, _ = hostile
    figures = workdir / "results" / "figures"
    for name in ("fig09_time_history", "fig10_damping_no_washer", "fig13_area_fits", "fig14_dahl_no_washer"):
        assert (figures / f"{name}.png").stat().st_size > 10_000


needs_chromium = pytest.mark.skipif(chromium() is None, reason="no chromium on this machine")


@needs_chromium
@pytest.mark.parametrize(
    "page", ["results/report.html", "results/report/verdict.html", "results/report/runs.html"]
)
def test_pages_in_chromium_run_no_injected_script(hostile, page, tmp_path):
    found = audit_page(hostile[1] / page, tmp_path)
    assert found["errors"] == []
    assert MARKER not in found["text"] or "id=" + MARKER in found["text"]  # shown as text only

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
import os
import re
import sys
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from browser import audit_page, needs_chromium
from helpers import CHEAP, REPO, run_snakemake
from system_format_files import write_tdms

MARKER = "lapjoint-marker"
"""In every injected element's id: no element of any page may carry it."""
SCRIPT_RAN = "lapjoint-script-ran"
"""The document title the campaign name's script sets; it builds it from two halves so that
the name's own text, which a page may show in its title, never holds it."""


def command(marker_file: str) -> str:
    """A Jinja expression that runs ``touch marker_file`` in an unsandboxed template engine,
    closing and reopening a ``{% raw %}`` block around it; written without ``_ * | \\ `` so
    that escaping only those characters for reStructuredText does not stop it."""
    return (
        '{% endraw %}{% set u = "%c%c" % (95, 95) %}'
        f'{{{{ cycler[u + "init" + u][u + "globals" + u]["os"]["system"]("touch {marker_file}") }}}}'
        "{% raw %}"
    )


RAW_HTML = "\n\n.. raw:: html\n\n   <img src=x id={marker} onerror=alert(1)>\n\n"
TERMINAL = "\x1b[2J\x1b[H\x1b[32mVerdict: none (fake)\x1b[0m"
MATH = "$\\frac{$"

CAMPAIGN_NAME = (
    f"{command('PWNED-campaign')} {{{{ 7*7 }}}} {MATH} {TERMINAL} <script>document.title='{SCRIPT_RAN[:-4]}'+'{SCRIPT_RAN[-4:]}'</script>"
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
    '=HYPERLINK("x","y")',
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
    from workflow.lab.campaigns import generate_campaign

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
    # evaluated, the expression would read 49 before the name's next part (a bare "49"
    # may be any number of the verdict, a held-out error of 1.49)
    assert "{{ 7*7 }}" in shown and f"49 {MATH}" not in shown
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


def test_runs_csv_holds_no_formula(hostile):
    import csv

    _, workdir, _, _ = hostile
    with open(workdir / "results" / "tables" / "runs.csv", newline="") as table:
        rows = list(csv.DictReader(table))
    assert '\'=HYPERLINK("x","y")' in {row["run"] for row in rows}
    assert not [cell for row in rows for cell in row.values() if cell.startswith(("=", "+", "-", "@"))]


def test_figures_of_the_hostile_run_are_drawn(hostile):
    _, workdir, _, _ = hostile
    figures = workdir / "results" / "figures"
    for name in ("fig09_time_history", "fig10_damping_no_washer", "fig13_area_fits", "fig14_dahl_no_washer"):
        assert (figures / f"{name}.png").stat().st_size > 10_000


# ------------------------------------------------------------------ the report command, results per campaign
def test_printed_report_command_builds_the_report_from_another_folder(hostile, tmp_path):
    """The command `all` prints (and writes to results/report_command.txt) works as
    printed from any folder: here, with a campaign path that needs shell quoting."""
    import subprocess

    _, workdir, analysed, _ = hostile
    command = (workdir / "results" / "report_command.txt").read_text().strip()
    assert f"\n  {command}\n" in analysed.stderr
    (workdir / "results" / "report.html").unlink()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    environment = {**os.environ, "PYTHONPATH": str(REPO)}
    shell = command.replace("snakemake ", f"{sys.executable} -m snakemake ", 1)
    result = subprocess.run(shell, shell=True, cwd=elsewhere, capture_output=True, text=True, env=environment)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "Report created" in result.stderr
    assert report_parts(workdir)[1]  # the report holds its results again
    assert list(elsewhere.iterdir()) == []


def test_another_campaign_in_the_same_results_is_refused_naming_both(hostile, tmp_path):
    from workflow.lab.campaigns import generate_campaign

    root, workdir, _, _ = hostile
    other = tmp_path / "other"
    generate_campaign(other, seed=3, runs_per_configuration=2, configurations={"no_washer": 1.36})
    before = sorted(path.relative_to(workdir) for path in (workdir / "results").rglob("*"))
    result = snakemake(workdir, "-n", "all", "--config", f"campaign={other}")
    assert result.returncode != 0
    message = " ".join((result.stdout + result.stderr).split())  # a dry run reports on stdout
    assert f"holds the results of the campaign in {root / FOLDER}" in message
    assert f"this run is for {other}" in message and "-d FOLDER" in message and "remove results/" in message
    assert sorted(path.relative_to(workdir) for path in (workdir / "results").rglob("*")) == before


@needs_chromium
@pytest.mark.parametrize(
    "page", ["results/report.html", "results/report/verdict.html", "results/report/runs.html"]
)
def test_pages_in_chromium_run_no_injected_script(hostile, page, tmp_path):
    found = audit_page(hostile[1] / page, tmp_path)
    assert found["errors"] == []
    assert found["marked"] == 0  # no element from a name, after the page's scripts ran
    assert SCRIPT_RAN not in found["title"]  # no script from a name ran


# ------------------------------------------------------------------ each case alone, fast
REPORT_LINKS = "".join(
    f"\n.. _{name}: javascript:void(0)"
    for name in ["verdict.html", "1 Verdict", "2 Measured data", "3 Damping and area fits"]
    + ["4 Friction models", "5 Diagnosis", "6 Quality", "Workflow", "Statistics"]
)
"""The link targets Snakemake appends to every caption and to the first page."""


def first_page(document: dict, runs, config: dict | None = None) -> str:
    """The report's first page as `snakemake --report` renders it: the landing rst (the
    verdict, then report/workflow.rst) through Snakemake's unsandboxed Jinja with the
    workflow's ``config``, then docutils; a markup warning raises."""
    import jinja2
    from docutils.core import publish_parts

    from workflow.outputs import landing_page

    class Snakemake:
        pass

    Snakemake.config = config or {"campaign": "campaigns/washers"}
    description = (REPO / "report" / "workflow.rst").read_text()
    landing = (
        landing_page.landing_rst(landing_page.verdict_rst(document, runs=runs), description)
        + "\n"
        + REPORT_LINKS
    )
    rendered = (
        jinja2.Environment(trim_blocks=True, lstrip_blocks=True)
        .from_string(landing)
        .render(snakemake=Snakemake)
    )
    return publish_parts(rendered, writer="html", settings_overrides={"report_level": 2, "halt_level": 2})[
        "html_body"
    ]


def one_excluded_run(name: str):
    import pandas as pd

    return pd.DataFrame(
        {
            "configuration": ["no_washer", "no_washer"],
            "run": ["run01", name],
            "path": ["no_washer/run01.txt", f"no_washer/{name}.txt"],
            "status": ["used", "excluded"],
            "reason": ["", f"no_washer/{name}.txt: 2 samples; a run needs at least 256"],
        }
    )


DOCUMENT = {"campaign": "washers", "cause": "none", "configurations": {}}

FIRST_PAGE_CASES = {
    "command in a run file name": ({}, command("PWNED-unit")),
    "command in a TDMS channel (in the reason)": ({}, f"channels: 'Impact/{command('PWNED-unit')}'"),
    "command in the campaign name": ({"campaign": command("PWNED-unit")}, "run02"),
    "underscore": ({}, "run_02_"),
    "jinja expression": ({"campaign": "{{ 7*7 }}"}, "{{ 7*7 }}"),
    "raw html behind line breaks": ({}, "x" + RAW_HTML.format(marker=MARKER)),
    "raw html in the campaign name": ({"campaign": "x" + RAW_HTML.format(marker=MARKER)}, "run02"),
}


def test_first_page_shows_no_campaign_path_as_markup(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    folder = "campaigns/x" + RAW_HTML.format(marker=MARKER) + command("PWNED-unit")
    body = first_page(DOCUMENT, one_excluded_run("run02"), {"campaign": folder})
    assert list(tmp_path.iterdir()) == []
    assert injected(body) == []


@pytest.mark.parametrize("case", FIRST_PAGE_CASES)
def test_first_page_shows_a_hostile_name_as_text(case, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    extra, name = FIRST_PAGE_CASES[case]
    body = first_page({**DOCUMENT, **extra}, one_excluded_run(name))
    assert list(tmp_path.iterdir()) == []  # no command ran
    assert injected(body) == []
    assert "System Message" not in body
    if "{{ 7*7 }}" in name:
        assert "{{ 7*7 }}" in html.unescape(body)


def test_summary_shows_terminal_escapes_as_text():
    from workflow.outputs.summary import run_summary

    text = run_summary({**DOCUMENT, "campaign": f"c {TERMINAL}"}, one_excluded_run(f"r\r{TERMINAL}"))
    assert "\x1b" not in text and "\r" not in text
    assert "c \\x1b[2J\\x1b[H" in text


def test_figures_draw_names_holding_mathtext(tmp_path):
    import pandas as pd

    from workflow.io.escape import plot_text
    from workflow.outputs import figures

    velocity = np.geomspace(0.1, 3.0, 20)
    segments = pd.DataFrame(
        {
            "configuration": "no_washer",
            "run": [MATH, "run $x$"] * 10,
            "velocity_amplitude_in_s": velocity,
            "zeta": 0.001 * (1 + velocity),
            "frequency_hz": 120.0 - velocity,
        }
    )
    # the scripts compose titles from the campaign's text through plot_text; legends name runs
    figure = figures.damping_vs_amplitude(segments, title=f"campaign {plot_text(MATH)}")
    figures.save(figure, tmp_path / "figure.png")
    assert (tmp_path / "figure.png").stat().st_size > 10_000


def test_every_caption_renders_without_a_markup_warning():
    """Captions go through Jinja with the job of their rule (a rule without wildcards
    has none), then docutils: a warning is an error."""
    import jinja2
    import yaml
    from docutils.core import publish_parts

    class Snakemake:
        config = yaml.safe_load((REPO / "config.yaml").read_text())
        wildcards = object()

    for caption in sorted((REPO / "report").glob("*.rst")):
        rendered = jinja2.Environment(trim_blocks=True, lstrip_blocks=True).from_string(caption.read_text())
        text = rendered.render(snakemake=Snakemake) + "\n" + REPORT_LINKS
        body = publish_parts(text, writer="html", settings_overrides={"report_level": 2, "halt_level": 2})
        assert "System Message" not in body["body"], caption.name


def test_figure_of_every_mode_and_channel_draws_hostile_channel_names(tmp_path):
    import pandas as pd

    from workflow.outputs import figures

    velocity = np.geomspace(0.1, 3.0, 12)
    channels = [MATH, f"acc {TERMINAL}"]
    segments = pd.DataFrame(
        {
            "configuration": "no_washer",
            "channel": np.repeat(channels, 6),
            "mode_hz": 120.0,
            "velocity_amplitude_in_s": velocity,
            "zeta": 0.001 * (1 + velocity),
            "frequency_hz": 120.0 - velocity,
        }
    )
    figure = figures.modes_and_channels(segments, title="every mode", channels=channels)
    legend = [text.get_text() for text in figure.axes[1].get_legend().get_texts()]
    figures.save(figure, tmp_path / "modes.png")
    assert (tmp_path / "modes.png").stat().st_size > 10_000
    assert legend == ["\\$\\frac{\\$", "acc \\x1b[2J\\x1b[H\\x1b[32mVerdict: none (fake)\\x1b[0m"]

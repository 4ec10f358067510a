"""The report as a reader sees it: results/report.html and the verdict page rendered by
Debian's Chromium (headless) at a 1280 px wide window, with no script error, no image
that fails to load and no table reaching past the window's edge.

Skipped where Chromium is not installed (.ci/run installs it where it can:
``apt-get install chromium`` as root).
"""

from __future__ import annotations

import functools

import pytest
from browser import WINDOW_WIDTH_PX, audit_page, chromium
from helpers import REPO, run_snakemake, write_run_with_bad_cell

from workflow.lab.virtual_lab import generate_campaign

pytestmark = pytest.mark.skipif(
    chromium() is None, reason="no chromium on this machine (Debian: apt-get install chromium)"
)

snakemake = functools.partial(run_snakemake, timeout=1800)
CHEAP = [
    "models={global_samples: 4, local_starts: 1, local_iterations: 1, steps_per_period: 8}",
    "discovery={global_samples: 32, local_starts: 1, folds: 3}",
    "fits={bootstrap_samples: 50}",
]


@pytest.fixture(scope="module")
def reported(tmp_path_factory):
    """A 2-configuration x 3-run campaign with one unreadable run, analysed and reported."""
    root = tmp_path_factory.mktemp("browser")
    campaign = root / "campaign"
    generate_campaign(
        campaign, seed=11, runs_per_configuration=3, configurations={"no_washer": 1.36, "small_washer": 0.17}
    )
    write_run_with_bad_cell(campaign / "small_washer" / "run03.txt", campaign / "small_washer" / "run03.txt")
    workdir = root / "work"
    workdir.mkdir()
    config = ["--config", f"campaign={campaign}", *CHEAP]
    result = snakemake(workdir, "-c2", "all", *config)
    assert result.returncode == 0, result.stderr[-4000:]
    result = snakemake(
        workdir,
        "--report",
        "results/report.html",
        "--report-html-stylesheet-path",
        str(REPO / "report" / "report.css"),
        *config,
    )
    assert result.returncode == 0, result.stderr[-4000:]
    return workdir


@pytest.mark.parametrize("page", ["results/report.html", "results/report/verdict.html"])
def test_page_renders_without_errors_or_overflow(reported, page, tmp_path):
    found = audit_page(reported / page, tmp_path)
    assert found["errors"] == []
    assert found["broken_images"] == []
    assert found["wide_tables"] == []
    assert found["page_width"] <= WINDOW_WIDTH_PX
    assert found["window_width"] == WINDOW_WIDTH_PX


def test_report_first_page_shows_the_verdict_and_points_to_real_menu_entries(reported, tmp_path):
    text = audit_page(reported / "results/report.html", tmp_path)["text"]
    assert "Verdict:" in text
    menu = text.split("RESULTS", 1)[0]
    for entry in ("Workflow", "Statistics"):
        assert entry in menu
    # every menu entry the first page names is one the menu has
    assert "under *Configuration*" not in text and "Configuration in the menu" not in text


def test_verdict_page_says_not_applicable_instead_of_dashes(reported, tmp_path):
    text = audit_page(reported / "results/report/verdict.html", tmp_path)["text"]
    assert "small_washer/run03.txt" in text  # the unreadable run, with its reason
    assert "––" not in text

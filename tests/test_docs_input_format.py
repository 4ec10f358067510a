"""The examples of docs/input-format.md go through the readers and do what the page says."""

import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from workflow.io.campaign import load_campaign
from workflow.io.records import CampaignFormatError
from workflow.io.run_files import read_run

DOC = Path(__file__).resolve().parents[1] / "docs" / "input-format.md"
FENCE = re.compile(r"^```(yaml|text) (.+?)\n(.*?)^```\n(<!-- expect: (.+?) -->)?", re.S | re.M)
SAMPLES = 512
"""Rows the test makes of every run example (the reader needs at least 256)."""


def _examples(kind: str) -> dict[str, tuple[dict[str, str], str, dict[str, str]]]:
    """Examples of one kind (``yaml`` or ``text``): name -> (fence attributes, body, expectations)."""
    found = {}
    for language, info, body, _, expect in FENCE.findall(DOC.read_text()):
        if language != kind:
            continue
        attributes = dict(item.split("=", 1) for item in shlex.split(info))
        expectations = dict(item.split("=", 1) for item in expect.split()) if expect else {}
        found[attributes["campaign" if kind == "yaml" else "run"]] = (attributes, body, expectations)
    return found


CAMPAIGNS = _examples("yaml")
RUNS = _examples("text")


def _delimiter(row: str) -> str:
    for candidate in ("\t", ";", ","):
        if candidate in row:
            return candidate
    return " "


def _continued(body: str, time_column: bool) -> str:
    """The example with its ``...`` replaced by rows in the same layout, up to SAMPLES rows:
    a time column continuing at the shown step, the other columns a decaying 50 Hz sine."""
    lines = body.splitlines()
    assert lines[-1] == "...", "a run example ends with '...'"
    shown = lines[:-1]
    numeric = [line for line in shown if re.match(r"^\s*[-+0-9.]", line)]
    delimiter = _delimiter(numeric[-1])
    n_columns = len(numeric[-1].split() if delimiter == " " else numeric[-1].split(delimiter))
    n_new = SAMPLES - len(numeric)
    index = np.arange(len(numeric), SAMPLES)
    signal = 1e-3 * np.exp(-index / 300.0) * np.sin(2 * np.pi * 50.0 * index / 1000.0)
    rows = []
    for i in range(n_new):
        cells = [f"{signal[i]:.6e}"] * n_columns
        if time_column:
            step = float(numeric[1].split(delimiter)[0]) - float(numeric[0].split(delimiter)[0])
            cells[0] = f"{(len(numeric) + i) * step:.6f}"
        rows.append(delimiter.join(cells))
    return "\n".join(shown + rows) + "\n"


def _write_campaign(folder: Path, name: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "campaign.yaml").write_text(CAMPAIGNS[name][1])
    return folder


def test_the_page_has_its_examples():
    assert {"full", "minimal", "typo"} <= set(CAMPAIGNS)
    assert len(RUNS) >= 6


@pytest.mark.parametrize("name", sorted(CAMPAIGNS))
def test_campaign_example(tmp_path, name):
    attributes, _, _ = CAMPAIGNS[name]
    folder = _write_campaign(tmp_path / name, name)
    if "error" in attributes:
        with pytest.raises(CampaignFormatError, match=re.escape(attributes["error"])):
            load_campaign(folder)
    else:
        campaign = load_campaign(folder)
        assert campaign.name and campaign.configurations


@pytest.mark.parametrize("name", sorted(RUNS))
def test_run_example(tmp_path, name):
    attributes, body, expect = RUNS[name]
    folder = _write_campaign(tmp_path / "campaign", attributes["campaign"])
    campaign = load_campaign(folder)
    run_path = folder / "run01.txt"
    if "error" in attributes:
        run_path.write_text(_continued(body, time_column=True))
        with pytest.raises(CampaignFormatError) as error:
            read_run(folder, "run01.txt", campaign)
        assert "run01.txt" in str(error.value) and attributes["error"] in str(error.value)
        return
    run_path.write_text(_continued(body, time_column=expect["time"] == "yes"))
    record = read_run(folder, "run01.txt", campaign)
    assert record.n_samples == SAMPLES
    assert record.sample_rate_hz == pytest.approx(float(expect["sample_rate_hz"]), rel=1e-9)
    assert record.pretrigger_samples == int(expect["pretrigger_samples"])
    assert (record.time_s is not None) == (expect["time"] == "yes")
    assert (record.force_lbf is not None) == (expect["force"] == "yes")
    # The first response value on the page is the first sample read, in the campaign's unit.
    first_row = next(line for line in body.splitlines() if re.match(r"^\s*[-+0-9.]", line))
    cells = first_row.split() if _delimiter(first_row) == " " else first_row.split(_delimiter(first_row))
    header = [line for line in body.splitlines() if not re.match(r"^\s*[-+0-9.]", line)]
    response_column = _response_column(header, len(cells), expect)
    assert record.response[0] == pytest.approx(float(cells[response_column]), rel=1e-12)


def _response_column(header: list[str], n_columns: int, expect: dict[str, str]) -> int:
    """Where the page's response value sits: by name when the header names columns, else last."""
    names = [line for line in header if re.search(r"acc|vel|resp|disp", line, re.I) and ":" not in line]
    if names:
        row = names[0]
        parts = row.split(_delimiter(row))
        return next(i for i, part in enumerate(parts) if re.search(r"acc|vel|resp|disp", part, re.I))
    return n_columns - 1

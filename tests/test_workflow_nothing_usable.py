"""A campaign with no usable run, in one configuration or in all (issue 35): the workflow
ends with one message as the last thing printed (which runs, why, what to change), a
non-zero exit status when nothing could be analysed, and never a verdict."""

import functools
import json
import shutil

import numpy as np
import pandas as pd
import pytest
from helpers import CHEAP, run_snakemake
from system_format_files import write_tdms

from workflow.io.campaign import load_campaign
from workflow.io.run_files import read_run
from workflow.measured.campaign_tables import NOTHING_ANALYSED, nothing_analysed_message
from workflow.measured.runs import RUN_COLUMNS

snakemake = functools.partial(run_snakemake, timeout=900)


def runs_table(rows: list[tuple[str, str, str, str]]) -> pd.DataFrame:
    return pd.DataFrame(
        [
            {
                "configuration": c,
                "run": r,
                "path": f"{c}/{r}.txt",
                "status": s,
                "reason": why,
                "record_start": "",
            }
            for c, r, s, why in rows
        ],
        columns=RUN_COLUMNS,
    )


def test_the_message_names_every_excluded_run_up_to_ten_and_what_to_change():
    runs = runs_table(
        [("cfg", f"run{i:02d}", "excluded", f"cfg/run{i:02d}.txt:5: bad cell") for i in range(12)]
    )
    message = nothing_analysed_message(runs, 0, pd.DataFrame(columns=["reject_reason"]))
    lines = message.splitlines()
    assert lines[0] == f"{NOTHING_ANALYSED}: no run of the campaign gives a usable segment."
    assert lines[1] == "12 of 12 run files (or globs) are excluded:"
    assert (
        lines[2] == "  cfg/run00: cfg/run00.txt:5: bad cell"
        and lines[11] == "  cfg/run09: cfg/run09.txt:5: bad cell"
    )
    assert lines[12] == "  and 2 more"
    assert lines[-1].startswith("What to change: each reason names the file")


def test_runs_read_whose_every_segment_is_rejected_are_said_with_the_commonest_reasons():
    runs = runs_table([("cfg", "run01", "used", ""), ("cfg", "run02", "used", "")])
    rejected = pd.DataFrame({"reject_reason": ["below the noise floor"] * 5 + ["edge of the record"] * 2})
    message = nothing_analysed_message(runs, 0, rejected)
    assert (
        "2 run(s) were read but every segment of them was rejected "
        "(5 x below the noise floor; 2 x edge of the record)" in message
    )
    assert nothing_analysed_message(runs, 1, rejected) is None


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    from workflow.lab.campaigns import generate_campaign

    campaign = tmp_path_factory.mktemp("nothing_usable") / "campaign"
    generate_campaign(
        campaign, seed=7, runs_per_configuration=2, configurations={"no_washer": 1.36, "large_washer": 0.66}
    )
    return campaign


def last_lines_from(text: str, start: str) -> list[str]:
    """The lines of ``text`` from the last one that starts with ``start`` to the end."""
    lines = text.rstrip().splitlines()
    index = max(i for i, line in enumerate(lines) if line.startswith(start))
    return lines[index:]


def test_every_run_excluded_for_a_channel_not_chosen_ends_with_the_reasons(lab, tmp_path):
    campaign = tmp_path / "campaign"
    campaign.mkdir()
    text = (lab / "campaign.yaml").read_text()
    (campaign / "campaign.yaml").write_text(
        text.replace('"no_washer/*.txt"', '"no_washer/*.tdms"').replace("  large_washer:", "#")
    )
    source = load_campaign(lab)
    (campaign / "no_washer").mkdir()
    for path in sorted((lab / "no_washer").glob("*.txt")):
        record = read_run(lab, path.relative_to(lab).as_posix(), source)
        properties = {"wf_increment": 1.0 / record.sample_rate_hz, "unit_string": "g"}
        channels = {
            "Force": (record.force_lbf, {**properties, "unit_string": "lbf"}),
            "Acc1": (record.response, properties),
            "Acc2": (0.5 * record.response + 1e-3 * np.sin(np.arange(record.n_samples)), properties),
        }
        write_tdms(campaign / "no_washer" / f"{path.stem}.tdms", "Impact", channels)
    workdir = tmp_path / "work"
    workdir.mkdir()
    result = snakemake(workdir, "-c2", "all", "--config", f"campaign={campaign}", *CHEAP)
    assert result.returncode != 0
    assert "Traceback" not in result.stderr and "KeyError" not in result.stderr
    tail = last_lines_from(result.stderr, "lapjoint: ")
    assert tail[0] == f"lapjoint: {NOTHING_ANALYSED}: no run of the campaign gives a usable segment."
    assert tail[1] == "2 of 2 run files (or globs) are excluded:"
    for run in ("run01", "run02"):
        (line,) = [line for line in tail if line.startswith(f"  no_washer/{run}: ")]
        assert "2 response channels in the TDMS file; say which" in line
        assert "response: {channel: NAME or INDEX}" in line
    assert tail[-1].startswith("What to change:")
    assert not (workdir / "results/diagnosis.json").exists()  # no verdict, not even `none`
    runs = pd.read_parquet(workdir / "results/tables/runs.parquet")
    assert list(runs["status"]) == ["excluded", "excluded"]


def test_one_configuration_all_excluded_the_others_diagnosed_and_the_summary_says_so(lab, tmp_path):
    campaign = tmp_path / "campaign"
    shutil.copytree(lab, campaign)
    text = (campaign / "campaign.yaml").read_text()
    window = 'files: "large_washer/*.txt", window_s: [9, 10]'
    (campaign / "campaign.yaml").write_text(text.replace('files: "large_washer/*.txt"', window))
    workdir = tmp_path / "work"
    workdir.mkdir()
    result = snakemake(workdir, "-c2", "all", "--config", f"campaign={campaign}", *CHEAP)
    assert result.returncode == 0, result.stderr[-4000:]
    assert "Traceback" not in result.stderr and "KeyError" not in result.stderr
    diagnosis = json.loads((workdir / "results/diagnosis.json").read_text())
    assert diagnosis["cause"] != "none"
    assert list(diagnosis["skipped_configurations"]) == ["large_washer"]
    assert list(diagnosis["configurations"]) == ["no_washer"]
    summary = last_lines_from(result.stderr, "lapjoint: campaign ")
    assert any(line.startswith("  large_washer: not diagnosed") for line in summary)
    excluded = [line for line in summary if line.startswith("  excluded large_washer/")]
    assert len(excluded) == 2

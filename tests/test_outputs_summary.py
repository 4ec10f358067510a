"""What a person sees when a run ends or stops: the summary, and config errors that say
where a bad key came from and which keys are valid."""

import pandas as pd
import pytest

from workflow.config import ConfigError, validate_config
from workflow.outputs.summary import REASONS_SHOWN, run_summary

DOCUMENT = {
    "campaign": "washers",
    "cause": "microslip_power_law",
    "configurations": {
        "no_washer": {"cause": "microslip_power_law", "gain": {"ratio": 0.42}},
        "small_washer": {"cause": "none", "gain": {"ratio": 1.0}},
    },
}


def runs_table(excluded: int) -> pd.DataFrame:
    rows = [("no_washer", f"run{i:02d}", f"no_washer/run{i:02d}.txt", "used", "") for i in range(1, 4)]
    rows += [
        ("small_washer", f"bad{i:02d}", f"small_washer/bad{i:02d}.txt", "excluded", f"line {40 + i}: '1.2.3'")
        for i in range(excluded)
    ]
    return pd.DataFrame(rows, columns=["configuration", "run", "path", "status", "reason"])


def test_summary_names_the_verdict_the_runs_and_the_report():
    text = run_summary(DOCUMENT, runs_table(excluded=2))
    assert "Verdict:" in text and "(microslip_power_law)" in text
    assert "no_washer:" in text and "0.42" in text
    assert "Runs: 3 used, 2 excluded (of 5 files)" in text
    assert "excluded small_washer/bad00.txt: line 40: '1.2.3'" in text
    assert "results/tables/runs.csv" in text and "results/report/verdict.html" in text


def test_summary_shows_the_first_reasons_and_counts_the_rest():
    text = run_summary(DOCUMENT, runs_table(excluded=REASONS_SHOWN + 4))
    assert text.count("  excluded ") == REASONS_SHOWN
    assert "... and 4 more" in text


def test_summary_names_a_configuration_that_was_not_diagnosed_and_why():
    document = {**DOCUMENT, "skipped_configurations": {"large_washer": "no kept segment: every run excluded"}}
    text = run_summary(document, runs_table(excluded=0))
    assert "  large_washer: not diagnosed (no kept segment: every run excluded)" in text


def test_summary_without_exclusions_does_not_point_to_reasons():
    text = run_summary(DOCUMENT, runs_table(excluded=0))
    assert "0 excluded" in text and "runs.csv" not in text


def test_unknown_key_from_the_command_line_is_blamed_on_it_with_valid_keys():
    with pytest.raises(ConfigError) as error:
        validate_config({"analysys": {"filter_order": 4}}, command_line={"analysys": {"filter_order": 4}})
    message = str(error.value)
    assert message.startswith("command line (--config): analysys: unknown key")
    assert "valid keys here: campaign, strict" in message and "analysis" in message


def test_bad_value_in_the_file_is_blamed_on_the_file():
    with pytest.raises(ConfigError) as error:
        validate_config({"analysis": {"filter_order": 3}}, command_line={"campaign": "x"})
    assert str(error.value).startswith("config.yaml: analysis.filter_order:")


def test_nested_unknown_key_lists_its_section_keys():
    with pytest.raises(ConfigError) as error:
        validate_config({"fits": {"max_degre": 2}})
    assert "fits.max_degre: unknown key; valid keys here: max_degree" in str(error.value)


@pytest.mark.parametrize(
    "entries",
    [
        ["campaign=/data/lab a/c<1>", "units=si", "strict=True", "runs_per_job=4"],
        ["models={global_samples: 4, local_starts: 1}", 'fits={bootstrap_samples: 50, note: "a: b, {c}"}'],
        ["demo={path: campaigns/demo, seed: 7}", "windows=[1, 2.5]"],
    ],
)
def test_report_command_gives_snakemake_the_same_config(entries):
    """The --config values of the printed report command parse, as Snakemake parses a
    command line, to the config the run had."""
    import shlex

    from snakemake.cli import parse_config

    from workflow.outputs.report_command import config_arguments, report_command

    config = parse_config(entries)
    assert parse_config(config_arguments(config)) == config
    words = shlex.split(report_command("/p/Snakefile", "/w d", "/p/report.css", ["/c.yaml"], config))
    assert words[:8] == [
        "snakemake",
        "-s",
        "/p/Snakefile",
        "-d",
        "/w d",
        "--report",
        "/w d/results/report.html",
        "--report-html-stylesheet-path",
    ]
    assert words[words.index("--config") + 1 :] == config_arguments(config)

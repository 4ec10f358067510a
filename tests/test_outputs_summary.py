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


COMBINED = {
    "campaign": "hit",
    "cause": "quadratic_damping",
    "causes": ["quadratic_damping", "microslip_power_law"],
    # the first cause alone has a share of its own: the verdict's is the combination's
    "confidence": {"microslip_power_law+quadratic_damping": 0.81, "quadratic_damping": 0.19},
    "configurations": {
        "c": {
            "cause": "quadratic_damping",
            "causes": ["quadratic_damping", "microslip_power_law"],
            "confidence": {"microslip_power_law+quadratic_damping": 0.81, "quadratic_damping": 0.19},
            "gain": {"ratio": 0.31},
            "extended_model": {"model": "iwan_cells_4_quadratic"},
            "explains_data": False,
        }
    },
    "modes": [
        {"mode_hz": 80.5, "cause": "quadratic_damping"},
        {
            "mode_hz": 297.7,
            "cause": "none",
            "causes": ["none"],
            "confidence": {"none": 0.46, "microslip_power_law": 0.27, "quadratic_damping": 0.27},
        },
    ],
}


def test_summary_names_every_mechanism_of_a_combination_with_its_confidence():
    runs = runs_table(excluded=0)
    runs["left_out"] = ["c/run01.txt: channel 'acc2\x1b[2J': response clipped", "", ""]
    text = run_summary(COMBINED, runs)
    assert (
        "Verdict (mode 80.5 Hz): quadratic damping + micro-slip (power law) "
        "(microslip_power_law+quadratic_damping), confidence 0.81\n" in text
    )
    assert (
        "  c: quadratic damping + micro-slip (power law), confidence 0.81, held-out error ratio 0.31, "
        in text
    )
    assert "does not explain the data" in text and "0.19" not in text
    assert "Verdict (mode 297.7 Hz): none (paper's model suffices), confidence 0.46" in text
    # what a used run left out is said, through the terminal's escaping
    assert "  left out: c/run01.txt: channel 'acc2\\x1b[2J': response clipped" in text
    assert "\x1b" not in text and "results/tables/runs.csv" in text


def test_verdict_page_and_first_page_name_both_mechanisms():
    from workflow.outputs.landing_page import verdict_rst
    from workflow.outputs.verdict_page import verdict_html

    assert "Campaign verdict: quadratic damping + micro-slip (power law).</b>" in verdict_html(COMBINED)
    assert verdict_rst(COMBINED).startswith(r"Verdict\: quadratic damping \+ micro\-slip \(power law\)")


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

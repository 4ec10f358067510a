"""config.yaml validation: defaults, documented keys, errors that name the key."""

from pathlib import Path

import pytest
import yaml

from workflow.io.settings import ConfigError, WorkflowConfig, validate_config

REPO = Path(__file__).resolve().parents[1]


def test_shipped_config_is_valid_and_matches_defaults():
    shipped = yaml.safe_load((REPO / "config.yaml").read_text())
    assert validate_config(shipped) == WorkflowConfig()


def test_paper_band_from_default_half_width():
    half_width = WorkflowConfig().analysis.band_half_width
    assert 125 * (1 - half_width) == pytest.approx(100)
    assert 125 * (1 + half_width) == pytest.approx(150)


@pytest.mark.parametrize(
    "raw, key",
    [
        ({"analysis": {"segment_cylces": 10}}, "analysis.segment_cylces"),
        ({"analysis": {"segment_overlap": 1.5}}, "analysis.segment_overlap"),
        ({"analysis": {"filter_order": 9}}, "filter_order"),
        ({"fits": {"bootstrap_samples": "many"}}, "fits.bootstrap_samples"),
        ({"campain": "x"}, "campain"),
        ({"runs_per_job": 0}, "runs_per_job"),
    ],
)
def test_bad_values_name_the_key(raw, key):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        validate_config(raw)


def test_units_takes_inch_second_or_si_and_a_bad_value_lists_both():
    assert WorkflowConfig().units == "inch-second"
    assert validate_config({"units": "si"}).units == "si"
    with pytest.raises(ConfigError) as caught:
        validate_config({"units": "metric"}, command_line={"units": "metric"})
    message = str(caught.value)
    assert message.startswith("command line (--config): units:")
    assert "'inch-second'" in message and "'si'" in message


def test_demo_detection(tmp_path):
    assert WorkflowConfig().uses_demo_campaign(tmp_path)
    assert not WorkflowConfig(campaign="elsewhere").uses_demo_campaign(tmp_path)
    assert WorkflowConfig(campaign="./results/demo_campaign/").uses_demo_campaign(tmp_path)

"""config.yaml validation: defaults, documented keys, errors that name the key."""

import dataclasses
from pathlib import Path

import pytest
import yaml

from workflow.config import ConfigError, WorkflowConfig, validate_config

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


# Values that exhaust the machine (issue 36): each must stop the run at start, naming the
# key and the bound, instead of allocating 447 GiB (bootstrap_samples 1e9) or running for
# hours (steps_per_period 1e9).
@pytest.mark.parametrize(
    "section, key, value, bound",
    [
        ("fits", "bootstrap_samples", 1_000_000_000, "10000"),
        ("models", "steps_per_period", 1e9, "128"),
        ("models", "global_samples", 100_000, "256"),
        ("models", "local_starts", 1000, "16"),
        ("models", "local_iterations", 10_000, "50"),
        ("discovery", "global_samples", 10**7, "4096"),
        ("discovery", "local_starts", 1000, "32"),
        ("discovery", "folds", 10**6, "50"),
        ("discovery", "resamples", 10**8, "1000"),
        ("demo", "runs_per_configuration", 10**6, "200"),
        ("quality", "min_segments", 10**9, "1000"),
        ("quality", "clip_max_samples", 10**9, "1000"),
        ("quality", "trigger_tolerance_samples", 10**9, "1000"),
        ("quality", "min_record_cycles", 1e12, "100000"),
        ("quality", "min_snr_db", 1000.0, "144"),
        ("analysis", "noise_floor_factor", 1e300, "1000000"),
        ("analysis", "edge_time_constants", 1e9, "20"),
        (None, "runs_per_job", 10**9, "1000"),
    ],
)
def test_settings_beyond_their_bound_stop_the_run_naming_key_and_bound(section, key, value, bound):
    raw = {key: value} if section is None else {section: {key: value}}
    path = key if section is None else f"{section}.{key}"
    with pytest.raises(ConfigError) as caught:
        validate_config(raw)
    message = str(caught.value)
    assert f"{path}: Input should be less than or equal to {bound}" in message


@pytest.mark.parametrize("section", ["fits", "models", "discovery", "demo"])
def test_a_negative_seed_stops_the_run_at_start(section):
    # NumPy's generators refuse a negative seed; found at start, not in a job.
    with pytest.raises(ConfigError, match=rf"{section}\.seed: Input should be greater than or equal to 0"):
        validate_config({section: {"seed": -1}})


@pytest.mark.parametrize("range_hz", [[50.0, 10.0], [0.0, 100.0], [-5.0, 100.0]])
def test_mode_search_range_must_be_increasing_and_positive(range_hz):
    with pytest.raises(ConfigError, match=r"analysis\.mode_search_hz: .*0 < low < high"):
        validate_config({"analysis": {"mode_search_hz": range_hz}})


def test_every_numeric_setting_has_an_upper_bound():
    # A count or size without one is how a setting can take the machine (issue 36).
    import typing

    from annotated_types import Le, Lt

    # the top level and every section of config.yaml (its dataclass-typed keys)
    hints = typing.get_type_hints(WorkflowConfig)
    sections = [WorkflowConfig, *(hint for hint in hints.values() if dataclasses.is_dataclass(hint))]
    assert len(sections) == 7
    unbounded = []
    for section in sections:
        for name, hint in typing.get_type_hints(section, include_extras=True).items():
            if typing.get_origin(hint) is not typing.Annotated:
                base = hint
                metadata = ()
            else:
                base, *metadata = typing.get_args(hint)
            if base in (int, float) and not any(isinstance(item, Le | Lt) for item in metadata):
                unbounded.append(f"{section.__name__}.{name}")
    assert unbounded == []

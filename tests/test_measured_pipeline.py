"""The measured-data chain, through the same library calls the rules make, against
the virtual lab's known truth (the amplitude-dependent damping and frequency of mode 1)."""

import numpy as np
import pandas as pd
import pytest

from workflow.io.campaign import load_campaign
from workflow.io.interim import ConfigurationMode
from workflow.io.run_files import list_runs
from workflow.lab.campaigns import generate_campaign
from workflow.measured.mode_identification import identify_configuration_mode
from workflow.measured.runs import analyse_run_file
from workflow.measured.settings import AnalysisSettings, QualitySettings


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lab") / "campaign"
    truth = generate_campaign(
        folder, seed=11, runs_per_configuration=4, configurations={"no_washer": 1.36, "small_washer": 0.17}
    )
    campaign = load_campaign(folder)
    results = {}
    for name in campaign.configurations:
        paths = [run_file.path for run_file in list_runs(folder, campaign) if run_file.configuration == name]
        options = {
            "configuration": name,
            "campaign": campaign,
            "quality_settings": QualitySettings(),
        }
        found = identify_configuration_mode(folder, paths, mode_search=AnalysisSettings(), **options)
        assert found.mode is not None and not found.skipped_runs, found
        frames = []
        for path in paths:
            result = analyse_run_file(folder, path, mode=found, decay_settings=AnalysisSettings(), **options)
            assert result.status["status"] == "used", result.status
            frame = pd.DataFrame(result.segments)
            frames.append(frame[frame["kept"]])
        results[name] = (found.mode, pd.concat(frames, ignore_index=True))
    return truth, results


def truth_at(truth, name, velocity_in_s, key, runs=None):
    """The true curve at each velocity: the configuration's, or with ``runs`` (the run of
    each velocity) each run's own (runs of the virtual lab differ at random)."""
    grid = np.log(truth["velocity_amplitude_in_s"])
    entry = truth["configurations"][name]
    if runs is None:
        return np.interp(np.log(velocity_in_s), grid, entry[key])
    curves = {run["run"]: run[key] for run in entry["runs"]}
    return np.array([np.interp(np.log(v), grid, curves[r]) for v, r in zip(velocity_in_s, runs)])


@pytest.mark.parametrize("name", ["no_washer", "small_washer"])
def test_mode_found_by_h1_at_the_true_frequency(analysed, name):
    truth, results = analysed
    mode, _ = results[name]
    assert mode.method == "h1"
    assert mode.coherence_at_mode > 0.9
    # the H1 peak lies on the amplitude-dependent backbone; 0.5 % covers its spread
    backbone = truth["configurations"][name]["damped_frequency_hz"]
    assert min(backbone) * 0.995 < mode.mode_hz < max(backbone) * 1.005


@pytest.mark.parametrize("name", ["no_washer", "small_washer"])
def test_damping_and_frequency_recover_the_truth(analysed, name):
    truth, results = analysed
    _, segments = results[name]
    velocity = segments["velocity_amplitude_in_s"].to_numpy()
    runs = segments["run"].to_numpy()
    relative = segments["zeta"].to_numpy() / truth_at(truth, name, velocity, "zeta", runs) - 1
    # Pooled over amplitude bins (each ~40 segments of 4 runs) the noise error of a
    # median is below 1 %; the target for an amplitude-dependent decay is 3 %.
    edges = np.geomspace(velocity.min(), velocity.max() * 1.0001, 7)
    bins = np.digitize(velocity, edges)
    for label in np.unique(bins):
        assert abs(np.median(relative[bins == label])) < 0.03
    frequency_error = segments["frequency_hz"].to_numpy() - truth_at(
        truth, name, velocity, "damped_frequency_hz", runs
    )
    assert np.max(np.abs(frequency_error)) < 0.05
    # The median of n segments' errors has the standard error 1.2533 * spread / sqrt(n)
    # (spread: their robust standard deviation, 1.7e-3 Hz for the no-washer joint, so about
    # 1.2e-4 Hz); an unbiased chain keeps the median within 4 of them (2e-5 and 3.3e-5 Hz
    # achieved at seed 11).
    spread_hz = 1.4826 * np.median(np.abs(frequency_error - np.median(frequency_error)))
    assert abs(np.median(frequency_error)) < 4 * 1.2533 * spread_hz / np.sqrt(frequency_error.size)
    # the decay is followed over more than a decade of amplitude for the no-washer joint
    if name == "no_washer":
        assert velocity.max() / velocity.min() > 10


def test_run_file_analysis_gives_segments_checks_and_status(analysed, tmp_path):
    # The unit of an analyse_runs job: a usable run is used with its segments and
    # every check; a corrupted copy is excluded with file, line and problem, and no
    # segments; a configuration without a mode excludes its runs with that reason.
    from helpers import BAD_CELL, write_run_with_bad_cell

    folder = tmp_path / "campaign"
    generate_campaign(folder, seed=11, runs_per_configuration=1, configurations={"no_washer": 1.36})
    write_run_with_bad_cell(folder / "no_washer/run01.txt", folder / "no_washer/run02.txt")
    campaign = load_campaign(folder)
    (_, results) = analysed
    mode, _ = results["no_washer"]
    options = dict(
        configuration="no_washer",
        campaign=campaign,
        quality_settings=QualitySettings(),
        decay_settings=AnalysisSettings(),
    )
    good = analyse_run_file(folder, "no_washer/run01.txt", mode=ConfigurationMode(mode), **options)
    assert good.status == {
        "configuration": "no_washer",
        "run": "run01",
        "path": "no_washer/run01.txt",
        "status": "used",
        "reason": "",
        "record_start": "",  # an ASCII file states no recording start
        "left_out": "",
        "response_units": {"response": "g"},
    }
    assert good.segments["kept"].sum() >= 3 and set(good.segments["run"]) == {"run01"}
    assert set(good.segments["mode"]) == {0} and set(good.segments["channel"]) == {"response"}
    assert good.quality["passed"][good.quality["applied"]].all()
    assert list(good.quality["check"]) == [
        "clipping",
        "excitation",
        "double_hit",
        "trigger",
        "record_length",
        "snr",
        "segments",
    ]

    bad = analyse_run_file(folder, "no_washer/run02.txt", mode=ConfigurationMode(mode), **options)
    assert bad.status["status"] == "excluded"
    assert "no_washer/run02.txt:40:" in bad.status["reason"] and BAD_CELL in bad.status["reason"]
    assert len(bad.segments["t_s"]) == 0 and list(bad.quality["check"]) == ["read"]

    no_mode = analyse_run_file(
        folder,
        "no_washer/run01.txt",
        mode=ConfigurationMode(None, "configuration no_washer: first mode not found"),
        **options,
    )
    assert no_mode.status["status"] == "excluded"
    assert no_mode.status["reason"] == "configuration no_washer: first mode not found"
    assert len(no_mode.segments["t_s"]) == 0

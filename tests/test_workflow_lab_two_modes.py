"""The real ``snakemake`` on the virtual lab's two-mode, two-sensor campaign, checked
against the lab's truth (docs/virtual-lab.md, "The joint on two modes"): every mode found
near its true frequency, every (mode, channel) analysed, a verdict per mode and per
channel, each mode's verdict its truth's cause where the truth's effect stands clearly
above the data's scatter."""

import json

import numpy as np
import pandas as pd
import pytest
import yaml
from helpers import CHEAP_BUT_DISCOVERY, run_snakemake

from workflow.lab.campaign_files import truth_path
from workflow.lab.campaigns import generate_campaign
from workflow.lab.sensors import Sensor

CHANNELS = ("acc1", "acc2")
CONFIGURATION = "joint"

CLEAR_EFFECT_IN_STANDARD_ERRORS = 10.0
"""An effect is clearly in a channel's data when the truth's change of ln(zeta) over the
amplitudes that channel measured is this many standard errors of the difference between
the mean ln(zeta) of its lower and upper halves of segments. Consecutive segments overlap
and share the run's draw, so the effective count is below the row count: 10 rather than
the 2-3 of independent samples."""


@pytest.fixture(scope="module")
def lab_run(tmp_path_factory):
    """Four runs of one 1.36 in^2 joint, the patches acting on modes 1 and 2, each run
    file holding two sensors (acc1 the paper's accelerometer, acc2 at 18 in, where the
    modes' shapes differ from acc1's), analysed once by ``snakemake -c2 all``."""
    root = tmp_path_factory.mktemp("lab_two_modes")
    campaign = root / "campaign"
    generate_campaign(
        campaign,
        seed=21,
        runs_per_configuration=4,
        configurations={CONFIGURATION: 1.36},
        sensors=(Sensor("acc1"), Sensor("acc2", 18.0)),
        nonlinear_modes=2,
    )
    work = root / "work"
    done = run_snakemake(
        work, "-c2", "all", "--config", f"campaign={campaign}", *CHEAP_BUT_DISCOVERY, timeout=900
    )
    assert done.returncode == 0, done.stderr[-4000:]
    truths = [json.loads(truth_path(campaign, mode).read_text()) for mode in (1, 2)]
    listed_hz = yaml.safe_load((campaign / "campaign.yaml").read_text())["modes_hz"]
    return work, truths, listed_hz


def table(work, name) -> pd.DataFrame:
    return pd.read_parquet(work / "results" / "tables" / f"{name}.parquet")


def test_both_modes_are_found_near_their_true_frequencies(lab_run):
    work, truths, listed_hz = lab_run
    assert len(listed_hz) == 2
    modes = table(work, "modes").sort_values("nominal_mode_hz")
    assert list(modes["nominal_mode_hz"]) == listed_hz
    assert list(modes["configuration"]) == [CONFIGURATION] * 2
    segments = table(work, "segments")
    for (_, found), truth, nominal_hz in zip(modes.iterrows(), truths, listed_hz, strict=True):
        configuration = truth["configurations"][CONFIGURATION]
        velocity = np.asarray(truth["velocity_amplitude_in_s"])
        # the first sensor's amplitudes: the truth's run curves are against its velocity
        measured = segments[(segments["mode_hz"] == nominal_hz) & (segments["channel"] == CHANNELS[0])]
        inside = (velocity >= measured["velocity_amplitude_in_s"].min()) & (
            velocity <= measured["velocity_amplitude_in_s"].max()
        )
        run_hz = np.array([np.asarray(run["damped_frequency_hz"])[inside] for run in configuration["runs"]])
        # the spectral peak lies among the runs' true frequencies over the decay,
        # give or take one bin of the record's spectrum
        bin_hz = 1.0 / found["record_duration_s"]
        assert run_hz.min() - bin_hz <= found["mode_hz"] <= run_hz.max() + bin_hz, (nominal_hz, found)
        assert found["mode_hz"] == pytest.approx(truth["mode_hz"], rel=0.01)
        # The response stands > 40 dB above its noise at both modes: the coherence falls
        # below 1 only by the joint, whose hits of 5-40 lbf ring up to 0.4 % apart at mode 1
        # (0.96 measured). The two sensors see mode 1 with opposite signs: one
        # cross-spectrum over both would cancel it (0.07).
        assert found["coherence_at_mode"] > 0.9, (nominal_hz, found)


def test_every_table_has_every_mode_on_every_channel(lab_run):
    work, _, listed_hz = lab_run
    pairs = {(mode_hz, channel) for mode_hz in listed_hz for channel in CHANNELS}
    for name in ("segments", "segments_rejected", "damping_curves", "damping_fits", "hypotheses"):
        rows = table(work, name)
        assert set(zip(rows["mode_hz"], rows["channel"])) == pairs, name
    quality = table(work, "quality")
    # record-level checks come before any mode; the rest are per (mode, channel)
    per_pair = quality.dropna(subset=["mode_hz"])
    assert set(zip(per_pair["mode_hz"], per_pair["channel"])) == pairs
    assert set(quality["channel"]) == set(CHANNELS)
    # the paper's models and the discovery's residuals are the first mode's, first channel's
    for name in ("model_fits", "diagnosis_residuals"):
        rows = table(work, name)
        assert set(zip(rows["mode_hz"], rows["channel"])) == {(listed_hz[0], CHANNELS[0])}, name
    runs = table(work, "runs")
    assert (runs["status"] == "used").all() and len(runs) == 4


def clear_effect_in_standard_errors(segments: pd.DataFrame, channel_truth: dict, velocity) -> float:
    """The truth's change of ln(zeta) over the segments' amplitudes, in standard errors of
    the difference between the mean ln(zeta) of the lower and upper halves of the
    segments; the scatter is the segments' relative deviation from the truth curve, each
    run's own offset (its drawn linear damping) removed."""
    log_v = np.log(velocity)
    log_zeta_true = np.log(np.asarray(channel_truth["zeta"]))
    v = segments["velocity_amplitude_in_s"].to_numpy()
    zeta_true = np.exp(np.interp(np.log(v), log_v, log_zeta_true))
    # relative, not logarithmic: a noisy segment's local damping can come out negative
    residual = segments["zeta"].to_numpy() / zeta_true - 1.0
    residual = residual - segments.assign(r=residual).groupby("run")["r"].transform("median").to_numpy()
    scatter = np.std(residual)
    standard_error = 2.0 * scatter / np.sqrt(len(segments))
    change = np.ptp(np.interp(np.log([v.min(), v.max()]), log_v, log_zeta_true))
    return change / standard_error


def test_a_verdict_per_mode_and_channel_matching_the_truth_where_its_effect_is_clear(lab_run):
    work, truths, listed_hz = lab_run
    document = json.loads((work / "results" / "diagnosis.json").read_text())
    assert [mode["mode_hz"] for mode in document["modes"]] == listed_hz
    top = {key: value for key, value in document.items() if key != "modes"}
    assert top == {key: value for key, value in document["modes"][0].items() if key != "mode_hz"}
    segments = table(work, "segments")
    clear_modes = 0
    for mode, truth in zip(document["modes"], truths, strict=True):
        expected = truth["causes"][0]
        velocity = np.asarray(truth["velocity_amplitude_in_s"])
        configuration = mode["configurations"][CONFIGURATION]
        assert set(configuration["channels"]) == set(CHANNELS)
        sizes = {
            channel: clear_effect_in_standard_errors(
                segments[(segments["mode_hz"] == mode["mode_hz"]) & (segments["channel"] == channel)],
                truth["configurations"][CONFIGURATION]["channels"][channel],
                velocity,
            )
            for channel in CHANNELS
        }
        if min(sizes.values()) >= CLEAR_EFFECT_IN_STANDARD_ERRORS:
            for channel in CHANNELS:
                assert configuration["channels"][channel]["cause"] == expected, (mode["mode_hz"], channel)
            clear_modes += 1
            assert configuration["cause"] == expected and mode["cause"] == expected, (mode["mode_hz"], sizes)
        else:
            assert mode["cause"] in {expected, "none"}, (mode["mode_hz"], sizes)
    # micro-slip on mode 1 of a 1.36 in^2 joint is far above the scatter on both sensors
    assert clear_modes >= 1


def test_no_sensor_sure_of_another_cause_where_the_effect_is_weak(lab_run):
    """Where a mode's effect is within a few standard errors of the scatter, a sensor's own
    verdict is the truth's cause or `none`, or it is less than 0.7 sure (output contract:
    a sensor that sees less may be less sure, never sure of something else)."""
    work, truths, _ = lab_run
    document = json.loads((work / "results" / "diagnosis.json").read_text())
    for mode, truth in zip(document["modes"], truths, strict=True):
        allowed = {truth["causes"][0], "none"}
        for channel in CHANNELS:
            entry = mode["configurations"][CONFIGURATION]["channels"][channel]
            sure = entry["confidence"].get(entry["cause"], 0.0)
            assert entry["cause"] in allowed or sure < 0.7, (mode["mode_hz"], channel, entry["cause"], sure)

"""A (mode, channel) of a hit that fails a decay-level check is left out, not the hit: a
sensor that sees only noise, or a mode at one sensor's node, says nothing about what the
other sensors and modes measured. Only where nothing passes is the run excluded."""

import json

import numpy as np
import pandas as pd
import pytest
from helpers import run_snakemake
from system_format_files import lms_export_group, write_testlab_mat

from workflow.io.campaign import load_campaign
from workflow.measured.mode_identification import identify_configuration_mode
from workflow.measured.runs import LEFT_OUT, analyse_run_file
from workflow.measured.settings import AnalysisSettings, QualitySettings

RATE_HZ = 2048.0
N = 8192


def hit(mode2_at: dict[str, float], clipped: bool = False, mode1_at: dict[str, float] | None = None):
    """Sensors (g) of one hit: mode 1 (80.5 Hz) at each sensor's ``mode1_at`` share (1 by
    default), mode 2 (297.7 Hz) at its ``mode2_at`` share, a 1e-5 g noise on each; and a
    sensor that sees no mode."""
    rng = np.random.default_rng(7)
    t = np.arange(N) / RATE_HZ
    first = np.exp(-2.0 * t) * np.sin(2 * np.pi * 80.5 * t)
    second = np.exp(-3.0 * t) * np.sin(2 * np.pi * 297.7 * t)
    mode1_at = mode1_at or {}
    sensors = {name: mode1_at.get(name, 1.0) * first + share * second for name, share in mode2_at.items()}
    sensors["dead"] = np.zeros(N)
    if clipped:
        # an overloaded sensor: the hit's first cycles flat at 0.6 of their peak
        sensors["acc2"] = np.clip(sensors["acc2"], -0.6, 0.6)
    return {name: values + 1e-5 * rng.standard_normal(N) for name, values in sensors.items()}


def write_hit_campaign(tmp_path, channels, modes, clipped=False, sensors=None):
    sensors = sensors or hit({"acc1": 0.5, "acc2": 0.0}, clipped)
    folder = tmp_path / "campaign"
    (folder / "c").mkdir(parents=True)
    group = lms_export_group(list(sensors), np.column_stack(list(sensors.values())), "g", 1.0 / RATE_HZ)
    write_testlab_mat(folder / "c" / "run.mat", {"Signal": group})
    (folder / "campaign.yaml").write_text(
        f"name: t\n{modes}\nresponse: {{quantity: acceleration, channels: {channels}}}\n"
        "configurations:\n  c: {files: 'c/*'}\n"
    )
    return folder


def analysed(tmp_path, channels, modes="mode_hz: 80.5", clipped=False):
    folder = write_hit_campaign(tmp_path, channels, modes, clipped)
    options = {"configuration": "c", "campaign": load_campaign(folder), "quality_settings": QualitySettings()}
    mode = identify_configuration_mode(folder, ["c/run.mat"], mode_search=AnalysisSettings(), **options)
    return analyse_run_file(folder, "c/run.mat", mode=mode, decay_settings=AnalysisSettings(), **options)


def kept_by(result):
    segments = result.segments
    return {
        (int(m), str(c)): int(
            np.count_nonzero(segments["kept"][(segments["mode"] == m) & (segments["channel"] == c)])
        )
        for m, c in set(zip(segments["mode"].tolist(), segments["channel"].tolist()))
    }


def test_a_sensor_that_sees_only_noise_is_left_out_and_the_hit_used(tmp_path):
    result = analysed(tmp_path, "[acc1, dead, acc2]")
    assert result.status["status"] == "used" and result.status["reason"] == ""
    left_out = result.status["left_out"]
    assert "c/run.mat: channel 'dead': signal-to-noise" in left_out and "acc1" not in left_out
    kept = kept_by(result)
    assert kept[(0, "dead")] == 0 and kept[(0, "acc1")] >= 10 and kept[(0, "acc2")] >= 10
    dead = result.segments["channel"] == "dead"
    assert set(result.segments["reject_reason"][dead]) == {LEFT_OUT}
    # its quality rows say what failed, the others passed
    quality = result.quality
    failed = quality["applied"] & ~quality["passed"]
    assert set(quality["channel"][failed]) == {"dead"}


def test_a_mode_at_one_sensors_node_is_left_out_for_that_sensor_only(tmp_path):
    result = analysed(tmp_path, "[acc1, acc2]", modes="modes_hz: [80.5, 297.7]")
    assert result.status["status"] == "used"
    left_out = result.status["left_out"]
    assert "c/run.mat: channel 'acc2', mode 297.7" in left_out and "usable log-decrement segments" in left_out
    assert "acc1" not in left_out
    kept = kept_by(result)
    assert kept[(1, "acc2")] == 0
    assert min(kept[(0, "acc1")], kept[(0, "acc2")], kept[(1, "acc1")]) >= 10


def test_a_clipped_sensor_is_left_out_in_every_mode(tmp_path):
    result = analysed(tmp_path, "[acc1, acc2]", modes="modes_hz: [80.5, 297.7]", clipped=True)
    assert result.status["status"] == "used"
    assert result.status["left_out"].startswith("c/run.mat: channel 'acc2': response clipped")
    # its decay is not analysed: no segment of it, in any mode
    kept = kept_by(result)
    assert set(kept) == {(0, "acc1"), (1, "acc1")} and min(kept.values()) >= 10


@pytest.mark.parametrize(
    ("channels", "clipped", "words"),
    [("[dead]", False, "signal-to-noise"), ("[acc2]", True, "response clipped")],
)
def test_a_hit_where_nothing_passes_is_excluded(tmp_path, channels, clipped, words):
    result = analysed(tmp_path, channels, clipped=clipped)
    assert result.status["status"] == "excluded" and result.status["left_out"] == ""
    assert words in result.status["reason"]


def test_the_workflow_reports_what_it_left_out_of_a_used_hit(tmp_path):
    folder = write_hit_campaign(tmp_path, "[acc1, dead, acc2]", "modes_hz: [80.5, 297.7]")
    work = tmp_path / "work"
    result = run_snakemake(work, "-c2", "discovery", "--config", f"campaign={folder}", timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    runs = pd.read_parquet(work / "results/tables/runs.parquet")
    assert runs["status"].tolist() == ["used"]
    assert (
        "channel 'dead', mode 80." in runs["left_out"][0]
        and "channel 'acc2', mode 297.7" in runs["left_out"][0]
    )
    segments = pd.read_parquet(work / "results/tables/segments.parquet")
    seen = set(zip(segments["mode_hz"].round(1), segments["channel"]))
    assert seen == {(80.5, "acc1"), (80.5, "acc2"), (297.7, "acc1")}
    rejected = pd.read_parquet(work / "results/tables/segments_rejected.parquet")
    assert set(rejected.loc[rejected["channel"] == "dead", "reject_reason"]) == {LEFT_OUT}
    modes = json.loads((work / "results/diagnosis.json").read_text())["modes"]
    assert [sorted(m["configurations"]["c"].get("channels") or {}) for m in modes][0] == ["acc1", "acc2"]


def test_the_paper_reads_the_first_channel_kept_and_each_mode_keeps_its_number(tmp_path):
    # the sensor listed first sees nothing: the paper's models, figures and residuals read
    # the next; the third sits at a node of mode 1, so its first mode kept is mode 2,
    # which stays mode 2 in the diagnosis
    sensors = hit({"acc1": 0.5, "acc2": 0.5}, mode1_at={"acc2": 1e-6})
    folder = write_hit_campaign(tmp_path, "[dead, acc1, acc2]", "modes_hz: [80.5, 297.7]", sensors=sensors)
    work = tmp_path / "work"
    result = run_snakemake(work, "-c2", "all", "--config", f"campaign={folder}", timeout=900)
    assert result.returncode == 0, result.stderr[-3000:]
    runs = pd.read_parquet(work / "results/tables/runs.parquet")
    assert "channel 'dead'" in runs["left_out"][0] and "channel 'acc2', mode 80." in runs["left_out"][0]
    for name in ("model_fits", "diagnosis_residuals"):
        rows = pd.read_parquet(work / f"results/tables/{name}.parquet")
        assert set(zip(rows["mode_hz"], rows["channel"])) == {(80.5, "acc1")}, name
    models = json.loads((work / "results/models/c.json").read_text())
    assert "skipped" not in models and set(models["models"]) == {"dahl", "lugre"}
    diagnosis = json.loads((work / "results/diagnosis.json").read_text())
    first, second = diagnosis["modes"]
    assert first["mode_hz"] == 80.5 and second["mode_hz"] == 297.7
    assert "acc2" not in (first["configurations"]["c"].get("channels") or {})
    assert set(second["configurations"]["c"]["channels"]) == {"acc1", "acc2"}


def test_a_sensor_whose_unit_contradicts_campaign_yaml_is_left_out_and_the_hit_used(tmp_path):
    sensors = hit({"acc1": 0.5, "acc2": 0.0})
    folder = tmp_path / "campaign"
    (folder / "c").mkdir(parents=True)
    groups = {
        "Signal": lms_export_group(["acc1"], sensors["acc1"][:, None], "g", 1.0 / RATE_HZ),
        "Laser": lms_export_group(["laser"], sensors["acc2"][:, None], "m/s", 1.0 / RATE_HZ),
    }
    write_testlab_mat(folder / "c" / "run.mat", groups)
    (folder / "campaign.yaml").write_text(
        "name: t\nmode_hz: 80.5\nresponse: {quantity: acceleration, channels: [laser, acc1]}\n"
        "configurations:\n  c: {files: 'c/*'}\n"
    )
    options = {"configuration": "c", "campaign": load_campaign(folder), "quality_settings": QualitySettings()}
    mode = identify_configuration_mode(folder, ["c/run.mat"], mode_search=AnalysisSettings(), **options)
    result = analyse_run_file(folder, "c/run.mat", mode=mode, decay_settings=AnalysisSettings(), **options)
    assert result.status["status"] == "used" and result.status["reason"] == ""
    assert result.status["left_out"].startswith("c/run.mat: ") and "unit 'm/s'" in result.status["left_out"]
    assert set(result.segments["channel"]) == {"acc1"} and result.segments["kept"].sum() >= 10
    refused = result.quality["check"] == "unit"
    assert (
        result.quality["channel"][refused].tolist() == ["laser"]
        and not result.quality["passed"][refused].any()
    )

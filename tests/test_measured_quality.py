"""Per-run quality checks on synthetic records: pass and fail cases and their messages."""

import numpy as np
from helpers import failed_check_reasons

from workflow.io.records import RunRecord
from workflow.measured.quality import (
    check_clipping,
    check_double_hit,
    check_excitation,
    check_record_length,
    check_snr,
    check_trigger,
)
from workflow.measured.settings import QualitySettings

FS_HZ = 2560.0
N = 8192
PRETRIGGER = 25


def ring_down(amplitude=5.0, n=N):
    t = np.arange(n) / FS_HZ
    return amplitude * np.exp(-3.0 * t) * np.sin(2 * np.pi * 125.3 * t + 0.3)


def hammer(peak_lbf=80.0, at_sample=PRETRIGGER + 2, width_samples=2.0, n=N):
    """A half-sine-like pulse whose rising flank passes 1 lbf near ``at_sample``."""
    index = np.arange(n)
    return peak_lbf * np.exp(-(((index - at_sample) / width_samples) ** 2))


def record(response=None, force=None, pretrigger_source="header"):
    response = ring_down() if response is None else response
    return RunRecord(
        path="cfg/run.txt",
        sample_rate_hz=FS_HZ,
        pretrigger_samples=PRETRIGGER,
        time_s=None,
        force_lbf=force,
        response=response,
        response_quantity="acceleration",
        response_unit="g",
        header={},
        n_samples=response.size,
        pretrigger_source=pretrigger_source,
    )


# ------------------------------------------------------------------ clipping


def test_clean_ring_down_is_not_clipped():
    assert check_clipping(ring_down(), 0.999, 3).reason is None


def test_flat_top_is_clipped_and_says_by_how_much():
    response = np.clip(ring_down(), -4.0, 4.0)
    at_rail = int(np.count_nonzero(np.abs(response) >= 0.999 * 4.0))
    reason = check_clipping(response, 0.999, 3, unit="g").reason
    assert reason is not None and reason.startswith("response clipped")
    assert f"{at_rail} samples" in reason
    assert "0.1 %" in reason and "peak 4 g" in reason and "(limit 3)" in reason


def test_clipping_limit_is_inclusive():
    response = np.zeros(100)
    response[[10, 20, 30]] = 1.0
    assert check_clipping(response, 0.999, 3).reason is None
    assert "4 samples" in check_clipping(np.r_[response, 1.0], 0.999, 3).reason


def test_zero_response_is_reported():
    assert "zero" in check_clipping(np.zeros(10), 0.999, 3).reason


# ------------------------------------------------------------------ double hit


def test_single_hit_passes():
    assert check_double_hit(hammer(), FS_HZ, 0.3, 0.005).reason is None


def test_second_hit_is_reported_with_size_and_delay():
    second_at = PRETRIGGER + 2 + 64  # 25 ms later
    force = hammer() + hammer(peak_lbf=40.0, at_sample=second_at)
    reason = check_double_hit(force, FS_HZ, 0.3, 0.005).reason
    assert reason is not None and reason.startswith("double hit")
    assert "40 lbf" in reason and "0.50 of the main 80 lbf" in reason
    assert "25 ms after" in reason and "(limit 0.30)" in reason


def test_second_hit_before_the_main_one():
    force = hammer(peak_lbf=30.0, at_sample=100) + hammer(peak_lbf=80.0, at_sample=200)
    assert "before" in check_double_hit(force, FS_HZ, 0.3, 0.005).reason


def test_small_second_pulse_or_close_ripple_passes():
    small = hammer() + hammer(peak_lbf=20.0, at_sample=200)  # 0.25 of the main pulse
    assert check_double_hit(small, FS_HZ, 0.3, 0.005).reason is None
    close = hammer() + hammer(peak_lbf=60.0, at_sample=PRETRIGGER + 2 + 8)  # 3 ms later
    assert check_double_hit(close, FS_HZ, 0.3, 0.005).reason is None


def test_inverted_force_sign_is_handled():
    force = -(hammer() + hammer(peak_lbf=40.0, at_sample=300))
    assert "double hit" in check_double_hit(force, FS_HZ, 0.3, 0.005).reason
    assert check_excitation(-hammer(), 1.0).reason is None


# ------------------------------------------------------------------ excitation


def test_excitation_pass_and_fail():
    assert check_excitation(hammer(), 1.0).reason is None
    reason = check_excitation(hammer(peak_lbf=0.42), 1.0).reason
    assert reason == "no real hit: peak force 0.42 lbf is below 1 lbf"
    assert "peak force 0 lbf" in check_excitation(np.zeros(100), 1.0).reason


# ------------------------------------------------------------------ trigger


def test_trigger_consistent_with_pretrigger():
    force = hammer()
    first = int(np.flatnonzero(force >= 1.0)[0])
    assert abs(first - PRETRIGGER) <= 5
    assert check_trigger(force, PRETRIGGER).reason is None


def test_trigger_far_after_the_pretrigger():
    reason = check_trigger(hammer(at_sample=900), PRETRIGGER).reason
    assert reason is not None and "after the pre-trigger length 25" in reason
    first = int(np.flatnonzero(hammer(at_sample=900) >= 1.0)[0])
    assert f"at sample {first}" in reason and f"{first - PRETRIGGER} samples after" in reason


def test_trigger_before_the_pretrigger_and_never():
    early = hammer(at_sample=5)
    assert "before the pre-trigger" in check_trigger(early, PRETRIGGER).reason
    assert "never reaches" in check_trigger(np.zeros(100), PRETRIGGER).reason


def test_trigger_level_is_a_parameter():
    force = hammer()
    first_at_20 = int(np.flatnonzero(force >= 20.0)[0])
    assert check_trigger(force, first_at_20, trigger_lbf=20.0).reason is None


# ------------------------------------------------------------------ record length and SNR


def test_record_length():
    assert check_record_length(8192, 2560.0, 125.0, 20.0).reason is None
    reason = check_record_length(256, 2560.0, 125.0, 20.0).reason
    assert reason == "record too short: 0.1 s holds 12.5 cycles of the 125 Hz mode (need 20)"


def test_snr():
    assert check_snr(100.0, 1.0, 20.0).reason is None  # 40 dB
    reason = check_snr(5.0, 1.0, 20.0).reason
    assert reason.startswith("signal-to-noise 14 dB is below 20 dB")
    assert "peak envelope 5" in reason and "noise floor 1" in reason
    assert check_snr(1.0, 0.0, 20.0).reason is None
    assert "no signal" in check_snr(0.0, 1.0, 20.0).reason


# ------------------------------------------------------------------ all checks


def test_run_quality_checks_good_run_passes():
    assert failed_check_reasons(record(force=hammer()), QualitySettings(), mode_hz=125.0) == []


def test_run_quality_checks_collects_every_failure():
    bad = record(response=np.clip(ring_down(), -1.0, 1.0), force=hammer() + hammer(60.0, 400))
    reasons = failed_check_reasons(bad, QualitySettings(min_record_cycles=1e5), mode_hz=5000.0)
    assert [r.split(":")[0] for r in reasons] == ["response clipped", "double hit", "record too short"]


def test_run_quality_checks_without_force_or_mode():
    assert failed_check_reasons(record(force=None), QualitySettings()) == []


def test_trigger_checked_only_when_pretrigger_stated():
    late = hammer(at_sample=900)
    stated = failed_check_reasons(record(force=late), QualitySettings())
    assert len(stated) == 1 and stated[0].startswith("trigger")
    assert failed_check_reasons(record(force=late, pretrigger_source="default"), QualitySettings()) == []


def test_missing_hit_is_one_reason_not_two():
    reasons = failed_check_reasons(record(force=hammer(peak_lbf=0.5)), QualitySettings())
    assert reasons == ["no real hit: peak force 0.5 lbf is below 1 lbf"]


def test_settings_thresholds_are_used():
    response = np.clip(ring_down(), -4.0, 4.0)
    at_rail = int(np.count_nonzero(np.abs(response) >= 0.999 * 4.0))
    assert at_rail > 3
    assert failed_check_reasons(record(response=response), QualitySettings(clip_max_samples=at_rail)) == []
    assert failed_check_reasons(record(response=response), QualitySettings(clip_max_samples=at_rail - 1))
    # A looser "at the peak" band counts more samples.
    loose = QualitySettings(clip_fraction_of_peak=0.9, clip_max_samples=at_rail)
    assert failed_check_reasons(record(response=response), loose)

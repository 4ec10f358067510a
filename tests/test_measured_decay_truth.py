"""The analysis settings off their defaults (segment length, overlap, filter order) and the
per-segment velocity conversion, against a synthetic linear ring-down whose damping ratio,
frequency and segment layout are known analytically."""

import numpy as np
import pytest
from test_measured_decay import band, ring_down

from workflow.io.interim import ModeInfo
from workflow.io.records import RunRecord
from workflow.measured.decay import analyse_decay
from workflow.measured.runs import analyse_run_with_quality
from workflow.measured.segment_fits import segment_bounds
from workflow.measured.settings import AnalysisSettings, QualitySettings

F_HZ, ZETA, FS_HZ, DURATION_S = 125.0, 0.002, 2560.0, 3.2
DAMPED_HZ = F_HZ * np.sqrt(1 - ZETA**2)
G_IN_S2 = 9.80665 / 0.0254
"""Standard gravity in in/s² (both factors exact by definition)."""

# Kept segments of a noiseless linear decay: the chain's damping error is at most 5.5e-3 of
# zeta and its frequency error 2.2e-5 of the frequency over every setting below (measured);
# the bounds leave a 1.8x and a 4.6x margin.
ZETA_RELATIVE_TOLERANCE = 0.01
FREQUENCY_RELATIVE_TOLERANCE = 1e-4


@pytest.mark.parametrize(
    "overlap, hop_samples, n_segments",
    # 128 Hz at 2560 Hz: 20 samples a cycle, 10-cycle segments of 200 samples in 1000 samples.
    [(0.0, 200, 5), (0.25, 150, 6), (0.5, 100, 9), (0.75, 50, 17), (0.9, 20, 41)],
)
def test_segments_advance_by_one_minus_the_overlap(overlap, hop_samples, n_segments):
    starts, stops = segment_bounds(0, 1000, 2560.0, 128.0, segment_cycles=10.0, segment_overlap=overlap)
    assert len(starts) == n_segments
    np.testing.assert_array_equal(starts, hop_samples * np.arange(n_segments))
    np.testing.assert_array_equal(stops - starts, 200)
    # centres at (k * hop + 100) / fs
    np.testing.assert_allclose(
        (starts + stops) / 2 / 2560.0, (hop_samples * np.arange(n_segments) + 100) / 2560.0
    )


@pytest.mark.parametrize(
    "settings, hop_samples",
    [
        # 125 Hz at 2560 Hz: 20.48 samples a cycle; length round(cycles * 20.48), hop
        # round(length * (1 - overlap)) samples.
        ({}, 102),  # 205 samples, half overlap: 102.5 rounds to even
        ({"segment_cycles": 5.0}, 51),  # 102 samples
        ({"segment_cycles": 20.0}, 205),  # 410 samples
        ({"segment_overlap": 0.0}, 205),
        ({"segment_overlap": 0.75}, 51),  # 51.25
        ({"filter_order": 4}, 102),
        ({"filter_order": 16}, 102),
    ],
)
def test_settings_off_their_defaults_recover_the_linear_decay(settings, hop_samples):
    x = ring_down(F_HZ, ZETA, FS_HZ, DURATION_S, snr_db=180.0)
    segments = analyse_decay(x, FS_HZ, band(F_HZ), mode_hz=F_HZ, **settings).segments
    kept = segments["kept"]
    # Most of the 3.2 s decay (about 80 % of its segments) is clear of the filter's edges.
    assert kept.sum() >= 0.8 * kept.size
    np.testing.assert_allclose(np.diff(segments["t_s"]), hop_samples / FS_HZ, rtol=1e-12)
    assert np.max(np.abs(segments["zeta"][kept] / ZETA - 1)) < ZETA_RELATIVE_TOLERANCE
    assert np.max(np.abs(segments["frequency_hz"][kept] / DAMPED_HZ - 1)) < FREQUENCY_RELATIVE_TOLERANCE


def test_velocity_uses_each_segments_own_frequency_not_the_mode_frequency():
    # The response rings at 130 Hz while the configuration's mode says 125 Hz (a run whose
    # joint stiffened): a segment's velocity amplitude is its acceleration amplitude over
    # 2 pi times its own frequency (130 Hz), 4 % below what the mode frequency would give.
    true_hz = 130.0
    acceleration_g = ring_down(true_hz, ZETA, FS_HZ, DURATION_S, snr_db=180.0)
    record = RunRecord(
        path="cfg/run01.txt",
        sample_rate_hz=FS_HZ,
        pretrigger_samples=25,
        time_s=None,
        force_lbf=None,
        response=acceleration_g,
        response_quantity="acceleration",
        response_unit="g",
        header={},
        n_samples=acceleration_g.size,
    )
    mode = ModeInfo(F_HZ, (100.0, 150.0), "campaign", None, 1, FS_HZ, DURATION_S)
    segments, _ = analyse_run_with_quality(
        record,
        configuration="cfg",
        run="run01",
        mode=mode,
        window=(0, record.n_samples),
        decay_settings=AnalysisSettings(
            filter_order=10,
            segment_cycles=10.0,
            segment_overlap=0.5,
            noise_floor_factor=10.0,
            edge_time_constants=3.0,
        ),
        quality_settings=QualitySettings(),
    )
    kept = segments["kept"]
    assert kept.sum() >= 10
    frequency_hz = segments["frequency_hz"][kept]
    np.testing.assert_allclose(
        frequency_hz, true_hz * np.sqrt(1 - ZETA**2), rtol=FREQUENCY_RELATIVE_TOLERANCE
    )
    expected_in_s = segments["response_amplitude"][kept] * G_IN_S2 / (2 * np.pi * frequency_hz)
    np.testing.assert_allclose(segments["velocity_amplitude_in_s"][kept], expected_in_s, rtol=1e-12)
    # and against the analytic envelope: 1 g at t = 0 decaying as exp(-zeta omega t)
    t_s = segments["t_s"][kept] - 25 / FS_HZ
    analytic_in_s = G_IN_S2 * np.exp(-ZETA * 2 * np.pi * true_hz * t_s) / (2 * np.pi * true_hz)
    np.testing.assert_allclose(segments["velocity_amplitude_in_s"][kept], analytic_in_s, rtol=0.01)


def test_segment_layout_at_its_limits():
    # the last segment ends at the range's end at most: 399 samples hold two 200-sample
    # segments 100 apart, 400 hold three
    assert segment_bounds(0, 399, 2560.0, 128.0, 10.0, 0.5)[1].tolist() == [200, 300]
    assert segment_bounds(0, 400, 2560.0, 128.0, 10.0, 0.5)[1].tolist() == [200, 300, 400]
    # a segment has at least 3 samples (a line through the log envelope and a residual),
    # and consecutive ones advance by at least one sample
    starts, stops = segment_bounds(0, 10, 1000.0, 500.0, segment_cycles=1.0, segment_overlap=0.9)
    assert starts.tolist() == list(range(8)) and np.all(stops - starts == 3)
    # Slow modes and slow sampling are valid: a 0.5 Hz mode, a 0.5 Hz sample rate.
    assert len(segment_bounds(0, 1000, 100.0, 0.5, segment_cycles=2.0)[0]) == 4  # 400 samples, hop 200
    assert len(segment_bounds(0, 100, 0.5, 0.01, segment_cycles=2.0)[0]) == 1
    # (starts are int64: np.arange of Python ints is int64 already under NumPy 2, so its
    # dtype argument is an equivalent mutant)
    assert starts.dtype == np.int64


@pytest.mark.parametrize("mode_hz, fs_hz", [(0.0, 2560.0), (-125.0, 2560.0), (125.0, 0.0), (125.0, -1.0)])
def test_segment_layout_needs_positive_frequencies(mode_hz, fs_hz):
    with pytest.raises(ValueError, match=r"^mode_hz and fs_hz must be positive$"):
        segment_bounds(0, 1000, fs_hz, mode_hz)


@pytest.mark.parametrize("overlap", [1.0, 1.5, -0.1])
def test_segments_cannot_overlap_whole(overlap):
    with pytest.raises(ValueError, match=rf"^segment_overlap must lie in \[0, 1\), got {overlap}$"):
        segment_bounds(0, 1000, 2560.0, 125.0, segment_overlap=overlap)

"""Tests of workflow.measured.mode against a two-mode linear system with known modes."""

import numpy as np
import pytest

from workflow.measured.mode import band_around, find_mode_hz, h1_frf, h1_over_channels, response_spectrum

FS_HZ = 2560.0
MODES_HZ = (125.0, 310.0)
ZETAS = (0.01, 0.008)
GAINS = (1.0, 0.6)


def exact_frf(f_hz: np.ndarray) -> np.ndarray:
    """Receptance of the two modes (the continuous-time truth)."""
    s = 2j * np.pi * np.asarray(f_hz)
    return sum(
        g / (s**2 + 2 * z * (2 * np.pi * f) * s + (2 * np.pi * f) ** 2)
        for f, z, g in zip(MODES_HZ, ZETAS, GAINS)
    )


def exact_peak_hz(low_hz: float, high_hz: float) -> float:
    """Where |H| peaks: the other mode's background moves it off f_n slightly."""
    fine = np.linspace(low_hz, high_hz, 200001)
    return float(fine[np.argmax(np.abs(exact_frf(fine)))])


def impulse_response(n_samples: int) -> np.ndarray:
    """Sampled unit-impulse response (displacement per force impulse) of two modes."""
    t = np.arange(n_samples) / FS_HZ
    h = np.zeros(n_samples)
    for f_hz, zeta, gain in zip(MODES_HZ, ZETAS, GAINS):
        wn = 2 * np.pi * f_hz
        wd = wn * np.sqrt(1 - zeta**2)
        h += gain * np.exp(-zeta * wn * t) * np.sin(wd * t) / wd
    return h


def hammer_runs(n_runs: int, lengths: list[int], seed: int = 1):
    """Half-sine hammer pulses (1.2 ms) of random size, response noise 0.2 % of its peak."""
    rng = np.random.default_rng(seed)
    forces, responses = [], []
    for k in range(n_runs):
        n = lengths[k % len(lengths)]
        force = np.zeros(n)
        pulse = np.sin(np.pi * np.arange(4) / 3)  # ~1.2 ms half sine: flat to >400 Hz
        force[25:29] = rng.uniform(5, 20) * pulse
        response = np.convolve(force, impulse_response(n))[:n] / FS_HZ
        response += 0.002 * np.abs(response).max() * rng.standard_normal(n)
        force += 0.001 * rng.standard_normal(n)
        forces.append(force)
        responses.append(response)
    return forces, responses


def test_h1_finds_both_modes_and_coherence_is_high_at_the_mode():
    forces, responses = hammer_runs(6, [8192, 7000])  # unequal lengths on purpose
    f_hz, h1, coherence = h1_frf(forces, responses, FS_HZ)
    # Resolution is 2560/7000 = 0.37 Hz; a resonance of half-power width 2.5 Hz is
    # interpolated to a small fraction of a bin, so 0.1 Hz is a fair bound.
    for low_hz, high_hz in ((100, 150), (250, 400)):
        truth = exact_peak_hz(low_hz, high_hz)
        assert find_mode_hz(f_hz, np.abs(h1), (low_hz, high_hz)) == pytest.approx(truth, abs=0.1)
    # At resonance the response is > 40 dB above its noise: gamma^2 > 1 - 1e-4.
    at_mode = np.argmin(np.abs(f_hz - MODES_HZ[0]))
    assert coherence[at_mode] > 0.99
    # Noise dominates between modes far from both, where |H| is small: coherence drops.
    assert coherence[np.argmin(np.abs(f_hz - 1000))] < coherence[at_mode]


def test_sensors_on_either_side_of_a_node_keep_the_mode_and_its_coherence():
    """Two sensors seeing the hits with opposite signs (either side of a node of the
    mode): averaged over channels their cross-spectra cancel; each channel's own H1
    keeps the mode at its analytic frequency with its high coherence."""
    forces, responses = hammer_runs(4, [8192])
    other_side = [-response for response in responses]
    pooled_f, pooled_h1, pooled_coherence = h1_frf(forces * 2, responses + other_side, FS_HZ)
    f_hz, magnitude, coherence = h1_over_channels(
        forces * 2, responses + other_side, ["a"] * 4 + ["b"] * 4, FS_HZ
    )
    np.testing.assert_array_equal(f_hz, pooled_f)
    at_mode = np.argmin(np.abs(f_hz - MODES_HZ[0]))
    # the pooled estimate is left with the noise alone (0.2 % of the response's peak)
    assert np.abs(pooled_h1[at_mode]) < 0.01 * magnitude[at_mode] and pooled_coherence[at_mode] < 0.01
    assert find_mode_hz(f_hz, magnitude, (100, 150)) == pytest.approx(exact_peak_hz(100, 150), abs=0.1)
    assert coherence[at_mode] > 0.99
    # one channel: h1_frf's magnitude and coherence
    _, one_h1, one_coherence = h1_frf(forces, responses, FS_HZ)
    _, one_magnitude, one_channel_coherence = h1_over_channels(forces, responses, [None] * 4, FS_HZ)
    np.testing.assert_array_equal(one_magnitude, np.abs(one_h1))
    np.testing.assert_array_equal(one_channel_coherence, one_coherence)


def test_h1_magnitude_matches_the_analytic_frf_at_the_mode():
    forces, responses = hammer_runs(4, [8192])
    f_hz, h1, _ = h1_frf(forces, responses, FS_HZ)
    exact = exact_frf(f_hz)
    band = np.abs(f_hz - MODES_HZ[0]) < 2.5  # the half-power band, +- zeta f_n
    # There the response is ~40 dB above the 0.2 % noise, the pulse spectrum is flat, and
    # the record decays to e^-32 (no truncation leakage); the sampled convolution's
    # aliasing is < 1 %: |H1| within 5 % of the exact receptance.
    np.testing.assert_allclose(np.abs(h1[band]), np.abs(exact[band]), rtol=0.05)


def test_search_range_decides_which_peak_is_found():
    forces, responses = hammer_runs(3, [8192])
    f_hz, psd = response_spectrum(responses, FS_HZ)
    assert find_mode_hz(f_hz, psd, (5, 200)) == pytest.approx(exact_peak_hz(5, 200), abs=0.1)
    assert find_mode_hz(f_hz, psd, (200, 1000)) == pytest.approx(exact_peak_hz(200, 1000), abs=0.1)


def test_no_interior_peak_raises_a_clear_error():
    f_hz = np.linspace(0, 100, 201)
    rising = 1 + f_hz
    with pytest.raises(ValueError, match="no spectral peak"):
        find_mode_hz(f_hz, rising, (20, 80))


def test_parabolic_refinement_is_exact_for_a_gaussian_peak():
    # ln of a Gaussian is a parabola, so the refinement recovers an off-grid centre exactly.
    f_hz = np.arange(0.0, 200.0, 1.0)
    magnitude = np.exp(-((f_hz - 123.37) ** 2) / (2 * 3.0**2))
    assert find_mode_hz(f_hz, magnitude, (100, 150)) == pytest.approx(123.37, abs=1e-9)


def test_band_around_gives_the_papers_band():
    assert band_around(125.0, 0.2) == pytest.approx((100.0, 150.0))
    with pytest.raises(ValueError):
        band_around(125.0, 1.2)


def test_runs_must_pair_up():
    with pytest.raises(ValueError, match="pair"):
        h1_frf([np.ones(100)], [np.ones(100), np.ones(100)], FS_HZ)


@pytest.mark.parametrize("segment", [1000, 999])  # even and odd: the Nyquist bin differs
def test_spectra_equal_scipys_welch_and_csd(segment):
    # The NumPy spectra replace scipy.signal's (boxcar window, no overlap, constant
    # detrend, density scaling); each run is averaged over its own whole segments and
    # runs are averaged equally. Agreement to rounding (1e-12 of the peak).
    from scipy import signal

    forces, responses = hammer_runs(3, [2500, 3100])
    options = dict(fs=FS_HZ, window="boxcar", nperseg=segment, noverlap=0, detrend="constant")
    cross = sum(signal.csd(f, x, **options)[1] for f, x in zip(forces, responses))
    auto_force = sum(signal.welch(f, **options)[1] for f in forces)
    auto_response = sum(signal.welch(x, **options)[1] for x in responses)
    f_hz, h1, coherence = h1_frf(forces, responses, FS_HZ, nperseg=segment)
    np.testing.assert_allclose(f_hz, signal.welch(forces[0], **options)[0], rtol=1e-15)
    # The DC bin of mean-removed segments is rounding noise in both: left out.
    np.testing.assert_allclose(h1[1:], (cross / auto_force)[1:], rtol=1e-9)
    np.testing.assert_allclose(
        coherence[1:], (np.abs(cross) ** 2 / (auto_force * auto_response))[1:], rtol=1e-9
    )
    _, psd = response_spectrum(responses, FS_HZ, nperseg=segment)
    np.testing.assert_allclose(psd, auto_response / 3, rtol=0, atol=1e-12 * auto_response.max())


def test_psd_integrates_to_the_variance():
    # Parseval: the one-sided density summed over the grid (step fs/n) is the mean-removed
    # signal's variance, exactly for a single rectangular segment.
    x = np.random.default_rng(4).standard_normal(4096) + 3.0
    f_hz, psd = response_spectrum([x], FS_HZ)
    assert psd.sum() * (f_hz[1] - f_hz[0]) == pytest.approx(x.var(), rel=1e-12)

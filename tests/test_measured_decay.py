"""Accuracy tests of workflow.measured.decay on ring-downs with known damping and frequency."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from workflow.measured import decay, filters, segment_fits
from workflow.measured.decay import analyse_decay
from workflow.measured.filters import analytic_signal, bandpass, envelope
from workflow.measured.segment_fits import log_decrement_segments, segment_bounds

PRETRIGGER = 25

CHAIN_FREQUENCY_BIAS = 1e-4
"""Bound on the analysis chain's relative frequency error on a noiseless linear decay
(at most 4.2e-5 measured over LINEAR_CASES, kept segments)."""


def ring_down(f_hz, zeta, fs_hz, duration_s, snr_db=40.0, seed=0, amplitude=1.0):
    """Linear decay of the mode, plus two stronger out-of-band modes, a pre-trigger of
    25 samples and white noise snr_db below the initial amplitude."""
    rng = np.random.default_rng(seed)
    n = int(round(duration_s * fs_hz))
    t = (np.arange(n) - PRETRIGGER) / fs_hz
    on = t >= 0
    x = np.zeros(n)
    for ratio, z, a in ((1.0, zeta, 1.0), (0.4, 0.02, 2.0), (2.7, 0.01, 3.0)):
        wn = 2 * np.pi * f_hz * ratio
        if ratio * f_hz < 0.45 * fs_hz:
            x[on] += a * np.exp(-z * wn * t[on]) * np.sin(wn * np.sqrt(1 - z * z) * t[on] + 0.3)
    x += 10 ** (-snr_db / 20) * rng.standard_normal(n)
    return amplitude * x


def band(f_hz):
    return (0.8 * f_hz, 1.2 * f_hz)


# (mode Hz, damping ratio, sample rate Hz, record s): 20-500 Hz, 0.05-2 %, fs >= 20 f.
LINEAR_CASES = [
    (20.0, 0.0005, 512.0, 8.0),
    (20.0, 0.02, 512.0, 3.2),
    (125.0, 0.0005, 2560.0, 3.2),
    (125.0, 0.005, 2560.0, 3.2),
    (125.0, 0.02, 2560.0, 3.2),
    (500.0, 0.0005, 10240.0, 2.0),
    (500.0, 0.02, 10240.0, 1.0),
]


def test_bandpass_squares_the_butterworth_magnitude():
    fs_hz, n = 2560.0, 2560 * 4
    t = np.arange(n) / fs_hz
    middle = slice(n // 4, 3 * n // 4)
    for f_hz, expected in ((125.0, 1.0), (100.0, 0.5), (150.0, 0.5)):
        y = bandpass(np.cos(2 * np.pi * f_hz * t), fs_hz, (100.0, 150.0), order=10)
        # Forward-backward: |H|^2, i.e. 1 at the centre and (1/sqrt 2)^2 at the edges.
        assert np.sqrt(2) * np.std(y[middle]) == pytest.approx(expected, rel=0.01)


def test_envelope_of_a_steady_tone_is_its_amplitude():
    fs_hz, n = 2560.0, 8192
    x = 3.0 * np.cos(2 * np.pi * 125.0 * np.arange(n) / fs_hz + 0.4)
    middle = slice(1000, n - 1000)  # FFT Hilbert errors live at the record ends
    np.testing.assert_allclose(envelope(x)[middle], 3.0, rtol=1e-3)
    phase = np.unwrap(np.angle(analytic_signal(x)))
    slope = np.polyfit(np.arange(n)[middle] / fs_hz, phase[middle], 1)[0]
    assert slope / (2 * np.pi) == pytest.approx(125.0, rel=1e-6)


def test_segment_bounds_length_and_hop():
    starts, stops = segment_bounds(100, 5000, 2560.0, 125.0, segment_cycles=10, segment_overlap=0.5)
    assert np.all(stops - starts == round(10 * 2560 / 125))  # 205 samples
    assert np.all(np.diff(starts) == round(205 * 0.5))
    assert starts[0] == 100 and stops[-1] <= 5000 and stops[-1] + 102 > 5000


def test_log_decrement_is_exact_on_an_exact_envelope_and_phase():
    # zeta = -s / sqrt(s^2 + wd^2) has no small-damping approximation: 10 % damping is
    # recovered to rounding error.
    fs_hz, f_hz, zeta = 1000.0, 50.0, 0.1
    wn = 2 * np.pi * f_hz
    t = np.arange(3000) / fs_hz
    env = np.exp(-zeta * wn * t)
    phase = wn * np.sqrt(1 - zeta**2) * t
    starts, stops = segment_bounds(0, 3000, fs_hz, f_hz)
    seg = log_decrement_segments(env, phase, fs_hz, starts, stops)
    np.testing.assert_allclose(seg["zeta"], zeta, rtol=1e-9)
    np.testing.assert_allclose(seg["frequency_hz"], f_hz * np.sqrt(1 - zeta**2), rtol=1e-9)


def test_segments_analysed_side_by_side_equal_a_line_fit_of_each(monkeypatch):
    """All segments' line fits at once (in blocks, here of a few segments, and with a
    segment of another length and one whose envelope touches zero) equal a separate
    least-squares line per segment to rounding (1e-10 relative), the ln-envelope's rms
    residual to 1e-6 (the reference residual, from an uncentred line, keeps fewer digits)."""
    rng = np.random.default_rng(3)
    fs_hz = 2560.0
    x = ring_down(125.0, 0.004, fs_hz, 3.2, snr_db=40.0, seed=4)
    z = analytic_signal(bandpass(x, fs_hz, band(125.0)))
    env, phase = np.abs(z), np.unwrap(np.angle(z))
    env[4000] = 0.0
    starts, stops = segment_bounds(100, x.size - 100, fs_hz, 125.0)
    starts, stops = np.append(starts, 1234), np.append(stops, 1234 + int(rng.integers(50, 90)))
    monkeypatch.setattr(segment_fits, "SEGMENT_BLOCK_SAMPLES", 3 * int(stops[0] - starts[0]))
    seg = log_decrement_segments(env, phase, fs_hz, starts, stops)
    for k, (start, stop) in enumerate(zip(starts, stops)):
        t = np.arange(start, stop) / fs_hz
        if env[start:stop].min() <= 0:
            assert np.isnan(seg["zeta"][k])
            continue
        (slope, log_at_0), (omega_d, _) = (
            np.polyfit(t, values[start:stop], 1) for values in (np.log(env), phase)
        )
        assert seg["zeta"][k] == pytest.approx(-slope / np.hypot(slope, omega_d), rel=1e-10)
        assert seg["frequency_hz"][k] == pytest.approx(omega_d / (2 * np.pi), rel=1e-10)
        log_residual = np.log(env[start:stop]) - (log_at_0 + slope * t)
        assert seg["fit_rms"][k] == pytest.approx(np.sqrt(np.mean(log_residual**2)), rel=1e-6)
        assert seg["amplitude"][k] == pytest.approx(env[start:stop].mean(), rel=1e-12)


@pytest.mark.parametrize("f_hz, zeta, fs_hz, duration_s", LINEAR_CASES)
def test_linear_decay_without_noise_is_unbiased_on_kept_segments(f_hz, zeta, fs_hz, duration_s):
    """The chain's bias, seen where noise is negligible (zeta_std < 0.2 % of zeta)."""
    x = ring_down(f_hz, zeta, fs_hz, duration_s, snr_db=180.0)
    seg = analyse_decay(x, fs_hz, band(f_hz), mode_hz=f_hz).segments
    precise = seg["kept"] & (seg["zeta_std"] < 0.002 * zeta)
    assert precise.sum() >= 3
    assert np.all(np.abs(seg["zeta"][precise] / zeta - 1) < 0.02)
    # The chain's own frequency error on these cases is at most 4.2e-5 of the frequency
    # (20 and 125 Hz at zeta 0.02; 2e-6 at 20 Hz, zeta 5e-4): 1e-4 of it is a 2.4x margin.
    assert np.all(
        np.abs(seg["frequency_hz"][precise] - f_hz * np.sqrt(1 - zeta**2)) < CHAIN_FREQUENCY_BIAS * f_hz
    )
    # The rules removed what was biased: the first segments after the hit are.
    assert not seg["kept"][0]
    assert abs(seg["zeta"][0] / zeta - 1) > 0.01


@pytest.mark.parametrize("f_hz, zeta, fs_hz, duration_s", LINEAR_CASES)
def test_linear_decay_at_40_db_snr_ten_runs(f_hz, zeta, fs_hz, duration_s):
    """A configuration of 10 runs at 40 dB: pooled kept segments recover zeta within 2 %
    and the frequency within the noise's share (the predicted standard error of the pooled
    estimate, x4) plus the chain's own bias; the per-segment standard errors
    are calibrated (normalised errors have unit spread)."""
    zetas, freqs, zeta_std, freq_std = [], [], [], []
    for seed in range(10):
        x = ring_down(f_hz, zeta, fs_hz, duration_s, seed=seed, amplitude=1 + 0.3 * seed)
        seg = analyse_decay(x, fs_hz, band(f_hz), mode_hz=f_hz).kept
        zetas += list(seg["zeta"])
        freqs += list(seg["frequency_hz"])
        zeta_std += list(seg["zeta_std"])
        freq_std += list(seg["frequency_std_hz"])
    zetas, freqs = np.array(zetas), np.array(freqs)
    zeta_std, freq_std = np.array(zeta_std), np.array(freq_std)
    assert zetas.size >= 10
    # Inverse-variance pooling; 50 % overlap makes neighbours correlated: x sqrt(2).
    w = 1 / zeta_std**2
    pooled = np.sum(w * zetas) / np.sum(w)
    pooled_std = np.sqrt(2 / np.sum(w))
    assert abs(pooled / zeta - 1) < max(0.02, 4 * pooled_std / zeta)
    wf = 1 / freq_std**2
    pooled_f = np.sum(wf * freqs) / np.sum(wf)
    # The noise's share (4 predicted standard errors) plus the chain's own bias: achieved
    # 3.1e-5 Hz at 20 Hz (allowed 2.4e-3), 6.5e-2 Hz at 500 Hz, zeta 0.02 (allowed 0.59).
    allowed_hz = 4 * np.sqrt(2 / np.sum(wf)) + CHAIN_FREQUENCY_BIAS * f_hz
    assert abs(pooled_f - f_hz * np.sqrt(1 - zeta**2)) < allowed_hz
    # zeta_std must not understate the scatter (it may overstate it on short records,
    # where the floor's windows are short and include some signal-model error). With
    # 50 % overlap about half the segments are independent; the bound is the 99.9 %
    # point of the sample standard deviation of that many unit normals (1.3 for 100
    # segments, 1.9 for 13).
    from scipy.stats import chi2

    normalised = (zetas - zeta) / zeta_std
    dof = max(zetas.size / 2 - 1, 1)
    assert np.std(normalised) < np.sqrt(chi2.ppf(0.999, dof) / dof)


def test_edge_and_noise_rules_follow_their_definitions():
    f_hz, zeta, fs_hz = 125.0, 0.01, 2560.0
    x = ring_down(f_hz, zeta, fs_hz, 3.2)
    result = analyse_decay(x, fs_hz, band(f_hz), mode_hz=f_hz, edge_time_constants=3.0)
    seg = result.segments
    edge = 3.0 * result.time_constant_s * fs_hz
    reasons = seg["reject_reason"]
    has = np.vectorize(lambda text, code: code in text.split(","))
    np.testing.assert_array_equal(
        has(reasons, "excitation_edge"), seg["start_index"] < result.start_index + edge
    )
    np.testing.assert_array_equal(has(reasons, "record_end"), seg["stop_index"] > x.size - edge)
    np.testing.assert_array_equal(has(reasons, "noise_floor"), seg["min_envelope"] < 10 * result.noise_floor)
    np.testing.assert_array_equal(seg["kept"], reasons == "")
    # The floor is the rms envelope of the in-band noise alone, measured here directly
    # by filtering the same noise: the estimate is within 25 % (20 noise values per
    # window, a low quantile over windows).
    noise = 10 ** (-40 / 20) * np.random.default_rng(0).standard_normal(x.size)
    true_floor = np.sqrt(np.mean(np.abs(analytic_signal(bandpass(noise, fs_hz, band(f_hz)))) ** 2))
    assert result.noise_floor == pytest.approx(true_floor, rel=0.25)


def test_beating_with_a_second_mode_in_band_is_flagged():
    fs_hz, n = 2560.0, 8192
    t = (np.arange(n) - PRETRIGGER) / fs_hz
    on = t >= 0
    x = np.zeros(n)
    for f_hz, a in ((125.0, 1.0), (133.0, 0.3)):  # 8 Hz beat, inside [100, 150] Hz
        x[on] += a * np.exp(-0.005 * 2 * np.pi * f_hz * t[on]) * np.sin(2 * np.pi * f_hz * t[on])
    x += 1e-4 * np.random.default_rng(3).standard_normal(n)
    seg = analyse_decay(x, fs_hz, (100.0, 150.0), mode_hz=125.0).segments
    flagged = np.char.find(seg["reject_reason"].astype(str), "envelope_rise") >= 0
    # The beat makes the envelope swing by +-30 %: most segments above the floor rise.
    above = seg["amplitude"] > 0.05
    assert flagged[above].mean() > 0.5


def test_mode_frequency_is_estimated_from_the_phase_when_not_given():
    x = ring_down(125.0, 0.005, 2560.0, 3.2)
    result = analyse_decay(x, 2560.0, (100.0, 150.0))
    assert result.mode_hz == pytest.approx(125.0, abs=0.05)


def nonlinear_ring_down(fs_hz=2560.0, duration_s=3.2, snr_db=120.0, seed=0):
    """Averaged model of a joint: zeta(A) = z0 + c A^p, softening omega_n(A)."""
    f0_hz, z0, c, p, soft = 125.0, 0.002, 0.01, 0.7, 0.01

    def zeta_of(a):
        return z0 + c * a**p

    def omega_of(a):
        return 2 * np.pi * f0_hz * (1 - soft * a**p)

    def rhs(_t, y):
        a = max(y[0], 0.0)
        return [-zeta_of(a) * omega_of(a) * a, omega_of(a) * np.sqrt(1 - zeta_of(a) ** 2)]

    n = int(round(duration_s * fs_hz))
    t = (np.arange(n) - PRETRIGGER) / fs_hz
    on = t >= 0
    sol = solve_ivp(rhs, (0, t[-1]), [1.0, 0.0], t_eval=t[on], rtol=1e-10, atol=1e-12, method="DOP853")
    x = np.zeros(n)
    x[on] = sol.y[0] * np.cos(sol.y[1])
    x += 10 ** (-snr_db / 20) * np.random.default_rng(seed).standard_normal(n)
    return x, zeta_of, omega_of


def test_amplitude_dependent_damping_and_frequency_are_recovered():
    x, zeta_of, omega_of = nonlinear_ring_down()
    seg = analyse_decay(x, 2560.0, (100.0, 150.0), mode_hz=125.0).kept
    assert seg["zeta"].size >= 20
    a = seg["amplitude"]
    # zeta varies within a segment, so the estimate is its segment average; at the mean
    # amplitude that differs from zeta(A) at second order, well under 3 %. Noise is
    # low (120 dB) so that this tests the estimator's bias, not the noise (which
    # test_linear_decay_at_40_db_snr_ten_runs covers).
    zeta_true = zeta_of(a)
    assert np.all(np.abs(seg["zeta"] / zeta_true - 1) < 0.03)
    f_true = omega_of(a) * np.sqrt(1 - zeta_true**2) / (2 * np.pi)
    # Frequency: within 3 % of the softening shift (f0 - f, up to 1.25 Hz) + 0.02 Hz.
    shift = 125.0 - f_true
    assert np.all(np.abs(seg["frequency_hz"] - f_true) < 0.03 * shift + 0.02)
    # The estimates span the amplitude dependence (not just its flat tail).
    assert seg["zeta"].max() > 3 * seg["zeta"].min()


# --- the NumPy-only filter against scipy.signal's forward-backward Butterworth -------


@pytest.mark.parametrize(
    "fs_hz, band_hz, order",
    [(2560.0, (100.0, 150.0), 10), (1024.0, (15.0, 22.0), 10), (51200.0, (120.0, 180.0), 6)],
)
def test_power_response_matches_scipy_butter_squared(fs_hz, band_hz, order):
    from scipy import signal as sp_signal

    sos = sp_signal.butter(order // 2, band_hz, btype="bandpass", fs=fs_hz, output="sos")
    frequency_hz, response = sp_signal.sosfreqz(sos, worN=4096, fs=fs_hz)
    expected = np.abs(response) ** 2
    got = filters.butterworth_bandpass_power(frequency_hz, fs_hz, band_hz, order)
    # same bilinear design: agreement to rounding in the pass band and the skirts
    assert np.max(np.abs(got - expected)) < 1e-9


def test_bandpass_equals_sosfiltfilt_away_from_the_record_ends():
    from scipy import signal as sp_signal

    rng = np.random.default_rng(3)
    fs_hz, band_hz = 2560.0, (100.0, 150.0)
    x = rng.normal(size=8192)
    sos = sp_signal.butter(5, band_hz, btype="bandpass", fs=fs_hz, output="sos")
    reference = sp_signal.sosfiltfilt(sos, x)
    got = filters.bandpass(x, fs_hz, band_hz, 10)
    # the two differ only in how the record ends are padded; 25 slowest-pole time
    # constants in, that difference has decayed by e^-25 ~ 1e-11
    edge = int(25 * filters.slowest_pole_time_constant_s(band_hz, 10) * fs_hz)
    scale = np.std(reference)
    assert np.max(np.abs(got[edge:-edge] - reference[edge:-edge])) < 1e-9 * scale


def test_analytic_signal_equals_scipy_hilbert():
    from scipy import signal as sp_signal

    rng = np.random.default_rng(4)
    for n in (1001, 1024):
        x = rng.normal(size=n)
        assert np.allclose(filters.analytic_signal(x), sp_signal.hilbert(x), atol=1e-12)


def test_per_run_analysis_does_not_import_scipy_signal():
    import subprocess
    import sys

    code = "import sys, workflow.measured.decay, workflow.measured.runs; print('scipy.signal' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_the_band_power_kept_between_records_gives_the_same_filter():
    """Records of one length, rate and band share the filter's |H|^2 (computed once and
    kept read-only): filtering with it kept gives what filtering anew gives, bit for bit."""
    rng = np.random.default_rng(5)
    fs_hz, band_hz = 2560.0, (100.0, 150.0)
    records = rng.normal(size=(3, 4096))
    filters._padded_band_power.cache_clear()
    fresh = []
    for x in records:
        fresh.append(filters.bandpass(x, fs_hz, band_hz, 10))
        filters._padded_band_power.cache_clear()
    kept = [filters.bandpass(x, fs_hz, np.array(band_hz), 10) for x in records]
    assert filters._padded_band_power.cache_info().hits == 2
    for a, b in zip(fresh, kept):
        assert np.array_equal(a, b)
    _, _, padded = filters._zero_phase_spectrum(records[0], fs_hz, band_hz, 10)
    with pytest.raises(ValueError):
        filters._padded_band_power(padded, fs_hz, band_hz, 10)[0] = 0.0


def test_analytic_bandpass_equals_the_two_sided_inverse_transform():
    """The two real inverse transforms give the analytic signal of the definition (the
    one-sided spectrum doubled, one complex inverse transform), to rounding."""
    rng = np.random.default_rng(6)
    fs_hz, band_hz = 2560.0, (100.0, 150.0)
    for n in (4095, 4096):
        x = rng.normal(size=n)
        spectrum, extension, padded = filters._zero_phase_spectrum(x, fs_hz, band_hz, 10)
        two_sided = np.zeros(padded, dtype=complex)
        two_sided[: spectrum.size] = spectrum
        two_sided[1 : (padded + 1) // 2] *= 2.0
        definition = np.fft.ifft(two_sided)[extension : extension + n]
        got = filters.analytic_bandpass(x, fs_hz, band_hz, 10)
        assert np.max(np.abs(got - definition)) < 1e-14 * np.max(np.abs(definition))
        assert np.array_equal(got.real, filters.bandpass(x, fs_hz, band_hz, 10))


def test_unwrapped_phase_equals_numpys_unwrap_bit_for_bit():
    """Jumps of every size, exact multiples of pi included (np.unwrap's ambiguous case)."""
    rng = np.random.default_rng(7)
    steps = rng.choice([0.3, -0.3, np.pi, -np.pi, 2 * np.pi, 3.5, -4.0, 7.0], size=5000)
    z = np.exp(1j * np.cumsum(steps)) * rng.uniform(0.5, 2.0, size=steps.size)
    assert np.array_equal(filters.unwrapped_phase_rad(z), np.unwrap(np.angle(z)))
    tone = np.exp(1j * 2 * np.pi * 151.0 * np.arange(20000) / 51200.0)
    assert np.array_equal(filters.unwrapped_phase_rad(tone), np.unwrap(np.angle(tone)))


# (mode Hz, damping ratio, sample rate Hz, record s, hit sample): records with a stretch
# between the two transients and records without one, light and heavier damping.
BIAS_CASES = [
    (125.0, 0.0005, 2560.0, 20.0, 300),
    (125.0, 0.02, 2560.0, 20.0, 30),
    (125.0, 0.002, 2560.0, 2.0, 300),
    (151.0, 0.0016, 51200.0, 2.56, 1283),
]


def _whole_record_bias(n, fs_hz, band_hz, mode_hz, zeta, starts, stops, onset):
    """The start-up bias measured on every segment of the whole band-passed synthetic."""
    z = filters.analytic_bandpass(decay._synthetic_decay(n, fs_hz, mode_hz, zeta, onset), fs_hz, band_hz)
    seg = log_decrement_segments(np.abs(z), filters.unwrapped_phase_rad(z), fs_hz, starts, stops)
    return seg["zeta"] / zeta - 1.0, seg["frequency_hz"] - mode_hz * np.sqrt(1.0 - zeta**2)


@pytest.mark.parametrize("f_hz, zeta, fs_hz, duration_s, onset", BIAS_CASES)
def test_startup_bias_equals_the_whole_record_chain(f_hz, zeta, fs_hz, duration_s, onset):
    """The bias measured only within reach of the two transients equals the whole
    record's to rounding (the phase reaches 2 pi f T, 2e4 rad: 1e-12 rad of rounding per
    sample, 1e-10 Hz on a segment's slope), and between the transients the whole
    record's is 0 to rounding too: the chain is exact on an endless decay."""
    n = int(round(duration_s * fs_hz))
    starts, stops = segment_bounds(onset, n, fs_hz, f_hz)
    bias = decay.startup_bias(n, fs_hz, band(f_hz), f_hz, zeta, starts, stops, onset_index=onset)
    zeta_error, frequency_error = _whole_record_bias(n, fs_hz, band(f_hz), f_hz, zeta, starts, stops, onset)
    assert np.abs(bias["zeta_relative_error"] - zeta_error).max() < 1e-10
    assert np.abs(bias["frequency_error_hz"] - frequency_error).max() < 1e-9
    settled = filters.settled_samples(fs_hz, band(f_hz), 10)
    depth = np.exp(-zeta * 2 * np.pi * f_hz * (stops - onset) / fs_hz)
    between = (starts >= onset + settled) & (stops <= n - settled) & (depth >= decay.SYNTHETIC_ROUNDING_DEPTH)
    assert np.abs(zeta_error[between]).max(initial=0.0) < 1e-10
    assert np.abs(frequency_error[between]).max(initial=0.0) < 1e-9
    assert np.abs(zeta_error[:2]).max() > 1e-3  # the transient itself is there and measured


@pytest.mark.parametrize("f_hz, zeta, fs_hz, duration_s, onset", BIAS_CASES)
def test_a_decay_cut_after_the_settling_time_keeps_its_band_passed_envelope_peak(
    f_hz, zeta, fs_hz, duration_s, onset
):
    """Where the band-pass puts a decay's envelope peak does not depend on the record
    beyond SETTLED_TIME_CONSTANTS slowest-pole time constants after the hit: the
    envelope near the peak equals the whole record's to rounding (1e-13 of the peak)."""
    n = int(round(duration_s * fs_hz))
    synthetic = decay._synthetic_decay(n, fs_hz, f_hz, zeta, onset)
    whole = np.abs(filters.analytic_bandpass(synthetic, fs_hz, band(f_hz)))
    reach = min(n, onset + filters.settled_samples(fs_hz, band(f_hz), 10))
    cut = np.abs(filters.analytic_bandpass(synthetic[:reach], fs_hz, band(f_hz)))
    peak = int(np.argmax(whole))
    assert int(np.argmax(cut)) == peak
    near = slice(max(0, peak - 100), min(reach, peak + 100))
    assert np.abs(cut[near] - whole[near]).max() < 1e-13 * whole[peak]


@pytest.mark.parametrize("f_hz, zeta, fs_hz, duration_s, onset", BIAS_CASES)
def test_the_synthetic_decay_is_the_exact_decay_to_the_rounding_of_its_phase(
    f_hz, zeta, fs_hz, duration_s, onset
):
    """The synthetic decay, built from products of complex exponentials, against the
    formula in extended precision: within 2 eps x the phase of each sample (the rounding
    of a phase of thousands of radians, which the direct formula in double precision
    carries too), and 0 before the onset."""
    n = int(round(duration_s * fs_hz))
    synthetic = decay._synthetic_decay(n, fs_hz, f_hz, zeta, onset)
    exact = np.zeros(n, dtype=np.longdouble)
    omega_n = 2 * np.longdouble(np.pi) * np.longdouble(f_hz)
    t = np.arange(n - onset, dtype=np.longdouble) / np.longdouble(fs_hz)
    phase = omega_n * np.sqrt(1 - np.longdouble(zeta) ** 2) * t
    exact[onset:] = np.exp(-np.longdouble(zeta) * omega_n * t) * np.sin(phase)
    assert np.all(synthetic[:onset] == 0.0)
    error = np.abs(synthetic - exact).astype(float)[onset:]
    assert np.all(error <= 2 * np.finfo(float).eps * np.maximum(phase.astype(float), 1.0))
    assert np.array_equal(
        decay._synthetic_decay(n, fs_hz, f_hz, zeta, onset, stop=onset + 5), synthetic[: onset + 5]
    )


@pytest.mark.parametrize("overlap", [0.0, 0.25, 0.5, 0.6, 0.9])
def test_envelope_rise_is_each_segments_largest_rise_to_the_bit(overlap):
    """The rises from blocks of one hop equal each segment's own running minimum's, to the
    bit (minima, maxima and one subtraction of the same two values), for segments that
    end inside a block, at the envelope's last sample, and at irregular starts."""
    from workflow.measured.segment_fits import envelope_rise

    rng = np.random.default_rng(5)
    for trial in range(40):
        n = int(rng.integers(60, 3000))
        noise = rng.standard_normal(n)
        envelope = np.exp(-np.linspace(0, 5, n)) + 0.05 * noise if trial % 2 else noise
        length = int(rng.integers(3, n // 3))
        starts, stops = segment_bounds(int(rng.integers(0, n // 4)), n, 1.0, 1.0, length, overlap)
        if trial % 5 == 0:  # irregular starts: each segment alone
            starts = np.sort(rng.choice(n - length, size=4, replace=False))
            stops = starts + length
        expected = [
            np.max(envelope[a:b] - np.minimum.accumulate(envelope[a:b])) for a, b in zip(starts, stops)
        ]
        assert np.array_equal(envelope_rise(envelope, starts, stops), expected)


@pytest.mark.parametrize("scale_rad", [1e-8, 1e-3, 1.0, 30.0, 1e5])
def test_sine_squared_by_the_tangent_equals_the_sine_to_a_few_units_in_the_last_place(scale_rad):
    from workflow.measured.segment_fits import _sine_squared

    angle_rad = np.random.default_rng(3).normal(scale=scale_rad, size=100_000)
    expected = np.sin(angle_rad) ** 2
    # tan, square, sum and quotient: about four roundings of 1.1e-16 each
    np.testing.assert_allclose(_sine_squared(angle_rad.copy()), expected, rtol=1e-15, atol=0)
    quarter_turns = np.array([np.pi / 2, -np.pi / 2, 3 * np.pi / 2, 0.0])
    np.testing.assert_allclose(_sine_squared(quarter_turns), [1.0, 1.0, 1.0, 0.0], rtol=1e-15, atol=0)

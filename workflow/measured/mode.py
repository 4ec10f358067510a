"""First-mode identification from impact-hammer runs.

The paper estimates the frequency response function (FRF) of the jointed beam from
several hammer hits, reads the first modal frequency off it, and chooses the band-pass
around that mode. These functions do the same for any campaign: an H1 estimate (or a
response-only spectrum when no force was recorded), a peak search inside a frequency
range, and the band around the peak.

Spectra are averaged over runs. Each run is transformed with a *rectangular* window
by default: a hammer record starts with the impulse (a few pre-trigger samples in), and
any tapering window (Hann, ...) would weight that impulse by almost zero and discard the
excitation. Runs of different lengths are handled by giving every run the same segment
length ``nperseg`` (the shortest run by default), so all spectra share one frequency grid.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = [
    "h1_frf",
    "h1_over_channels",
    "response_spectrum",
    "centred_spectra",
    "find_mode_hz",
    "band_around",
    "line_hold_fraction",
    "forced_line_problem",
    "find_decaying_modes",
]

LINE_TRACK_RELATIVE_WIDTH: float = 0.01
"""Standard deviation of the Gaussian band that tracks one spectral line's amplitude over
time, as a fraction of the line's frequency: lines 4 % apart (a shaker's 18.000 Hz
harmonic beside an 18.79 Hz mode) are separated by more than 60 dB, and the track's time
resolution, 1 / (2 pi 0.01 f), is 16 periods of the line."""

STATIONARY_HOLD_FRACTION: float = 0.5
"""A spectral line whose amplitude stays within 3 dB of its peak over at least this
fraction of the analysis window does not decay there: an exponential decay holds 3 dB
for ln(2) / 2 / sigma, so holding half the window means falling by less than a factor 2
across all of it. Such a line is forced (a shaker dwell, mains hum), not a mode."""

TRACK_POINTS_PER_BIN: int = 32
"""Instants per bin of the tracking band at which :func:`line_hold_fraction` reads a
line's track (every sample of a shorter run): the track holds no period shorter than the
run over the band's bins, so 32 instants per bin resolve its 3 dB crossings to 1/32 of
its fastest period, and a long record's track is not computed at every sample (a 131,072
sample record at 51.2 kHz: 9,920 instants for a 151 Hz line)."""

CLEAR_MODE_OVER_FLOOR: float = 10.0
"""Least ratio of a mode's spectral amplitude to the spectrum's median amplitude over
the searched range (20 dB above the noise floor) for ``modes_hz: auto`` to take it."""


def _as_runs(runs: Sequence[np.ndarray], name: str) -> list[np.ndarray]:
    arrays = [np.asarray(run, dtype=float) for run in runs]
    if not arrays:
        raise ValueError(f"{name}: at least one run is needed")
    for index, run in enumerate(arrays):
        if run.ndim != 1:
            raise ValueError(f"{name}[{index}] must be 1-D, got shape {run.shape}")
        if run.size < 2:
            raise ValueError(f"{name}[{index}] has fewer than 2 samples")
        if not np.all(np.isfinite(run)):
            raise ValueError(f"{name}[{index}] contains NaN or inf")
    return arrays


def _segment_length(runs: list[np.ndarray], nperseg: int | None) -> int:
    shortest = min(run.size for run in runs)
    if nperseg is None:
        return shortest
    if not 2 <= nperseg <= shortest:
        raise ValueError(f"nperseg must lie in [2, {shortest}] (the shortest run), got {nperseg}")
    return int(nperseg)


def _segment_spectra(run: np.ndarray, segment: int) -> np.ndarray:
    """Spectra of the run's non-overlapping segments, each mean-removed, rectangular
    window; the samples after the last whole segment are not used."""
    count = run.size // segment
    segments = run[: count * segment].reshape(count, segment)
    return np.fft.rfft(segments - segments.mean(axis=1, keepdims=True), axis=1)


def _cross_spectral_density(
    first_spectra: np.ndarray, second_spectra: np.ndarray, segment: int, fs_hz: float
) -> np.ndarray:
    """One-sided cross-spectral density ``mean(conj(A) B)`` over segments, in
    (unit of A)(unit of B)/Hz; the same as ``scipy.signal.csd`` with a boxcar window,
    no overlap and constant detrending (NumPy only: scipy.signal costs this rule
    a second of import)."""
    density = (np.conj(first_spectra) * second_spectra).mean(axis=0) / (fs_hz * segment)
    # One-sided: every bin but DC (and Nyquist, for an even segment) holds the power of
    # its negative-frequency twin too.
    last = -1 if segment % 2 == 0 else None
    density[1:last] *= 2.0
    return density


def h1_frf(
    force_runs: Sequence[np.ndarray],
    response_runs: Sequence[np.ndarray],
    fs_hz: float,
    nperseg: int | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """H1 frequency response estimate and coherence averaged over hammer runs.

    Parameters
    ----------
    force_runs, response_runs : sequence of 1-D array_like
        Force and response of each run (same number of runs; within a run, the two
        channels have equal length; runs may differ in length). Any units.
    fs_hz : float
        Sample rate, Hz.
    nperseg : int, optional
        Samples per spectral segment, the same for every run so that all spectra share
        one frequency grid. Default: the shortest run's length (one segment per run,
        frequency resolution ``fs_hz / nperseg`` Hz). Runs longer than ``nperseg`` are
        split into non-overlapping segments (Welch averaging within the run).

    Returns
    -------
    frequency_hz : ndarray
        Frequencies, Hz, from 0 to ``fs_hz / 2``.
    h1 : ndarray of complex
        ``G_fx / G_ff`` (response unit per force unit), with cross- and auto-spectra
        averaged over runs before dividing.
    coherence : ndarray
        Ordinary coherence ``|G_fx|**2 / (G_ff * G_xx)``, in [0, 1]. With a single
        segment in total it is identically 1 and carries no information.

    Notes
    -----
    H1 is unbiased by noise on the response channel (noise on the force channel biases
    it low). Averaging spectra, not FRFs, is what makes H1 and the coherence meaningful.
    """
    forces = _as_runs(force_runs, "force_runs")
    responses = _as_runs(response_runs, "response_runs")
    if len(forces) != len(responses):
        raise ValueError(f"{len(forces)} force runs but {len(responses)} response runs; they must pair up")
    for index, (force, response) in enumerate(zip(forces, responses)):
        if force.size != response.size:
            raise ValueError(f"run {index}: force has {force.size} samples, response {response.size}")
    segment = _segment_length(forces, nperseg)
    g_ff = g_xx = g_fx = 0.0
    for force, response in zip(forces, responses):
        force_spectra = _segment_spectra(force, segment)
        response_spectra = _segment_spectra(response, segment)
        g_fx = g_fx + _cross_spectral_density(force_spectra, response_spectra, segment, fs_hz)
        g_ff = g_ff + _cross_spectral_density(force_spectra, force_spectra, segment, fs_hz).real
        g_xx = g_xx + _cross_spectral_density(response_spectra, response_spectra, segment, fs_hz).real
    frequency_hz = np.fft.rfftfreq(segment, 1.0 / fs_hz)
    with np.errstate(divide="ignore", invalid="ignore"):
        h1 = g_fx / g_ff
        coherence = np.abs(g_fx) ** 2 / (g_ff * g_xx)
    # Bins with no force energy (e.g. exactly zero after detrending) have no estimate.
    h1 = np.where(g_ff > 0, h1, np.nan)
    coherence = np.clip(np.where((g_ff > 0) & (g_xx > 0), coherence, np.nan), 0.0, 1.0)
    return frequency_hz, h1, coherence


def h1_over_channels(
    force_runs: Sequence[np.ndarray],
    response_runs: Sequence[np.ndarray],
    channel_of_run: Sequence[str | None],
    fs_hz: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """H1 magnitude and coherence of several response channels, each channel's H1
    averaged over its own runs (:func:`h1_frf`).

    Sensors on either side of a node see a mode with opposite signs: a cross-spectrum
    averaged over channels would cancel the mode, so the channels' ``|H1|`` are summed
    and their coherences averaged instead. With one channel this is :func:`h1_frf`'s
    ``|H1|`` and coherence.

    Parameters
    ----------
    force_runs, response_runs : sequence of 1-D array_like
        Force and response of each (run, channel) pair, as for :func:`h1_frf`.
    channel_of_run : sequence of str or None
        The channel of each pair; pairs of one channel are averaged together.
    fs_hz : float
        Sample rate, Hz.

    Returns
    -------
    frequency_hz : ndarray
        Frequencies, Hz.
    h1_magnitude : ndarray
        Sum over channels of ``|H1|`` (response unit per force unit).
    coherence : ndarray
        Mean over channels of each channel's ordinary coherence, in [0, 1].
    """
    if len(channel_of_run) != len(response_runs):
        raise ValueError(f"{len(channel_of_run)} channel names for {len(response_runs)} responses")
    # one segment length for every channel, so that their spectra share one grid
    segment = _segment_length(_as_runs(force_runs, "force_runs"), None)
    magnitude = coherence = 0.0
    channels = list(dict.fromkeys(channel_of_run))
    for channel in channels:
        mine = [i for i, other in enumerate(channel_of_run) if other == channel]
        frequency_hz, h1, channel_coherence = h1_frf(
            [force_runs[i] for i in mine], [response_runs[i] for i in mine], fs_hz, nperseg=segment
        )
        magnitude = magnitude + np.abs(h1)
        coherence = coherence + channel_coherence
    return frequency_hz, magnitude, coherence / len(channels)


def centred_spectra(response_runs: Sequence[np.ndarray]) -> list[np.ndarray]:
    """One-sided spectrum (``rfft``) of each whole run, its mean removed: what the
    response spectrum of a run in one segment and the line track of every run transform,
    computed once for both."""
    return [np.fft.rfft(run - run.mean()) for run in _as_runs(response_runs, "response_runs")]


def response_spectrum(
    response_runs: Sequence[np.ndarray],
    fs_hz: float,
    nperseg: int | None = None,
    *,
    spectra: Sequence[np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Power spectral density of the response averaged over runs (no force recorded).

    Parameters
    ----------
    response_runs : sequence of 1-D array_like
        Response of each run, any unit U; runs may differ in length.
    fs_hz : float
        Sample rate, Hz.
    nperseg : int, optional
        Samples per segment, common to all runs; default the shortest run's length.
    spectra : sequence of ndarray, optional
        The runs' :func:`centred_spectra`, used for the runs of one segment.

    Returns
    -------
    frequency_hz : ndarray
        Frequencies, Hz.
    psd : ndarray
        One-sided power spectral density, U**2/Hz, averaged over runs.
    """
    responses = _as_runs(response_runs, "response_runs")
    segment = _segment_length(responses, nperseg)
    total = 0.0
    for index, response in enumerate(responses):
        if spectra is not None and response.size == segment:
            segments = spectra[index][None, :]
        else:
            segments = _segment_spectra(response, segment)
        total = total + _cross_spectral_density(segments, segments, segment, fs_hz).real
    return np.fft.rfftfreq(segment, 1.0 / fs_hz), total / len(responses)


def find_mode_hz(frequency_hz: np.ndarray, magnitude: np.ndarray, search_hz: tuple[float, float]) -> float:
    """Frequency of the largest spectral peak inside a search range.

    Parameters
    ----------
    frequency_hz : array_like
        Uniformly spaced, increasing frequencies, Hz.
    magnitude : array_like
        Spectral magnitude at those frequencies (``|H1|``, a PSD, ...; complex values are
        replaced by their modulus). Any unit; only its shape matters.
    search_hz : (float, float)
        Lowest and highest frequency, Hz, where the peak may lie.

    Returns
    -------
    float
        Peak frequency, Hz: the largest local maximum (a bin above both neighbours)
        inside the range, refined by a parabola through the log magnitude of the peak
        bin and its two neighbours. A resonance peak is close to a parabola in log
        magnitude, so the refinement is accurate to a small fraction of a bin.

    Raises
    ------
    ValueError
        If the range holds no interior peak (e.g. the spectrum only rises or falls
        across it, which means the mode lies outside the range).

    Examples
    --------
    The peak of a single-mode FRF at 120 Hz:

    >>> f = np.linspace(0.0, 200.0, 401)
    >>> frf = 1.0 / (1.0 - (f / 120.0) ** 2 + 0.02j * f / 120.0)
    >>> round(find_mode_hz(f, frf, (50.0, 180.0)), 1)
    120.0
    """
    frequency_hz = np.asarray(frequency_hz, dtype=float)
    magnitude = np.abs(np.asarray(magnitude))
    if frequency_hz.shape != magnitude.shape or frequency_hz.ndim != 1:
        raise ValueError("frequency_hz and magnitude must be 1-D arrays of equal length")
    low_hz, high_hz = (float(value) for value in search_hz)
    if not low_hz < high_hz:
        raise ValueError(f"search range must be increasing, got {search_hz}")
    step_hz = np.diff(frequency_hz)
    if step_hz.size == 0 or not np.allclose(step_hz, step_hz[0], rtol=1e-6):
        raise ValueError("frequency_hz must be uniformly spaced")
    # Log of a zero (or NaN) bin is replaced by the smallest finite value so that it can
    # never be a peak but also never breaks the comparison.
    finite = np.isfinite(magnitude) & (magnitude > 0)
    if not finite.any():
        raise ValueError("magnitude has no positive finite value")
    floor = np.log(magnitude[finite].min()) - 1.0
    # Logs only of the interior bins in range (contiguous: the frequencies increase) and
    # of their two neighbours, the only bins compared.
    inside = np.flatnonzero((frequency_hz[1:-1] >= low_hz) & (frequency_hz[1:-1] <= high_hz)) + 1
    first, stop = (int(inside[0]) - 1, int(inside[-1]) + 2) if inside.size else (0, 0)
    finite = finite[first:stop]
    log_mag = np.full(stop - first, floor)
    log_mag[finite] = np.log(magnitude[first:stop][finite])

    # the bins compared with their neighbours as slices (views), not gathered copies
    centre = log_mag[1:-1]
    is_peak = (centre > log_mag[:-2]) & (centre > log_mag[2:])
    candidates = np.flatnonzero(is_peak & finite[1:-1]) + 1
    if candidates.size == 0:
        raise ValueError(
            f"no spectral peak inside the search range {low_hz:g}-{high_hz:g} Hz: the "
            "spectrum only rises or falls there, so the mode lies outside it (widen "
            "the range or check mode_hz)"
        )
    peak = candidates[np.argmax(log_mag[candidates])]
    left, centre, right = log_mag[peak - 1 : peak + 2]
    curvature = left - 2.0 * centre + right  # negative at a strict maximum
    offset_bins = 0.5 * (left - right) / curvature
    return float(frequency_hz[first + peak] + offset_bins * step_hz[0])


def band_around(mode_hz: float, half_width_fraction: float) -> tuple[float, float]:
    """Band-pass edges centred (arithmetically) on a mode.

    Parameters
    ----------
    mode_hz : float
        Mode frequency, Hz (> 0).
    half_width_fraction : float
        Half width as a fraction of ``mode_hz``, in (0, 1).

    Returns
    -------
    (low_hz, high_hz) : tuple of float
        ``mode_hz * (1 - half_width_fraction)``, ``mode_hz * (1 + half_width_fraction)``;
        0.2 around 125 Hz gives the paper's (100, 150) Hz.

    Examples
    --------
    >>> band_around(100.0, 0.2)
    (80.0, 120.0)
    """
    if not mode_hz > 0:
        raise ValueError(f"mode_hz must be positive, got {mode_hz}")
    if not 0 < half_width_fraction < 1:
        raise ValueError(f"half_width_fraction must lie in (0, 1), got {half_width_fraction}")
    return (mode_hz * (1.0 - half_width_fraction), mode_hz * (1.0 + half_width_fraction))


def line_hold_fraction(
    response_runs: Sequence[np.ndarray],
    fs_hz: float,
    line_hz: float,
    *,
    spectra: Sequence[np.ndarray] | None = None,
) -> float:
    """Fraction of the record over which a spectral line stays within 3 dB of its peak.

    Each run's amplitude at ``line_hz`` is tracked over time through a Gaussian band of
    standard deviation :data:`LINE_TRACK_RELATIVE_WIDTH` x ``line_hz`` (analytic signal
    from the FFT, no sidelobes); three track time constants at each end are left out.
    A free decay gives a small fraction (ln 2 / 2 over its decay exponent across the
    window); a forced line, steady while the record lasts, gives nearly 1.

    Parameters
    ----------
    response_runs : sequence of 1-D array_like
        The analysed part of each run, any unit.
    fs_hz : float
        Sample rate, Hz.
    line_hz : float
        Frequency of the line, Hz (below ``fs_hz / 2``).
    spectra : sequence of ndarray, optional
        The runs' :func:`centred_spectra`, when the caller has them.

    Returns
    -------
    float
        The median over runs, in [0, 1]; 0 when no run is long enough to track it.
    """
    sigma_hz = LINE_TRACK_RELATIVE_WIDTH * line_hz
    edge_s = 3.0 / (2.0 * np.pi * sigma_hz)
    fractions = []
    for index, run in enumerate(_as_runs(response_runs, "response_runs")):
        edge = int(np.ceil(edge_s * fs_hz))
        if run.size <= 4 * edge:
            continue
        spectrum = np.fft.rfft(run - run.mean()) if spectra is None else spectra[index]
        track = _line_track(spectrum, run.size, fs_hz, line_hz, sigma_hz, points_per_bin=TRACK_POINTS_PER_BIN)
        edge_points = int(np.ceil(edge * track.size / run.size))
        track = track[edge_points:-edge_points]
        peak = track.max()
        fractions.append(float(np.mean(track >= peak / np.sqrt(2.0))) if peak > 0 else 0.0)
    return float(np.median(fractions)) if fractions else 0.0


def _line_track(
    spectrum: np.ndarray,
    n: int,
    fs_hz: float,
    line_hz: float,
    sigma_hz: float,
    *,
    points_per_bin: int | None = None,
) -> np.ndarray:
    """Amplitude over time of the part of a run of ``n`` samples whose one-sided spectrum
    (``rfft``) is ``spectrum`` in a Gaussian band of standard deviation ``sigma_hz``
    around ``line_hz`` (positive frequencies only: the analytic signal of the band,
    halved), in the unit of the run: at every sample, or with ``points_per_bin`` (2 or
    more) at that many instants per bin of the band, ``j n / points``, spread evenly over
    the run (every sample where that is fewer).

    The band's gain underflows to exactly 0 beyond 40 standard deviations, so it is
    computed inside them only; at 0 Hz and at negative frequencies it is 0 (``line_hz``
    is 100 standard deviations from them). The analytic signal of the band's ``K`` bins
    ``X[k]`` is ``(2 / n) S(t)``, ``S(t) = sum_k X[k] exp(2 pi i k t / n)``, and its
    squared modulus ``|S|^2 = C[0] + 2 Re sum_m C[m] exp(2 pi i m t / n)`` with the
    spectrum's autocorrelation ``C[m] = sum_k X[k + m] conj(X[k])``: one real inverse
    transform of ``C`` (K squared products) instead of two of the band. ``|S|^2`` holds
    no period shorter than ``n / (K - 1)`` samples, so the transform of ``C`` to ``points
    >= 2 K - 1`` values gives it exactly at those instants (a trigonometric polynomial's
    samples), without the samples in between.
    """
    if points_per_bin is not None and points_per_bin < 2:
        raise ValueError(f"points_per_bin must be 2 or more, got {points_per_bin}")
    frequency_hz = np.fft.rfftfreq(n, 1.0 / fs_hz)
    inside = np.flatnonzero(np.abs(frequency_hz - line_hz) < 40.0 * sigma_hz)
    points = n if points_per_bin is None else min(n, points_per_bin * inside.size)
    if not inside.size:
        return np.zeros(n)
    banded = spectrum[inside] * np.exp(-0.5 * ((frequency_hz[inside] - line_hz) / sigma_hz) ** 2)
    autocorrelation = np.correlate(banded, banded, mode="full")[banded.size - 1 :]
    squared = np.fft.irfft(autocorrelation, points)
    # |S|^2 = points irfft(C); rounding may leave it a hair below 0 where the band is
    # silent (in place: at every sample the track is as long as the run)
    np.maximum(squared, 0.0, out=squared)
    squared /= n / points * n
    return np.sqrt(squared, out=squared)


def forced_line_problem(
    response_runs: Sequence[np.ndarray],
    fs_hz: float,
    line_hz: float,
    frequency_hz: np.ndarray,
    magnitude: np.ndarray,
    *,
    spectra: Sequence[np.ndarray] | None = None,
) -> str | None:
    """Why the spectral line at ``line_hz`` is not a mode (it does not decay in the
    analysis window, :func:`line_hold_fraction`), or None when it decays.

    The message names the line and, when it sits at 2 to 5 times a lower line that does
    not decay either, says which harmonic of that line it is (a shaker dwell's). ``spectra``:
    the runs' :func:`centred_spectra`, when the caller has them.
    """
    hold = line_hold_fraction(response_runs, fs_hz, line_hz, spectra=spectra)
    if hold < STATIONARY_HOLD_FRACTION:
        return None
    step_hz = float(frequency_hz[1] - frequency_hz[0])
    harmonic = ""
    for order in range(2, 6):
        base_hz = line_hz / order
        if base_hz < 2 * step_hz:
            break
        near = np.abs(frequency_hz - base_hz) <= 1.5 * step_hz
        if not near.any():
            continue
        local = np.asarray(np.abs(magnitude))[near]
        # a line there: well above the spectrum around it, and steady too
        around = np.abs(frequency_hz - base_hz) <= 0.1 * base_hz
        if local.max() < 10.0 * np.median(np.abs(np.asarray(magnitude))[around]):
            continue
        if line_hold_fraction(response_runs, fs_hz, base_hz, spectra=spectra) >= STATIONARY_HOLD_FRACTION:
            suffix = {2: "nd", 3: "rd"}.get(order, "th")
            harmonic = f", the {order}{suffix} harmonic of the steady line at {base_hz:.3f} Hz"
            break
    return (
        f"the spectral line at {line_hz:.3f} Hz does not decay in the analysis window: it stays "
        f"within 3 dB of its peak over {100 * hold:.0f} % of it (a mode's free decay falls by more "
        f"than half across the window){harmonic}; it is a forced line (a shaker dwell, hum), not a mode"
    )


def _local_peaks(
    frequency_hz: np.ndarray, magnitude: np.ndarray, search_hz: tuple[float, float]
) -> np.ndarray:
    """Indices of the bins above both neighbours inside the search range, largest first."""
    centre = magnitude[1:-1]
    is_peak = (centre > magnitude[:-2]) & (centre >= magnitude[2:])
    in_range = (frequency_hz[1:-1] >= search_hz[0]) & (frequency_hz[1:-1] <= search_hz[1])
    peaks = np.flatnonzero(is_peak & in_range) + 1
    return peaks[np.argsort(magnitude[peaks])[::-1]]


def find_decaying_modes(
    response_runs: Sequence[np.ndarray],
    fs_hz: float,
    frequency_hz: np.ndarray,
    magnitude: np.ndarray,
    search_hz: tuple[float, float],
    band_half_width: float,
    min_prominence: float,
    *,
    spectra: Sequence[np.ndarray] | None = None,
) -> tuple[list[float], list[str]]:
    """Every clear, decaying mode of a spectrum (``modes_hz: auto``).

    A peak is a clear mode when it is the largest within its own band (``band_half_width``
    of its frequency on either side), stands ``min_prominence`` times above the spectrum
    at both band edges, and :data:`CLEAR_MODE_OVER_FLOOR` times above the spectrum's
    median over ``search_hz``; it is a mode only when it decays in the analysis window
    (:func:`forced_line_problem`).

    Parameters
    ----------
    response_runs : sequence of 1-D array_like
        The analysed part of each run (and channel).
    fs_hz : float
        Sample rate, Hz.
    frequency_hz, magnitude : ndarray
        The spectrum (an amplitude: ``|H1|`` or the square root of a PSD).
    search_hz : (float, float)
        Where modes are looked for, Hz.
    band_half_width : float
        Half width of a mode's band, fraction of its frequency.
    min_prominence : float
        Least ratio of a mode's amplitude to the spectrum at its band's edges.
    spectra : sequence of ndarray, optional
        The runs' :func:`centred_spectra`, when the caller has them.

    Returns
    -------
    modes_hz : list of float
        The modes, increasing, each refined as :func:`find_mode_hz` does.
    left_out : list of str
        Why each clear peak that is not a mode was left out (a forced line).
    """
    frequency_hz = np.asarray(frequency_hz, dtype=float)
    magnitude = np.abs(np.asarray(magnitude, dtype=float))
    magnitude = np.where(np.isfinite(magnitude), magnitude, 0.0)
    in_range = (frequency_hz >= search_hz[0]) & (frequency_hz <= search_hz[1])
    floor = float(np.median(magnitude[in_range])) if in_range.any() else 0.0
    modes_hz, left_out = [], []
    for peak in _local_peaks(frequency_hz, magnitude, search_hz):
        peak_hz = float(frequency_hz[peak])
        band = band_around(peak_hz, band_half_width)
        in_band = (frequency_hz >= band[0]) & (frequency_hz <= band[1])
        if magnitude[peak] < magnitude[in_band].max() or magnitude[peak] < CLEAR_MODE_OVER_FLOOR * floor:
            continue
        edges = np.interp(band, frequency_hz, magnitude)
        if magnitude[peak] < min_prominence * edges.max():
            continue
        mode_hz = find_mode_hz(frequency_hz, magnitude, band)
        problem = forced_line_problem(response_runs, fs_hz, mode_hz, frequency_hz, magnitude, spectra=spectra)
        if problem is not None:
            left_out.append(problem)
            continue
        modes_hz.append(mode_hz)
    return sorted(modes_hz), left_out

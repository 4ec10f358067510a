"""Zero-phase Butterworth band-pass and analytic signal of a record, by FFT.

Running a Butterworth filter forward and backward cancels its phase and squares its
magnitude; :func:`bandpass` and :func:`analytic_bandpass` apply that squared magnitude
in the frequency domain (the same linear operator away from the record ends, with NumPy's
FFT only). The decay analysis (:mod:`workflow.measured.decay`) band-passes both parts of
the analytic signal, equal to the paper's band-pass-then-Hilbert on an infinite record
and with far smaller end artefacts on a finite one.

Everything here is unit-agnostic: the output has the unit of the input.
"""

from __future__ import annotations

import functools

import numpy as np

from workflow.measured.settings import AnalysisSettings

__all__ = [
    "analytic_signal",
    "bandpass",
    "envelope",
    "filter_time_constant_s",
    "butterworth_bandpass_power",
    "slowest_pole_time_constant_s",
    "analytic_bandpass",
    "settled_samples",
    "unwrapped_phase_rad",
    "SETTLED_TIME_CONSTANTS",
]


def butterworth_bandpass_power(
    frequency_hz: np.ndarray,
    fs_hz: float,
    band_hz: tuple[float, float],
    order: int = AnalysisSettings.filter_order,
) -> np.ndarray:
    """Squared magnitude |H|^2 of the digital Butterworth band-pass, at given frequencies.

    Parameters
    ----------
    frequency_hz : array_like
        Frequencies, Hz, in ``[0, fs_hz / 2]``.
    fs_hz : float
        Sample rate, Hz.
    band_hz : (float, float)
        Pass band edges (-3 dB of the one-way filter), Hz.
    order : int, optional
        Total band-pass order (even): an order ``order // 2`` low-pass prototype,
        as ``scipy.signal.butter(order // 2, band_hz, 'bandpass', fs=fs_hz)`` designs it.

    Returns
    -------
    ndarray
        ``1 / (1 + ((W**2 - W0**2) / (B W))**order)`` with the bilinear pre-warped
        frequency ``W = 2 fs tan(pi f / fs)``, ``W0**2 = W1 W2`` and ``B = W2 - W1``
        from the band edges: the exact magnitude of the bilinear-transform design.
    """
    half = order // 2
    warp = lambda f: 2.0 * fs_hz * np.tan(np.pi * np.asarray(f, dtype=float) / fs_hz)  # noqa: E731
    w1, w2 = warp(band_hz[0]), warp(band_hz[1])
    w = warp(frequency_hz)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = (w * w - w1 * w2) / ((w2 - w1) * w)
        power = 1.0 / (1.0 + ratio ** (2 * half))
    return np.where(w > 0, np.nan_to_num(power, nan=0.0), 0.0)


SETTLED_TIME_CONSTANTS = 40.0
"""Slowest-pole time constants (:func:`slowest_pole_time_constant_s`) after which the
band-pass's impulse response, and so any start-up transient it causes, is down by
e^-40 (4e-18), below double-precision rounding."""


def settled_samples(fs_hz: float, band_hz: tuple[float, float], order: int) -> int:
    """:data:`SETTLED_TIME_CONSTANTS` slowest-pole time constants, in whole samples."""
    return int(np.ceil(SETTLED_TIME_CONSTANTS * slowest_pole_time_constant_s(band_hz, order) * fs_hz))


def _check_band(fs_hz: float, band_hz: tuple[float, float], order: int) -> tuple[float, float]:
    low_hz, high_hz = (float(edge) for edge in band_hz)
    if order < 2 or order % 2:
        raise ValueError(f"order must be an even integer >= 2, got {order}")
    if not 0.0 < low_hz < high_hz < fs_hz / 2.0:
        raise ValueError(f"band_hz must satisfy 0 < low < high < fs/2 = {fs_hz / 2:g} Hz, got {band_hz}")
    return low_hz, high_hz


@functools.lru_cache(maxsize=8)
def _fast_fft_length(n: int) -> int:
    """Smallest ``2**a * 3**b * 5**c`` not below ``n``: a length NumPy's FFT transforms
    fast (``scipy.fft.next_fast_len`` would do, but importing ``scipy.fft`` costs a
    run-analysis job 0.1-0.2 s, more than the transforms it would speed up)."""
    best = 1 << max(0, int(n - 1).bit_length())
    power5 = 1
    while power5 < best:
        power35 = power5
        while power35 < best:
            # the smallest power of 2 that brings power35 to n or above
            candidate = power35 << max(0, int(-(-n // power35) - 1).bit_length())
            best = min(best, candidate)
            power35 *= 3
        power5 *= 5
    return best


def _zero_phase_spectrum(
    x: np.ndarray, fs_hz: float, band_hz: tuple[float, float], order: int
) -> tuple[np.ndarray, int, int]:
    """One-sided spectrum (``rfft``) of the odd-extended, zero-padded record times |H|^2.

    Returns the filtered one-sided spectrum, the extension length and the padded
    length. The record is extended at each end by a point reflection (continuous
    value and slope) of ``3 * (order + 1)`` samples, the length
    ``scipy.signal.sosfiltfilt`` pads by, then zero-padded by at least
    :data:`SETTLED_TIME_CONSTANTS` slowest-pole time constants (to a length the FFT
    transforms fast) so that the filter's impulse response does not wrap around. The extension is short on
    purpose: for an oscillation the point reflection equals the true continuation plus
    ``2 x_end (1 - cos(omega k))``, an in-band artefact that grows with the extension's
    length ``k`` (measured on a 125 Hz decay: the last segment's damping error was
    +1.3 % with this length, -7.7 % with 15 time constants).
    """
    n = x.size
    extension = int(min(n - 1, 3 * (order + 1)))
    padded = _fast_fft_length(n + 2 * extension + settled_samples(fs_hz, band_hz, order))
    # extended and zero-padded in one array (a concatenation, then padding, copy it twice)
    extended = np.zeros(padded)
    extended[:extension] = 2.0 * x[0] - x[extension:0:-1]
    extended[extension : extension + n] = x
    extended[extension + n : n + 2 * extension] = 2.0 * x[-1] - x[-2 : -extension - 2 : -1]
    spectrum = np.fft.rfft(extended)
    del extended
    # In place: a long record's padded spectrum is the largest array of a run's analysis.
    spectrum *= _padded_band_power(padded, float(fs_hz), (float(band_hz[0]), float(band_hz[1])), order)
    return spectrum, extension, padded


@functools.lru_cache(maxsize=2)
def _padded_band_power(padded: int, fs_hz: float, band_hz: tuple[float, float], order: int) -> np.ndarray:
    """|H|^2 on the one-sided FFT grid of ``padded`` samples (read-only). Kept for the
    next call: the records of a run group or of a fit's simulated batch share their
    length, rate and band, and this was a quarter of each one's analysis."""
    frequency_hz = np.fft.rfftfreq(padded, d=1.0 / fs_hz)
    power = butterworth_bandpass_power(frequency_hz, fs_hz, band_hz, order)
    power.flags.writeable = False
    return power


def bandpass(
    x: np.ndarray, fs_hz: float, band_hz: tuple[float, float], order: int = AnalysisSettings.filter_order
) -> np.ndarray:
    """Zero-phase Butterworth band-pass.

    Parameters
    ----------
    x : array_like
        Signal, any unit, 1-D.
    fs_hz : float
        Sample rate, Hz.
    band_hz : (float, float)
        Pass band edges (-3 dB of the one-way filter), Hz, ``0 < low < high < fs_hz/2``.
    order : int, optional
        Total order of the band-pass (even; the paper's 10).

    Returns
    -------
    ndarray
        Filtered signal, same unit and length as ``x``.

    Notes
    -----
    Running a Butterworth filter forward and backward (``sosfiltfilt``) cancels its
    phase and squares its magnitude; this applies that squared magnitude
    (:func:`butterworth_bandpass_power`) directly in the frequency domain, which
    is the same linear operator away from the record ends and needs only NumPy's
    FFT (a workflow job then starts in a fraction of the time that importing
    ``scipy.signal`` takes). The band edges are -6 dB and the start-up transient
    appears at both ends of the record and on both sides of the hammer hit; the
    segments it spoils are rejected (``excitation_edge``, ``record_end``,
    ``filter_transient``).
    """
    x = np.asarray(x, dtype=float)
    _check_band(fs_hz, band_hz, order)
    spectrum, extension, padded = _zero_phase_spectrum(x, fs_hz, band_hz, order)
    return np.fft.irfft(spectrum, padded)[extension : extension + x.size]


def filter_time_constant_s(band_hz: tuple[float, float]) -> float:
    """Envelope time constant of a band-pass, ``1 / (pi * bandwidth_hz)``, seconds.

    A band-pass of bandwidth B acts on the envelope like a low-pass of cut-off B/2,
    whose time constant is ``1 / (2 pi B/2)``.
    """
    low_hz, high_hz = band_hz
    return 1.0 / (np.pi * (high_hz - low_hz))


def slowest_pole_time_constant_s(
    band_hz: tuple[float, float], order: int = AnalysisSettings.filter_order
) -> float:
    """Decay time of the band-pass impulse response's slowest pole, seconds.

    The Butterworth prototype of order ``N = order // 2`` has its pole closest to
    the imaginary axis at a real part ``sin(pi / (2 N))`` of the cut-off; mapped to
    the band-pass that is a decay rate ``sin(pi / (2 N)) * pi * bandwidth``, slower
    than :func:`filter_time_constant_s` suggests by ``1 / sin(pi / (2 N))`` (3.2 for
    the paper's order 10).
    """
    low_hz, high_hz = band_hz
    return 1.0 / (np.sin(np.pi / order) * np.pi * (high_hz - low_hz))


def _analytic_mask(n: int) -> np.ndarray:
    """FFT weights that turn a real signal's spectrum into its analytic signal's."""
    mask = np.zeros(n)
    mask[0] = 1.0
    if n % 2 == 0:
        mask[n // 2] = 1.0
        mask[1 : n // 2] = 2.0
    else:
        mask[1 : (n + 1) // 2] = 2.0
    return mask


def analytic_signal(x: np.ndarray) -> np.ndarray:
    """Analytic signal ``x + i H[x]`` (discrete Hilbert transform, FFT based).

    Parameters
    ----------
    x : array_like
        Real signal, any unit.

    Returns
    -------
    ndarray of complex
        Its modulus is the envelope of the paper's eq. (1); its unwrapped angle is
        the instantaneous phase, rad. Same definition as ``scipy.signal.hilbert``.
    """
    x = np.asarray(x, dtype=float)
    return np.fft.ifft(np.fft.fft(x) * _analytic_mask(x.size))


def envelope(x: np.ndarray) -> np.ndarray:
    """Envelope ``sqrt(x**2 + H[x]**2)`` (paper eq. 1), same unit as ``x``."""
    return np.abs(analytic_signal(x))


def analytic_bandpass(
    x: np.ndarray, fs_hz: float, band_hz: tuple[float, float], order: int = AnalysisSettings.filter_order
) -> np.ndarray:
    """Analytic signal of the band-passed response.

    Parameters
    ----------
    x : array_like
        Raw response over the whole record, any unit U.
    fs_hz : float
        Sample rate, Hz.
    band_hz : (float, float)
        Pass band, Hz.
    order : int, optional
        Total band-pass order (:func:`bandpass`).

    Returns
    -------
    ndarray of complex
        Its real part equals ``bandpass(x)``; its modulus is the envelope of eq. (1).

    Notes
    -----
    Filtering and the Hilbert transform are both linear and time invariant; here
    both act at once on the extended, zero-padded record. Taking the Hilbert
    transform of the already-cropped filtered record instead (the paper's order,
    literally) would add the transform of the crop: the zero-phase filter spreads
    the hit backward past the first sample, and the Hilbert transform of that
    abrupt cut has a slowly decaying ``1/t`` tail (near 0 Hz) that swamps the
    envelope once the mode has decayed by 60-70 dB (measured: 4e-4 of the initial
    amplitude on a noise-free 125 Hz decay, against 2e-7 this way).
    """
    x = np.asarray(x, dtype=float)
    _check_band(fs_hz, band_hz, order)
    spectrum, extension, padded = _zero_phase_spectrum(x, fs_hz, band_hz, order)
    # The analytic signal's spectrum is the one-sided one doubled (DC and Nyquist once),
    # zero at negative frequencies: its real part is the inverse real FFT of the
    # one-sided spectrum, its imaginary part that of the spectrum times -i (the Hilbert
    # transform). Two real transforms take a third of the time of one complex transform
    # of the padded length.
    record = slice(extension, extension + x.size)
    analytic = np.empty(x.size, dtype=complex)
    inverse = np.fft.irfft(spectrum, padded)
    analytic.real = inverse[record]
    spectrum *= -1j
    analytic.imag = np.fft.irfft(spectrum, padded, out=inverse)[record]
    return analytic


def unwrapped_phase_rad(analytic: np.ndarray) -> np.ndarray:
    """Unwrapped angle of an analytic signal, rad: ``np.unwrap(np.angle(analytic))`` to
    the bit, with the 2 pi corrections computed only at the samples where the angle
    jumps (a few per period) instead of at every sample.

    Examples
    --------
    >>> z = np.exp(1j * 0.9 * np.arange(40))
    >>> bool(np.array_equal(unwrapped_phase_rad(z), np.unwrap(np.angle(z))))
    True
    """
    # np.angle's own arctan2, on contiguous copies of the two parts: the same values in
    # half the time of its strided views
    analytic = np.asarray(analytic)
    phase = np.arctan2(np.ascontiguousarray(analytic.imag), np.ascontiguousarray(analytic.real))
    step = np.diff(phase)
    jumps = np.flatnonzero(~(np.abs(step) < np.pi))
    if not jumps.size:
        return phase
    # np.unwrap's formula, on the jumps only
    jump = step[jumps]
    wrapped = np.mod(jump + np.pi, 2 * np.pi) - np.pi
    wrapped[(wrapped == -np.pi) & (jump > 0)] = np.pi
    # A running sum of the corrections, as np.unwrap's over every step (the steps
    # between jumps add exact zeros); each sample carries those of the jumps before it.
    corrections = np.concatenate([[0.0], np.cumsum(wrapped - jump)])
    counts = np.diff(np.concatenate([[0], jumps + 1, [phase.size]]))
    return phase + np.repeat(corrections, counts)

"""Segment-by-segment estimates of a ring-down's analytic signal: the segments' bounds,
the least-squares lines through ln e(t) and phi(t) that give each segment's damping and
frequency (the paper's eqs. 1-3), the in-band noise floor, the envelope's rise inside a
segment and the noise's standard errors of each estimate.

:func:`workflow.measured.decay.analyse_decay` runs them on a record and flags the
segments that cannot be trusted.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from workflow.measured.settings import AnalysisSettings

__all__ = [
    "SEGMENT_BLOCK_SAMPLES",
    "envelope_rise",
    "log_decrement_segments",
    "noise_floor",
    "noise_standard_errors",
    "segment_blocks",
    "segment_bounds",
    "window_rows",
]


def segment_bounds(
    start_index: int,
    stop_index: int,
    fs_hz: float,
    mode_hz: float,
    segment_cycles: float = AnalysisSettings.segment_cycles,
    segment_overlap: float = AnalysisSettings.segment_overlap,
) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping segments of a fixed number of cycles.

    Parameters
    ----------
    start_index, stop_index : int
        First sample and one past the last sample the segments may cover.
    fs_hz : float
        Sample rate, Hz.
    mode_hz : float
        Frequency of the mode, Hz; sets the segment length.
    segment_cycles : float, optional
        Cycles per segment (the paper's "about 10").
    segment_overlap : float, optional
        Overlap fraction of consecutive segments, in [0, 1).

    Returns
    -------
    starts, stops : ndarray of int
        Segment ``k`` covers samples ``starts[k]:stops[k]``. Segments are
        ``round(segment_cycles * fs_hz / mode_hz)`` samples long (at least 3) and
        advance by ``round(length * (1 - segment_overlap))`` (at least 1). Empty when
        the range is shorter than one segment.
    """
    if not mode_hz > 0 or not fs_hz > 0:
        raise ValueError("mode_hz and fs_hz must be positive")
    if not 0.0 <= segment_overlap < 1.0:
        raise ValueError(f"segment_overlap must lie in [0, 1), got {segment_overlap}")
    length = max(3, int(round(segment_cycles * fs_hz / mode_hz)))
    hop = max(1, int(round(length * (1.0 - segment_overlap))))
    starts = np.arange(int(start_index), int(stop_index) - length + 1, hop, dtype=np.int64)
    return starts, starts + length


def _centred_times_s(length: int, fs_hz: float) -> np.ndarray:
    """Sample times of a window of ``length`` samples from its centre, s (mean 0)."""
    return (np.arange(length) - 0.5 * (length - 1)) / fs_hz


def _line_fits(
    t_centred: np.ndarray, y: np.ndarray, *, residual: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Least-squares ``y = a + b t`` of each row of ``y`` (shape (K, L)) against the
    times ``t_centred`` (shape (L,), mean 0) shared by every row; returns (a at the
    centre, b, rms residual or None without ``residual``), each of shape (K,)."""
    intercept = y.mean(axis=1)
    # Sums along each row (not einsum, whose order depends on the shape, nor np.dot,
    # a threaded BLAS call that stalls on a loaded machine): a row gives the same
    # sums, to the last bit, whether fitted alone or beside others. The times sum to
    # 0, so the slope needs no centred values (their rounding and the products' differ
    # by 1e-14 of an unwrapped phase's slope); the residual does, and the products go
    # into one scratch array: a fresh one per step costs as much as the arithmetic.
    if not residual:
        slope = np.multiply(y, t_centred).sum(axis=1) / np.sum(t_centred * t_centred)
        return intercept, slope, None
    y_centred = y - intercept[:, None]
    scratch = np.multiply(y_centred, t_centred)
    slope = scratch.sum(axis=1) / np.sum(t_centred * t_centred)
    y_centred -= np.multiply(slope[:, None], t_centred, out=scratch)
    return intercept, slope, np.sqrt(np.mean(np.square(y_centred, out=y_centred), axis=1))


SEGMENT_BLOCK_SAMPLES = 2**20
"""Segments are analysed in blocks of at most this many samples (all their samples
side by side, so that a long record's overlapping segments do not fill memory)."""


def window_rows(values: np.ndarray, length: int, first: np.ndarray) -> np.ndarray:
    """The windows ``values[k : k + length]`` for each ``k`` in ``first``, as rows: a view
    when ``first`` advances in equal steps (as :func:`segment_bounds` gives), a copy
    otherwise."""
    rows = sliding_window_view(values, length)
    step = np.diff(first)
    if first.size > 1 and step[0] > 0 and np.all(step == step[0]):
        return rows[first[0] : first[-1] + 1 : step[0]]
    return rows[first]


def segment_blocks(starts: np.ndarray, stops: np.ndarray):
    """Yield ``(rows, length)``: indices of segments of one length, at most
    :data:`SEGMENT_BLOCK_SAMPLES` samples of them at a time."""
    lengths = np.asarray(stops) - np.asarray(starts)
    for length in np.unique(lengths):
        same = np.flatnonzero(lengths == length)
        per_block = max(1, SEGMENT_BLOCK_SAMPLES // max(int(length), 1))
        for rows in np.array_split(same, -(-same.size // per_block)):
            yield rows, int(length)


def log_decrement_segments(
    envelope: np.ndarray,
    phase_rad: np.ndarray,
    fs_hz: float,
    starts: np.ndarray,
    stops: np.ndarray,
    *,
    residuals: bool = True,
) -> dict[str, np.ndarray]:
    """Local damping ratio and frequency of each segment (paper eqs. 2-3).

    Parameters
    ----------
    envelope : array_like
        Envelope of the filtered response over the record, any unit U.
    phase_rad : array_like
        Unwrapped phase of the analytic signal over the record, rad.
    fs_hz : float
        Sample rate, Hz.
    starts, stops : array_like of int
        Segment ``k`` covers samples ``starts[k]:stops[k]`` (from :func:`segment_bounds`).
    residuals : bool, optional
        False leaves ``fit_rms`` NaN (for a caller that needs the slopes only).

    Returns
    -------
    dict of ndarray, one entry per segment:
        ``t_s``: segment centre, s from the first sample; ``amplitude``: mean envelope,
        U; ``zeta``: damping ratio (fraction of critical); ``frequency_hz``: damped
        frequency ``omega_d / 2 pi``, Hz; ``decay_rate_1_s``: ``-s = zeta omega_n``,
        1/s; ``fit_rms``: rms residual of the ln-envelope line (relative amplitude
        scatter); ``min_envelope``: smallest envelope value, U; ``start_index``,
        ``stop_index``.

    Notes
    -----
    For ``x = A exp(-zeta omega_n t) cos(omega_d t)`` the envelope slope is exactly
    ``s = -zeta omega_n`` and the phase slope exactly ``omega_d = omega_n sqrt(1 -
    zeta^2)``, so ``zeta = -s / sqrt(s^2 + omega_d^2)`` holds without the small-damping
    approximation. A growing envelope gives a negative zeta (kept, not clipped).

    Examples
    --------
    The envelope and phase of a 50 Hz mode with 1 % damping, in two segments of one second:

    >>> fs_hz, zeta, omega_n = 1000.0, 0.01, 2 * np.pi * 50.0
    >>> t = np.arange(2000) / fs_hz
    >>> omega_d = omega_n * np.sqrt(1 - zeta**2)
    >>> segments = log_decrement_segments(
    ...     np.exp(-zeta * omega_n * t), omega_d * t, fs_hz, np.array([0, 1000]), np.array([1000, 2000])
    ... )
    >>> segments["zeta"].round(6).tolist(), segments["frequency_hz"].round(3).tolist()
    ([0.01, 0.01], [49.997, 49.997])
    """
    envelope = np.asarray(envelope, dtype=float)
    phase_rad = np.asarray(phase_rad, dtype=float)
    starts = np.asarray(starts, dtype=np.int64)
    stops = np.asarray(stops, dtype=np.int64)
    count = starts.size
    out = {
        name: np.full(count, np.nan)
        for name in (
            "t_s",
            "amplitude",
            "zeta",
            "frequency_hz",
            "decay_rate_1_s",
            "fit_rms",
            "min_envelope",
        )
    }
    with np.errstate(divide="ignore"):
        # ln undefined where the envelope touches 0: those segments are left NaN,
        # flagged invalid_fit by analyse_decay
        log_envelope = np.log(envelope)
    for rows, length in segment_blocks(starts, stops):
        t_centred = _centred_times_s(length, fs_hz)
        first = starts[rows]
        values = window_rows(envelope, length, first)
        out["t_s"][rows] = (first + 0.5 * (length - 1)) / fs_hz
        out["amplitude"][rows] = values.mean(axis=1)
        out["min_envelope"][rows] = values.min(axis=1)
        fit = out["min_envelope"][rows] > 0.0
        rows, first = rows[fit], first[fit]
        _, slope, fit_rms = _line_fits(
            t_centred, window_rows(log_envelope, length, first), residual=residuals
        )
        _, omega_d, _ = _line_fits(t_centred, window_rows(phase_rad, length, first), residual=False)
        if residuals:
            out["fit_rms"][rows] = fit_rms
        out["decay_rate_1_s"][rows] = -slope
        out["zeta"][rows] = -slope / np.hypot(slope, omega_d)
        out["frequency_hz"][rows] = omega_d / (2.0 * np.pi)
    out["start_index"] = starts.copy()
    out["stop_index"] = stops.copy()
    return out


def noise_floor(
    envelope: np.ndarray,
    fs_hz: float,
    *,
    phase_rad: np.ndarray | None = None,
    window_samples: int | None = None,
    start_index: int = 0,
    stop_index: int | None = None,
    quantile: float = 0.25,
    bandwidth_hz: float | None = None,
) -> float:
    """In-band noise floor of a ring-down, estimated from the record itself.

    Parameters
    ----------
    envelope : array_like
        Envelope of the band-passed response, any unit U.
    fs_hz : float
        Sample rate, Hz (only used for the default window).
    phase_rad : array_like, optional
        Unwrapped analytic-signal phase, rad. With it, the noise is also measured
        under the decaying signal (see Notes); without it only where noise dominates.
    window_samples : int, optional
        Length of the windows the range is cut into. Default 0.1 s worth of samples.
        Use several noise correlation times (``>> 1 / bandwidth``).
    start_index, stop_index : int, optional
        Range to use (the decay, clear of the filter's end effects).
    quantile : float, optional
        Quantile of the per-window estimates returned (low, because signal-model
        error only ever adds to a window's estimate).
    bandwidth_hz : float, optional
        Noise bandwidth, Hz. With it, the residual of the 4-parameter phasor fit is
        corrected for the degrees of freedom the fit absorbs: a window of duration T
        holds about ``bandwidth_hz * T`` independent noise values, and the residual
        variance is low by the factor ``1 - 4 / (bandwidth_hz * T)``.

    Returns
    -------
    float
        RMS amplitude of the noise's envelope, U: ``sqrt(2) * sigma`` for in-band
        noise of standard deviation sigma (the envelope level that noise alone shows).

    Notes
    -----
    Rule: cut the range into non-overlapping windows. In each, model the analytic
    signal as one exponentially decaying, linearly advancing phasor
    ``exp(a + s t + i (phi0 + omega t))`` (least-squares lines through ln e and phi)
    and take the rms of the complex residual, which is ``sqrt(2) sigma`` wherever the
    signal dominates (both quadratures of the noise remain); also take the rms of the
    envelope itself, which is ``sqrt(2) sigma`` where noise dominates. The window's
    estimate is the smaller of the two, and the floor the ``quantile`` over windows.
    Unlike "the quietest stretch of the record" this still works when the record ends
    long before the decay reaches the noise (light damping), where the quietest
    stretch is still signal. Beating with another mode in the band counts as noise
    here, which is what it is for a single-mode estimate.
    """
    envelope = np.asarray(envelope, dtype=float)
    stop_index = envelope.size if stop_index is None else int(stop_index)
    start_index = int(start_index)
    if window_samples is None:
        window_samples = int(round(0.1 * fs_hz))
    window_samples = max(8, int(window_samples))
    if stop_index - start_index < window_samples:
        # Too short for windows: one window over whatever there is.
        window_samples = max(2, stop_index - start_index)
    if stop_index - start_index < 2:
        raise ValueError("noise_floor needs at least 2 samples in [start_index, stop_index)")
    count = (stop_index - start_index) // window_samples
    windows = envelope[start_index : start_index + count * window_samples].reshape(count, window_samples)
    estimates = np.sqrt(np.mean(windows**2, axis=1))
    if phase_rad is not None:
        phases = np.asarray(phase_rad, dtype=float)[start_index : start_index + count * window_samples]
        phases = phases.reshape(count, window_samples)
        t_centred = _centred_times_s(window_samples, fs_hz)
        fitted = np.flatnonzero(windows.min(axis=1) > 0)
        per_block = max(1, SEGMENT_BLOCK_SAMPLES // window_samples)
        for rows in np.array_split(fitted, -(-fitted.size // per_block)) if fitted.size else ():
            every = rows.size == count  # all windows: views, no copies
            values, phase = (windows, phases) if every else (windows[rows], phases[rows])
            a, s, _ = _line_fits(t_centred, np.log(values), residual=False)
            phi0, omega, _ = _line_fits(t_centred, phase, residual=False)
            # |v e^(i phase) - m e^(i psi)|^2 = (v - m)^2 + 4 v m sin^2((phase - psi) / 2):
            # the complex residual without complex exponentials or cancellation; computed
            # in place, in this order of operations
            model = np.multiply(s[:, None], t_centred)
            np.exp(np.add(a[:, None], model, out=model), out=model)
            half_angle = phase - phi0[:, None]
            half_angle -= omega[:, None] * t_centred
            half_angle *= 0.5
            sine_squared = _sine_squared(half_angle)
            cross = np.multiply(4.0, values)
            cross *= model
            cross *= sine_squared
            squared = np.subtract(values, model, out=model)
            np.square(squared, out=squared)
            squared += cross
            residual = np.sqrt(np.mean(squared, axis=1))
            if bandwidth_hz is not None:
                dof = bandwidth_hz * window_samples / fs_hz
                residual = residual / np.sqrt(max(1.0 - 4.0 / dof, 0.25))
            estimates[rows] = np.minimum(estimates[rows], residual)
    # "lower": an actual window's value, so that with a few windows one clean window
    # is enough (interpolating towards a window spoilt by a transient is not).
    return float(np.quantile(estimates, quantile, method="lower"))


def _sine_squared(angle_rad: np.ndarray) -> np.ndarray:
    """``sin(angle)**2``, in place of ``angle``, as ``tan**2 / (1 + tan**2)``: NumPy's
    float64 tangent is vectorised and its sine is not (0.09 against 0.8 ms on 100,000
    angles), and the two agree to a few units in the last place (the tangent of a double
    is finite: no angle in floating point is an odd multiple of pi / 2)."""
    tangent_squared = np.square(np.tan(angle_rad, out=angle_rad), out=angle_rad)
    return np.divide(tangent_squared, 1.0 + tangent_squared, out=tangent_squared)


def envelope_rise(envelope: np.ndarray, starts: np.ndarray, stops: np.ndarray) -> np.ndarray:
    """Largest rise of the envelope inside each segment.

    Parameters
    ----------
    envelope : array_like
        Envelope over the record, U.
    starts, stops : array_like of int
        Segments.

    Returns
    -------
    ndarray
        ``max over i <= j of e[j] - e[i]`` within each segment, U (0 for a
        non-increasing envelope).
    """
    envelope = np.asarray(envelope, dtype=float)
    starts = np.asarray(starts, dtype=np.int64)
    rises = np.zeros(starts.size)
    for rows, length in segment_blocks(starts, stops):
        first = starts[rows]
        step = np.diff(first)
        if first.size > 1 and 0 < step[0] <= length and np.all(step == step[0]):
            rises[rows] = _rises_in_steps(envelope, int(first[0]), int(step[0]), first.size, length)
        else:
            for row, start in zip(rows, first):
                rises[row] = _rises_in_steps(envelope, int(start), length, 1, length)[0]
    return rises


def _rises_in_steps(envelope: np.ndarray, first: int, step: int, count: int, length: int) -> np.ndarray:
    """:func:`envelope_rise` of ``count`` segments of ``length`` samples starting every
    ``step <= length`` samples from ``first``.

    The samples are cut into blocks of ``step``: a segment is ``q`` whole blocks and the
    first ``r`` samples of the next (``length = q step + r``), and its rise is the largest
    of each part's own rise and of each part's highest value less the lowest before it.
    Each sample's running minimum is taken once, in its block, instead of once in every
    segment that holds it; minima, maxima and one subtraction of the same two values give
    the same numbers as the segments' own running minima, to the bit (tested)."""
    q, r = divmod(length, step)
    blocks = count + q - (0 if r else 1)
    span = envelope[first : first + blocks * step]
    if span.size < blocks * step:  # only the first r samples of the last block are used
        span = np.concatenate([span, np.zeros(blocks * step - span.size)])
    values = span.reshape(blocks, step)
    lowest = np.minimum.accumulate(values, axis=1)
    block_lowest = lowest[:, -1].copy()
    rise_in_block = np.subtract(values, lowest, out=lowest)
    block_rise, block_highest = rise_in_block.max(axis=1), values.max(axis=1)
    rises, low = block_rise[:count].copy(), block_lowest[:count].copy()
    for part in range(1, q):
        rows = slice(part, part + count)
        np.maximum(rises, np.maximum(block_rise[rows], block_highest[rows] - low), out=rises)
        np.minimum(low, block_lowest[rows], out=low)
    if r:
        rows = slice(q, q + count)
        rise_in_prefix = rise_in_block[rows, :r].max(axis=1)
        np.maximum(rises, np.maximum(rise_in_prefix, values[rows, :r].max(axis=1) - low), out=rises)
    return rises


def noise_standard_errors(
    env: np.ndarray,
    floor: float,
    fs_hz: float,
    starts: np.ndarray,
    stops: np.ndarray,
    *,
    low_hz: float,
    high_hz: float,
    frequency_hz: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Standard errors of each segment's zeta and frequency due to in-band noise.

    In-band noise of standard deviation sigma = floor / sqrt(2) perturbs ln e and the
    phase by sigma / e per sample (each quadrature), with a spectrum flat over a
    two-sided width equal to the bandwidth B, i.e. density sigma^2 / B at 0 Hz. The
    least-squares slope over a segment of duration T then has variance
    ``12 * mean((sigma / e)^2) / (B * T^3)`` (valid for T >> 1/B, conservative
    otherwise). zeta_std = slope_std / omega_n; frequency_std = slope_std / (2 pi).
    """
    bandwidth_hz = high_hz - low_hz
    sigma = floor / np.sqrt(2.0)
    zeta_std = np.full(starts.size, np.nan)
    frequency_std = np.full(starts.size, np.nan)
    relative_power = (sigma / np.maximum(env, 1e-300)) ** 2
    for rows, length in segment_blocks(starts, stops):
        duration_s = length / fs_hz
        relative = window_rows(relative_power, length, starts[rows]).mean(axis=1)
        slope_std = np.sqrt(12.0 * relative / (bandwidth_hz * duration_s**3))
        zeta_std[rows] = slope_std / (2.0 * np.pi * frequency_hz[rows])
        frequency_std[rows] = slope_std / (2.0 * np.pi)
    return zeta_std, frequency_std

"""Piecewise-linear log decrement of one ring-down record (the paper's eqs. 1-3).

The chain for one run is::

    response --Hilbert--> analytic --bandpass (both parts)--> z = e * exp(i phi)
    (equal to the paper's band-pass-then-Hilbert on an infinite record; far smaller
    end artefacts on a finite one, see workflow.measured.filters.analytic_bandpass)
    segments of ~10 cycles: least-squares lines through ln e(t) and phi(t)
    slope of ln e:  s = -zeta * omega_n ;  slope of phi: omega_d = omega_n sqrt(1 - zeta^2)
    => zeta = -s / sqrt(s^2 + omega_d^2),  amplitude = mean of e over the segment

Every segment is returned; the ones that cannot be trusted are flagged with the
rule that rejected them (``kept`` False, ``reject_reason`` a comma-separated list of
the codes below) instead of being dropped, so that a reader can see what was removed
and why. The rules are computed from the data and the filter, never from hand-picked
times (docs/decay_analysis.md gives the measured effect of each):

``excitation_edge``
    The segment starts less than ``edge_time_constants`` filter time constants
    ``tau = 1 / (pi * bandwidth_hz)`` after the decay start (the excitation peak). The
    zero-phase band-pass smears the hit over about tau on both sides, and the
    envelope there is the filter's start-up transient, not the mode's decay.
``record_end``
    The segment ends less than ``edge_time_constants`` time constants before the end
    of the record, where the backward pass of the zero-phase filter starts up (and
    the FFT-based Hilbert transform wraps around).
``filter_transient``
    Running the same chain on a noise-free synthetic linear decay with the record's
    frequency, median damping, band and length (:func:`startup_bias`) gives an error
    above ``bias_tolerance`` (1 %) in damping, or above ``FREQUENCY_BIAS_TOLERANCE_HZ``
    in frequency, on this segment. The filter transients decay at the
    rate of the band-pass's slowest poles, but their effect is relative to the mode's
    own decay rate, so light damping needs far more than a fixed number of time
    constants (measured: 19 tau at 0.05 % damping, 12.5 tau at 2 %).
``noise_floor``
    The segment's smallest envelope value is below ``noise_floor_factor`` times the
    in-band noise floor (:func:`~workflow.measured.segment_fits.noise_floor`): the log of a noise-dominated envelope
    is biased and its slope meaningless.
``envelope_rise``
    The envelope rises inside the segment by more than ``RISE_FLOOR_FACTOR`` noise
    floors. A free decay of a single mode never grows, whatever its damping law; a
    rise beyond what noise does means beating with another mode inside the band, or
    a transient (a second hit, filter ringing), and a line through ln e there is wrong.
``off_band``
    The segment's frequency lies outside the pass band: whatever the phase follows
    there, it is not the filtered mode.
``invalid_fit``
    The envelope touches zero or the fit is not finite.

Everything here is unit-agnostic: the response may be in any unit; the amplitudes
come out in that unit.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from workflow.measured.filters import (
    analytic_bandpass,
    filter_time_constant_s,
    settled_samples,
    unwrapped_phase_rad,
)
from workflow.measured.segment_fits import (
    envelope_rise,
    log_decrement_segments,
    noise_floor,
    noise_standard_errors,
    segment_bounds,
)
from workflow.measured.settings import AnalysisSettings

__all__ = [
    "DecayResult",
    "REJECT_CODES",
    "RISE_FLOOR_FACTOR",
    "analyse_decay",
    "startup_bias",
]


REJECT_CODES = (
    "excitation_edge",
    "record_end",
    "filter_transient",
    "noise_floor",
    "envelope_rise",
    "off_band",
    "invalid_fit",
)
"""Codes that may appear (comma-separated) in ``segments['reject_reason']``."""


FREQUENCY_BIAS_TOLERANCE_HZ = 0.005
"""Largest start-up bias of a segment's frequency that the ``filter_transient`` rule
accepts, Hz: a quarter of the 0.02 Hz accuracy the analysis is held to, because the
synthetic decay follows the transient's decay but not the hit's exact shape
(measured: it predicted 0.0067 Hz where a 500 Hz, 2 % decay showed 0.0204 Hz)."""


SYNTHETIC_ROUNDING_DEPTH = 1e-6
"""Fraction of its start below which the synthetic decay of :func:`startup_bias` is
analysed on every segment: there the FFT's rounding, 1e-16 of the start, exceeds 1e-10
of the decay, and what the chain gives is no longer the endless decay's exact answer."""


RISE_FLOOR_FACTOR = 4.0
"""Envelope rise, in noise floors, beyond which a segment is flagged ``envelope_rise``.

The noise floor is the RMS noise envelope sqrt(2)*sigma, where sigma is the standard
deviation of the in-band noise; on a strong signal the envelope fluctuates with standard
deviation sigma, so 4 floors = 5.7 sigma, above the largest rise noise alone produces
over a segment of a few correlation times (about 2 sqrt(2 ln N) sigma for N independent
values, under 5 sigma for N < 20)."""


@dataclass
class DecayResult:
    """Everything :func:`analyse_decay` computed for one record.

    Attributes
    ----------
    filtered, envelope, phase_rad : ndarray
        Band-passed response (U), its envelope (U) and unwrapped phase (rad), over the
        whole record.
    noise_floor : float
        In-band noise floor, U (:func:`~workflow.measured.segment_fits.noise_floor`).
    start_index, stop_index : int
        Decay start (excitation peak unless given) and end of the analysed range.
    mode_hz : float
        Mode frequency used for the segment length, Hz.
    band_hz : (float, float)
        Band-pass edges, Hz.
    time_constant_s : float
        Filter envelope time constant ``1 / (pi * bandwidth)``, s.
    segments : dict of ndarray
        :func:`~workflow.measured.segment_fits.log_decrement_segments` output plus ``zeta_std`` and
        ``frequency_std_hz`` (standard errors due to the in-band noise),
        ``envelope_rise`` (U), ``startup_bias_zeta`` and ``startup_bias_hz`` (the
        chain's own error on a synthetic decay, :func:`startup_bias`), ``kept``
        (bool) and ``reject_reason`` (str, "" when kept, else comma-separated codes
        of :data:`REJECT_CODES`).
    """

    filtered: np.ndarray
    envelope: np.ndarray
    phase_rad: np.ndarray
    noise_floor: float
    start_index: int
    stop_index: int
    mode_hz: float
    band_hz: tuple[float, float]
    time_constant_s: float
    segments: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def kept(self) -> dict[str, np.ndarray]:
        """The kept segments only."""
        mask = self.segments["kept"]
        return {name: values[mask] for name, values in self.segments.items()}


def _synthetic_decay(
    n_samples: int, fs_hz: float, mode_hz: float, zeta: float, onset_index: int, stop: int | None = None
) -> np.ndarray:
    """Unit ``exp(-zeta omega_n t) sin(omega_d t)`` from rest at ``onset_index``, its first
    ``stop`` samples (default all ``n_samples``)."""
    stop = n_samples if stop is None else min(int(stop), n_samples)
    x = np.zeros(stop)
    if onset_index < stop:
        x[onset_index:] = _decay_from_rest(n_samples, fs_hz, mode_hz, zeta)[: stop - onset_index]
    return x


@functools.lru_cache(maxsize=1)
def _decay_from_rest(n_samples: int, fs_hz: float, mode_hz: float, zeta: float) -> np.ndarray:
    """Unit ``exp(-zeta omega_n t) sin(omega_d t)`` at ``t = k / fs_hz``, ``k`` from 0 to
    ``n_samples - 1`` (read-only). Kept for the next call: a record's probe and its
    start-up bias are the same decay started at two samples.

    It is the imaginary part of ``exp(p k)``, ``p = (-zeta omega_n + i omega_d) / fs_hz``,
    taken as ``exp(p B b) exp(p j)`` for ``k = B b + j``, ``B`` about ``sqrt(n_samples)``:
    2 sqrt(n) complex exponentials and n products instead of an exponential and a sine of
    every sample (NumPy's float64 sine is not vectorised): a third of their time. Either
    way the phase of sample ``k`` is rounded once it is thousands of radians: both are
    within 2 eps x that phase of the exact decay (tested).
    """
    omega_n = 2.0 * np.pi * mode_hz
    pole = complex(-zeta * omega_n, omega_n * np.sqrt(1.0 - zeta**2)) / fs_hz
    block = max(1, int(np.ceil(np.sqrt(n_samples))))
    within = np.exp(pole * np.arange(block))
    block_starts = np.exp(pole * block * np.arange(-(-n_samples // block)))
    x = np.multiply.outer(block_starts.real, within.imag)
    x += np.multiply.outer(block_starts.imag, within.real)
    x = x.ravel()[:n_samples]
    x.flags.writeable = False
    return x


def startup_bias(
    n_samples: int,
    fs_hz: float,
    band_hz: tuple[float, float],
    mode_hz: float,
    zeta: float,
    starts: np.ndarray,
    stops: np.ndarray,
    *,
    onset_index: int,
    filter_order: int = AnalysisSettings.filter_order,
) -> dict[str, np.ndarray]:
    """Bias the analysis chain itself puts on each segment of a known linear decay.

    Parameters
    ----------
    n_samples : int
        Record length, samples.
    fs_hz : float
        Sample rate, Hz.
    band_hz : (float, float)
        Pass band, Hz.
    mode_hz : float
        Undamped natural frequency of the synthetic decay, Hz.
    zeta : float
        Its damping ratio (> 0).
    starts, stops : array_like of int
        Segments to evaluate.
    onset_index : int
        Sample at which the synthetic decay starts from rest (the hit).
    filter_order : int, optional
        Band-pass order.

    Returns
    -------
    dict of ndarray
        ``zeta_relative_error`` (estimate / truth - 1) and ``frequency_error_hz``
        (estimate - damped frequency) of each segment, on a noise-free
        ``exp(-zeta omega_n t) sin(omega_d t)`` starting at ``onset_index``; exactly 0
        on the segments out of both transients' reach
        (:func:`~workflow.measured.filters.settled_samples` from the onset and from the
        record end) while the decay stays above :data:`SYNTHETIC_ROUNDING_DEPTH` of its
        start, the chain's answer on an endless decay (the whole record's chain gives
        1e-11 there).

    Notes
    -----
    The filter start-up transient after the hit and the backward pass's start-up at
    the record end decay at the rate of the band-pass's slowest poles (for a
    Butterworth of total order N, ``sin(pi / N)`` times slower than ``1/tau``), while
    their effect on the damping estimate is relative to the mode's own decay rate.
    How long they matter therefore depends on the damping itself (light damping
    needs longer), which a fixed number of time constants cannot capture; running
    the chain on a synthetic decay with the record's parameters measures it.
    """
    starts = np.asarray(starts, dtype=np.int64)
    stops = np.asarray(stops, dtype=np.int64)
    synthetic = _synthetic_decay(n_samples, fs_hz, mode_hz, zeta, onset_index)
    z = analytic_bandpass(synthetic, fs_hz, band_hz, filter_order)
    bias = {
        "zeta_relative_error": np.zeros(starts.size),
        "frequency_error_hz": np.zeros(starts.size),
    }
    # Between the two transients the chain sees an endless decay, on which its estimates
    # are exact: the bias there is 0 (measured: 1e-14 and below), and only the segments
    # within reach of the onset or of the record end are analysed, and those where the
    # decay has fallen so far that the transform's rounding (1e-16 of its start) is no
    # longer negligible (SYNTHETIC_ROUNDING_DEPTH).
    settled = settled_samples(fs_hz, band_hz, filter_order)
    deep = onset_index + np.log(1.0 / SYNTHETIC_ROUNDING_DEPTH) / (zeta * 2.0 * np.pi * mode_hz) * fs_hz
    near_onset = np.flatnonzero(starts < onset_index + settled)
    near_end = np.flatnonzero(stops > min(n_samples - settled, deep))
    if near_onset.size and near_end.size and stops[near_onset].max() >= starts[near_end].min():
        groups = [np.union1d(near_onset, near_end)]
    else:
        groups = [rows for rows in (near_onset, near_end) if rows.size]
    for rows in groups:
        first, last = int(starts[rows].min()), int(stops[rows].max())
        part = z[first:last]
        estimates = log_decrement_segments(
            np.abs(part),
            unwrapped_phase_rad(part),
            fs_hz,
            starts[rows] - first,
            stops[rows] - first,
            residuals=False,
        )
        bias["zeta_relative_error"][rows] = estimates["zeta"] / zeta - 1.0
        bias["frequency_error_hz"][rows] = estimates["frequency_hz"] - mode_hz * np.sqrt(1.0 - zeta**2)
    return bias


def analyse_decay(
    response: np.ndarray,
    fs_hz: float,
    band_hz: tuple[float, float],
    *,
    mode_hz: float | None = None,
    filter_order: int = AnalysisSettings.filter_order,
    segment_cycles: float = AnalysisSettings.segment_cycles,
    segment_overlap: float = AnalysisSettings.segment_overlap,
    noise_floor_factor: float = AnalysisSettings.noise_floor_factor,
    edge_time_constants: float = AnalysisSettings.edge_time_constants,
    start_index: int | None = None,
    stop_index: int | None = None,
    bias_tolerance: float = 0.01,
) -> DecayResult:
    """Local damping and frequency versus amplitude for one ring-down record.

    Parameters
    ----------
    response : array_like
        Measured response over the whole record (pre-trigger included), any unit U.
    fs_hz : float
        Sample rate, Hz.
    band_hz : (float, float)
        Band-pass edges around the mode, Hz.
    mode_hz : float, optional
        Mode frequency, Hz, for the segment length. Default: the mean instantaneous
        frequency of the filtered decay, weighted by the squared envelope.
    filter_order : int, optional
        Total Butterworth band-pass order (even).
    segment_cycles, segment_overlap : float, optional
        Segment length in cycles and overlap fraction (:func:`~workflow.measured.segment_fits.segment_bounds`).
    noise_floor_factor : float, optional
        Segments whose smallest envelope value is below this times the noise floor
        are rejected (``noise_floor``).
    edge_time_constants : float, optional
        Segments within this many filter time constants of the decay start or of the
        record end are rejected (``excitation_edge``, ``record_end``).
    start_index : int, optional
        First sample of the free decay. Default: the envelope's maximum (the
        excitation peak as seen through the band-pass) before ``stop_index``.
    stop_index : int, optional
        One past the last sample analysed; default the record end.
    bias_tolerance : float, optional
        Segments where the chain's own bias on a synthetic linear decay with this
        record's frequency and (median) damping exceeds this relative damping error
        are rejected (``filter_transient``; :func:`startup_bias`).

    Returns
    -------
    DecayResult
        See its documentation; rejected segments are flagged, not removed.
    """
    response = np.asarray(response, dtype=float)
    if response.ndim != 1:
        raise ValueError(f"response must be 1-D, got shape {response.shape}")
    if not np.all(np.isfinite(response)):
        raise ValueError("response contains NaN or inf")
    n = response.size
    stop = n if stop_index is None else int(stop_index)
    if not 0 < stop <= n:
        raise ValueError(f"stop_index must lie in (0, {n}], got {stop_index}")

    z = analytic_bandpass(response, fs_hz, band_hz, filter_order)
    env = np.abs(z)
    phase = unwrapped_phase_rad(z)
    filtered = z.real.copy()
    del z  # a long record's largest array: only its parts above are used

    start = int(np.argmax(env[:stop])) if start_index is None else int(start_index)
    if not 0 <= start < stop:
        raise ValueError(f"start_index must lie in [0, {stop}), got {start_index}")

    if mode_hz is None:
        weights = env[start:stop] ** 2
        inst_hz = np.gradient(phase[start:stop]) * fs_hz / (2.0 * np.pi)
        mode_hz = float(np.sum(weights * inst_hz) / np.sum(weights))

    tau_s = filter_time_constant_s(band_hz)
    edge = int(np.ceil(edge_time_constants * tau_s * fs_hz))
    starts, stops = segment_bounds(start, stop, fs_hz, mode_hz, segment_cycles, segment_overlap)
    segments = log_decrement_segments(env, phase, fs_hz, starts, stops)

    bandwidth_hz = band_hz[1] - band_hz[0]
    # The floor is measured clear of the filter's end effects, in windows at least one
    # segment long and long against the noise correlation time 1/bandwidth (20
    # independent noise values, the 4 the phasor fit absorbs corrected for; windows of
    # 6 correlation times, uncorrected, underestimated it by a factor 1.45).
    # Short records get at least 4 windows (a low quantile needs several).
    window = max(
        int(stops[0] - starts[0]) if starts.size else 0,
        min(int(round(20 * fs_hz / bandwidth_hz)), (stop - start) // 4),
    )

    def measure_floor(first: int, last: int) -> float:
        if last - first < 2:
            first, last = start, stop
        return noise_floor(
            env,
            fs_hz,
            phase_rad=phase,
            window_samples=window,
            start_index=first,
            stop_index=last,
            bandwidth_hz=bandwidth_hz,
        )

    def data_checks(floor: float) -> dict[str, np.ndarray]:
        finite = np.isfinite(segments["zeta"]) & np.isfinite(segments["frequency_hz"])
        frequency_hz = np.where(finite, segments["frequency_hz"], band_hz[0])
        return {
            "excitation_edge": starts < start + edge,
            "record_end": stops > n - edge,
            "noise_floor": segments["min_envelope"] < noise_floor_factor * floor,
            "envelope_rise": rise > RISE_FLOOR_FACTOR * floor,
            "off_band": (frequency_hz < band_hz[0]) | (frequency_hz > band_hz[1]),
            "invalid_fit": ~finite,
            "filter_transient": np.zeros(starts.size, dtype=bool),
        }

    rise = envelope_rise(env, starts, stops)
    # Pass 1: a floor from everything clear of the fixed edges, to find the segments
    # that look usable and the record's typical damping and frequency.
    floor = measure_floor(start + edge, min(stop, n - edge))
    checks = data_checks(floor)
    preliminary = ~np.any(list(checks.values()), axis=0)
    bias = {
        "zeta_relative_error": np.full(starts.size, np.nan),
        "frequency_error_hz": np.full(starts.size, np.nan),
    }
    zeta_ref = float(np.median(segments["zeta"][preliminary])) if preliminary.any() else np.nan
    if zeta_ref > 0:
        # Pass 2: the chain's own bias on a synthetic decay like this one marks the
        # filter transients; the floor is re-measured without them (light damping
        # makes them last far longer than the fixed edges, and they would otherwise
        # count as noise).
        fn_ref = float(np.median(segments["frequency_hz"][preliminary])) / np.sqrt(1.0 - zeta_ref**2)
        onset = start
        if start_index is None:
            # Align the synthetic's envelope peak with the record's: the band-pass
            # delays the envelope maximum behind the hit, by about one slowest-pole
            # time constant. The synthetic beyond SETTLED_TIME_CONSTANTS of them after
            # the hit changes the envelope at its peak by less than rounding (measured:
            # 1e-15 of it, against 1e-8 with 20 of them, on 125 and 151 Hz decays of
            # 0.01-3 % damping), so the probe is band-passed that far only.
            reach = start + settled_samples(fs_hz, band_hz, filter_order)
            probe = analytic_bandpass(
                _synthetic_decay(n, fs_hz, fn_ref, zeta_ref, start, stop=reach),
                fs_hz,
                band_hz,
                filter_order,
            )
            onset = max(0, 2 * start - int(np.argmax(np.abs(probe[:stop]))))
            del probe
        bias = startup_bias(
            n,
            fs_hz,
            band_hz,
            fn_ref,
            zeta_ref,
            starts,
            stops,
            onset_index=onset,
            filter_order=filter_order,
        )
        transient = ~(np.abs(bias["zeta_relative_error"]) <= bias_tolerance) | ~(
            np.abs(bias["frequency_error_hz"]) <= FREQUENCY_BIAS_TOLERANCE_HZ
        )
        clean = ~transient & ~checks["excitation_edge"] & ~checks["record_end"]
        if clean.any():
            floor = measure_floor(int(starts[clean].min()), int(stops[clean].max()))
        checks = data_checks(floor)
        checks["filter_transient"] = transient

    segments["zeta_std"], segments["frequency_std_hz"] = noise_standard_errors(
        env,
        floor,
        fs_hz,
        starts,
        stops,
        low_hz=band_hz[0],
        high_hz=band_hz[1],
        frequency_hz=segments["frequency_hz"],
    )
    reasons = np.array(
        [",".join(code for code in REJECT_CODES if checks[code][k]) for k in range(starts.size)],
        dtype=str,
    )
    segments["envelope_rise"] = rise
    segments["startup_bias_zeta"] = bias["zeta_relative_error"]
    segments["startup_bias_hz"] = bias["frequency_error_hz"]
    segments["kept"] = reasons == ""
    segments["reject_reason"] = reasons
    return DecayResult(
        filtered=filtered,
        envelope=env,
        phase_rad=phase,
        noise_floor=floor,
        start_index=start,
        stop_index=stop,
        mode_hz=float(mode_hz),
        band_hz=(float(band_hz[0]), float(band_hz[1])),
        time_constant_s=tau_s,
        segments=segments,
    )

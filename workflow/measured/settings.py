"""The measured stage's sections of config.yaml: ``analysis`` (mode search, band-pass,
segmented log decrement), ``quality`` (the per-run checks) and ``fits`` (damping
polynomials and their bands).

The stage's functions take their defaults from these classes; :mod:`workflow.config`
validates them at workflow start (types, bounds, unknown keys).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from annotated_types import Ge, Gt, Le, Lt

from workflow.io.validation import FORBID_UNKNOWN_KEYS, After, Seed

__all__ = [
    "AnalysisSettings",
    "DECAY_KEYS",
    "QualitySettings",
    "DampingFitSettings",
]


def _even(order: int) -> int:
    if order % 2:
        raise ValueError(f"must be even (a band-pass has an even order), got {order}")
    return order


def _frequency_range(range_hz: tuple[float, float] | None) -> tuple[float, float] | None:
    if range_hz is not None and not 0.0 < range_hz[0] < range_hz[1]:
        raise ValueError(f"must be [low, high] Hz with 0 < low < high, got {list(range_hz)}")
    return range_hz


@dataclass(frozen=True)
class AnalysisSettings:
    """How each ring-down is turned into damping and frequency vs amplitude."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    filter_order: Annotated[int, Ge(2), Le(20), After(_even)] = 10
    """Order of the Butterworth band-pass (even; the paper used 10). Applied
    forward and backward (zero phase), which squares its magnitude response."""

    band_half_width: Annotated[float, Gt(0.0), Lt(0.9)] = 0.2
    """When campaign.yaml gives no ``band_hz``: band = mode * (1 -/+ this).
    0.2 around 125 Hz gives the paper's [100, 150] Hz."""

    mode_search_hz: Annotated[tuple[float, float] | None, After(_frequency_range)] = None
    """Frequency range searched for the first mode when campaign.yaml gives no
    ``mode_hz``; None searches from 5 Hz to 0.4 * sample rate."""

    mode_search_fraction: Annotated[float, Gt(0.0), Lt(0.9)] = 0.3
    """With ``mode_hz`` given, the mode is searched in mode_hz * (1 -/+ this)."""

    segment_cycles: Annotated[float, Ge(2.0), Le(200.0)] = 10.0
    """Length of one log-decrement segment, in cycles of the mode (paper: about 10)."""

    segment_overlap: Annotated[float, Ge(0.0), Lt(0.95)] = 0.5
    """Fraction by which consecutive segments overlap."""

    # 1e6 (120 dB) is a 24-bit recorder's dynamic range: above it no segment is ever kept.
    noise_floor_factor: Annotated[float, Ge(1.0), Le(1e6)] = 10.0
    """A segment is kept only while its smallest envelope value exceeds this
    factor times the in-band noise floor (the rms envelope of the in-band noise,
    measured on the residual of a decaying phasor fitted window by window:
    docs/decay_analysis.md). 10 keeps segments 20 dB above the floor."""

    # After 20 time constants the filter's transient is e^-20 = 2e-9 of the step, below any
    # recorder's resolution: more drops segments for nothing.
    edge_time_constants: Annotated[float, Ge(0.0), Le(20.0)] = 3.0
    """Segments closer than this many filter time constants (the band-pass
    envelope settling time, 1 / (pi * bandwidth)) to the excitation peak or to
    the end of the record are dropped as filter end effects."""

    def decay_options(self) -> dict[str, float]:
        """The keys one run's decay analysis reads, as keyword arguments of
        :func:`workflow.measured.decay.analyse_decay`."""
        return {name: getattr(self, name) for name in DECAY_KEYS}


DECAY_KEYS = (
    "filter_order",
    "segment_cycles",
    "segment_overlap",
    "noise_floor_factor",
    "edge_time_constants",
)
"""The :class:`AnalysisSettings` keys of one run's decay analysis (the others choose the mode
and its band)."""


@dataclass(frozen=True)
class QualitySettings:
    """Per-run quality checks; a run failing one is excluded with its reason."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    clip_fraction_of_peak: Annotated[float, Gt(0.5), Le(1.0)] = 0.9999
    """Samples within this fraction of the record's absolute peak count as
    'at the peak'. 0.9999 keeps a clean sine peak below 2 such samples up to
    about 300 samples per cycle, while a clipped flat top has many."""

    # A clean sine has about 0.0045 of a cycle within 0.9999 of its peak: 23 samples at the
    # slowest mode searched (5 Hz) sampled at 25.6 kHz, 900 at 1 MHz; 1000 counts no real
    # record as clipped.
    clip_max_samples: Annotated[int, Ge(1), Le(1000)] = 3
    """More samples than this at the peak (a flat top) means the response clipped."""

    double_hit_ratio: Annotated[float, Gt(0.0), Lt(1.0)] = 0.3
    """A second force pulse, separated from the first by at least
    ``double_hit_gap_s``, larger than this fraction of the first is a double hit."""

    # A hammer's rebound follows within milliseconds; a pulse a second later is another test.
    double_hit_gap_s: Annotated[float, Gt(0.0), Le(1.0)] = 0.005

    # 5000 lbf (22 kN) is the range of the largest modal sledge hammers.
    min_peak_force_lbf: Annotated[float, Ge(0.0), Le(5000.0)] = 1.0
    """Peak hammer force below this (the original trigger level) means no real hit."""

    # 144 dB is a 24-bit recorder's dynamic range: no record has more.
    min_snr_db: Annotated[float, Ge(0.0), Le(144.0)] = 20.0
    """Peak in-band envelope over the noise floor, in dB, below which a run is
    too noisy for a decrement."""

    # A 60 s record of a 125 Hz mode in 10-cycle segments overlapping by half has 1500
    # segments, of which the noise floor keeps a few hundred: 1000 excludes every real run.
    min_segments: Annotated[int, Ge(1), Le(1000)] = 3
    """A run that yields fewer usable segments than this is excluded."""

    # A hammer pulse rises in under 1 ms: 1000 samples at 1 MHz.
    trigger_tolerance_samples: Annotated[int, Ge(0), Le(1000)] = 5
    """How far the force's first crossing of the 1 lbf trigger level may sit from
    the stated pre-trigger length: the recorder triggers on its own copy of the
    signal, and the hammer pulse rises over a few samples."""

    # A ring-down of a lightly damped joint (zeta 1e-4) falls 20 dB in about 3700 cycles;
    # 1e5 cycles excludes every real run.
    min_record_cycles: Annotated[float, Gt(0.0), Le(1e5)] = 20.0
    """Shortest record, in cycles of the mode: three 10-cycle segments overlapping
    by half, plus margin."""

    # 1e4 (80 dB) is above any resonance over its search range's ends (40-170 x measured).
    min_mode_prominence: Annotated[float, Ge(1.0), Le(1e4)] = 2.0
    """Least ratio of the spectral peak taken as the mode to the spectrum at either
    end of the search range: a resonance inside the range stands 40-170 x above
    both ends (virtual lab and real campaigns), the flank of a mode outside it about
    1 x the end it rises towards."""


@dataclass(frozen=True)
class DampingFitSettings:
    """Polynomial fits of damping vs velocity amplitude and area."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    max_degree: Annotated[int, Ge(0), Le(6)] = 3
    """Highest polynomial degree tried; the degree is chosen by leave-one-run-out
    cross-validation."""

    log_amplitude: bool = True
    """Fit against log10(velocity amplitude) (amplitudes span decades)."""

    # The Monte Carlo error of the band's 2.5 % quantile with B resamples is
    # sqrt(0.025 * 0.975 / B) in coverage: 0.16 % at 10000, far below what 2-200 runs
    # resolve; 10000 curves on the grid take a few MB and seconds (1e9 took 447 GiB).
    bootstrap_samples: Annotated[int, Ge(50), Le(10_000)] = 400
    """Bootstrap resamples over runs for confidence bands."""

    confidence: Annotated[float, Gt(0.5), Lt(1.0)] = 0.95

    seed: Seed = 20040614

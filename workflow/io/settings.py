"""Workflow configuration (``config.yaml``), validated at workflow start.

Every key is documented here and in ``config.yaml``. Unknown keys and bad values
stop the run at once with a message that names the key, so a typo is never
silently ignored.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from annotated_types import Ge, Gt, Le, Lt

from workflow.io.validation import FORBID_UNKNOWN_KEYS, UNKNOWN_KEY_ERRORS, After, validate

if TYPE_CHECKING:
    from pydantic import ValidationError


__all__ = [
    "Seed",
    "AnalysisSettings",
    "DECAY_KEYS",
    "QualitySettings",
    "DampingFitSettings",
    "ModelSettings",
    "DiscoverySettings",
    "DemoSettings",
    "WorkflowConfig",
    "ConfigError",
    "valid_keys",
    "format_validation_error",
    "validate_config",
]


def _even(order: int) -> int:
    if order % 2:
        raise ValueError(f"must be even (a band-pass has an even order), got {order}")
    return order


def _frequency_range(range_hz: tuple[float, float] | None) -> tuple[float, float] | None:
    if range_hz is not None and not 0.0 < range_hz[0] < range_hz[1]:
        raise ValueError(f"must be [low, high] Hz with 0 < low < high, got {list(range_hz)}")
    return range_hz


Seed = Annotated[int, Ge(0), Lt(2**63)]
"""A random generator's seed: NumPy takes only non-negative integers, and the outputs that
record it hold a signed 64-bit integer."""


# Upper bounds: every count, iteration and sample number has one, so that a setting cannot
# take the machine (2 cores, 24 GiB, shared) for hours or allocate what it does not have;
# each bound sits where more no longer changes a result the physics or the statistics can
# resolve, with the cost at the bound stated beside it.


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


@dataclass(frozen=True)
class ModelSettings:
    """Fitting and simulating the friction models."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    # Each is one simulated ring-down; 256 is 64 times the default's cost, and the best of 16
    # was never chosen on 28 fits.
    global_samples: Annotated[int, Ge(4), Le(256)] = 4
    """Parameter sets tried in the global (quasi-random) stage of each time-domain
    fit, beside the optimum of the averaged model (which has its own global search
    and is far cheaper); they guard against a poor averaged start. Each costs one
    simulated and analysed ring-down. On 28 fits (the demo, two real campaigns,
    hidden-effect campaigns generated with the averaged model and in the time domain)
    the best of 16 had 3 to 874 times the averaged start's cost and was never chosen
    (docs/performance.md)."""

    # Each refined start costs local_iterations batched simulations: 16 is 16 times the default.
    local_starts: Annotated[int, Ge(1), Le(16)] = 1
    """Best candidates refined by the local optimiser."""

    # Each costs one batched simulation; from the averaged start 4 suffice, and 50 (12 times
    # the default's cost) is far past where Levenberg-Marquardt stops improving.
    local_iterations: Annotated[int, Ge(1), Le(50)] = 4
    """Levenberg-Marquardt iterations of the time-domain refinement (each costs
    one batched simulation of every parameter perturbation)."""

    # RK4's error falls as h^4: 128 steps (8 x the default) bring the envelope error below
    # 1e-3 / 8^4 = 2.4e-7, under any recorder's noise, at 8 times the cost (1e9 ran past 300 s).
    steps_per_period: Annotated[int, Ge(8), Le(128)] = 16
    """Fixed RK4 steps per period of the mode (16 keeps the envelope error below
    1e-3 against a tight-tolerance reference: bench/bench_integrator.py)."""

    seed: Seed = 1976


@dataclass(frozen=True)
class DiscoverySettings:
    """Fitting the averaged candidate models and deciding the cause (docs/discovery.md):
    the optimiser settings of :func:`workflow.models.averaged_fit.fit_model` (global
    samples, local starts, seed), the folds of the held-out error and the resamples
    behind each verdict's confidence."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    # Rounded up to a power of two (a Sobol set); 4096 points place a sample within a quarter
    # of each range of a six-parameter box (4096^(-1/6)), at 16 times the default's cost.
    global_samples: Annotated[int, Ge(16), Le(4096)] = 256
    """Quasi-random parameter sets in the global stage of each averaged-model fit."""

    # Each start is one local fit, in every fold and resample: 32 is 8 times the default.
    local_starts: Annotated[int, Ge(1), Le(32)] = 4
    """Best global candidates refined locally."""

    # K = min(folds, number of runs); 50 is more runs than a campaign's configuration
    # holds (the demo's limit is 200 in all), at 10 times the default's cost.
    folds: Annotated[int, Ge(2), Le(50)] = 5
    """Folds over runs for the held-out error (contiguous amplitude blocks with one run)."""

    seed: Seed = 1976

    # Each resample repeats the decision; a confidence's Monte Carlo error is at most
    # 0.5 / sqrt(B): 5 % at the default, 1.6 % at 1000, at 10 times the cost.
    resamples: Annotated[int, Ge(10), Le(1000)] = 100
    """Bayesian-bootstrap reweightings of the runs (of half decades of amplitude with one
    run) behind each verdict's ``confidence`` (docs/discovery.md, Confidence)."""


@dataclass(frozen=True)
class DemoSettings:
    """The built-in virtual-lab campaign generated when ``campaign`` points at ``path``."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    path: str = "results/demo_campaign"
    seed: Seed = 2004
    # 200 runs in each of the demo's three configurations: 600 run files to generate and analyse.
    runs_per_configuration: Annotated[int, Ge(1), Le(200)] = 10
    frequency_spread: Annotated[float, Ge(0.0), Le(0.01)] = 3e-4
    """Run-to-run relative standard deviation of the natural frequency (the virtual lab's
    ``LabSettings.frequency_spread``; docs/virtual-lab.md). 0 turns it off."""
    damping_spread: Annotated[float, Ge(0.0), Le(0.5)] = 0.03
    """Run-to-run relative standard deviation of the linear modal damping."""
    slip_force_spread: Annotated[float, Ge(0.0), Le(0.5)] = 0.03
    """Run-to-run relative standard deviation of the joint's slip forces."""


@dataclass(frozen=True)
class WorkflowConfig:
    """Top level of ``config.yaml``."""

    __pydantic_config__ = FORBID_UNKNOWN_KEYS

    campaign: str = "results/demo_campaign"
    """Campaign folder (campaign-format.md); relative to the working directory."""

    strict: bool = False
    """True: a run that cannot be read or fails a quality check stops the workflow.
    False: it is excluded from fits and listed with its reason in runs.parquet."""

    # Runs are analysed one after the other (memory is one run's); 1000 is a 60 s job.
    runs_per_job: Annotated[int, Ge(1), Le(1000)] = 10
    """Run files analysed (read, checked, band-passed, segmented) by one job. Each
    job spends about 0.25 s starting (Python, Snakemake's script preamble, NumPy)
    and 0.06 s per run on signal work, and Snakemake's own bookkeeping grows with the
    number of jobs; 1 gives one job per run file. Results do not depend on it."""

    units: Literal["inch-second", "si"] = "inch-second"
    """Units of the results: ``inch-second`` (in/s, in, in², lbf: the paper's, and the
    output contract's columns) or ``si``: the tables gain SI columns beside the
    inch-second ones (``velocity_amplitude_m_s`` ...), and figures, notes and the verdict
    page show m/s, m, m², N (workflow.io.units.UNIT_SYSTEMS). Frequencies are Hz either way."""

    analysis: AnalysisSettings = field(default_factory=AnalysisSettings)
    quality: QualitySettings = field(default_factory=QualitySettings)
    fits: DampingFitSettings = field(default_factory=DampingFitSettings)
    models: ModelSettings = field(default_factory=ModelSettings)
    discovery: DiscoverySettings = field(default_factory=DiscoverySettings)
    demo: DemoSettings = field(default_factory=DemoSettings)

    def uses_demo_campaign(self, workdir: Path | str = ".") -> bool:
        """Whether ``campaign`` is the built-in demo (which a rule then generates)."""
        root = Path(workdir)
        return (root / self.campaign).resolve() == (root / self.demo.path).resolve()


class ConfigError(ValueError):
    """A configuration value is wrong; the message names the key."""


def valid_keys(path: tuple) -> list[str]:
    """The keys config.yaml accepts at ``path`` (() is the top level); [] below a leaf."""
    import typing

    section: Any = WorkflowConfig
    for part in path:
        hints = typing.get_type_hints(section) if isinstance(section, type) else {}
        section = hints.get(str(part))
    if not (isinstance(section, type) and hasattr(section, "__dataclass_fields__")):
        return []
    return list(section.__dataclass_fields__)


def _given(overrides: Mapping[str, Any] | None, path: tuple) -> bool:
    """Whether ``path`` was set in ``overrides`` (the command line's --config)."""
    level: Any = overrides or {}
    for part in path:
        if not isinstance(level, Mapping) or str(part) not in level:
            return False
        level = level[str(part)]
    return True


def format_validation_error(
    error: ValidationError, source: str, command_line: Mapping[str, Any] | None = None
) -> str:
    """One line per problem: ``where: key.path: what is wrong``, where is the command
    line when the key was given with ``--config``, else ``source``; an unknown key is
    followed by the keys valid at its place."""
    lines = []
    for item in error.errors():
        path = tuple(item["loc"])
        key = ".".join(str(part) for part in path) or "(top level)"
        origin = "command line (--config)" if _given(command_line, path) else source
        message = item["msg"]
        if item["type"] in UNKNOWN_KEY_ERRORS:
            keys = valid_keys(path[:-1])
            message = "unknown key" + (f"; valid keys here: {', '.join(keys)}" if keys else "")
        lines.append(f"{origin}: {key}: {message}")
    return "\n".join(lines)


def validate_config(
    raw: dict[str, Any] | None, source: str = "config.yaml", command_line: Mapping[str, Any] | None = None
) -> WorkflowConfig:
    """Validate the merged Snakemake config; raise ConfigError naming every bad key and
    where it came from (``command_line``: the keys given with ``--config``)."""
    from pydantic import ValidationError

    try:
        return validate(WorkflowConfig, raw or {})
    except ValidationError as error:
        raise ConfigError(format_validation_error(error, source, command_line)) from None

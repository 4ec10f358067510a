"""Workflow configuration (``config.yaml``), validated at workflow start.

Every key is documented here and in ``config.yaml``. Unknown keys and bad values
stop the run at once with a message that names the key, so a typo is never
silently ignored.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class AnalysisSettings(_Strict):
    """How each ring-down is turned into damping and frequency vs amplitude."""

    filter_order: int = Field(10, ge=2, le=20)
    """Order of the Butterworth band-pass (even; the paper used 10). Applied
    forward and backward (zero phase), which squares its magnitude response."""

    band_half_width: float = Field(0.2, gt=0.0, lt=0.9)
    """When campaign.yaml gives no ``band_hz``: band = mode * (1 -/+ this).
    0.2 around 125 Hz gives the paper's [100, 150] Hz."""

    mode_search_hz: tuple[float, float] | None = None
    """Frequency range searched for the first mode when campaign.yaml gives no
    ``mode_hz``; None searches from 5 Hz to 0.4 * sample rate."""

    mode_search_fraction: float = Field(0.3, gt=0.0, lt=0.9)
    """With ``mode_hz`` given, the mode is searched in mode_hz * (1 -/+ this)."""

    segment_cycles: float = Field(10.0, ge=2.0, le=200.0)
    """Length of one log-decrement segment, in cycles of the mode (paper: about 10)."""

    segment_overlap: float = Field(0.5, ge=0.0, lt=0.95)
    """Fraction by which consecutive segments overlap."""

    noise_floor_factor: float = Field(10.0, ge=1.0)
    """A segment is kept only while its smallest envelope value exceeds this
    factor times the in-band noise floor (estimated from the record's quietest
    stretch). 10 keeps segments 20 dB above the floor."""

    edge_time_constants: float = Field(3.0, ge=0.0)
    """Segments closer than this many filter time constants (the band-pass
    envelope settling time, 1 / (pi * bandwidth)) to the excitation peak or to
    the end of the record are dropped as filter end effects."""


class QualitySettings(_Strict):
    """Per-run quality checks; a run failing one is excluded with its reason."""

    clip_fraction_of_peak: float = Field(0.9999, gt=0.5, le=1.0)
    """Samples within this fraction of the record's absolute peak count as
    'at the peak'. 0.9999 keeps a clean sine peak below 2 such samples up to
    about 300 samples per cycle, while a clipped flat top has many."""

    clip_max_samples: int = Field(3, ge=1)
    """More samples than this at the peak (a flat top) means the response clipped."""

    double_hit_ratio: float = Field(0.3, gt=0.0, lt=1.0)
    """A second force pulse, separated from the first by at least
    ``double_hit_gap_s``, larger than this fraction of the first is a double hit."""

    double_hit_gap_s: float = Field(0.005, gt=0.0)

    min_peak_force_lbf: float = Field(1.0, ge=0.0)
    """Peak hammer force below this (the original trigger level) means no real hit."""

    min_snr_db: float = Field(20.0)
    """Peak in-band envelope over the noise floor, in dB, below which a run is
    too noisy for a decrement."""

    min_segments: int = Field(3, ge=1)
    """A run that yields fewer usable segments than this is excluded."""

    trigger_tolerance_samples: int = Field(5, ge=0)
    """How far the force's first crossing of the 1 lbf trigger level may sit from
    the stated pre-trigger length: the recorder triggers on its own copy of the
    signal, and the hammer pulse rises over a few samples."""

    min_record_cycles: float = Field(20.0, gt=0.0)
    """Shortest record, in cycles of the mode: three 10-cycle segments overlapping
    by half, plus margin."""

    min_mode_prominence: float = Field(2.0, ge=1.0)
    """Least ratio of the spectral peak taken as the mode to the spectrum at either
    end of the search range: a resonance inside the range stands 40-170 x above
    both ends (virtual lab and real campaigns), the flank of a mode outside it about
    1 x the end it rises towards."""


class FitSettings(_Strict):
    """Polynomial fits of damping vs velocity amplitude and area."""

    max_degree: int = Field(3, ge=0, le=6)
    """Highest polynomial degree tried; the degree is chosen by leave-one-run-out
    cross-validation."""

    log_amplitude: bool = True
    """Fit against log10(velocity amplitude) (amplitudes span decades)."""

    bootstrap_samples: int = Field(400, ge=50)
    """Bootstrap resamples over runs for confidence bands."""

    confidence: float = Field(0.95, gt=0.5, lt=1.0)

    seed: int = 20040614


class ModelSettings(_Strict):
    """Fitting and simulating the friction models."""

    global_samples: int = Field(16, ge=4)
    """Parameter sets tried in the global (quasi-random) stage of each time-domain
    fit, beside the optimum of the averaged model (which has its own global search
    and is far cheaper); they guard against a poor averaged start."""

    local_starts: int = Field(1, ge=1)
    """Best candidates refined by the local optimiser."""

    local_iterations: int = Field(4, ge=1)
    """Levenberg-Marquardt iterations of the time-domain refinement (each costs
    one batched simulation of every parameter perturbation)."""

    steps_per_period: int = Field(16, ge=8)
    """Fixed RK4 steps per period of the mode (16 keeps the envelope error below
    1e-3 against a tight-tolerance reference: bench/bench_integrator.py)."""

    seed: int = 1976


class DiscoverySettings(_Strict):
    """Fitting the averaged candidate models and deciding the cause (docs/discovery.md)."""

    global_samples: int = Field(256, ge=16)
    """Quasi-random parameter sets in the global stage of each averaged-model fit."""

    local_starts: int = Field(4, ge=1)
    """Best global candidates refined locally."""

    folds: int = Field(5, ge=2)
    """Folds over runs for the held-out error (contiguous amplitude blocks with one run)."""

    seed: int = 1976


class DemoSettings(_Strict):
    """The built-in virtual-lab campaign generated when ``campaign`` points at ``path``."""

    path: str = "results/demo_campaign"
    seed: int = 2004
    runs_per_configuration: int = Field(10, ge=1, le=200)


class WorkflowConfig(_Strict):
    """Top level of ``config.yaml``."""

    campaign: str = "results/demo_campaign"
    """Campaign folder (campaign-format.md); relative to the working directory."""

    strict: bool = False
    """True: a run that cannot be read or fails a quality check stops the workflow.
    False: it is excluded from fits and listed with its reason in runs.parquet."""

    analysis: AnalysisSettings = AnalysisSettings()
    quality: QualitySettings = QualitySettings()
    fits: FitSettings = FitSettings()
    models: ModelSettings = ModelSettings()
    discovery: DiscoverySettings = DiscoverySettings()
    demo: DemoSettings = DemoSettings()

    @model_validator(mode="after")
    def _even_filter_order(self) -> "WorkflowConfig":
        if self.analysis.filter_order % 2:
            raise ValueError(
                "analysis.filter_order must be even (a band-pass has an even order), "
                f"got {self.analysis.filter_order}"
            )
        return self

    def uses_demo_campaign(self, workdir: Path | str = ".") -> bool:
        """Whether ``campaign`` is the built-in demo (which a rule then generates)."""
        root = Path(workdir)
        return (root / self.campaign).resolve() == (root / self.demo.path).resolve()


class ConfigError(ValueError):
    """A configuration value is wrong; the message names the key."""


def format_validation_error(error: ValidationError, source: str) -> str:
    """One line per problem: ``source: key.path: what is wrong``."""
    lines = []
    for item in error.errors():
        key = ".".join(str(part) for part in item["loc"]) or "(top level)"
        message = item["msg"]
        if item["type"] == "extra_forbidden":
            message = "unknown key (check its spelling against config.yaml's documented keys)"
        lines.append(f"{source}: {key}: {message}")
    return "\n".join(lines)


def validate_config(raw: dict[str, Any] | None, source: str = "config.yaml") -> WorkflowConfig:
    """Validate the merged Snakemake config; raise ConfigError naming every bad key."""
    try:
        return WorkflowConfig.model_validate(raw or {})
    except ValidationError as error:
        raise ConfigError(format_validation_error(error, source)) from None

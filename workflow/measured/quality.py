"""Per-run quality checks.

Each check is a pure function over arrays that returns what it measured and a reason:
None when the run passes, else which check failed and by how much (the reason is what
runs.parquet shows a person for an excluded run). :func:`quality_rows` applies the
checks that need no decay analysis; :func:`analysis_rows` those that need the in-band
envelope and noise floor.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workflow.io.records import RunRecord
from workflow.measured.settings import QualitySettings

__all__ = [
    "CheckResult",
    "check_clipping",
    "check_double_hit",
    "check_excitation",
    "check_trigger",
    "check_record_length",
    "check_mode_found",
    "check_snr",
    "QC_COLUMNS",
    "quality_columns",
    "quality_rows",
    "analysis_rows",
]


class CheckResult(NamedTuple):
    """What a check measured (in the unit its quality row states) and its verdict."""

    value: float
    reason: str | None  # None: passed


def _oriented_force(force_lbf: ArrayLike) -> NDArray[np.float64]:
    """Force with the hammer pulse positive (some exports record compression < 0)."""
    force = np.asarray(force_lbf, dtype=np.float64)
    if force.size and abs(force.min()) > abs(force.max()):
        return -force
    return force


def check_clipping(
    response: ArrayLike, clip_fraction_of_peak: float, clip_max_samples: int, unit: str = ""
) -> CheckResult:
    """Flat-topped (clipped) response: too many samples at the record's absolute peak.

    Parameters
    ----------
    response : array_like
        The response, any unit.
    clip_fraction_of_peak : float
        Samples with ``|x| >= clip_fraction_of_peak * max|x|`` count as at the peak.
    clip_max_samples : int
        More samples than this at the peak means the response clipped.
    unit : str, optional
        Unit of ``response``, only for the message.

    Returns
    -------
    CheckResult
        The measured value (the unit its quality row states) and ``reason``: None
        when the run passes, else what failed and by how much.
    """
    magnitude = np.abs(np.asarray(response, dtype=np.float64))
    if magnitude.size == 0:
        return CheckResult(math.nan, "response is empty")
    peak = float(magnitude.max())
    if peak == 0.0:
        return CheckResult(math.nan, "response is zero throughout: a dead or disconnected channel")
    at_peak = int(np.count_nonzero(magnitude >= clip_fraction_of_peak * peak))
    if at_peak == magnitude.size:
        # Every sample at the "peak": the record has no ring-down at all, which a
        # clipped measurement always has between its flat tops.
        response = np.asarray(response, dtype=np.float64)
        low, high = float(response.min()), float(response.max())
        unit_text = f" {unit}" if unit else ""
        if low == high:
            return CheckResult(
                at_peak, f"response is constant ({low:.4g}{unit_text}) throughout: a dead or stuck channel"
            )
        return CheckResult(
            at_peak,
            f"response stays between {low:.4g} and {high:.4g}{unit_text} throughout (an offset with no "
            "ring-down): a dead or stuck channel",
        )
    if at_peak <= clip_max_samples:
        return CheckResult(at_peak, None)
    return CheckResult(
        at_peak,
        (
            f"response clipped: {at_peak} samples within {100 * (1 - clip_fraction_of_peak):.3g} % "
            f"of the peak {peak:.4g}{' ' + unit if unit else ''} (limit {clip_max_samples})"
        ),
    )


def check_double_hit(force_lbf: ArrayLike, fs_hz: float, ratio: float, gap_s: float) -> CheckResult:
    """Two hammer pulses: a second one larger than ``ratio`` of the main one.

    Pulses are the stretches where the force exceeds ``ratio`` times its peak; a
    stretch whose own peak lies at least ``gap_s`` from the main peak is a second hit
    (closer stretches are the same pulse dipping below the level).

    Parameters
    ----------
    force_lbf : array_like
        Hammer force, lbf.
    fs_hz : float
        Sample rate, Hz.
    ratio : float
        Fraction of the main peak above which a second pulse counts.
    gap_s : float
        Least separation of the two peaks, s.

    Returns
    -------
    CheckResult
        The measured value (the unit its quality row states) and ``reason``: None
        when the run passes, else what failed and by how much.
    """
    force = _oriented_force(force_lbf)
    if force.size == 0:
        return CheckResult(math.nan, None)
    main_index = int(np.argmax(force))
    main_peak_lbf = float(force[main_index])
    if main_peak_lbf <= 0.0:
        return CheckResult(math.nan, None)  # no pulse at all: check_excitation reports it
    above = force > ratio * main_peak_lbf
    # Boundaries of the stretches above the level.
    edges = np.flatnonzero(np.diff(above.astype(np.int8)))
    starts = np.concatenate(([0] if above[0] else [], edges[~above[edges]] + 1)).astype(int)
    stops = np.concatenate((edges[above[edges]] + 1, [force.size] if above[-1] else [])).astype(int)
    gap_samples = gap_s * fs_hz
    second_index, second_peak_lbf = -1, -math.inf
    for start, stop in zip(starts, stops):
        index = start + int(np.argmax(force[start:stop]))
        if abs(index - main_index) >= gap_samples and force[index] > second_peak_lbf:
            second_index, second_peak_lbf = index, float(force[index])
    if second_index < 0:
        return CheckResult(0.0, None)
    separation_ms = 1e3 * (second_index - main_index) / fs_hz
    when = f"{abs(separation_ms):.3g} ms {'after' if separation_ms > 0 else 'before'}"
    return CheckResult(
        second_peak_lbf / main_peak_lbf,
        (
            f"double hit: a second force pulse of {second_peak_lbf:.3g} lbf "
            f"({second_peak_lbf / main_peak_lbf:.2f} of the main {main_peak_lbf:.3g} lbf pulse) "
            f"{when} it (limit {ratio:.2f})"
        ),
    )


def check_excitation(force_lbf: ArrayLike, min_peak_force_lbf: float) -> CheckResult:
    """Missing or tiny hammer hit.

    Parameters
    ----------
    force_lbf : array_like
        Hammer force, lbf.
    min_peak_force_lbf : float
        Smallest acceptable peak force, lbf.

    Returns
    -------
    CheckResult
        The measured value (the unit its quality row states) and ``reason``: None
        when the run passes, else what failed and by how much.
    """
    force = _oriented_force(force_lbf)
    peak_lbf = float(force.max()) if force.size else 0.0
    value = peak_lbf if force.size else math.nan
    if peak_lbf >= min_peak_force_lbf and peak_lbf > 0.0:
        return CheckResult(value, None)
    return CheckResult(
        value, f"no real hit: peak force {peak_lbf:.3g} lbf is below {min_peak_force_lbf:.3g} lbf"
    )


def check_trigger(
    force_lbf: ArrayLike,
    pretrigger_samples: int,
    trigger_lbf: float = 1.0,
    tolerance_samples: int = QualitySettings.trigger_tolerance_samples,
) -> CheckResult:
    """The force first reaches the trigger level where the pre-trigger says it should.

    A triggered record holds ``pretrigger_samples`` samples before the trigger, so the
    force first reaches ``trigger_lbf`` near that sample. Much earlier means the
    record caught an earlier event (or a wrong pre-trigger); much later means the
    recorder did not trigger on this hit.

    Parameters
    ----------
    force_lbf : array_like
        Hammer force, lbf.
    pretrigger_samples : int
        Samples before the trigger, from the header or campaign.yaml.
    trigger_lbf : float, optional
        Trigger level, lbf (the original lab's 1 lbf).
    tolerance_samples : int, optional
        Accepted distance of the first crossing from ``pretrigger_samples``.

    Returns
    -------
    CheckResult
        The measured value (the unit its quality row states) and ``reason``: None
        when the run passes, else what failed and by how much.
    """
    force = _oriented_force(force_lbf)
    crossings = np.flatnonzero(force >= trigger_lbf)
    if crossings.size == 0:
        return CheckResult(
            math.inf, f"trigger: the force never reaches the trigger level {trigger_lbf:.3g} lbf"
        )
    first = int(crossings[0])
    offset = first - pretrigger_samples
    if abs(offset) <= tolerance_samples:
        return CheckResult(abs(offset), None)
    return CheckResult(
        abs(offset),
        (
            f"trigger: the force first reaches {trigger_lbf:.3g} lbf at sample {first}, "
            f"{abs(offset)} samples {'after' if offset > 0 else 'before'} the pre-trigger "
            f"length {pretrigger_samples} (tolerance {tolerance_samples})"
        ),
    )


def check_record_length(n_samples: int, fs_hz: float, mode_hz: float, min_cycles: float) -> CheckResult:
    """Record long enough to hold ``min_cycles`` cycles of the mode.

    Parameters
    ----------
    n_samples : int
        Samples in the record.
    fs_hz : float
        Sample rate, Hz.
    mode_hz : float
        Frequency of the mode, Hz.
    min_cycles : float
        Fewest cycles needed.

    Returns
    -------
    CheckResult
        The measured value (the unit its quality row states) and ``reason``: None
        when the run passes, else what failed and by how much.
    """
    duration_s = n_samples / fs_hz
    cycles = duration_s * mode_hz
    if cycles >= min_cycles:
        return CheckResult(cycles, None)
    return CheckResult(
        cycles,
        (
            f"record too short: {duration_s:.3g} s holds {cycles:.3g} cycles of the "
            f"{mode_hz:.4g} Hz mode (need {min_cycles:.3g})"
        ),
    )


def check_mode_found(
    frequency_hz: ArrayLike,
    magnitude: ArrayLike,
    mode_hz: float,
    search_hz: tuple[float, float],
    min_prominence: float = QualitySettings.min_mode_prominence,
) -> str | None:
    """The peak found in the search range is a resonance, not the flank of a mode outside it.

    Parameters
    ----------
    frequency_hz : array_like
        Increasing frequencies of the spectrum, Hz.
    magnitude : array_like
        Spectral amplitude (``|H1|`` or the square root of a PSD) at those frequencies.
    mode_hz : float
        The peak taken as the mode, Hz.
    search_hz : (float, float)
        The range the mode was searched in, Hz.
    min_prominence : float, optional
        Least ratio of the amplitude at ``mode_hz`` to the amplitude at each end of the
        range.

    Returns
    -------
    str or None
        None when the mode stands out, else the reason.
    """
    frequency_hz = np.asarray(frequency_hz, dtype=np.float64)
    magnitude = np.abs(np.asarray(magnitude))
    low_hz, high_hz = float(search_hz[0]), float(search_hz[1])
    peak = float(np.interp(mode_hz, frequency_hz, magnitude))
    ends = {
        "lower": float(np.interp(low_hz, frequency_hz, magnitude)),
        "upper": float(np.interp(high_hz, frequency_hz, magnitude)),
    }
    end, level = max(ends.items(), key=lambda item: item[1])
    if level <= 0.0 or peak >= min_prominence * level:
        return None
    return (
        f"no resonance in the search range {low_hz:.4g}-{high_hz:.4g} Hz: its largest peak, at "
        f"{mode_hz:.4g} Hz, stands only {peak / level:.3g} x above the spectrum at the range's "
        f"{end} end (a resonance stands at least {min_prominence:g} x above both ends); the "
        "mode lies outside the range (check mode_hz in campaign.yaml or analysis.mode_search_hz)"
    )


def check_snr(peak_envelope: float, noise_floor: float, min_snr_db: float) -> CheckResult:
    """Peak in-band envelope over the noise floor, in dB, at least ``min_snr_db``.

    Parameters
    ----------
    peak_envelope : float
        Largest envelope amplitude of the filtered response (response unit).
    noise_floor : float
        In-band noise amplitude (same unit).
    min_snr_db : float
        Smallest acceptable 20 log10(peak / noise).

    Returns
    -------
    CheckResult
        The measured value (the unit its quality row states) and ``reason``: None
        when the run passes, else what failed and by how much.
    """
    if not peak_envelope > 0.0:
        return CheckResult(-math.inf, f"signal-to-noise: no signal (peak envelope {peak_envelope:.3g})")
    if not noise_floor > 0.0:
        return CheckResult(math.inf, None)  # a noiseless record: unlimited signal-to-noise
    snr_db = 20.0 * math.log10(peak_envelope / noise_floor)
    if snr_db >= min_snr_db:
        return CheckResult(snr_db, None)
    return CheckResult(
        snr_db,
        (
            f"signal-to-noise {snr_db:.3g} dB is below {min_snr_db:.3g} dB "
            f"(peak envelope {peak_envelope:.3g}, noise floor {noise_floor:.3g})"
        ),
    )


QC_COLUMNS: list[str] = ["check", "applied", "passed", "value", "threshold", "unit", "reason"]
"""Columns of a per-run quality table (one row per check; see :func:`quality_rows`)."""


def quality_columns(configuration: str, run: str, rows: list[dict]) -> dict[str, np.ndarray]:
    """One run's quality rows as typed columns, led by ``configuration``, ``run``, ``mode``
    (the index of the configuration's mode, -1 for a record-level check) and ``channel``
    (empty for a file that could not be read).

    A passed check's ``reason`` (None in the rows) is the empty string.
    """
    n = len(rows)
    return {
        "configuration": np.full(n, configuration),
        "run": np.full(n, run),
        "mode": np.array([row.get("mode", -1) for row in rows], dtype=int),
        "channel": np.array([row.get("channel", "") for row in rows], dtype=str),
        "check": np.array([row["check"] for row in rows], dtype=str),
        "applied": np.array([row["applied"] for row in rows], dtype=bool),
        "passed": np.array([row["passed"] for row in rows], dtype=bool),
        "value": np.array([row["value"] for row in rows], dtype=float),
        "threshold": np.array([row["threshold"] for row in rows], dtype=float),
        "unit": np.array([row["unit"] for row in rows], dtype=str),
        "reason": np.array([row["reason"] or "" for row in rows], dtype=str),
    }


def quality_rows(
    record: RunRecord,
    settings: QualitySettings,
    *,
    mode_hz: float | None = None,
) -> list[dict]:
    """The record-level checks of one run, one row per check.

    Each row holds ``check`` (name), ``applied`` (False when the check does not apply:
    no force column, pre-trigger not stated, mode unknown, or no hit to trigger on),
    ``passed``, the measured ``value`` and its ``threshold`` and ``unit``, and the
    ``reason`` (empty when passed). Value and verdict come from one measurement per
    check (the ``check_*`` functions return its verdict), so the table and runs.parquet
    never disagree. The decay-level checks (signal-to-noise, segment count) are
    rows made by :func:`analysis_rows`.

    Returns
    -------
    list of dict
        Rows with the keys of :data:`QC_COLUMNS`, in a fixed order of checks.
    """

    def row(check, result, threshold, unit, applied=True):
        return {
            "check": check,
            "applied": applied,
            "passed": applied and result.reason is None,
            "value": float(result.value) if applied else math.nan,
            "threshold": float(threshold),
            "unit": unit,
            "reason": result.reason or "",
        }

    not_applied = CheckResult(math.nan, None)
    force = record.force_lbf
    has_force = force is not None
    excitation = check_excitation(force, settings.min_peak_force_lbf) if has_force else not_applied
    trigger_applies = has_force and excitation.reason is None and record.pretrigger_source != "default"
    return [
        row(
            "clipping",
            check_clipping(
                record.response,
                settings.clip_fraction_of_peak,
                settings.clip_max_samples,
                record.response_unit,
            ),
            settings.clip_max_samples,
            "samples at the peak (at most)",
        ),
        row(
            "excitation",
            excitation,
            settings.min_peak_force_lbf,
            "lbf peak force (at least)",
            applied=has_force,
        ),
        row(
            "double_hit",
            check_double_hit(
                force, record.sample_rate_hz, settings.double_hit_ratio, settings.double_hit_gap_s
            )
            if has_force
            else not_applied,
            settings.double_hit_ratio,
            "second pulse / main pulse (at most)",
            applied=has_force,
        ),
        row(
            "trigger",
            check_trigger(
                force, record.pretrigger_samples, tolerance_samples=settings.trigger_tolerance_samples
            )
            if trigger_applies
            else not_applied,
            settings.trigger_tolerance_samples,
            "samples from the pre-trigger length (at most)",
            applied=trigger_applies,
        ),
        row(
            "record_length",
            check_record_length(record.n_samples, record.sample_rate_hz, mode_hz, settings.min_record_cycles)
            if mode_hz is not None
            else not_applied,
            settings.min_record_cycles,
            "cycles of the mode (at least)",
            applied=mode_hz is not None,
        ),
    ]


def analysis_rows(
    peak_envelope: float, noise_floor: float, n_segments: int, settings: QualitySettings
) -> list[dict]:
    """The decay-level checks as rows of a quality table (see :func:`quality_rows`)."""
    snr_db, snr_reason = check_snr(peak_envelope, noise_floor, settings.min_snr_db)
    segments_reason = None
    if n_segments < settings.min_segments:
        segments_reason = (
            f"only {n_segments} usable log-decrement segments (at least {settings.min_segments} needed)"
        )
    return [
        {
            "check": "snr",
            "applied": True,
            "passed": snr_reason is None,
            "value": snr_db,
            "threshold": float(settings.min_snr_db),
            "unit": "dB (at least)",
            "reason": snr_reason or "",
        },
        {
            "check": "segments",
            "applied": True,
            "passed": segments_reason is None,
            "value": float(n_segments),
            "threshold": float(settings.min_segments),
            "unit": "usable segments (at least)",
            "reason": segments_reason or "",
        },
    ]

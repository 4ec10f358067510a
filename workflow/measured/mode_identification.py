"""The modes of each configuration, found in its runs (``identify_mode`` rule).

Every mode campaign.yaml asks for (``mode_hz``, ``modes_hz`` or ``auto``) is searched in
the analysed part of every response channel of every readable run; the result is the
configuration's :class:`~workflow.io.interim.ConfigurationMode`, never an exception for
bad data.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping

import numpy as np

from workflow.io.interim import ConfigurationMode, ModeInfo
from workflow.io.limits import MAX_QUOTED_PROBLEMS, QUOTED_CHARACTERS, shortened
from workflow.io.record_rules import rates_agree
from workflow.io.records import RunRecord
from workflow.measured import mode as modal_id
from workflow.measured import quality
from workflow.measured.runs import analysis_window, read_with_quality, record_problems, window_problems
from workflow.measured.settings import AnalysisSettings, QualitySettings

__all__ = [
    "mode_search_range",
    "WINDOW_ADVICE",
    "channel_responses",
    "identify_mode",
    "identify_configuration_mode",
    "identify_configuration_modes",
    "find_every_mode",
]


def mode_search_range(
    sample_rate_hz: float,
    campaign_mode_hz: float | None,
    mode_search_hz: tuple[float, float] | None,
    mode_search_fraction: float,
) -> tuple[float, float]:
    """Frequency range in which the first mode is searched, Hz."""
    if campaign_mode_hz is not None:
        return (
            campaign_mode_hz * (1.0 - mode_search_fraction),
            campaign_mode_hz * (1.0 + mode_search_fraction),
        )
    if mode_search_hz is not None:
        return mode_search_hz
    return 5.0, 0.4 * sample_rate_hz


WINDOW_ADVICE = (
    "give the configuration window_s: [start, end] in campaign.yaml, the seconds of every run "
    "where the free decay is (after the excitation stops)"
)
"""What a message about a line that does not decay asks the user for."""


def channel_responses(
    records: list[RunRecord], windows: list[tuple[int, int]]
) -> tuple[list[np.ndarray], list[tuple[RunRecord, tuple[int, int]]], list[str | None]]:
    """The analysed part of every response channel of every run, for the mode search, the
    run and window each comes from, and its channel's name (None for a one-channel
    record). With several channels each is divided by its RMS over every run, so that a
    sensor in a larger unit (or nearer an antinode) does not hide the modes the others
    see; one channel is left as recorded."""
    parts, owners, names = [], [], []
    for record, (start, stop) in zip(records, windows):
        for channel in record.responses or (None,):
            values = record.response if channel is None else channel.values
            parts.append(values[start:stop])
            owners.append((record, (start, stop)))
            names.append(None if channel is None else channel.name)
    if len(set(names)) > 1:
        for name in set(names):
            mine = [i for i, other in enumerate(names) if other == name]
            rms = np.sqrt(np.mean(np.concatenate([parts[i] for i in mine]) ** 2))
            for i in mine:
                parts[i] = parts[i] / rms if rms > 0 else parts[i]
    return parts, owners, names


def identify_mode(
    records: list[RunRecord],
    *,
    windows: list[tuple[int, int]],
    campaign_mode_hz: float | None,
    campaign_band_hz: tuple[float, float] | None,
    band_half_width: float,
    mode_search_hz: tuple[float, float] | None,
    mode_search_fraction: float,
    min_mode_prominence: float = QualitySettings.min_mode_prominence,
) -> ModeInfo:
    """First-mode frequency of a configuration from all its readable runs.

    The H1 frequency-response estimate (with coherence) is used when every run
    recorded the force, the averaged response spectrum otherwise. The band is
    campaign.yaml's ``band_hz`` when given, else ``mode * (1 -/+ band_half_width)``.
    """
    if not records:
        raise ValueError("no readable run to identify the mode from")
    sample_rate_hz = records[0].sample_rate_hz
    search_hz = mode_search_range(sample_rate_hz, campaign_mode_hz, mode_search_hz, mode_search_fraction)
    responses, owners, channels = channel_responses(records, windows)
    spectra = None
    coherence_at_mode = None
    if all(record.force_lbf is not None for record in records):
        forces = [owner.force_lbf[start:stop] for owner, (start, stop) in owners]
        frequency_hz, amplitude, coherence = modal_id.h1_over_channels(
            forces, responses, channels, sample_rate_hz
        )
        mode_hz = modal_id.find_mode_hz(frequency_hz, amplitude, search_hz)
        coherence_at_mode = float(np.interp(mode_hz, frequency_hz, coherence))
        method = "h1"
    else:
        spectra = modal_id.centred_spectra(responses)
        frequency_hz, psd = modal_id.response_spectrum(responses, sample_rate_hz, spectra=spectra)
        mode_hz = modal_id.find_mode_hz(frequency_hz, psd, search_hz)
        method = "spectrum"
        amplitude = np.sqrt(np.abs(psd))
    # A noise ripple on the flank of a mode outside the range is not the mode.
    not_a_resonance = quality.check_mode_found(
        frequency_hz, amplitude, mode_hz, search_hz, min_prominence=min_mode_prominence
    )
    if not_a_resonance:
        raise ValueError(not_a_resonance)
    if not np.isfinite(mode_hz):
        raise ValueError(f"the {method} spectrum of the runs gives no finite peak frequency")
    if coherence_at_mode is not None and not np.isfinite(coherence_at_mode):
        coherence_at_mode = None  # no force energy at the mode: no coherence estimate
    forced = modal_id.forced_line_problem(
        responses, sample_rate_hz, mode_hz, frequency_hz, amplitude, spectra=spectra
    )
    if forced is not None:
        raise ValueError(f"{forced}; {WINDOW_ADVICE}")
    if campaign_band_hz is not None:
        band_hz = (float(campaign_band_hz[0]), float(campaign_band_hz[1]))
    else:
        band_hz = modal_id.band_around(mode_hz, band_half_width)
    if band_hz[1] >= sample_rate_hz / 2.0:
        raise ValueError(
            f"the band [{band_hz[0]:.6g}, {band_hz[1]:.6g}] Hz around the mode at {mode_hz:.6g} Hz reaches the "
            f"Nyquist frequency {sample_rate_hz / 2.0:.6g} Hz; give a narrower band_hz in campaign.yaml"
        )
    return ModeInfo(
        mode_hz=float(mode_hz),
        band_hz=band_hz,
        method=method,
        coherence_at_mode=coherence_at_mode,
        n_runs=len(records),
        sample_rate_hz=float(sample_rate_hz),
        record_duration_s=float(np.median([(stop - start) for start, stop in windows]) / sample_rate_hz),
    )


def identify_configuration_mode(
    campaign_dir,
    run_paths: list[str],
    *,
    configuration: str,
    campaign,
    mode_search: AnalysisSettings,
    quality_settings: QualitySettings,
    reads: Mapping[str, tuple[RunRecord | None, list[dict]]] | None = None,
) -> ConfigurationMode:
    """First mode of one configuration from its run files; never raises for bad data.

    Runs that cannot be read or fail a record-level check are left out (listed in
    ``skipped_runs`` with their reasons); when no mode is found, ``error`` says why, and
    every run of the configuration is later excluded with that reason while the other
    configurations go on.

    Parameters
    ----------
    campaign_dir : path
        The campaign folder.
    run_paths : list of str
        The configuration's run files, relative to ``campaign_dir``.
    configuration : str
        The configuration.
    campaign : Campaign
        The validated campaign.yaml.
    mode_search : AnalysisSettings
        Mode search range and band width.
    quality_settings : QualitySettings
        Record-level checks and the least prominence of a mode.
    reads : mapping, optional
        Run path -> the run as :func:`~workflow.measured.runs.read_with_quality` gave it,
        for the runs already read; the others are read here.
    """
    from pathlib import PurePosixPath

    window_s = campaign.configurations[configuration].window_s
    records, windows, run_paths_used, skipped = [], [], [], {}
    reads = reads or {}
    for run_path in run_paths:
        record, rows = reads.get(run_path) or read_with_quality(
            campaign_dir, run_path, campaign, quality_settings
        )
        problems, channel_failures = record_problems(run_path, rows)
        if not problems:
            problems = window_problems(campaign_dir, run_path, record, campaign, configuration)
        if problems:
            skipped[PurePosixPath(run_path).stem] = problems
            continue
        # a clipped sensor's harmonics are not modes: the search reads the others
        records.append(record.without_channels({row["channel"] for row in channel_failures}))
        windows.append(analysis_window(record, window_s))
        run_paths_used.append(run_path)
    if not records:
        reasons = [problem for problems in skipped.values() for problem in problems]
        if len(reasons) > MAX_QUOTED_PROBLEMS:
            hidden = len(reasons) - MAX_QUOTED_PROBLEMS
            reasons = [*reasons[:MAX_QUOTED_PROBLEMS], f"and {hidden} more (runs.parquet lists every reason)"]
        return ConfigurationMode(
            None,
            f"configuration {configuration}: first mode not found: every run of the configuration is "
            f"excluded ({len(skipped)} of {len(run_paths)}): " + "; ".join(reasons),
            skipped,
        )
    common_hz = _common_sample_rate_hz([record.sample_rate_hz for record in records])
    for index in reversed(range(len(records))):
        rate_hz = records[index].sample_rate_hz
        if not rates_agree(rate_hz, common_hz):
            # one spectrum grid for all: a run at another rate would be read at the wrong frequencies
            skipped[PurePosixPath(run_paths_used[index]).stem] = [
                f"{run_paths_used[index]}: left out of the mode search only: sample rate {rate_hz:.9g} Hz "
                f"differs from the {common_hz:.9g} Hz of most runs of the configuration"
            ]
            del records[index], windows[index]
    try:
        return identify_configuration_modes(
            records, windows, configuration, campaign, mode_search, quality_settings, skipped
        )
    except Exception as error:  # a fault of the search must not stop the other configurations
        logging.getLogger(__name__).exception("configuration %s: mode search failed", configuration)
        return ConfigurationMode(
            None,
            f"configuration {configuration}: first mode not found: {type(error).__name__}: "
            f"{shortened(str(error), 10 * QUOTED_CHARACTERS)} (an error of the mode search, not a known "
            "fault of the files: the job's log has the trace)",
            skipped,
        )


def identify_configuration_modes(
    records: list[RunRecord],
    windows: list[tuple[int, int]],
    configuration: str,
    campaign,
    mode_search: AnalysisSettings,
    quality_settings: QualitySettings,
    skipped: dict[str, list[str]],
) -> ConfigurationMode:
    """Every mode campaign.yaml asks of one configuration's readable runs (``modes_hz``,
    ``mode_hz`` or ``auto``, :meth:`~workflow.io.campaign.Campaign.mode_requests`); a mode
    that is not found is the configuration's error, naming it."""
    options = {
        "windows": windows,
        "band_half_width": mode_search.band_half_width,
        "mode_search_hz": mode_search.mode_search_hz,
        "mode_search_fraction": mode_search.mode_search_fraction,
        "min_mode_prominence": quality_settings.min_mode_prominence,
    }
    left_out: list[str] = []
    requests = campaign.mode_requests()
    if campaign.auto_modes:
        try:
            found_hz, left_out = find_every_mode(records, **options)
        except ValueError as error:
            return ConfigurationMode(None, f"configuration {configuration}: no mode found: {error}", skipped)
        requests = tuple((mode_hz, None) for mode_hz in found_hz)
        # each found mode is the largest peak of its own band: search no wider
        options["mode_search_fraction"] = min(mode_search.mode_search_fraction, mode_search.band_half_width)
    modes = []
    for index, (mode_hz, band_hz) in enumerate(requests):
        which = "first mode" if index == 0 else f"mode {mode_hz:.6g} Hz"
        try:
            modes.append(
                identify_mode(records, campaign_mode_hz=mode_hz, campaign_band_hz=band_hz, **options)
            )
        except ValueError as error:
            return ConfigurationMode(
                None,
                f"configuration {configuration}: {which} not found: {error}",
                skipped,
                left_out=tuple(left_out),
            )
    return ConfigurationMode(modes[0], "", skipped, tuple(modes[1:]), tuple(left_out))


def find_every_mode(
    records: list[RunRecord],
    *,
    windows: list[tuple[int, int]],
    band_half_width: float,
    mode_search_hz: tuple[float, float] | None,
    mode_search_fraction: float,
    min_mode_prominence: float,
) -> tuple[list[float], list[str]]:
    """Every clear, decaying mode of a configuration's runs (``modes_hz: auto``), Hz,
    from the spectrum of every channel (:func:`channel_responses`), searched below
    0.4 x the sample rate (or in config ``mode_search_hz``); and why each clear peak
    left out is not a mode. Raises ValueError when there is none."""
    if not records:
        raise ValueError("no readable run to find the modes in")
    sample_rate_hz = records[0].sample_rate_hz
    search_hz = mode_search_range(sample_rate_hz, None, mode_search_hz, mode_search_fraction)
    responses, _, _ = channel_responses(records, windows)
    spectra = modal_id.centred_spectra(responses)
    frequency_hz, psd = modal_id.response_spectrum(responses, sample_rate_hz, spectra=spectra)
    found, left_out = modal_id.find_decaying_modes(
        responses,
        sample_rate_hz,
        frequency_hz,
        np.sqrt(psd),
        search_hz,
        band_half_width,
        min_mode_prominence,
        spectra=spectra,
    )
    if not found:
        reasons = "".join(f"; {reason}" for reason in left_out)
        advice = f"; {WINDOW_ADVICE}" if left_out else ""
        raise ValueError(
            f"no clear, decaying mode in {search_hz[0]:.4g}-{search_hz[1]:.4g} Hz{reasons}{advice}"
        )
    return found, left_out


def _common_sample_rate_hz(rates_hz: list[float]) -> float:
    """The sample rate that most of the rates agree with (the first of equals)."""
    agreeing = [sum(rates_agree(rate, other) for other in rates_hz) for rate in rates_hz]
    return rates_hz[int(np.argmax(agreeing))]

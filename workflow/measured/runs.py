"""The measured-data chain, one stage per function, as the workflow's rules call it.

Each function takes already-read records and plain settings and returns tables or
small documents; the scripts in ``scripts/`` only read inputs and write outputs.

The run-level stages return columns as NumPy arrays and this module imports pandas
only inside the campaign-level functions: a run-analysis job then starts without
pandas.
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from workflow.io import units
from workflow.io.campaign import SINGLE_CHANNEL_NAME, RunRecord
from workflow.io.interim import ConfigurationMode, ModeInfo
from workflow.io.limits import MAX_QUOTED_PROBLEMS, QUOTED_CHARACTERS, quoted, shortened
from workflow.io.record_rules import rates_agree
from workflow.io.settings import (
    AnalysisSettings,
    DampingFitSettings,
    DecaySettings,
    ModeSearchSettings,
    QualitySettings,
)
from workflow.measured import decay, quality
from workflow.measured import mode as modal_id

if TYPE_CHECKING:
    import pandas as pd


__all__ = [
    "analysis_window",
    "window_problem",
    "mode_search_range",
    "WINDOW_ADVICE",
    "channel_responses",
    "identify_mode",
    "RUN_COLUMNS",
    "SEGMENT_COLUMNS",
    "empty_segments",
    "analyse_run_with_quality",
    "read_with_quality",
    "labelled",
    "analyse_every_mode_and_channel",
    "failed_checks",
    "read_and_check",
    "RunAnalysis",
    "analyse_run_file",
    "identify_configuration_mode",
    "identify_configuration_modes",
    "find_every_mode",
    "analyse_campaign",
    "response_unit_label",
    "nominal_modes_hz",
    "with_nominal_mode",
    "first_mode_and_channel",
    "with_mode_and_channel",
    "first_mode_rows",
    "collect_tables",
    "NOTHING_ANALYSED",
    "nothing_analysed_message",
    "nothing_analysed_in_tables",
    "fit_damping_curves",
    "fit_mode_damping_curves",
]


def analysis_window(record: RunRecord, window_s: tuple[float, float] | None) -> tuple[int, int]:
    """Sample indices [start, stop) of the part of a run to analyse.

    Without ``window_s`` the whole record is used (the decay start is then found
    at the excitation peak by the decay analysis).
    """
    if window_s is None:
        return 0, record.n_samples
    # clamped before rounding: a window end of 1e308 s is past the record, not an overflow
    start = int(round(min(max(window_s[0] * record.sample_rate_hz, 0.0), record.n_samples)))
    stop = int(round(min(max(window_s[1] * record.sample_rate_hz, start), record.n_samples)))
    return start, stop


def window_problem(record: RunRecord, window_s: tuple[float, float] | None, configuration: str) -> str | None:
    """Why campaign.yaml's ``window_s`` leaves too little of a record to analyse, or None.

    The window is the part of every run to analyse, in s from the start of the file
    (campaign-format.md); the part of it inside the record must hold at least
    :data:`~workflow.io.campaign.MIN_SAMPLES` samples, as a whole run file must.
    """
    from workflow.io.campaign import MIN_SAMPLES

    if window_s is None:
        return None
    start, stop = analysis_window(record, window_s)
    if stop - start >= MIN_SAMPLES:
        return None
    return (
        f"campaign.yaml configurations.{configuration}.window_s [{window_s[0]:.6g}, {window_s[1]:.6g}] s "
        f"holds {stop - start} samples of this record, which spans 0 to "
        f"{record.n_samples / record.sample_rate_hz:.6g} s ({record.n_samples} samples at "
        f"{record.sample_rate_hz:.6g} Hz); the part of the run to analyse needs at least {MIN_SAMPLES} samples"
    )


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
        frequency_hz, psd = modal_id.response_spectrum(responses, sample_rate_hz)
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
    forced = modal_id.forced_line_problem(responses, sample_rate_hz, mode_hz, frequency_hz, amplitude)
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


RUN_COLUMNS = ["configuration", "run", "path", "status", "reason", "record_start"]
"""Columns of the runs table (``record_start``: ISO 8601 recording start, empty when the
file states none; :mod:`workflow.io.recording_time`)."""

SEGMENT_COLUMNS = [
    "configuration",
    "run",
    "mode",
    "channel",
    "t_s",
    "response_amplitude",
    "velocity_amplitude_in_s",
    "frequency_hz",
    "zeta",
    "fit_rms",
    "kept",
    "reject_reason",
]


_SEGMENT_DTYPES = {
    "configuration": str,
    "run": str,
    "mode": int,
    "channel": str,
    "kept": bool,
    "reject_reason": str,
}


def empty_segments() -> dict[str, np.ndarray]:
    """The columns of a segments table with no rows."""
    return {name: np.array([], dtype=_SEGMENT_DTYPES.get(name, float)) for name in SEGMENT_COLUMNS}


def analyse_run_with_quality(
    record: RunRecord,
    *,
    configuration: str,
    run: str,
    mode: ModeInfo,
    window: tuple[int, int],
    decay_settings: DecaySettings,
    quality_settings: QualitySettings,
) -> tuple[dict[str, np.ndarray], list[dict]]:
    """Band-pass, envelope and segmented log decrement of one run, with its checks.

    Parameters
    ----------
    record : RunRecord
        The run, read.
    configuration, run : str
        Its configuration and run name (written into every row).
    mode : ModeInfo
        The configuration's mode and band.
    window : (int, int)
        Sample indices [start, stop) to analyse (:func:`analysis_window`).
    decay_settings : DecaySettings
        The decay analysis settings (filter order, segment length and overlap, noise
        floor factor, edge time constants).
    quality_settings : QualitySettings
        The thresholds of the decay-level checks (signal-to-noise, usable segments).

    Returns
    -------
    segments : dict of ndarray
        The columns of :data:`SEGMENT_COLUMNS`: every segment with ``kept`` and
        ``reject_reason``; times are seconds from the start of the file;
        ``velocity_amplitude_in_s`` uses each segment's local frequency.
    quality_rows : list of dict
        The decay-level quality checks (signal-to-noise, usable segments) as rows
        of the quality table (:func:`workflow.measured.quality.analysis_rows`).
    """
    start, stop = window
    result = decay.analyse_decay(
        record.response,
        record.sample_rate_hz,
        mode.band_hz,
        mode_hz=mode.mode_hz,
        **asdict(decay_settings),
        start_index=start if window != (0, record.n_samples) else None,
        stop_index=stop,
    )
    segments = result.segments
    n_segments = len(segments["t_s"])
    columns = {
        "configuration": np.full(n_segments, configuration),
        "run": np.full(n_segments, run),
        "t_s": np.asarray(segments["t_s"], dtype=float),
        "response_amplitude": np.asarray(segments["amplitude"], dtype=float),
        "velocity_amplitude_in_s": units.velocity_amplitude_in_s(
            np.asarray(segments["amplitude"], dtype=float),
            record.response_quantity,
            record.response_unit,
            np.asarray(segments["frequency_hz"], dtype=float),
        ),
        "frequency_hz": np.asarray(segments["frequency_hz"], dtype=float),
        "zeta": np.asarray(segments["zeta"], dtype=float),
        "fit_rms": np.asarray(segments["fit_rms"], dtype=float),
        "kept": np.asarray(segments["kept"], dtype=bool),
        "reject_reason": np.asarray(segments["reject_reason"], dtype=str),
    }
    peak_envelope = float(np.max(result.envelope[result.start_index : stop]))
    rows = quality.analysis_rows(
        peak_envelope, result.noise_floor, int(columns["kept"].sum()), quality_settings
    )
    return columns, rows


def read_with_quality(
    campaign_dir, path: str, campaign, quality_settings
) -> tuple[RunRecord | None, list[dict]]:
    """Read one run file and apply the record-level quality checks.

    Returns the record (None when it cannot be read) and one row per check
    (:func:`workflow.measured.quality.quality_rows`); an unreadable file gives a single
    ``read`` row whose reason names the file, the line and what is wrong.
    """
    from workflow.io.campaign import CampaignFormatError, read_run

    try:
        record = read_run(campaign_dir, path, campaign)
    except CampaignFormatError as error:
        reason = str(error)
    except Exception as error:  # a fault of the reader on one file must not stop the others
        logging.getLogger(__name__).exception("%s: not read", path)
        reason = _fault_reason(campaign_dir, path, "read", error)
    else:
        requested_hz = [mode_hz for mode_hz, _ in campaign.mode_requests() if mode_hz is not None]
        names = record.channel_names() or (SINGLE_CHANNEL_NAME,)
        rows = []
        for name in names:
            # the lowest mode asks the most of a record's length in cycles
            mine = quality.quality_rows(
                record.for_channel(name) if record.responses else record,
                quality_settings,
                mode_hz=min(requested_hz, default=None),
            )
            rows += [labelled(row, name, len(names) > 1) for row in mine]
        return record, rows
    return None, [
        {
            "check": "read",
            "applied": True,
            "passed": False,
            "value": float("nan"),
            "threshold": float("nan"),
            "unit": "",
            "reason": reason,
        }
    ]


def labelled(row: dict, channel: str, several: bool, mode: int = -1, mode_hz: float | None = None) -> dict:
    """A quality row with the channel and mode (index, -1 for a record-level check) it
    belongs to; with several channels (or modes) its reason names them."""
    reason = row["reason"]
    if reason:
        where = [f"channel {quoted(channel)}"] if several else []
        where += [f"mode {mode_hz:.6g} Hz"] if mode_hz is not None else []
        reason = f"{', '.join(where)}: {reason}" if where else reason
    return {**row, "reason": reason, "channel": channel, "mode": mode}


def _window_problems(
    campaign_dir, run_path: str, record: RunRecord, campaign, configuration: str
) -> list[str]:
    """The window problem of one read run (:func:`window_problem`) as a message naming the file."""
    problem = window_problem(record, campaign.configurations[configuration].window_s, configuration)
    return [] if problem is None else [f"{(Path(campaign_dir) / run_path).as_posix()}: {problem}"]


def _fault_reason(campaign_dir, path: str, step: str, error: Exception) -> str:
    """The exclusion reason of a run whose reading or analysis raised an unexpected error."""
    stage = "reader" if step == "read" else "analysis"
    return (
        f"{(Path(campaign_dir) / path).as_posix()}: not {step}: {type(error).__name__}: "
        f"{shortened(str(error), 10 * QUOTED_CHARACTERS)} (an error of the {stage}, not a known fault "
        "of the file: the job's log has the trace)"
    )


def analyse_every_mode_and_channel(
    record: RunRecord,
    *,
    configuration: str,
    run: str,
    mode: ConfigurationMode,
    window: tuple[int, int],
    decay_settings: DecaySettings,
    quality_settings: QualitySettings,
) -> tuple[dict[str, np.ndarray], list[dict]]:
    """:func:`analyse_run_with_quality` for every mode of the configuration on every
    response channel of the run: the segments (with ``mode``, the mode's index, and
    ``channel``) and the decay-level quality rows (:func:`labelled`)."""
    names = record.channel_names() or (SINGLE_CHANNEL_NAME,)
    several = len(names) > 1 or len(mode.modes) > 1
    parts, decay_rows = [], []
    for index, info in enumerate(mode.modes):
        for name in names:
            columns, mine = analyse_run_with_quality(
                record.for_channel(name) if record.responses else record,
                configuration=configuration,
                run=run,
                mode=info,
                window=window,
                decay_settings=decay_settings,
                quality_settings=quality_settings,
            )
            n = len(columns["t_s"])
            parts.append({**columns, "mode": np.full(n, index), "channel": np.full(n, name)})
            mode_hz = info.mode_hz if len(mode.modes) > 1 else None
            decay_rows += [labelled(row, name, several, index, mode_hz) for row in mine]
    return {key: np.concatenate([part[key] for part in parts]) for key in SEGMENT_COLUMNS}, decay_rows


def failed_checks(path: str, rows: list[dict]) -> list[str]:
    """Messages of the failed checks, each naming the file."""
    return [
        row["reason"] if row["check"] == "read" else f"{path}: {row['reason']}"
        for row in rows
        if row["applied"] and not row["passed"]
    ]


def read_and_check(campaign_dir, path: str, campaign, quality_settings) -> tuple[RunRecord | None, list[str]]:
    """Read one run file and apply the record-level quality checks.

    Returns the record (None when it cannot be read) and the list of problems,
    each a message that names the file and what is wrong.
    """
    record, rows = read_with_quality(campaign_dir, path, campaign, quality_settings)
    return record, failed_checks(path, rows)


@dataclass(frozen=True)
class RunAnalysis:
    """What the workflow keeps of one run file: its segments (columns of
    :data:`SEGMENT_COLUMNS`), its quality checks (columns of
    :func:`workflow.measured.quality.quality_columns`) and its status (used, or excluded with
    the reason)."""

    segments: dict[str, np.ndarray]
    quality: dict[str, np.ndarray]
    status: dict[str, str]


def analyse_run_file(
    campaign_dir,
    run_path: str,
    *,
    configuration: str,
    campaign,
    mode: ConfigurationMode,
    quality_settings: QualitySettings,
    decay_settings: DecaySettings,
) -> RunAnalysis:
    """Read, check and analyse one run file; a run that cannot be used is excluded
    with its reason, never raised.

    Parameters
    ----------
    campaign_dir : path
        The campaign folder.
    run_path : str
        The run file, relative to ``campaign_dir``.
    configuration : str
        Its configuration.
    campaign : Campaign
        The validated campaign.yaml.
    mode : ConfigurationMode
        The configuration's mode search result (:func:`identify_configuration_mode`);
        without a mode, the run is excluded with the reason none was found.
    quality_settings : QualitySettings
        Quality thresholds.
    decay_settings : DecaySettings
        The decay analysis settings.
    """
    from pathlib import PurePosixPath

    run = PurePosixPath(run_path).stem
    segments = empty_segments()
    record, rows = read_with_quality(campaign_dir, run_path, campaign, quality_settings)
    problems = failed_checks(run_path, rows)
    if record is not None and not problems:
        problems = _window_problems(campaign_dir, run_path, record, campaign, configuration)
    if record is not None and not problems:
        if mode.mode is None:
            problems = [mode.error]
        else:
            try:
                segments, decay_rows = analyse_every_mode_and_channel(
                    record,
                    configuration=configuration,
                    run=run,
                    mode=mode,
                    window=analysis_window(record, campaign.configurations[configuration].window_s),
                    decay_settings=decay_settings,
                    quality_settings=quality_settings,
                )
            except Exception as error:  # a fault on one run must not stop the others
                logging.getLogger(__name__).exception("%s: not analysed", run_path)
                problems = [_fault_reason(campaign_dir, run_path, "analysed", error)]
            else:
                rows += decay_rows
                problems = failed_checks(run_path, decay_rows)
    status = {
        "configuration": configuration,
        "run": run,
        "path": run_path,
        "status": "excluded" if problems else "used",
        "reason": "; ".join(problems),
        "record_start": "" if record is None else record.record_start,
        "response_units": {} if record is None else {c.name: c.unit for c in record.responses},
    }
    return RunAnalysis(segments, quality.quality_columns(configuration, run, rows), status)


def identify_configuration_mode(
    campaign_dir,
    run_paths: list[str],
    *,
    configuration: str,
    campaign,
    mode_search: ModeSearchSettings,
    quality_settings: QualitySettings,
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
    mode_search : ModeSearchSettings
        Mode search range and band width.
    quality_settings : QualitySettings
        Record-level checks and the least prominence of a mode.
    """
    from pathlib import PurePosixPath

    window_s = campaign.configurations[configuration].window_s
    records, windows, run_paths_used, skipped = [], [], [], {}
    for run_path in run_paths:
        record, problems = read_and_check(campaign_dir, run_path, campaign, quality_settings)
        if not problems:
            problems = _window_problems(campaign_dir, run_path, record, campaign, configuration)
        if problems:
            skipped[PurePosixPath(run_path).stem] = problems
            continue
        records.append(record)
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
    mode_search: ModeSearchSettings,
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
    frequency_hz, psd = modal_id.response_spectrum(responses, sample_rate_hz)
    found, left_out = modal_id.find_decaying_modes(
        responses, sample_rate_hz, frequency_hz, np.sqrt(psd), search_hz, band_half_width, min_mode_prominence
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


def analyse_campaign(
    campaign_dir, analysis: AnalysisSettings, quality_settings: QualitySettings
) -> pd.DataFrame:
    """Kept segments of every usable run of a campaign, in one process.

    The workflow's rules ``identify_mode``, ``analyse_runs`` and ``collect_tables`` make
    the same calls, split over jobs; this is the whole chain for studies over many
    campaigns (``bench/hit_rate.py``).

    Returns the rows ``results/tables/segments.parquet`` would hold.
    """
    import pandas as pd

    from workflow.io.campaign import list_runs, load_campaign

    campaign = load_campaign(campaign_dir)
    run_files = list_runs(campaign_dir, campaign)
    frames = []
    for name, spec in campaign.configurations.items():
        paths = [run_file.path for run_file in run_files if run_file.configuration == name]
        options = {"configuration": name, "campaign": campaign, "quality_settings": quality_settings}
        mode = identify_configuration_mode(campaign_dir, paths, mode_search=analysis.mode_search(), **options)
        for path in paths:
            result = analyse_run_file(
                campaign_dir, path, mode=mode, decay_settings=analysis.decay(), **options
            )
            if result.status["status"] != "used":
                continue
            segments = pd.DataFrame(result.segments)
            kept = segments[segments["kept"]].drop(columns=["kept", "reject_reason"])
            kept["bearing_area_in2"] = spec.bearing_area_in2 if spec.bearing_area_in2 is not None else np.nan
            frames.append(kept)
    if not frames:
        columns = [name for name in SEGMENT_COLUMNS if name not in ("kept", "reject_reason")]
        return pd.DataFrame(columns=[*columns, "bearing_area_in2"])
    return pd.concat(frames, ignore_index=True)


def response_unit_label(campaign, statuses: list[dict]) -> str:
    """The unit of the tables' ``response_amplitude``, for the Parquet metadata:
    campaign.yaml's response unit, else the one the run files record (each channel's
    when they differ), with the quantity; e.g. ``m/s (velocity)``."""
    quantity = campaign.response.quantity
    if campaign.response.unit is not None:
        return f"{campaign.response.unit} ({quantity})"
    found: dict[str, set[str]] = {}
    for status in statuses:
        for channel, unit in status.get("response_units", {}).items():
            found.setdefault(channel, set()).add(unit)
    every = sorted(set().union(*found.values())) if found else []
    if len(every) == 1:
        return f"{every[0]} ({quantity})"
    if not every:
        return f"unit of the run files ({quantity})"
    return f"{quantity}, per channel: " + "; ".join(
        f"{name} {', '.join(sorted(units_))}" for name, units_ in found.items()
    )


def nominal_modes_hz(campaign, configurations_modes: list[tuple[ModeInfo, ...]]) -> list[float]:
    """The nominal frequency of each analysed mode (the tables' ``mode_hz``), Hz, in the
    configurations' mode order: campaign.yaml's (``modes_hz`` or ``mode_hz``) when it
    gives one, else the median over the configurations of the frequency found for the
    mode of that rank."""
    count = max((len(modes) for modes in configurations_modes), default=0)
    requested = [mode_hz for mode_hz, _ in campaign.mode_requests()]
    nominal = []
    for index in range(count):
        given = requested[index] if index < len(requested) else None
        found = [modes[index].mode_hz for modes in configurations_modes if index < len(modes)]
        nominal.append(float(given) if given is not None else float(np.median(found)))
    return nominal


def with_nominal_mode(table: pd.DataFrame, nominal_hz: list[float]) -> pd.DataFrame:
    """The table with its ``mode`` index column replaced by ``mode_hz`` (the nominal mode
    frequency; NaN for a row of no mode), placed with ``channel`` after ``run``."""
    lookup = np.array([*nominal_hz, np.nan])
    index = table["mode"].to_numpy(dtype=int)
    table = table.drop(columns=["mode"])
    table.insert(2, "mode_hz", lookup[np.where(index >= 0, index, len(nominal_hz))] if len(index) else [])
    channel = table.pop("channel")
    table.insert(3, "channel", channel)
    return table


def first_mode_and_channel(table: pd.DataFrame, channel: str) -> pd.DataFrame:
    """The rows of the first (lowest) mode and of ``channel``: the paper's models, the
    diagnosis and the paper's figures analyse this one mode and sensor. A table without
    ``mode_hz`` or ``channel`` columns is returned whole."""
    if "mode_hz" in table and len(table):
        first_hz = table["mode_hz"].min()
        table = (
            table[table["mode_hz"].isna() | (table["mode_hz"] == first_hz)]
            if not np.isnan(first_hz)
            else table
        )
    if "channel" in table:
        table = table[table["channel"] == channel]
    return table


def with_mode_and_channel(table: pd.DataFrame, mode_hz: float | None, channel: str) -> pd.DataFrame:
    """The table of one mode and channel with ``mode_hz`` and ``channel`` columns right
    after ``configuration`` (or first): the tables every campaign's outputs share."""
    table = table.copy()
    at = table.columns.get_loc("configuration") + 1 if "configuration" in table else 0
    table.insert(at, "mode_hz", np.nan if mode_hz is None else float(mode_hz))
    table.insert(at + 1, "channel", channel)
    return table


def first_mode_rows(modes: pd.DataFrame) -> pd.DataFrame:
    """The modes table's rows of the first mode (and of configurations where none was found)."""
    first_hz = modes["nominal_mode_hz"].min()
    return modes[modes["nominal_mode_hz"].isna() | (modes["nominal_mode_hz"] == first_hz)]


def collect_tables(
    *, segment_paths, quality_paths, status_paths, mode_paths, campaign, excluded_paths=()
) -> dict[str, pd.DataFrame]:
    """Merge the per-run outputs into the campaign's tables.

    ``mode_paths`` are the configurations' mode files (``<configuration>.json``,
    :func:`workflow.io.interim.write_mode`); the other paths list every ``analyse_runs``
    job's files. ``excluded_paths`` are runs-table rows for what the campaign's globs
    lead to that no job reads (:meth:`workflow.io.campaign.ExcludedPath.status`):
    directories, links leading outside the campaign, unreadable files, globs that match
    nothing.

    Returns ``segments`` (kept segments of used runs: the output contract's
    table), ``rejected`` (every other segment, with its reason), ``runs`` (one
    row per run file, used or excluded, then the excluded paths), ``quality`` (one
    row per run and quality check: value, threshold, passed) and ``modes`` (one row
    per configuration).
    """
    from pathlib import Path

    import pandas as pd

    from workflow.io.interim import read_mode, read_run_statuses
    from workflow.io.tables import read_columns

    status_rows = read_run_statuses(status_paths)
    statuses = pd.DataFrame(status_rows + list(excluded_paths))
    statuses = statuses.reindex(columns=RUN_COLUMNS).fillna({"record_start": ""})
    runs = statuses.reset_index(drop=True)
    frames = [pd.DataFrame(read_columns(path)) for path in segment_paths]
    frames = [frame for frame in frames if len(frame)]
    all_segments = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(empty_segments())
    used = set(
        zip(runs.loc[runs["status"] == "used", "configuration"], runs.loc[runs["status"] == "used", "run"])
    )
    run_used = np.array(
        [(c, r) in used for c, r in zip(all_segments["configuration"], all_segments["run"])], dtype=bool
    )
    keep = run_used & all_segments["kept"].to_numpy(dtype=bool)
    rejected = all_segments[~keep].copy()
    rejected.loc[~run_used[~keep], "reject_reason"] = "run excluded (see runs.parquet)"
    areas = {
        name: (spec.bearing_area_in2 if spec.bearing_area_in2 is not None else np.nan)
        for name, spec in campaign.configurations.items()
    }
    segments = all_segments[keep].drop(columns=["kept", "reject_reason"]).copy()
    segments["bearing_area_in2"] = segments["configuration"].map(areas).astype(float)

    found_modes = {Path(path).stem: read_mode(path) for path in mode_paths}
    nominal_hz = nominal_modes_hz(campaign, [found.modes for found in found_modes.values()])
    mode_rows = []
    for name, found in found_modes.items():
        for index, mode in enumerate(found.modes or (None,)):
            mode_rows.append(
                {
                    "configuration": name,
                    "nominal_mode_hz": nominal_hz[index] if mode else np.nan,
                    "mode_hz": mode.mode_hz if mode else np.nan,
                    "band_low_hz": mode.band_hz[0] if mode else np.nan,
                    "band_high_hz": mode.band_hz[1] if mode else np.nan,
                    "method": mode.method if mode else "not found",
                    "sample_rate_hz": mode.sample_rate_hz if mode else np.nan,
                    "record_duration_s": mode.record_duration_s if mode else np.nan,
                    "coherence_at_mode": (mode.coherence_at_mode if mode else None) or np.nan,
                    "bearing_area_in2": areas.get(name, np.nan),
                    "error": found.error,
                }
            )
    quality_table = pd.concat([pd.DataFrame(read_columns(path)) for path in quality_paths], ignore_index=True)
    return {
        "segments": with_nominal_mode(segments, nominal_hz).reset_index(drop=True),
        "rejected": with_nominal_mode(rejected, nominal_hz).reset_index(drop=True),
        "runs": runs,
        "quality": with_nominal_mode(quality_table, nominal_hz),
        "modes": pd.DataFrame(mode_rows),
        "response_unit": response_unit_label(
            campaign, [row for row in status_rows if row["status"] == "used"]
        ),
    }


NOTHING_ANALYSED = "nothing could be analysed"
"""How :func:`nothing_analysed_message` begins."""


def nothing_analysed_message(runs: pd.DataFrame, n_kept_segments: int, rejected: pd.DataFrame) -> str | None:
    """Why nothing of a campaign could be analysed (no kept segment at all), or None.

    Parameters
    ----------
    runs : DataFrame
        The runs table (:data:`RUN_COLUMNS`): every run file, used or excluded with its reason.
    n_kept_segments : int
        Rows of the segments table (kept segments of used runs).
    rejected : DataFrame
        The rejected segments, with ``configuration``, ``run`` and ``reject_reason``.

    Returns
    -------
    str or None
        Which runs, why (the first reasons, each naming its file or campaign.yaml key) and
        what to change, for the last lines a user reads; None when some segment was kept.
    """
    if n_kept_segments > 0:
        return None
    used = runs[runs["status"] == "used"]
    excluded = runs[runs["status"] != "used"]
    lines = [f"{NOTHING_ANALYSED}: no run of the campaign gives a usable segment."]
    if len(excluded):
        lines.append(f"{len(excluded)} of {len(runs)} run files (or globs) are excluded:")
        for row in excluded.head(MAX_QUOTED_PROBLEMS).itertuples():
            name = f"{row.configuration}/{row.run}" if row.run else row.path
            lines.append(f"  {name}: {shortened(str(row.reason), 10 * QUOTED_CHARACTERS)}")
        if len(excluded) > MAX_QUOTED_PROBLEMS:
            lines.append(f"  and {len(excluded) - MAX_QUOTED_PROBLEMS} more")
    if len(used):
        counts = rejected["reject_reason"].value_counts().head(3)
        reasons = "; ".join(f"{count} x {shortened(str(reason))}" for reason, count in counts.items())
        lines.append(
            f"{len(used)} run(s) were read but every segment of them was rejected"
            + (f" ({reasons})" if reasons else " (none was long enough to measure)")
        )
    lines.append(
        "What to change: each reason names the file (and line) or the campaign.yaml key at fault; "
        "correct those, or choose the channel, window_s, band_hz or mode_hz that fit the records "
        "(docs/input-format.md). Every run and its reason: results/tables/runs.csv"
    )
    return "\n".join(lines)


def nothing_analysed_in_tables(runs_path, segments_path, rejected_path) -> str | None:
    """:func:`nothing_analysed_message` of the tables rule ``collect_tables`` wrote."""
    from workflow.io.tables import read_table

    return nothing_analysed_message(
        read_table(runs_path), len(read_table(segments_path)), read_table(rejected_path)
    )


def fit_damping_curves(
    segments: pd.DataFrame,
    areas_in2: dict[str, float | None],
    settings: DampingFitSettings,
    *,
    grid_points: int = 60,
    area_amplitudes: int = 5,
) -> dict[str, pd.DataFrame]:
    """:func:`fit_mode_damping_curves` for each (mode, channel) of the segments (their
    ``mode_hz`` and ``channel`` columns, led by the first mode), each table with the two
    columns after ``configuration``. A table without the two columns is one mode and
    channel."""
    import pandas as pd

    if "mode_hz" not in segments or "channel" not in segments or segments.empty:
        return fit_mode_damping_curves(
            segments, areas_in2, settings, grid_points=grid_points, area_amplitudes=area_amplitudes
        )
    parts: dict[str, list[pd.DataFrame]] = {}
    for (mode_hz, channel), part in segments.groupby(["mode_hz", "channel"], sort=False):
        tables = fit_mode_damping_curves(
            part, areas_in2, settings, grid_points=grid_points, area_amplitudes=area_amplitudes
        )
        for name, table in tables.items():
            parts.setdefault(name, []).append(with_mode_and_channel(table, mode_hz, str(channel)))
    return {name: pd.concat(tables, ignore_index=True) for name, tables in parts.items()}


def fit_mode_damping_curves(
    segments: pd.DataFrame,
    areas_in2: dict[str, float | None],
    settings: DampingFitSettings,
    *,
    grid_points: int = 60,
    area_amplitudes: int = 5,
) -> dict[str, pd.DataFrame]:
    """Polynomial fits of damping vs velocity amplitude per configuration, their
    bootstrap-over-runs bands, the paper's two hypotheses, and damping vs area.

    ``settings`` are the ``fits`` section of config.yaml (highest degree, log amplitude,
    bootstrap resamples, confidence, seed).

    Returns ``fits`` (one row per configuration), ``curves`` (fit and band on a
    grid over each configuration's amplitude range), ``hypotheses`` and ``area``
    (fitted damping of each configuration at amplitudes common to all).
    """
    import pandas as pd

    from workflow.measured import curves

    fit_rows, curve_frames, by_configuration, fits = [], [], {}, {}
    for offset, (name, part) in enumerate(segments.groupby("configuration", sort=False)):
        v = part["velocity_amplitude_in_s"].to_numpy(float)
        zeta = part["zeta"].to_numpy(float)
        run = part["run"].to_numpy(str)
        fit = curves.fit_damping_polynomial(
            v, zeta, run, max_degree=settings.max_degree, log_amplitude=settings.log_amplitude
        )
        fits[name] = fit
        by_configuration[name] = (v, zeta, run)
        grid = np.geomspace(v.min(), v.max(), grid_points)
        lower, centre, upper = curves.bootstrap_band(
            v,
            zeta,
            run,
            fit.degree,
            grid,
            n_boot=settings.bootstrap_samples,
            confidence=settings.confidence,
            seed=settings.seed + offset,
            log_amplitude=settings.log_amplitude,
        )
        area = areas_in2.get(name)
        curve_frames.append(
            pd.DataFrame(
                {
                    "configuration": name,
                    "bearing_area_in2": np.nan if area is None else area,
                    "velocity_amplitude_in_s": grid,
                    "zeta": centre,
                    "zeta_low": lower,
                    "zeta_high": upper,
                }
            )
        )
        fit_rows.append(
            {
                "configuration": name,
                "bearing_area_in2": np.nan if area is None else area,
                "degree": fit.degree,
                "coefficients": [float(c) for c in fit.coefficients],
                "x_transform": fit.x_transform,
                "cv_scheme": fit.cv_scheme,
                "cv_rmse_at_degree": float(fit.cv_rmse[fit.degree]),
                "n_runs": fit.n_runs,
                "n_segments": fit.n_points,
                "amplitude_low_in_s": fit.amplitude_range_in_s[0],
                "amplitude_high_in_s": fit.amplitude_range_in_s[1],
            }
        )
    known_areas = {name: a for name, a in areas_in2.items() if a is not None and name in fits}
    hypotheses = curves.hypothesis_tests(
        segments,
        known_areas or None,
        max_degree=settings.max_degree,
        log_amplitude=settings.log_amplitude,
        n_boot=settings.bootstrap_samples,
        confidence=settings.confidence,
        seed=settings.seed,
    )
    area_rows = []
    common = curves.common_amplitude_range(by_configuration) if len(by_configuration) > 1 else None
    if common is not None and len(known_areas) >= 2:
        amplitudes = np.geomspace(common[0], common[1], area_amplitudes + 2)[1:-1]
        for offset, name in enumerate(known_areas):
            v, zeta, run = by_configuration[name]
            lower, centre, upper = curves.bootstrap_band(
                v,
                zeta,
                run,
                fits[name].degree,
                amplitudes,
                n_boot=settings.bootstrap_samples,
                confidence=settings.confidence,
                seed=settings.seed + 100 + offset,
                log_amplitude=settings.log_amplitude,
            )
            for amplitude, low, mid, high in zip(amplitudes, lower, centre, upper):
                area_rows.append(
                    {
                        "configuration": name,
                        "bearing_area_in2": known_areas[name],
                        "velocity_amplitude_in_s": amplitude,
                        "zeta": mid,
                        "zeta_low": low,
                        "zeta_high": high,
                    }
                )
    area = pd.DataFrame(
        area_rows,
        columns=[
            "configuration",
            "bearing_area_in2",
            "velocity_amplitude_in_s",
            "zeta",
            "zeta_low",
            "zeta_high",
        ],
    )
    return {
        "fits": pd.DataFrame(fit_rows),
        "curves": pd.concat(curve_frames, ignore_index=True) if curve_frames else pd.DataFrame(),
        "hypotheses": hypotheses,
        "area": area,
    }

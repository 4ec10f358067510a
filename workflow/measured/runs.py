"""One run file through the measured chain (``analyse_runs`` rule): read, checked,
every mode and channel analysed, its segments, quality checks and status.

Each function takes already-read records and plain settings and returns columns or
small documents; the scripts in ``scripts/`` only read inputs and write outputs. The
modes searched are found by :mod:`workflow.measured.mode_identification`, and the
campaign's tables are made by :mod:`workflow.measured.campaign_tables`.

The run-level stages return columns as NumPy arrays and do not import pandas: a
run-analysis job then starts without pandas.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from workflow.io import units
from workflow.io.campaign import SINGLE_CHANNEL_NAME
from workflow.io.interim import ConfigurationMode, ModeInfo
from workflow.io.limits import QUOTED_CHARACTERS, quoted, shortened
from workflow.io.records import RunRecord
from workflow.measured import decay, quality
from workflow.measured.settings import AnalysisSettings, QualitySettings

__all__ = [
    "analysis_window",
    "window_problem",
    "RUN_COLUMNS",
    "SEGMENT_COLUMNS",
    "empty_segments",
    "analyse_run_with_quality",
    "read_with_quality",
    "labelled",
    "analyse_every_mode_and_channel",
    "LEFT_OUT",
    "leave_out",
    "record_problems",
    "failed_checks",
    "RunAnalysis",
    "analyse_run_file",
    "window_problems",
    "read_runs",
    "analyse_run_group",
    "first_exclusion",
    "write_run_group",
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
    :data:`~workflow.io.records.MIN_SAMPLES` samples, as a whole run file must.
    """
    from workflow.io.records import MIN_SAMPLES

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


RUN_COLUMNS = ["configuration", "run", "path", "status", "reason", "record_start", "left_out"]
"""Columns of the runs table (``record_start``: ISO 8601 recording start, empty when the
file states none, :mod:`workflow.io.recording_time`; ``left_out``: why a used run's channels
or modes that failed a decay-level check were left out, :func:`leave_out`)."""


LEFT_OUT = "channel or mode left out of the run (see runs.parquet left_out)"
"""The ``reject_reason`` of the segments of a used run's (mode, channel) that failed a
decay-level check (:func:`leave_out`)."""


SEGMENT_COLUMNS = [
    "configuration",
    "run",
    "mode",
    "channel",
    "response_quantity",
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
    "response_quantity": str,
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
    decay_settings: AnalysisSettings,
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
    decay_settings : AnalysisSettings
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
        **decay_settings.decay_options(),
        start_index=start if window != (0, record.n_samples) else None,
        stop_index=stop,
    )
    segments = result.segments
    n_segments = len(segments["t_s"])
    columns = {
        "configuration": np.full(n_segments, configuration),
        "run": np.full(n_segments, run),
        "response_quantity": np.full(n_segments, record.response_quantity),
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
    from workflow.io.records import CampaignFormatError
    from workflow.io.run_files import read_run

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
        rows += [
            {**_failed_row("unit", why), "channel": name, "mode": -1} for name, why in record.refused_channels
        ]
        return record, rows
    return None, [_failed_row("read", reason)]


def _failed_row(check: str, reason: str) -> dict:
    """The quality row of a check that failed with no measured value: a file that could not
    be read (``read``), a response channel the reader refused (``unit``)."""
    return {
        "check": check,
        "applied": True,
        "passed": False,
        "value": float("nan"),
        "threshold": float("nan"),
        "unit": "",
        "reason": reason,
    }


def labelled(row: dict, channel: str, several: bool, mode: int = -1, mode_hz: float | None = None) -> dict:
    """A quality row with the channel and mode (index, -1 for a record-level check) it
    belongs to; with several channels (or modes) its reason names them."""
    reason = row["reason"]
    if reason:
        where = [f"channel {quoted(channel)}"] if several else []
        where += [f"mode {mode_hz:.6g} Hz"] if mode_hz is not None else []
        reason = f"{', '.join(where)}: {reason}" if where else reason
    return {**row, "reason": reason, "channel": channel, "mode": mode}


def window_problems(
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
    decay_settings: AnalysisSettings,
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


def leave_out(segments: dict[str, np.ndarray], pairs: set[tuple[int, str]]) -> dict[str, np.ndarray]:
    """The segments with those of every (mode index, channel) of ``pairs`` rejected as
    :data:`LEFT_OUT`.

    A sensor near a node of one mode, or a mode one sensor barely sees, says nothing about
    what the other channels and modes of the same hit measured: only that (mode, channel)
    is left out of the run (:func:`analyse_run_file`).
    """
    out = np.zeros(segments["mode"].size, dtype=bool)
    for mode, channel in pairs:
        out |= (segments["mode"] == mode) & (segments["channel"] == channel)
    return {
        **segments,
        "kept": segments["kept"] & ~out,
        "reject_reason": np.where(out, LEFT_OUT, segments["reject_reason"]),
    }


CHANNEL_CHECKS = ("clipping", "unit")
"""Record-level checks of one response channel: one that fails leaves the channel out."""


def record_problems(path: str, rows: list[dict]) -> tuple[list[str], list[dict]]:
    """What the record-level checks of a read run (:func:`read_with_quality`'s rows) say:
    the messages that exclude it, and the failed rows of :data:`CHANNEL_CHECKS` of the channels to leave
    out. A clipped sensor, or one whose unit contradicts campaign.yaml, is left out of the
    hit the others measured; any other failed check (reading, the hit, the record's length),
    or every channel left out, excludes the run."""
    failed = [row for row in rows if row["applied"] and not row["passed"]]
    channel_failures = [row for row in failed if row["check"] in CHANNEL_CHECKS]
    every = {row.get("channel") for row in rows}
    if len(channel_failures) < len(failed) or {row["channel"] for row in channel_failures} >= every:
        return failed_checks(path, rows), []
    return [], channel_failures


def failed_checks(path: str, rows: list[dict]) -> list[str]:
    """Messages of the failed checks, each naming the file."""
    return [
        row["reason"] if row["check"] == "read" else f"{path}: {row['reason']}"
        for row in rows
        if row["applied"] and not row["passed"]
    ]


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
    decay_settings: AnalysisSettings,
    read: tuple[RunRecord | None, list[dict]] | None = None,
) -> RunAnalysis:
    """Read, check and analyse one run file; a run that cannot be used is excluded
    with its reason, never raised. A (mode, channel) of a run that fails a decay-level
    check (signal-to-noise, usable segments) while another passes is left out
    (:func:`leave_out`), and so is every mode of a clipped channel, or of one whose unit
    contradicts campaign.yaml, while another is kept: the run is used, its status's
    ``left_out`` saying why.

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
        The configuration's mode search result (:func:`workflow.measured.mode_identification.identify_configuration_mode`);
        without a mode, the run is excluded with the reason none was found.
    quality_settings : QualitySettings
        Quality thresholds.
    decay_settings : AnalysisSettings
        The decay analysis settings.
    read : (RunRecord or None, list of dict), optional
        The run as :func:`read_with_quality` gave it, when the job has read it already
        (for the mode search): the file is then not read again.
    """
    from pathlib import PurePosixPath

    run = PurePosixPath(run_path).stem
    segments = empty_segments()
    if read is None:
        read = read_with_quality(campaign_dir, run_path, campaign, quality_settings)
    record, rows = read[0], list(read[1])
    problems, channel_failures = record_problems(run_path, rows)
    left_out: list[str] = []
    if record is not None and not problems:
        problems = window_problems(campaign_dir, run_path, record, campaign, configuration)
    if record is not None and not problems:
        if mode.mode is None:
            problems = [mode.error]
        else:
            try:
                segments, decay_rows = analyse_every_mode_and_channel(
                    # a clipped channel's decay is not analysed
                    record.without_channels({row["channel"] for row in channel_failures}),
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
                # a (mode, channel) that fails a decay-level check is left out; the run is
                # excluded only when nothing is left
                failed = [row for row in decay_rows if row["applied"] and not row["passed"]]
                pairs = {(row["mode"], row["channel"]) for row in failed}
                if pairs == {(row["mode"], row["channel"]) for row in decay_rows}:
                    problems = failed_checks(run_path, decay_rows)
                elif pairs or channel_failures:
                    segments = leave_out(segments, pairs)
                    left_out = failed_checks(run_path, channel_failures + failed)
    if problems and channel_failures:
        problems = [*failed_checks(run_path, channel_failures), *problems]
    status = {
        "configuration": configuration,
        "run": run,
        "path": run_path,
        "status": "excluded" if problems else "used",
        "reason": "; ".join(problems),
        "record_start": "" if record is None else record.record_start,
        "left_out": "; ".join(left_out),
        "response_units": {} if record is None else {c.name: c.unit for c in record.responses},
    }
    return RunAnalysis(segments, quality.quality_columns(configuration, run, rows), status)


def read_runs(campaign_dir, run_paths: list[str], campaign, quality_settings) -> dict[str, tuple]:
    """Run path -> the run as :func:`read_with_quality` gives it, for every path: a job
    that searches a configuration's modes and analyses some of its runs reads each once."""
    return {path: read_with_quality(campaign_dir, path, campaign, quality_settings) for path in run_paths}


def analyse_run_group(
    campaign_dir,
    run_paths: list[str],
    *,
    reads: dict[str, tuple] | None = None,
    **options,
) -> list[RunAnalysis]:
    """:func:`analyse_run_file` for each of a job's runs (``options`` are its keywords),
    with the runs in ``reads`` (:func:`read_runs`) not read again; each excluded run is
    logged as a warning (strict mode stops on :func:`first_exclusion`)."""
    log = logging.getLogger(__name__)
    reads = reads or {}
    results = []
    for run_path in run_paths:
        result = analyse_run_file(campaign_dir, run_path, read=reads.get(run_path), **options)
        if result.status["status"] == "excluded":
            log.warning("excluded %s", result.status["reason"])
        else:
            if result.status["left_out"]:
                log.warning("left out of a used run: %s", result.status["left_out"])
            kept = result.segments["kept"]
            log.info("%s: %d segments kept of %d", run_path, int(kept.sum()), len(kept))
        results.append(result)
    return results


def first_exclusion(results: list[RunAnalysis]) -> str | None:
    """The reason the first excluded run of ``results`` was excluded, or None if every
    run was analysed (strict mode stops the job on it)."""
    return next((r.status["reason"] for r in results if r.status["status"] == "excluded"), None)


def write_run_group(segments_path, quality_path, status_path, results: list[RunAnalysis]) -> None:
    """A job's interim files of its runs: their segments and quality rows (column
    files) and their statuses (JSON)."""
    from workflow.io.interim import write_run_statuses
    from workflow.io.tables import concatenate_columns, write_columns

    write_columns(segments_path, concatenate_columns([result.segments for result in results]))
    write_columns(quality_path, concatenate_columns([result.quality for result in results]))
    write_run_statuses(status_path, [result.status for result in results])

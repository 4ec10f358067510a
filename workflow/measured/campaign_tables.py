"""The campaign's tables from the per-run outputs, and the damping fits on them.

``collect_tables`` merges the run groups' columns and statuses into the campaign's
tables (``mode_hz`` the nominal frequency of each mode), ``fit_damping_curves`` fits
every mode and channel, ``nothing_analysed_*`` says why no segment was kept;
``analyse_campaign`` runs the whole measured chain in one process.

Pandas is imported inside the functions, as by the rest of the measured chain.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from workflow.io.interim import ModeInfo
from workflow.io.limits import MAX_QUOTED_PROBLEMS, QUOTED_CHARACTERS, shortened
from workflow.measured.mode_identification import identify_configuration_mode
from workflow.measured.runs import RUN_COLUMNS, SEGMENT_COLUMNS, analyse_run_file, empty_segments, read_runs
from workflow.measured.settings import AnalysisSettings, DampingFitSettings, QualitySettings

if TYPE_CHECKING:
    from collections.abc import Sequence

    import pandas as pd

__all__ = [
    "analyse_campaign",
    "response_unit_label",
    "recorded_quantity",
    "nominal_modes_hz",
    "with_nominal_mode",
    "first_mode_and_channel",
    "paper_channel",
    "with_mode_and_channel",
    "first_mode_rows",
    "collect_tables",
    "NOTHING_ANALYSED",
    "nothing_analysed_message",
    "nothing_analysed_in_tables",
    "fit_damping_curves",
    "fit_mode_damping_curves",
]


def analyse_campaign(
    campaign_dir, analysis: AnalysisSettings, quality_settings: QualitySettings
) -> pd.DataFrame:
    """Kept segments of every usable run of a campaign, in one process.

    The workflow's rules ``identify_mode``, ``analyse_runs`` and ``collect_tables`` make
    the same calls, split over jobs (each run read once here); this is the whole chain for studies over many
    campaigns (``bench/hit_rate.py``).

    Returns the rows ``results/tables/segments.parquet`` would hold.
    """
    import pandas as pd

    from workflow.io.campaign import load_campaign
    from workflow.io.run_files import list_runs

    campaign = load_campaign(campaign_dir)
    run_files = list_runs(campaign_dir, campaign)
    frames = []
    for name, spec in campaign.configurations.items():
        paths = [run_file.path for run_file in run_files if run_file.configuration == name]
        options = {"configuration": name, "campaign": campaign, "quality_settings": quality_settings}
        reads = read_runs(campaign_dir, paths, campaign, quality_settings)
        mode = identify_configuration_mode(campaign_dir, paths, mode_search=analysis, reads=reads, **options)
        for path in paths:
            result = analyse_run_file(
                campaign_dir,
                path,
                mode=mode,
                decay_settings=analysis,
                read=reads.pop(path),
                **options,
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
    from workflow.io.units import response_quantity_of

    quantity = campaign.response.quantity
    if campaign.response.unit is not None:
        return f"{campaign.response.unit} ({quantity})"
    found: dict[str, set[str]] = {}
    for status in statuses:
        for channel, unit in status.get("response_units", {}).items():
            found.setdefault(channel, set()).add(unit)
    every = sorted(set().union(*found.values())) if found else []
    if len(every) == 1:
        return f"{every[0]} ({quantity or response_quantity_of(every[0])})"
    if not every:
        return f"unit of the run files ({quantity or 'the quantity of each file unit'})"
    if quantity is None:
        return "per channel: " + "; ".join(
            f"{name} " + ", ".join(f"{unit} ({response_quantity_of(unit)})" for unit in sorted(units_))
            for name, units_ in found.items()
        )
    return f"{quantity}, per channel: " + "; ".join(
        f"{name} {', '.join(sorted(units_))}" for name, units_ in found.items()
    )


def recorded_quantity(segments: pd.DataFrame, default: str) -> str:
    """What the segments' records measured (their ``response_quantity``), ``default``
    where they have no rows or no such column.

    Raises
    ------
    ValueError
        The rows come from records of several quantities (pooled channels).
    """
    found = segments["response_quantity"].unique().tolist() if "response_quantity" in segments else []
    if len(found) > 1:
        raise ValueError(
            f"segments of several response quantities ({', '.join(map(str, found))}), expected one"
        )
    return str(found[0]) if found else default


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


def _first_mode(table: pd.DataFrame) -> pd.DataFrame:
    """The rows of the first (lowest) mode and of no mode; a table without ``mode_hz``
    whole."""
    if "mode_hz" in table and len(table):
        first_hz = table["mode_hz"].min()
        if not np.isnan(first_hz):
            return table[table["mode_hz"].isna() | (table["mode_hz"] == first_hz)]
    return table


def first_mode_and_channel(table: pd.DataFrame, channel: str) -> pd.DataFrame:
    """The rows of the first (lowest) mode and of ``channel``: the paper's models, the
    diagnosis and the paper's figures analyse this one mode and sensor
    (:func:`paper_channel`). A table without ``mode_hz`` or ``channel`` columns is
    returned whole."""
    table = _first_mode(table)
    if "channel" in table:
        table = table[table["channel"] == channel]
    return table


def paper_channel(segments: pd.DataFrame, channels: Sequence[str]) -> str:
    """The response channel the paper's models and figures read: the first of
    ``channels`` (campaign.yaml's order) with a kept segment of the first mode in the
    segments table, so that a sensor left out of every hit (clipped, its unit refused,
    too weak) does not leave them unfitted; the first listed where no channel has one.

    Examples
    --------
    >>> import pandas as pd
    >>> kept = pd.DataFrame({"mode_hz": [80.5, 80.5, 297.7], "channel": ["acc2", "acc3", "laser"]})
    >>> paper_channel(kept, ["laser", "acc2", "acc3"])
    'acc2'
    >>> paper_channel(kept.iloc[:0], ["laser", "acc2"])
    'laser'
    """
    seen = set(_first_mode(segments)["channel"]) if "channel" in segments else set()
    return next((channel for channel in channels if channel in seen), channels[0])


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
    lead to that no job reads (:meth:`workflow.io.run_files.ExcludedPath.status`):
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
    statuses = statuses.reindex(columns=RUN_COLUMNS).fillna({"record_start": "", "left_out": ""})
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
        The runs table (:data:`workflow.measured.runs.RUN_COLUMNS`): every run file, used or excluded with its reason.
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
    from workflow.io.tables import read_table, table_rows

    # where segments were kept the message is None and no table is read (the job imports
    # no pandas, 0.3 s of its start)
    n_kept_segments = table_rows(segments_path)
    if n_kept_segments > 0:
        return None
    return nothing_analysed_message(read_table(runs_path), n_kept_segments, read_table(rejected_path))


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
    from workflow.measured.hypotheses import common_amplitude_range, hypothesis_tests

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
    hypotheses = hypothesis_tests(
        segments,
        known_areas or None,
        max_degree=settings.max_degree,
        log_amplitude=settings.log_amplitude,
        n_boot=settings.bootstrap_samples,
        confidence=settings.confidence,
        seed=settings.seed,
    )
    area_rows = []
    common = common_amplitude_range(by_configuration) if len(by_configuration) > 1 else None
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

"""Tests of the source paper's two hypotheses on the measured damping curves.

* H1: at low amplitude the damping rises with amplitude.
* H2: the damping rises with the bearing area over which micro-slip can occur.

Input and conventions as :mod:`workflow.measured.curves` (segments of one configuration
as aligned ``velocity_amplitude_in_s``, ``zeta``, ``run``); runs are the independent
units, so every bootstrap resamples runs, and each test's confidence interval is a
bootstrap-t interval over runs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from scipy import special

from workflow.measured.curves import (
    IDENTITY,
    LOG10,
    can_fit,
    fit_damping_polynomial,
    fit_variable,
    run_indices,
    validated_damping_data,
)

__all__ = [
    "H1_NAME",
    "H2_NAME",
    "NOT_APPLICABLE",
    "HYPOTHESIS_COLUMNS",
    "amplitude_hypothesis",
    "common_amplitude_range",
    "area_hypothesis",
    "hypothesis_tests",
]


#: Names of the two hypotheses, as they appear in the ``hypothesis`` column.
H1_NAME = "H1: damping rises with amplitude at low amplitude"


H2_NAME = "H2: damping rises with bearing area"


NOT_APPLICABLE = "not applicable"
"""Verdict of a test the campaign cannot run (H2 without two bearing areas), as opposed
to ``inconclusive``: a test that ran and could not decide."""


#: Columns of the hypothesis table, in order.
HYPOTHESIS_COLUMNS = [
    "hypothesis",
    "configuration",
    "statistic",
    "estimate",
    "ci_low",
    "ci_high",
    "confidence",
    "supported",
    "verdict",
    "amplitude_low_in_s",
    "amplitude_high_in_s",
    "n_runs",
    "n_boot_valid",
    "note",
]


# -------------------------------------------------------------------- hypotheses


def _bootstrap_t_interval(
    estimate: float, replicates: np.ndarray, n_runs: int, confidence: float
) -> tuple[float, float]:
    """Confidence interval from the bootstrap standard error of a run-level statistic.

    ``estimate -/+ t_{n_runs - 1} * sqrt(n_runs / (n_runs - 1)) * sd(replicates)``.

    With few runs the plain percentile interval of a run bootstrap is too
    narrow: the bootstrap variance is biased low by ``(n_runs - 1) / n_runs``
    and the normal quantile ignores that the variance itself is estimated from
    ``n_runs`` units. Correcting both (variance factor and Student-t quantile
    with ``n_runs - 1`` degrees of freedom) gives intervals whose false-support
    rate on flat data is close to nominal (checked in the tests; the plain
    percentile interval falsely rejected about 19 % / 10 % / 8.5 % of the time
    at 5 / 10 / 20 runs for a nominal 5 %).
    """
    replicates = replicates[np.isfinite(replicates)]
    if n_runs < 2 or replicates.size < 2 or not np.isfinite(estimate):
        return np.nan, np.nan
    half_width = (
        # Student-t quantile; scipy.special, not scipy.stats, keeps this job's start-up
        # 0.6 s shorter.
        special.stdtrit(n_runs - 1, 0.5 + confidence / 2.0)
        * np.sqrt(n_runs / (n_runs - 1.0))
        * replicates.std(ddof=1)
    )
    return float(estimate - half_width), float(estimate + half_width)


def _verdict(ci_low: float, ci_high: float) -> tuple[bool, str]:
    """(supported, verdict) from a confidence interval of a positive-is-support statistic."""
    if np.isfinite(ci_low) and ci_low > 0:
        return True, "supported"
    if np.isfinite(ci_high) and ci_high < 0:
        return False, "contradicted"
    return False, "inconclusive"


def _row(**values: object) -> dict:
    """One hypothesis-table row with every column present."""
    row = {column: values.get(column, np.nan) for column in HYPOTHESIS_COLUMNS}
    row["note"] = values.get("note", "")
    return row


def _line_slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope dy/dx; NaN if x has no spread or fewer than 3 points."""
    if x.size < 3:
        return np.nan
    dx = x - x.mean()
    sxx = np.dot(dx, dx)
    if sxx <= 0:
        return np.nan
    return float(np.dot(dx, y - y.mean()) / sxx)


def amplitude_hypothesis(
    velocity_amplitude_in_s: np.ndarray,
    zeta: np.ndarray,
    run: Sequence | np.ndarray,
    *,
    configuration: str = "all",
    lower_fraction: float = 1.0 / 3.0,
    n_boot: int = 400,
    confidence: float = 0.95,
    seed: int = 0,
) -> pd.DataFrame:
    """Test H1 (damping rises with amplitude at low amplitude) for one configuration.

    Parameters
    ----------
    velocity_amplitude_in_s, zeta, run : array_like
        Segments of one configuration (in/s, dimensionless, labels).
    configuration : str, optional
        Name written in the ``configuration`` column.
    lower_fraction : float, optional
        The low-amplitude window is the lowest ``lower_fraction`` of the
        configuration's log10-amplitude span:
        ``v <= v_min * (v_max / v_min) ** lower_fraction``.
    n_boot, confidence, seed : optional
        Bootstrap resamples over runs, CI level, random seed.

    Returns
    -------
    pandas.DataFrame
        One row (columns :data:`HYPOTHESIS_COLUMNS`). ``estimate`` is the
        least-squares slope d(zeta)/d(log10 v) of the segments inside the window
        (damping-ratio change per decade of velocity amplitude); the CI is
        ``estimate -/+ t * sd`` with ``sd`` the standard deviation of the same
        slope over run resamples (runs drawn with replacement among the runs
        that have segments in the window), corrected for few runs as described
        in :func:`_bootstrap_t_interval`.
        ``supported`` when the CI lies entirely above 0; ``contradicted`` when
        entirely below; else ``inconclusive``. With fewer than two runs in the
        window no CI is computed and the verdict is ``inconclusive``.

    Notes
    -----
    The window is fixed from all the data (not re-derived per resample), so
    every resample estimates the same quantity.
    """
    amplitude, damping, labels = validated_damping_data(velocity_amplitude_in_s, zeta, run)
    x = np.log10(amplitude)
    x_low, x_high = x.min(), x.min() + lower_fraction * (x.max() - x.min())
    window = x <= x_high
    amplitude_low, amplitude_high = float(10**x_low), float(10**x_high)
    statistic = (
        "slope of zeta vs log10(velocity amplitude / (1 in/s)) over the lowest "
        f"{lower_fraction:.3g} of the log-amplitude span "
        f"({amplitude_low:.3g}-{amplitude_high:.3g} in/s), per decade"
    )
    xw, yw, lw = x[window], damping[window], labels[window]
    estimate = _line_slope(xw, yw)
    runs = run_indices(lw)
    n_runs = len(runs)
    ci_low = ci_high = np.nan
    n_valid = 0
    note = ""
    if n_runs < 2:
        note = "fewer than two runs reach the low-amplitude window: no between-run CI"
    elif not np.isfinite(estimate):
        note = "too few segments or no amplitude spread in the low-amplitude window"
    else:
        rng = np.random.default_rng(seed)
        slopes = np.full(n_boot, np.nan)
        for b in range(n_boot):
            chosen = np.concatenate([runs[k] for k in rng.integers(0, n_runs, n_runs)])
            slopes[b] = _line_slope(xw[chosen], yw[chosen])
        n_valid = int(np.isfinite(slopes).sum())
        ci_low, ci_high = _bootstrap_t_interval(estimate, slopes, n_runs, confidence)
        if not np.isfinite(ci_low):
            note = "too few usable resamples for a CI"
    supported, verdict = _verdict(ci_low, ci_high)
    return pd.DataFrame(
        [
            _row(
                hypothesis=H1_NAME,
                configuration=configuration,
                statistic=statistic,
                estimate=estimate,
                ci_low=float(ci_low),
                ci_high=float(ci_high),
                confidence=confidence,
                supported=supported,
                verdict=verdict,
                amplitude_low_in_s=amplitude_low,
                amplitude_high_in_s=amplitude_high,
                n_runs=n_runs,
                n_boot_valid=n_valid,
                note=note,
            )
        ],
        columns=HYPOTHESIS_COLUMNS,
    )


def common_amplitude_range(
    data_by_configuration: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray]],
) -> tuple[float, float] | None:
    """Velocity-amplitude range (in/s) that every configuration covers with most of its runs.

    For each configuration the range is ``[median of the runs' smallest
    amplitudes, median of the runs' largest amplitudes]`` — the amplitudes
    that at least half of its runs reach — and the common range is the
    intersection over configurations. Returns None when it is empty.
    """
    low, high = 0.0, np.inf
    for amplitude, _, labels in data_by_configuration.values():
        amplitude = np.asarray(amplitude, dtype=float)
        labels = np.asarray(labels)
        runs = run_indices(labels)
        low = max(low, float(np.median([amplitude[r].min() for r in runs])))
        high = min(high, float(np.median([amplitude[r].max() for r in runs])))
    if not low < high:
        return None
    return low, high


def _area_slopes(areas_in2: np.ndarray, zeta_by_configuration: np.ndarray) -> np.ndarray:
    """Least-squares slope d(zeta)/d(area) across configurations at every amplitude.

    ``zeta_by_configuration`` is ``[configuration, amplitude]``; a column with a
    NaN gives NaN.
    """
    da = areas_in2 - areas_in2.mean()
    return da @ (zeta_by_configuration - zeta_by_configuration.mean(axis=0)) / np.dot(da, da)


def area_hypothesis(
    data_by_configuration: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray]],
    areas_in2: Mapping[str, float],
    degrees: Mapping[str, int],
    *,
    n_amplitudes: int = 5,
    n_boot: int = 400,
    confidence: float = 0.95,
    seed: int = 0,
    log_amplitude: bool = True,
) -> pd.DataFrame:
    """Test H2 (damping rises with bearing area) across configurations.

    Parameters
    ----------
    data_by_configuration : mapping
        Configuration name -> ``(velocity_amplitude_in_s, zeta, run)`` arrays.
    areas_in2 : mapping
        Configuration name -> bearing area, in^2. Configurations without an
        area (or without data) are left out.
    degrees : mapping
        Configuration name -> polynomial degree of its damping curve (from
        :func:`workflow.measured.curves.fit_damping_polynomial`), held fixed in the bootstrap.
    n_amplitudes : int, optional
        Number of common velocity amplitudes tested: the interior points of a
        log-spaced grid of ``n_amplitudes + 2`` points over the common range
        (:func:`common_amplitude_range`); with an odd number the middle one is
        the range's geometric mean.
    n_boot, confidence, seed, log_amplitude : optional
        Bootstrap resamples, CI level, random seed, fit variable.

    Returns
    -------
    pandas.DataFrame
        One row per common amplitude (slope d(zeta)/d(area) of the fitted
        damping ratios vs bearing area, 1/in^2, least squares across
        configurations) and a last, combined row: the mean of those slopes over
        the common amplitudes. CIs are ``estimate -/+ t * sd`` (see
        :func:`_bootstrap_t_interval`; the configuration with the fewest runs
        sets ``t`` and the small-sample factor), ``sd`` being the standard
        deviation over bootstrap replicates in which the runs of every
        configuration are resampled independently, each curve refitted at its
        fixed degree and kept only
        within the amplitude range of its resample (replicates that do not
        reach an amplitude are dropped there; ``n_boot_valid`` counts the
        rest). When fewer than two configurations have areas, when the common
        range is empty, or when a configuration has fewer than two runs (its
        between-run scatter cannot be resampled), a single ``inconclusive``
        row with the reason in ``note`` is returned (or the CIs are NaN).
    """
    names = [
        name
        for name in data_by_configuration
        if name in areas_in2 and areas_in2[name] is not None and np.isfinite(areas_in2[name])
    ]
    base = dict(hypothesis=H2_NAME, configuration="all", confidence=confidence)
    statistic_combined = (
        "mean over the common velocity amplitudes of the slope of fitted zeta vs bearing area, 1/in^2"
    )
    areas = np.array([float(areas_in2[name]) for name in names])
    if len(names) < 2 or np.unique(areas).size < 2:
        row = _row(
            **base,
            statistic=statistic_combined,
            supported=False,
            verdict=NOT_APPLICABLE,
            n_runs=0,
            n_boot_valid=0,
            note="needs at least two configurations with different bearing areas",
        )
        return pd.DataFrame([row], columns=HYPOTHESIS_COLUMNS)

    data = {name: validated_damping_data(*data_by_configuration[name]) for name in names}
    common = common_amplitude_range(data)
    n_runs_total = int(sum(np.unique(d[2]).size for d in data.values()))
    if common is None:
        row = _row(
            **base,
            statistic=statistic_combined,
            supported=False,
            verdict=NOT_APPLICABLE,
            n_runs=n_runs_total,
            n_boot_valid=0,
            note="the configurations share no common velocity-amplitude range",
        )
        return pd.DataFrame([row], columns=HYPOTHESIS_COLUMNS)

    x_transform = LOG10 if log_amplitude else IDENTITY
    grid = np.logspace(np.log10(common[0]), np.log10(common[1]), n_amplitudes + 2)[1:-1]
    x_grid = fit_variable(grid, x_transform)

    def curve(name: str, index: np.ndarray | None) -> np.ndarray:
        amplitude, damping, _ = data[name]
        if index is not None:
            amplitude, damping = amplitude[index], damping[index]
        x = fit_variable(amplitude, x_transform)
        out = np.full(grid.size, np.nan)
        if not can_fit(x, degrees[name]):
            return out
        inside = (grid >= amplitude.min()) & (grid <= amplitude.max())
        out[inside] = np.polyval(np.polyfit(x, damping, degrees[name]), x_grid[inside])
        return out

    estimate = _area_slopes(areas, np.vstack([curve(name, None) for name in names]))
    runs = {name: run_indices(data[name][2]) for name in names}
    single = [name for name in names if len(runs[name]) < 2]
    slopes = np.full((n_boot, grid.size), np.nan)
    note = ""
    if single:
        note = "no between-run CI: configuration(s) with a single run: " + ", ".join(single)
    else:
        rng = np.random.default_rng(seed)
        for b in range(n_boot):
            table = []
            for name in names:
                run_list = runs[name]
                draw = rng.integers(0, len(run_list), len(run_list))
                table.append(curve(name, np.concatenate([run_list[k] for k in draw])))
            slopes[b] = _area_slopes(areas, np.vstack(table))

    # the configuration with the fewest runs limits how well the between-run
    # scatter is known: its run count sets the t quantile and variance factor
    n_runs_min = min(len(runs[name]) for name in names)
    rows = []
    for j, amplitude in enumerate(grid):
        valid = slopes[np.isfinite(slopes[:, j]), j]
        ci_low, ci_high = _bootstrap_t_interval(estimate[j], valid, n_runs_min, confidence)
        supported, verdict = _verdict(ci_low, ci_high)
        rows.append(
            _row(
                **base,
                statistic=(
                    f"slope of fitted zeta vs bearing area at velocity amplitude {amplitude:.3g} in/s, 1/in^2"
                ),
                estimate=float(estimate[j]),
                ci_low=float(ci_low),
                ci_high=float(ci_high),
                supported=supported,
                verdict=verdict,
                amplitude_low_in_s=float(amplitude),
                amplitude_high_in_s=float(amplitude),
                n_runs=n_runs_total,
                n_boot_valid=int(valid.size),
                note=note,
            )
        )
    complete = np.all(np.isfinite(slopes), axis=1)
    combined = slopes[complete].mean(axis=1)
    ci_low, ci_high = _bootstrap_t_interval(float(np.mean(estimate)), combined, n_runs_min, confidence)
    supported, verdict = _verdict(ci_low, ci_high)
    rows.append(
        _row(
            **base,
            statistic=statistic_combined + f" ({grid.size} amplitudes, {grid[0]:.3g}-{grid[-1]:.3g} in/s)",
            estimate=float(np.mean(estimate)),
            ci_low=float(ci_low),
            ci_high=float(ci_high),
            supported=supported,
            verdict=verdict,
            amplitude_low_in_s=float(grid[0]),
            amplitude_high_in_s=float(grid[-1]),
            n_runs=n_runs_total,
            n_boot_valid=int(combined.size),
            note=note,
        )
    )
    return pd.DataFrame(rows, columns=HYPOTHESIS_COLUMNS)


def hypothesis_tests(
    segments: pd.DataFrame,
    areas_in2: Mapping[str, float] | None = None,
    *,
    max_degree: int = 3,
    log_amplitude: bool = True,
    n_boot: int = 400,
    confidence: float = 0.95,
    seed: int = 0,
) -> pd.DataFrame:
    """H1 for every configuration and H2 across them, from the segments table.

    Parameters
    ----------
    segments : pandas.DataFrame
        Columns ``configuration``, ``run``, ``velocity_amplitude_in_s`` (in/s)
        and ``zeta`` (as in ``results/tables/segments.parquet``). Run labels
        are taken within their configuration.
    areas_in2 : mapping, optional
        Configuration -> bearing area (in^2); H2 needs two or more.
    max_degree, log_amplitude, n_boot, confidence, seed : optional
        As in :func:`workflow.measured.curves.fit_damping_polynomial` and the bootstrap functions.

    Returns
    -------
    pandas.DataFrame
        H1 rows (one per configuration, in order of first appearance) followed
        by the H2 rows of :func:`area_hypothesis`.
    """
    tables = []
    data: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    degrees: dict[str, int] = {}
    for name, group in segments.groupby("configuration", sort=False):
        arrays = (
            group["velocity_amplitude_in_s"].to_numpy(float),
            group["zeta"].to_numpy(float),
            group["run"].astype(str).to_numpy(),
        )
        data[str(name)] = arrays
        degrees[str(name)] = fit_damping_polynomial(
            *arrays, max_degree=max_degree, log_amplitude=log_amplitude
        ).degree
        tables.append(
            amplitude_hypothesis(
                *arrays, configuration=str(name), n_boot=n_boot, confidence=confidence, seed=seed
            )
        )
    tables.append(
        area_hypothesis(
            data,
            dict(areas_in2 or {}),
            degrees,
            n_boot=n_boot,
            confidence=confidence,
            seed=seed,
            log_amplitude=log_amplitude,
        )
    )
    return pd.concat(tables, ignore_index=True)

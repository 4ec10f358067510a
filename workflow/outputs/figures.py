"""Figures in one style: units on every axis, legends naming runs and models,
logarithmic amplitude axes (amplitudes span decades), legible at report size.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.ticker import FuncFormatter, LogLocator  # noqa: E402

STYLE = {
    "figure.figsize": (7.0, 4.6),
    "figure.dpi": 110,
    "savefig.dpi": 130,
    "font.size": 10,
    "axes.titlesize": 11,
    "axes.labelsize": 10,
    "legend.fontsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
}

VELOCITY_LABEL = "velocity amplitude (in/s)"
DAMPING_LABEL = "equivalent damping ratio ζ (%)"
FREQUENCY_LABEL = "damped frequency of the mode (Hz)"


def save(figure: plt.Figure, path: Path | str) -> None:
    """Save ``figure`` as PNG (through a temporary name, so no half-written file stays)."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    temporary = target.with_name(f".{target.stem}.tmp.png")
    figure.savefig(temporary, bbox_inches="tight")
    plt.close(figure)
    temporary.replace(target)


def amplitude_axis(axis: plt.Axes) -> None:
    """Logarithmic velocity-amplitude x axis with plain tick labels (0.2, 0.5, 1, 2 ...),
    which stay legible whether the data span a fraction of a decade or several."""
    plain = FuncFormatter(lambda value, _: f"{value:g}")
    axis.set_xscale("log")
    axis.xaxis.set_major_formatter(plain)
    axis.xaxis.set_minor_locator(LogLocator(subs=(2.0, 5.0)))
    axis.xaxis.set_minor_formatter(plain)
    axis.set_xlabel(VELOCITY_LABEL)


def run_colours(runs: list[str]) -> dict[str, tuple]:
    """One colour per run, in run order."""
    cmap = plt.get_cmap("viridis")
    count = max(len(runs) - 1, 1)
    return {run: cmap(0.9 * index / count) for index, run in enumerate(runs)}


def _plot_runs(
    axis: plt.Axes,
    segments: pd.DataFrame,
    column: str,
    *,
    scale: float = 1.0,
    markersize: float = 3.0,
    alpha: float = 0.8,
    labels: bool = True,
) -> list[str]:
    """One marker series per run (coloured in run order); returns the run names."""
    runs = list(dict.fromkeys(segments["run"]))
    colours = run_colours(runs)
    for run in runs:
        part = segments[segments["run"] == run]
        axis.plot(
            part["velocity_amplitude_in_s"],
            scale * part[column],
            "o",
            markersize=markersize,
            color=colours[run],
            alpha=alpha,
            label=run if labels else None,
        )
    return runs


def time_history(
    time_s: np.ndarray,
    raw: np.ndarray,
    filtered: np.ndarray,
    envelope: np.ndarray,
    *,
    response_label: str,
    title: str,
    band_hz: tuple[float, float],
    decay_start_s: float | None = None,
) -> plt.Figure:
    """Paper figure 9: unfiltered and band-passed response with its Hilbert envelope."""
    with plt.rc_context(STYLE):
        figure, (top, bottom) = plt.subplots(2, 1, figsize=(7.0, 5.6), sharex=True)
        top.plot(time_s, raw, color="0.35", linewidth=0.6, label="unfiltered")
        top.set_ylabel(response_label)
        top.set_title(title)
        top.legend(loc="upper right")
        bottom.plot(
            time_s,
            filtered,
            color="tab:blue",
            linewidth=0.6,
            label=f"band-passed [{band_hz[0]:.0f}, {band_hz[1]:.0f}] Hz",
        )
        bottom.plot(time_s, envelope, color="tab:red", linewidth=1.2, label="Hilbert envelope (eq. 1)")
        bottom.plot(time_s, -envelope, color="tab:red", linewidth=1.2)
        if decay_start_s is not None:
            for axis in (top, bottom):
                axis.axvline(
                    decay_start_s,
                    color="k",
                    linestyle=":",
                    linewidth=0.8,
                    label="decay start (excitation peak)",
                )
        bottom.set_xlabel("time (s)")
        bottom.set_ylabel(response_label)
        bottom.legend(loc="upper right")
        figure.tight_layout()
    return figure


def damping_vs_amplitude(
    segments: pd.DataFrame,
    *,
    title: str,
    curve: pd.DataFrame | None = None,
    models: dict[str, pd.DataFrame] | None = None,
) -> plt.Figure:
    """Paper figures 10-12 (and 14-15 with ``models``): local damping vs velocity amplitude.

    Parameters
    ----------
    segments : DataFrame
        Kept segments of one configuration (columns ``run``,
        ``velocity_amplitude_in_s``, ``zeta``).
    curve : DataFrame, optional
        Polynomial fit on a grid: ``velocity_amplitude_in_s``, ``zeta``,
        ``zeta_low``, ``zeta_high`` (confidence band).
    models : dict, optional
        Model name -> DataFrame with ``velocity_amplitude_in_s`` and ``zeta``.
    """
    with plt.rc_context(STYLE):
        figure, axis = plt.subplots()
        runs = _plot_runs(axis, segments, "zeta", scale=100)
        if curve is not None and len(curve):
            axis.fill_between(
                curve["velocity_amplitude_in_s"],
                100 * curve["zeta_low"],
                100 * curve["zeta_high"],
                color="k",
                alpha=0.12,
                label="95 % band (bootstrap over runs)",
            )
            axis.plot(
                curve["velocity_amplitude_in_s"],
                100 * curve["zeta"],
                color="k",
                linewidth=1.6,
                label="polynomial fit",
            )
        for (name, frame), style in zip((models or {}).items(), ("-", "--", "-.", ":")):
            axis.plot(frame["velocity_amplitude_in_s"], 100 * frame["zeta"], style, linewidth=2.0, label=name)
        amplitude_axis(axis)
        axis.set_ylabel(DAMPING_LABEL)
        axis.set_title(title)
        axis.legend(ncol=2 if len(runs) > 6 else 1, loc="best")
        figure.tight_layout()
    return figure


def frequency_vs_amplitude(
    segments: pd.DataFrame,
    *,
    title: str,
    models: dict[str, pd.DataFrame] | None = None,
) -> plt.Figure:
    """Backbone: local damped frequency vs velocity amplitude, per run (and models)."""
    with plt.rc_context(STYLE):
        figure, axis = plt.subplots()
        runs = _plot_runs(axis, segments, "frequency_hz")
        for (name, frame), style in zip((models or {}).items(), ("-", "--", "-.", ":")):
            axis.plot(
                frame["velocity_amplitude_in_s"], frame["frequency_hz"], style, linewidth=2.0, label=name
            )
        amplitude_axis(axis)
        axis.set_ylabel(FREQUENCY_LABEL)
        axis.set_title(title)
        axis.legend(ncol=2 if len(runs) > 6 else 1, loc="best")
        figure.tight_layout()
    return figure


def area_fits(curves: pd.DataFrame, area_table: pd.DataFrame, *, title: str) -> plt.Figure:
    """Paper figure 13: fitted damping vs amplitude per configuration, and vs bearing area.

    Parameters
    ----------
    curves : DataFrame
        ``configuration``, ``bearing_area_in2``, ``velocity_amplitude_in_s``,
        ``zeta``, ``zeta_low``, ``zeta_high``.
    area_table : DataFrame
        ``velocity_amplitude_in_s``, ``bearing_area_in2``, ``zeta`` and optionally
        ``zeta_low``/``zeta_high``: damping vs area at common amplitudes.
    """
    with plt.rc_context(STYLE):
        figure, (left, right) = plt.subplots(1, 2, figsize=(11.0, 4.6))
        for name, part in curves.groupby("configuration", sort=False):
            area = part["bearing_area_in2"].iloc[0]
            label = f"{name} ({area:.2f} in²)" if np.isfinite(area) else name
            (line,) = left.plot(
                part["velocity_amplitude_in_s"], 100 * part["zeta"], linewidth=1.8, label=label
            )
            left.fill_between(
                part["velocity_amplitude_in_s"],
                100 * part["zeta_low"],
                100 * part["zeta_high"],
                color=line.get_color(),
                alpha=0.15,
            )
        amplitude_axis(left)
        left.set_ylabel(DAMPING_LABEL)
        left.set_title("polynomial fits with 95 % bands")
        left.legend(loc="best")
        amplitudes = list(dict.fromkeys(area_table["velocity_amplitude_in_s"]))
        colours = run_colours([f"{value:.3g}" for value in amplitudes])
        for amplitude in amplitudes:
            part = area_table[area_table["velocity_amplitude_in_s"] == amplitude].sort_values(
                "bearing_area_in2"
            )
            colour = colours[f"{amplitude:.3g}"]
            if {"zeta_low", "zeta_high"} <= set(part.columns):
                right.errorbar(
                    part["bearing_area_in2"],
                    100 * part["zeta"],
                    yerr=[100 * (part["zeta"] - part["zeta_low"]), 100 * (part["zeta_high"] - part["zeta"])],
                    fmt="o-",
                    color=colour,
                    capsize=3,
                    label=f"{amplitude:.3g} in/s",
                )
            else:
                right.plot(
                    part["bearing_area_in2"],
                    100 * part["zeta"],
                    "o-",
                    color=colour,
                    label=f"{amplitude:.3g} in/s",
                )
        right.set_xlabel("bearing area (in²)")
        right.set_ylabel(DAMPING_LABEL)
        right.set_title("damping vs bearing area at common amplitudes")
        if amplitudes:
            right.legend(loc="best", title="velocity amplitude")
        figure.suptitle(title)
        figure.tight_layout()
    return figure


def friction_loops(loops: list[tuple[float, np.ndarray, np.ndarray]], *, title: str) -> plt.Figure:
    """Paper figures 7 and 8: friction force vs displacement for several amplitudes.

    Parameters
    ----------
    loops : list of (amplitude_in, displacement_in, force_lbf)
    """
    with plt.rc_context(STYLE):
        figure, axis = plt.subplots()
        colours = run_colours([f"{amplitude:g}" for amplitude, _, _ in loops])
        for amplitude, displacement, force in loops:
            axis.plot(
                displacement,
                force,
                color=colours[f"{amplitude:g}"],
                linewidth=1.4,
                label=f"amplitude {amplitude:g} in",
            )
        axis.axhline(0, color="k", linewidth=0.5)
        axis.axvline(0, color="k", linewidth=0.5)
        axis.set_xlabel("relative displacement (in)")
        axis.set_ylabel("friction force (lbf)")
        axis.set_title(title)
        axis.legend(loc="upper left")
        figure.tight_layout()
    return figure


def model_comparison(
    segments: pd.DataFrame,
    models: dict[str, pd.DataFrame],
    *,
    title: str,
) -> plt.Figure:
    """Paper figures 14 and 15: measured damping and frequency vs velocity amplitude
    with the fitted simulations (two panels sharing the amplitude axis)."""
    with plt.rc_context(STYLE):
        figure, (top, bottom) = plt.subplots(2, 1, figsize=(7.0, 7.0), sharex=True)
        runs = _plot_runs(top, segments, "zeta", scale=100, markersize=2.5, alpha=0.6)
        _plot_runs(bottom, segments, "frequency_hz", markersize=2.5, alpha=0.6, labels=False)
        for (name, frame), style in zip(models.items(), ("-", "--", "-.", ":")):
            top.plot(
                frame["velocity_amplitude_in_s"],
                100 * frame["zeta"],
                style,
                color="k",
                linewidth=2.0,
                label=name,
            )
            bottom.plot(
                frame["velocity_amplitude_in_s"],
                frame["frequency_hz"],
                style,
                color="k",
                linewidth=2.0,
                label=name,
            )
        amplitude_axis(top)
        top.set_xlabel("")
        top.set_ylabel(DAMPING_LABEL)
        top.set_title(title)
        top.legend(ncol=3 if len(runs) > 6 else 2, loc="best", fontsize=7)
        amplitude_axis(bottom)
        bottom.set_ylabel(FREQUENCY_LABEL)
        if models:
            bottom.legend(loc="best")
        figure.tight_layout()
    return figure

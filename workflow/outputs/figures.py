"""Figures in one style: units on every axis, legends naming runs and models,
logarithmic amplitude axes (amplitudes span decades), legible at report size.

The tables hold velocities in in/s, areas in in², forces in lbf; every figure takes a
:class:`~workflow.io.units.UnitSystem` (config ``units``) and shows its axes, labels and
notes in it.
"""

from __future__ import annotations

import logging
import textwrap
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

__all__ = [
    "STYLE",
    "DAMPING_LABEL",
    "FREQUENCY_LABEL",
    "save",
    "PlainLogFormatter",
    "plain_log_axis",
    "velocity_label",
    "velocity",
    "amplitude_axis",
    "legend_beside",
    "lay_out",
    "bounding_boxes_measured_once",
    "misfit_ranges",
    "misfit_sentence",
    "curve_at",
    "run_colours",
    "time_history",
    "damping_vs_amplitude",
    "damping_misfit",
    "frequency_misfit",
    "frequency_vs_amplitude",
    "CHANNEL_MARKERS",
    "modes_and_channels",
    "area_fits",
    "PARAMETER_SYMBOLS",
    "parameter_text",
    "friction_loops",
    "model_comparison",
]


matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import ticker  # noqa: E402
from matplotlib.backend_bases import DrawEvent  # noqa: E402
from matplotlib.layout_engine import TightLayoutEngine  # noqa: E402

from workflow.io.escape import plot_text  # noqa: E402
from workflow.io.units import INCH_SECOND, MODEL_PARAMETER_UNITS, UnitSystem  # noqa: E402
from workflow.outputs.readability import reaches_past_edge, readability_problems  # noqa: E402

if TYPE_CHECKING:  # tables come in as DataFrames; figures 7-8 are drawn without pandas
    import pandas as pd

log = logging.getLogger(__name__)

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
    # plain tick labels: 123.30 rather than "+1.233e2" beside the axis
    "axes.formatter.useoffset": False,
    # titles just above the panel, where matplotlib's automatic placement puts them when
    # nothing is drawn above a panel (no top ticks, no offset text: readability.py);
    # placing them costs a sixth of a figure's work
    "axes.titley": 1.0,
}

DAMPING_LABEL = "equivalent damping ratio ζ (%)"
FREQUENCY_LABEL = "damped frequency of the mode (Hz)"


def save(figure: plt.Figure, path: Path | str) -> None:
    """Save ``figure`` as PNG (through a temporary name, so no half-written file stays);
    log a warning naming every readability problem found
    (:func:`workflow.outputs.readability.readability_problems`).

    The figure is saved as laid out (:func:`lay_out` keeps what it draws inside it) and
    its problems are those of the draw that renders it: no layout of its own (a fifth of
    a figure's work). Only a figure with a text or a legend reaching past its edge
    (:func:`workflow.outputs.readability.reaches_past_edge`) is saved again, cropped to
    all it draws (``bbox_inches="tight"``, whose bounding box takes a layout more: a
    tenth of a figure's work)."""
    target = Path(path)
    checked: list[tuple[list[str], bool]] = []

    def check_first_draw(event: DrawEvent) -> None:
        if not checked:
            checked.append(
                (readability_problems(figure, event.renderer), reaches_past_edge(figure, event.renderer))
            )

    target.parent.mkdir(parents=True, exist_ok=True)
    temporary = target.with_name(f".{target.stem}.tmp.png")
    connection = figure.canvas.mpl_connect("draw_event", check_first_draw)
    try:
        figure.savefig(temporary)
        problems, past_edge = checked[0]
        if past_edge:
            figure.savefig(temporary, bbox_inches="tight")
    finally:
        figure.canvas.mpl_disconnect(connection)
    plt.close(figure)
    temporary.replace(target)
    for problem in problems:
        log.warning("figure %s is hard to read: %s", target.name, problem)


class PlainLogFormatter(ticker.Formatter):
    """Plain numbers (0.2, 1, 50) on a logarithmic axis, minor ticks labelled only where
    they do not crowd: every one within half a decade, 2, 3 and 5 within one, 2 and 5
    within two, none beyond (the decades alone then carry the scale)."""

    def __init__(self, minor: bool = False):
        self.minor = minor

    def __call__(self, value: float, pos: int | None = None) -> str:
        if value <= 0:
            return ""
        if self.minor:
            low, high = sorted(self.axis.get_view_interval())
            decades = np.log10(high / low) if low > 0 else np.inf
            mantissa = round(value / 10 ** np.floor(np.log10(value) + 1e-9), 6)
            if decades > 2.0 or (decades > 1.0 and mantissa not in (2.0, 5.0)):
                return ""
            if decades > 0.5 and mantissa not in (2.0, 3.0, 5.0):
                return ""
        return f"{value:g}"


def plain_log_axis(axis: matplotlib.axis.Axis) -> None:
    """A logarithmic axis (already set so) labelled by :class:`PlainLogFormatter`."""
    axis.set_major_formatter(PlainLogFormatter())
    axis.set_minor_locator(ticker.LogLocator(subs=np.arange(2.0, 10.0)))
    axis.set_minor_formatter(PlainLogFormatter(minor=True))


def velocity_label(units: UnitSystem = INCH_SECOND) -> str:
    """``velocity amplitude (in/s)``, or in the unit system's velocity unit."""
    return f"velocity amplitude ({units.velocity})"


def velocity(frame: pd.DataFrame, units: UnitSystem = INCH_SECOND) -> np.ndarray:
    """A table's ``velocity_amplitude_in_s`` in the unit system's velocity unit."""
    return units.per_in_s * frame["velocity_amplitude_in_s"].to_numpy(float)


def amplitude_axis(axis: plt.Axes, units: UnitSystem = INCH_SECOND) -> None:
    """Logarithmic velocity-amplitude x axis with plain tick labels (0.2, 0.5, 1, 2 ...),
    which stay legible whether the data span a fraction of a decade or several."""
    axis.set_xscale("log")
    plain_log_axis(axis.xaxis)
    axis.set_xlabel(velocity_label(units))


def legend_beside(axis: plt.Axes, **options) -> None:
    """The legend right of the panel, where it covers no data (runs can be many)."""
    handles, _ = axis.get_legend_handles_labels()
    if handles:
        columns = 2 if len(handles) > 16 else 1
        axis.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, ncol=columns, **options)


def lay_out(figure: plt.Figure, notes: Sequence[str] = (), width: int = 110) -> None:
    """Lay the panels out tightly, with the sentences of ``notes`` under them (outside
    the data) when there are any: one layout, each a large share of a figure's work.

    The layout is matplotlib's ``figure.tight_layout``, run by its engine directly:
    ``tight_layout`` leaves a placeholder layout engine on the figure, for which every
    ``savefig`` draws the whole figure once more (texts and ticks laid out, nothing
    rendered) before the draw it saves.
    """
    notes = [sentence for sentence in notes if sentence]
    if not notes:
        TightLayoutEngine(rect=None).execute(figure)
        return
    text = "\n".join(textwrap.fill(sentence, width) for sentence in notes)
    lines = text.count("\n") + 1
    height_in = figure.get_size_inches()[1]
    bottom = min(0.4, (0.2 + 0.16 * lines) / height_in)
    with bounding_boxes_measured_once(figure):
        TightLayoutEngine(rect=(0.0, bottom, 1.0, 1.0)).execute(figure)
    figure.text(0.01, 0.01, text, fontsize=8, ha="left", va="bottom", color="0.15")


@contextmanager
def bounding_boxes_measured_once(figure: plt.Figure) -> Iterator[None]:
    """Within the block, each panel's bounding box (with its labels and ticks) is measured
    once per set of arguments and renderer, then reused.

    A tight layout into a rectangle (``tight_layout(rect=...)``) measures every panel
    twice at the same place, the second time to fit the margins found by the first into
    the rectangle: the same boxes, each a full layout of the panel's ticks and texts
    (half the layout's time). Nothing may move a panel inside the block.
    """
    measured: dict[tuple, object] = {}

    def memoised(axis: plt.Axes) -> Callable[..., object]:
        measure = axis.get_tightbbox

        def get_tightbbox(renderer=None, *args, **kwargs):
            key = (id(axis), id(renderer), args, tuple(sorted(kwargs.items())))
            if key not in measured:
                measured[key] = measure(renderer, *args, **kwargs)
            return measured[key]

        return get_tightbbox

    own = {axis: vars(axis).get("get_tightbbox") for axis in figure.axes}
    for axis in own:
        axis.get_tightbbox = memoised(axis)
    try:
        yield
    finally:
        for axis, method in own.items():
            if method is None:
                del axis.get_tightbbox
            else:
                axis.get_tightbbox = method


def _filled_bins(code: np.ndarray, min_points: int) -> np.ndarray:
    """Group label of each point, counted from the top of the amplitudes down:
    consecutive amplitude bins (``code``) joined downward until a group holds
    ``min_points``; a short group left at the bottom (where a ring-down lingers and bins
    are full) joins the one above. Labels rise with amplitude.

    Examples
    --------
    >>> _filled_bins(np.array([0, 0, 0, 1, 1, 2, 3, 3, 3, 4]), 3).tolist()
    [0, 0, 0, 1, 1, 1, 2, 2, 2, 2]
    """
    codes, counts = np.unique(code, return_counts=True)
    group_of_code, group, filled = {}, 0, 0
    for value, count in zip(codes[::-1], counts[::-1]):
        group_of_code[value] = group
        filled += count
        if filled >= min_points:
            group, filled = group + 1, 0
    if 0 < filled and group > 0:  # the bottom's few points join the group above
        group_of_code = {value: min(label, group - 1) for value, label in group_of_code.items()}
    top = max(group_of_code.values())
    return np.array([top - group_of_code[value] for value in code], dtype=int)


def misfit_ranges(
    amplitude: np.ndarray,
    measured: np.ndarray,
    predicted: np.ndarray,
    *,
    per_decade: int = 8,
    min_points: int = 5,
) -> list[tuple[float, float, float]]:
    """Amplitude bins where a fitted curve misses the data by more than their scatter.

    Parameters
    ----------
    amplitude : array
        Velocity amplitude of each segment, in/s (> 0).
    measured, predicted : array
        The quantity measured and the curve's value at the same amplitudes (same unit;
        pass logarithms for damping, whose scatter grows with its size).
    per_decade : int
        Bins per decade of amplitude.
    min_points : int
        Fewest segments for a bin to count (a scatter needs a few): from the top down, a
        bin with fewer is joined with the next ones below, so that the sparse top of a
        ring-down, where a decay passes quickest and friction models differ most, is
        judged too.

    Returns
    -------
    list of (low_in_s, high_in_s, offset_in_scatter)
        Contiguous bins merged; ``offset_in_scatter`` is the largest |mean residual| /
        (the residuals' scatter in that bin, from their differences between neighbours in
        amplitude, ``sqrt(mean(diff^2) / 2)``) over the merged bins. A bin
        counts when that ratio exceeds 2: the curve passes outside most of the points
        there, a misfit no scatter explains.
    """
    amplitude = np.asarray(amplitude, dtype=float)
    residual = np.asarray(measured, dtype=float) - np.asarray(predicted, dtype=float)
    keep = (amplitude > 0) & np.isfinite(residual)
    amplitude, residual = amplitude[keep], residual[keep]
    ranges: list[tuple[float, float, float]] = []
    if amplitude.size < min_points:
        return ranges
    group = _filled_bins(np.floor(per_decade * np.log10(amplitude)).astype(int), min_points)
    previous = None
    order = np.argsort(amplitude)
    amplitude, residual, group = amplitude[order], residual[order], group[order]
    for label in np.unique(group):
        inside = residual[group == label]
        # the segments' scatter from neighbour to neighbour: a misfit that changes across
        # the bin (the top of a ring-down) is not counted as scatter
        scatter = np.sqrt(np.mean(np.diff(inside) ** 2) / 2.0)
        offset = abs(np.mean(inside)) / scatter if scatter > 0 else np.inf
        if offset <= 2.0:
            continue
        low, high = amplitude[group == label].min(), amplitude[group == label].max()
        if previous is not None and previous == label - 1:
            start, _, worst = ranges.pop()
            ranges.append((start, high, max(worst, offset)))
        else:
            ranges.append((low, high, offset))
        previous = label
    return ranges


def misfit_sentence(
    name: str, quantity: str, ranges: list[tuple[float, float, float]], units: UnitSystem = INCH_SECOND
) -> str | None:
    """'NAME misses the measured QUANTITY at 0.2-0.5 in/s (by 3.1 scatter) ...' or None.

    ``ranges`` are :func:`misfit_ranges` of amplitudes in in/s; the sentence gives them
    in ``units``."""
    if not ranges:
        return None
    scale = units.per_in_s
    parts = [f"{scale * low:.3g}-{scale * high:.3g} {units.velocity}" for low, high, _ in ranges]
    worst = max(offset for _, _, offset in ranges)
    return (
        f"{name} misses the measured {quantity} at {', '.join(parts)}: there its mean is off by up to "
        f"{worst:.1f} times the segments' scatter."
    )


def curve_at(frame: pd.DataFrame, column: str, amplitude: np.ndarray) -> np.ndarray:
    """A curve's ``column`` interpolated (in log amplitude) at ``amplitude``; NaN outside it."""
    grid = frame["velocity_amplitude_in_s"].to_numpy(float)
    values = frame[column].to_numpy(float)
    order = np.argsort(grid)
    grid, values = grid[order], values[order]
    if grid.size < 2:
        return np.full(np.shape(amplitude), np.nan)
    return np.interp(np.log10(amplitude), np.log10(grid), values, left=np.nan, right=np.nan)


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
    units: UnitSystem = INCH_SECOND,
) -> list[str]:
    """One marker series per run (coloured in run order); returns the run names."""
    runs = list(dict.fromkeys(segments["run"]))
    colours = run_colours(runs)
    for run in runs:
        part = segments[segments["run"] == run]
        axis.plot(
            velocity(part, units),
            scale * part[column],
            "o",
            markersize=markersize,
            color=colours[run],
            alpha=alpha,
            label=plot_text(run) if labels else None,
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
    """Paper figure 9: unfiltered and band-passed response with its Hilbert envelope.

    Examples
    --------
    >>> time_s = np.arange(2000) / 2000.0
    >>> ringing = np.exp(-4.0 * time_s) * np.sin(2 * np.pi * 125.0 * time_s)
    >>> figure = time_history(time_s, ringing, ringing, np.exp(-4.0 * time_s), response_label="acceleration (g)",
    ...                       title="no_washer / run01", band_hz=(100.0, 150.0))
    >>> [axis.get_ylabel() for axis in figure.axes], figure.axes[0].get_title()
    (['acceleration (g)', 'acceleration (g)'], 'no_washer / run01')
    >>> plt.close(figure)
    """
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
        lay_out(figure)
    return figure


def damping_vs_amplitude(
    segments: pd.DataFrame,
    *,
    title: str,
    curve: pd.DataFrame | None = None,
    models: dict[str, pd.DataFrame] | None = None,
    units: UnitSystem = INCH_SECOND,
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
    units : UnitSystem
        The units of the axes and notes.
    """
    with plt.rc_context(STYLE):
        figure, axis = plt.subplots(figsize=(8.4, 4.6))
        _plot_runs(axis, segments, "zeta", scale=100, units=units)
        notes = []
        fitted = {}
        # with one run there is nothing to bootstrap over: no band, and none in the legend
        if curve is not None and np.isfinite(curve["zeta_low"]).any():
            axis.fill_between(
                velocity(curve, units),
                100 * curve["zeta_low"],
                100 * curve["zeta_high"],
                color="k",
                alpha=0.12,
                label="95 % band (bootstrap over runs)",
            )
        if curve is not None and len(curve):
            axis.plot(
                velocity(curve, units),
                100 * curve["zeta"],
                color="k",
                linewidth=1.6,
                label="polynomial fit",
            )
            fitted["The polynomial fit"] = curve
        for (name, frame), style in zip((models or {}).items(), ("-", "--", "-.", ":")):
            axis.plot(velocity(frame, units), 100 * frame["zeta"], style, linewidth=2.0, label=name)
            fitted[name] = frame
        for name, frame in fitted.items():
            notes.append(damping_misfit(segments, frame, name, units))
        _finish_amplitude_panel(figure, axis, segments, DAMPING_LABEL, title, notes, units)
    return figure


def _finish_amplitude_panel(
    figure, axis, segments: pd.DataFrame, ylabel: str, title: str, notes: list, units: UnitSystem
) -> None:
    """Axes, labels, legend and notes of a curve against velocity amplitude; a note on the
    panel itself when no segment was usable."""
    if segments.empty:
        axis.text(0.5, 0.5, "no usable segment", ha="center", va="center", transform=axis.transAxes)
    amplitude_axis(axis, units)
    axis.set_ylabel(ylabel)
    axis.set_title(title)
    legend_beside(axis)
    lay_out(figure, notes)


def damping_misfit(
    segments: pd.DataFrame, frame: pd.DataFrame, name: str, units: UnitSystem = INCH_SECOND
) -> str | None:
    """The sentence saying where a fitted damping curve misses the segments (or None)."""
    amplitude = segments["velocity_amplitude_in_s"].to_numpy(float)
    zeta = segments["zeta"].to_numpy(float)
    predicted = curve_at(frame, "zeta", amplitude)
    with np.errstate(invalid="ignore", divide="ignore"):
        ranges = misfit_ranges(amplitude, np.log(zeta), np.log(predicted))
    return misfit_sentence(name, "damping", ranges, units)


def frequency_misfit(
    segments: pd.DataFrame, frame: pd.DataFrame, name: str, units: UnitSystem = INCH_SECOND
) -> str | None:
    """The sentence saying where a fitted frequency curve misses the segments (or None)."""
    amplitude = segments["velocity_amplitude_in_s"].to_numpy(float)
    predicted = curve_at(frame, "frequency_hz", amplitude)
    ranges = misfit_ranges(amplitude, segments["frequency_hz"].to_numpy(float), predicted)
    return misfit_sentence(name, "frequency", ranges, units)


def frequency_vs_amplitude(
    segments: pd.DataFrame,
    *,
    title: str,
    models: dict[str, pd.DataFrame] | None = None,
    units: UnitSystem = INCH_SECOND,
) -> plt.Figure:
    """Backbone: local damped frequency vs velocity amplitude, per run (and models)."""
    with plt.rc_context(STYLE):
        figure, axis = plt.subplots(figsize=(8.4, 4.6))
        _plot_runs(axis, segments, "frequency_hz", units=units)
        notes = []
        for (name, frame), style in zip((models or {}).items(), ("-", "--", "-.", ":")):
            axis.plot(velocity(frame, units), frame["frequency_hz"], style, linewidth=2.0, label=name)
            notes.append(frequency_misfit(segments, frame, name, units))
        _finish_amplitude_panel(figure, axis, segments, FREQUENCY_LABEL, title, notes, units)
    return figure


CHANNEL_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
"""One marker per configuration on the figure of every mode and channel."""


def modes_and_channels(
    segments: pd.DataFrame, *, title: str, channels: Sequence[str], units: UnitSystem = INCH_SECOND
) -> plt.Figure:
    """Damping and frequency against velocity amplitude of every mode, one row a mode, each
    channel in its own colour (configurations by marker): whether the sensors of a hit
    agree shows at once.

    Parameters
    ----------
    segments : DataFrame
        ``results/tables/segments.parquet`` (its ``mode_hz`` and ``channel`` columns).
    title : str
        The figure's title.
    channels : sequence of str
        The channels in campaign.yaml's order (the colours' order).
    units : UnitSystem
        Config ``units``.
    """
    modes_hz = sorted(segments["mode_hz"].dropna().unique())
    colours = dict(zip(channels, plt.get_cmap("tab10").colors))
    configurations = list(dict.fromkeys(segments["configuration"]))
    with plt.rc_context(STYLE):
        figure, axes = plt.subplots(
            max(1, len(modes_hz)), 2, figsize=(11.0, 2.0 + 2.6 * max(1, len(modes_hz))), squeeze=False
        )
        for row, mode_hz in zip(axes, modes_hz):
            mode = segments[segments["mode_hz"] == mode_hz]
            for (column, scale), label, axis in zip(
                (("zeta", 100.0), ("frequency_hz", 1.0)), (DAMPING_LABEL, FREQUENCY_LABEL), row
            ):
                for (configuration, channel), part in mode.groupby(["configuration", "channel"], sort=False):
                    marker = CHANNEL_MARKERS[configurations.index(configuration) % len(CHANNEL_MARKERS)]
                    axis.plot(
                        velocity(part, units),
                        scale * part[column].to_numpy(float),
                        marker,
                        markersize=3.5,
                        alpha=0.7,
                        color=colours.get(channel, "0.4"),
                        label=plot_text(
                            channel if len(configurations) == 1 else f"{channel} ({configuration})"
                        ),
                    )
                amplitude_axis(axis, units)
                axis.set_ylabel(label)
                axis.set_title(f"mode {mode_hz:.5g} Hz")
            legend_beside(row[1], fontsize=8)
        figure.suptitle(title)
        lay_out(figure)
    return figure


def area_fits(
    curves: pd.DataFrame, area_table: pd.DataFrame, *, title: str, units: UnitSystem = INCH_SECOND
) -> plt.Figure:
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
            area = units.per_in2 * part["bearing_area_in2"].iloc[0]
            label = f"{name} ({area:.3g} {units.area})" if np.isfinite(area) else name
            (line,) = left.plot(velocity(part, units), 100 * part["zeta"], linewidth=1.8, label=label)
            left.fill_between(
                velocity(part, units),
                100 * part["zeta_low"],
                100 * part["zeta_high"],
                color=line.get_color(),
                alpha=0.15,
            )
        amplitude_axis(left, units)
        left.set_ylabel(DAMPING_LABEL)
        left.set_title("polynomial fits with 95 % bands")
        if curves.empty:
            left.text(0.5, 0.5, "no damping fit", ha="center", va="center", transform=left.transAxes)
        else:
            left.legend(loc="best")
        amplitudes = list(dict.fromkeys(area_table["velocity_amplitude_in_s"]))
        colours = run_colours([f"{value:.3g}" for value in amplitudes])
        for amplitude in amplitudes:
            part = area_table[area_table["velocity_amplitude_in_s"] == amplitude].sort_values(
                "bearing_area_in2"
            )
            colour = colours[f"{amplitude:.3g}"]
            area = units.per_in2 * part["bearing_area_in2"]
            label = f"{units.per_in_s * amplitude:.3g} {units.velocity}"
            if {"zeta_low", "zeta_high"} <= set(part.columns):
                right.errorbar(
                    area,
                    100 * part["zeta"],
                    yerr=[100 * (part["zeta"] - part["zeta_low"]), 100 * (part["zeta_high"] - part["zeta"])],
                    fmt="o-",
                    color=colour,
                    capsize=3,
                    label=label,
                )
            else:
                right.plot(area, 100 * part["zeta"], "o-", color=colour, label=label)
        # areas in m² are small numbers (1e-4): few ticks at round steps, as plain numbers
        right.xaxis.set_major_locator(ticker.MaxNLocator(4, steps=[1, 2, 5, 10]))
        right.xaxis.set_major_formatter(ticker.FuncFormatter(lambda value, _: f"{value:.6g}"))
        right.set_xlabel(f"bearing area ({units.area})")
        right.set_ylabel(DAMPING_LABEL)
        right.set_title("damping vs bearing area at common amplitudes")
        if amplitudes:
            right.legend(loc="best", title="velocity amplitude")
        else:
            right.text(
                0.5,
                0.5,
                "not applicable: damping vs bearing area needs\n"
                "two or more configurations with bearing_area_in2\nin campaign.yaml",
                ha="center",
                va="center",
                transform=right.transAxes,
            )
            right.set_axis_off()
        figure.suptitle(title)
        lay_out(figure)
    return figure


PARAMETER_SYMBOLS = {
    "sigma": "σ",
    "sigma0": "σ0",
    "sigma1": "σ1",
    "fc": "Fc",
    "alpha0": "α0",
    "alpha1": "α1",
    "alpha2": "α2",
    "v0": "v0",
    "vd": "vd",
}
"""Dahl / LuGre parameter -> its symbol in the paper."""


def parameter_text(params: dict[str, float], units: UnitSystem = INCH_SECOND) -> str:
    """``σ = 39.5 lbf/in, Fc = 38 lbf``: friction-model parameters (given in inch-pound
    units) with their units, in ``units``."""
    parts = []
    for name, value in params.items():
        unit, unit_si, factor_si = MODEL_PARAMETER_UNITS[name]
        if units.name == "si":
            unit, value = unit_si, value * factor_si
        parts.append(f"{PARAMETER_SYMBOLS.get(name, name)} = {value:.3g} {unit}")
    return ", ".join(parts)


def friction_loops(
    loops: list[tuple[float, np.ndarray, np.ndarray]], *, title: str, units: UnitSystem = INCH_SECOND
) -> plt.Figure:
    """Paper figures 7 and 8: friction force vs displacement for several amplitudes.

    Parameters
    ----------
    loops : list of (amplitude_in, displacement_in, force_lbf)
    units : UnitSystem
        The units of the axes and labels.
    """
    with plt.rc_context(STYLE):
        figure, axis = plt.subplots()
        colours = run_colours([f"{amplitude:g}" for amplitude, _, _ in loops])
        for amplitude, displacement, force in loops:
            axis.plot(
                units.per_in * np.asarray(displacement),
                units.per_lbf * np.asarray(force),
                color=colours[f"{amplitude:g}"],
                linewidth=1.4,
                label=f"amplitude {units.per_in * amplitude:.3g} {units.length}",
            )
        axis.axhline(0, color="k", linewidth=0.5)
        axis.axvline(0, color="k", linewidth=0.5)
        axis.set_xlabel(f"relative displacement ({units.length})")
        axis.set_ylabel(f"friction force ({units.force})")
        axis.set_title(title)
        axis.legend(loc="upper left")
        lay_out(figure)
    return figure


def model_comparison(
    segments: pd.DataFrame,
    models: dict[str, pd.DataFrame],
    *,
    title: str,
    units: UnitSystem = INCH_SECOND,
) -> plt.Figure:
    """Paper figures 14 and 15: measured damping and frequency vs velocity amplitude
    with the fitted simulations (two panels sharing the amplitude axis)."""
    with plt.rc_context(STYLE):
        figure, (top, bottom) = plt.subplots(2, 1, figsize=(8.4, 7.0), sharex=True)
        _plot_runs(top, segments, "zeta", scale=100, markersize=2.5, alpha=0.6, units=units)
        _plot_runs(bottom, segments, "frequency_hz", markersize=2.5, alpha=0.6, labels=False, units=units)
        notes = []
        for (name, frame), style in zip(models.items(), ("-", "--", "-.", ":")):
            top.plot(
                velocity(frame, units),
                100 * frame["zeta"],
                style,
                color="k",
                linewidth=2.0,
                label=name,
            )
            bottom.plot(
                velocity(frame, units),
                frame["frequency_hz"],
                style,
                color="k",
                linewidth=2.0,
                label=name,
            )
            notes += [
                damping_misfit(segments, frame, name, units),
                frequency_misfit(segments, frame, name, units),
            ]
        if any(notes):
            notes.append(
                "Such a misfit is a finding, not a failed fit: it is what the diagnosis "
                "(verdict page, discovery figures) sets out to explain."
            )
        amplitude_axis(top, units)
        top.set_xlabel("")
        top.set_ylabel(DAMPING_LABEL)
        top.set_title(title)
        legend_beside(top, fontsize=7)
        amplitude_axis(bottom, units)
        bottom.set_ylabel(FREQUENCY_LABEL)
        if models:
            legend_beside(bottom)
        lay_out(figure, notes)
    return figure

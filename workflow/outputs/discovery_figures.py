"""Figures of the model discovery (results/diagnosis.json and the residual table).

* :func:`residuals_figure`: normalised residuals vs amplitude of the baseline and the
  extended model, damping and frequency, with the +-2 scatter band and binned means.
* :func:`candidates_figure`: held-out error of every candidate per configuration.
* :func:`heldout_figure`: the across-configurations prediction of a left-out area.

All take what :func:`workflow.discovery.campaign.campaign_document` and
:func:`workflow.discovery.campaign.residual_table` return; nothing is refitted here.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib import ticker  # noqa: E402

from workflow.discovery.confidence import verdict_key  # noqa: E402
from workflow.discovery.misfit import MIN_BIN_RUNS, MIN_BIN_SEGMENTS_ONE_RUN  # noqa: E402
from workflow.io.escape import plot_text  # noqa: E402
from workflow.io.units import INCH_SECOND, UnitSystem  # noqa: E402
from workflow.outputs.figures import STYLE, lay_out, plain_log_axis, velocity, velocity_label  # noqa: E402
from workflow.outputs.plain_words import left_out_caveat  # noqa: E402
from workflow.outputs.report_html import fmt  # noqa: E402

__all__ = [
    "binned_means",
    "residual_ticks",
    "residuals_figure",
    "candidate_rows",
    "candidates_figure",
    "heldout_figure",
]

ROLE_COLOURS = {"baseline": "tab:red", "extended": "tab:blue"}
CURVE_LABELS = {
    "zeta": "damping residual\n(ln ζ_measured/ζ_model) / scatter (1)",
    "frequency_hz": "frequency residual\n(f_measured/f_model − 1) / scatter (1)",
}
CURVE_NAMES = {"zeta": "damping", "frequency_hz": "frequency"}
"""The residual table's curves as the diagnosis evidence names them."""
LINEAR_LIMIT = 4.0
"""The residual axis is linear within this many scatters (the ±2 band stays readable),
logarithmic beyond (misfits span decades)."""
ERROR_LABEL = "held-out error (RMS residual / scatter, 1)"


def _configuration_document(document: Mapping, configuration: str | None = None) -> Mapping:
    """The per-configuration entry of a campaign document (or the entry itself)."""
    if "configurations" in document:
        return document["configurations"][configuration]
    return document


def _message_panel(ax: plt.Axes, message: str, title: str) -> None:
    """A panel that says why there is nothing to plot."""
    ax.text(0.5, 0.5, message, ha="center", va="center", wrap=True, transform=ax.transAxes)
    ax.set_axis_off()
    ax.set_title(title)


BINNED_MEAN_NOTE = (
    "Lines with markers: each model's mean residual per half decade of amplitude (the mean "
    "over runs of each run's mean), the numbers the verdict quotes. Baseline: filled where "
    "the misfit is significant (statistically clear after correction and larger than the "
    "models' accuracy), open where not; half decades with fewer than "
    f"{MIN_BIN_RUNS} runs (one run: {MIN_BIN_SEGMENTS_ONE_RUN} segments) are not judged and have no mean."
)


def binned_means(entry: Mapping, role: str) -> list[dict]:
    """The binned means a role's residual panel draws, from the diagnosis evidence.

    The baseline's are the discrepancy test's bins (``evidence.binned_residuals``, each
    with its significance), the extended model's those of ``explains_data``
    (``evidence.explains_data.bins``): both ``mean_over_scatter`` per half decade, the
    numbers the verdict's sentences quote.
    """
    evidence = entry.get("evidence") or {}
    if role == "baseline":
        return list(evidence.get("binned_residuals") or [])
    return list((evidence.get("explains_data") or {}).get("bins") or [])


def _draw_binned_means(
    ax: plt.Axes, bins: list[dict], curve: str, role: str, model: str, units: UnitSystem
) -> None:
    """Each bin's mean as a bar across its amplitudes with a marker at its centre: filled
    for a significant misfit (or a bin with no test, the extended model's), open for a
    tested bin that is not one. The marker lines' gid is ``"<role> binned mean"``."""
    rows = sorted((b for b in bins if b["curve"] == curve), key=lambda b: b["v_low_in_s"])
    if not rows:
        return
    colour = ROLE_COLOURS[role]
    low = units.per_in_s * np.array([b["v_low_in_s"] for b in rows])
    high = units.per_in_s * np.array([b["v_high_in_s"] for b in rows])
    means = np.array([b["mean_over_scatter"] for b in rows])
    ax.hlines(means, low, high, color=colour, lw=2.0)
    centres = np.sqrt(low * high)
    tested = any("significant" in b for b in rows)
    filled = np.array([b.get("significant", True) for b in rows], dtype=bool)
    name = f"{role}: {model}, mean per half decade"
    for mask, face, label in (
        (filled, colour, f"{name},\nsignificant misfit" if tested else name),
        (~filled, "white", f"{name},\nnot significant"),
    ):
        if mask.any():
            (line,) = ax.plot(
                centres[mask], means[mask], "o", color=colour, mfc=face, mew=1.5, ms=6, label=label
            )
            line.set_gid(f"{role} binned mean")


def residual_ticks(limit: float) -> list[float]:
    """Residual-axis ticks: 0, +-2 (the scatter band), +-4 (where the axis turns
    logarithmic: without it a mean of 4.4 reads as 7) and +-10, 100 ... up to ``limit``;
    spaced so that their labels cannot meet on the linear-then-logarithmic axis.

    Examples
    --------
    >>> residual_ticks(12.0)
    [-10.0, -4.0, -2.0, 0.0, 2.0, 4.0, 10.0]
    """
    ticks = [2.0, LINEAR_LIMIT]
    power = 10.0
    while power <= limit:
        ticks.append(power)
        power *= 10.0
    return sorted([0.0, *ticks, *(-tick for tick in ticks)])


def residuals_figure(
    residuals: pd.DataFrame, configuration: str, document: Mapping, units: UnitSystem = INCH_SECOND
) -> plt.Figure:
    """Residuals vs amplitude of the baseline and the extended model of one configuration.

    Parameters
    ----------
    residuals : DataFrame
        :func:`workflow.discovery.campaign.residual_table` (all configurations or this one).
    configuration : str
    document : mapping
        The campaign's diagnosis document (or this configuration's entry): names the
        cause and the models in the title and legends.
    units : UnitSystem
        The unit of the amplitude axis.

    Returns
    -------
    Figure
        Two panels sharing the log amplitude axis: damping and frequency residuals,
        each segment divided by the measured scatter, the +-2 band (95 % of the
        segments of a model that fits) and each model's mean per quarter decade; the
        residual axis is linear within +-4 and logarithmic beyond (misfits span decades).
        A configuration the document lists as not diagnosed (``skipped_configurations``)
        gets one panel that says why.
    """
    skipped = document.get("skipped_configurations") or {}
    if "configurations" in document and configuration not in document["configurations"]:
        reason = skipped.get(configuration, "not in the diagnosis document")
        with plt.rc_context(STYLE):
            fig, ax = plt.subplots(figsize=(9.0, 3.2))
            _message_panel(
                ax,
                f"{configuration}: not diagnosed\n({reason})",
                f"{configuration}: residuals of the friction models",
            )
            return fig
    entry = _configuration_document(document, configuration)
    rows = residuals[residuals["configuration"] == configuration]
    cause = entry.get("cause", "?")
    models = {"baseline": entry["baseline"]["model"], "extended": entry["extended_model"]["model"]}
    gain = entry.get("gain", {}).get("ratio")
    with plt.rc_context(STYLE):
        fig, axes = plt.subplots(2, 1, sharex=True, figsize=(9.6, 7.6))
        roles = ["baseline"] if models["extended"] == models["baseline"] else ["baseline", "extended"]
        for ax, curve in zip(axes, ("zeta", "frequency_hz")):
            ax.axhspan(-2, 2, color="0.85", alpha=0.6, lw=0, label="±2 scatter")
            ax.axhline(0.0, color="0.4", lw=0.8)
            for role in roles:
                sub = rows[(rows["role"] == role) & (rows["curve"] == curve)]
                ax.scatter(
                    velocity(sub, units),
                    sub["residual"].to_numpy(float),
                    s=5,
                    alpha=0.25,
                    color=ROLE_COLOURS[role],
                    lw=0,
                )
                _draw_binned_means(
                    ax, binned_means(entry, role), CURVE_NAMES[curve], role, models[role], units
                )
            ax.set_xscale("log")
            plain_log_axis(ax.xaxis)
            ax.set_ylabel(CURVE_LABELS[curve])
            finite = rows.loc[rows["curve"] == curve, "residual"].to_numpy(float)
            finite = finite[np.isfinite(finite)]
            lim = max(LINEAR_LIMIT, float(np.max(np.abs(finite))) * 1.2) if finite.size else LINEAR_LIMIT
            # linear within +-4 (the scatter band stays readable), logarithmic beyond
            ax.set_yscale("symlog", linthresh=LINEAR_LIMIT, linscale=1.5)
            ax.set_ylim(-lim, lim)
            ax.yaxis.set_major_locator(ticker.FixedLocator(residual_ticks(lim)))
            ax.yaxis.set_major_formatter(ticker.FormatStrFormatter("%g"))
            ax.yaxis.set_minor_locator(ticker.NullLocator())
            if not len(rows[rows["curve"] == curve]):
                ax.text(0.5, 0.5, "no residuals", ha="center", va="center", transform=ax.transAxes)
        # one legend for both panels: a kind of marker may appear in one panel only
        handles = {}
        for ax in axes:
            for handle, label in zip(*ax.get_legend_handles_labels()):
                handles.setdefault(label, handle)
        # the band, then each role's significant then other means
        handles = dict(
            sorted(
                handles.items(),
                key=lambda item: (
                    not item[0].startswith("±"),
                    item[0].startswith("extended"),
                    "not significant" in item[0],
                ),
            )
        )
        axes[0].legend(
            handles.values(), handles.keys(), loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0
        )
        axes[-1].set_xlabel(velocity_label(units))
        ratio = f", gain ratio {gain:.2f}" if gain is not None else ""
        fig.suptitle(f"{plot_text(configuration)}: cause {cause}{ratio}")
        lay_out(fig, [BINNED_MEAN_NOTE], width=120)
        fig.align_ylabels(axes)
    return fig


def candidate_rows(entry: Mapping) -> list[dict]:
    """The candidates a configuration's panel of :func:`candidates_figure` shows, best first.

    Each ranked cause (``ranking``) with its model and held-out error; where the verdict's
    extended model is not its cause's candidate (the slip thresholds recovered from the
    data, ``evidence.threshold_distribution``), that model too, with its own held-out error
    (``gain.extended``, the error the verdict page quotes for it). ``verdict`` marks the
    row of the verdict's extended model.

    Examples
    --------
    >>> entry = {"cause": "microslip_power_law", "causes": ["microslip_power_law"],
    ...     "baseline": {"model": "lugre"}, "extended_model": {"model": "iwan_cells_6"},
    ...     "gain": {"extended": 1.7},
    ...     "ranking": [{"cause": "microslip_power_law", "score": 5.1}, {"cause": "none", "score": 63.0}],
    ...     "evidence": {"candidates": {"microslip_power_law": {"model": "iwan"}}}}
    >>> [(r["model"], r["score"], r["verdict"]) for r in candidate_rows(entry)]
    [('iwan_cells_6', 1.7, True), ('iwan', 5.1, False), ('lugre', 63.0, False)]
    """
    evidence = entry.get("evidence") or {}
    candidates = evidence.get("candidates") or {}
    combinations = evidence.get("combinations") or {}
    extended = (entry.get("extended_model") or {}).get("model")
    verdict = verdict_key(entry.get("causes") or [entry.get("cause") or "?"])
    rows = []
    for ranked in entry.get("ranking", []):
        cause = ranked["cause"]
        if cause == "none":
            model = (entry.get("baseline") or {}).get("model", "?")
        else:
            model = (candidates.get(cause) or combinations.get(cause) or {}).get("model", "?")
        rows.append({"cause": cause, "model": model, "score": ranked["score"], "verdict": False})
    own = [r for r in rows if r["cause"] == verdict]
    if own and extended and own[0]["model"] != extended and verdict not in ("none", "unknown"):
        score = (entry.get("gain") or {}).get("extended")
        rows.append({"cause": verdict, "model": extended, "score": score, "verdict": True})
    elif own:
        own[0]["verdict"] = True
    return sorted(rows, key=lambda r: np.inf if r["score"] is None else r["score"])


def candidates_figure(document: Mapping) -> plt.Figure:
    """Held-out error of every candidate cause, per configuration, baseline marked.

    Parameters
    ----------
    document : mapping
        The campaign's diagnosis document (``configurations`` -> ``ranking``).

    Returns
    -------
    Figure
        A dot plot per configuration (one panel each, stacked): each candidate's
        held-out error on a logarithmic axis (ratios between candidates read as
        distances), the baseline ``none`` as a grey dot and a dashed line, the verdict
        as a large outlined dot. Dots, not bars: a bar on a log axis starts nowhere.
    """
    entries = document.get("configurations", {})
    names = list(entries)
    with plt.rc_context(STYLE):
        rows = [len(candidate_rows(entries[name])) for name in names] or [1]
        heights = [max(count, 1) * 0.32 + 0.9 for count in rows]
        fig, axes = plt.subplots(
            len(rows),
            1,
            figsize=(8.4, sum(heights) + 0.6),
            squeeze=False,
            gridspec_kw={"height_ratios": heights},
        )
        axes = axes[:, 0]
        if not names:
            axes[0].text(
                0.5, 0.5, "no configuration diagnosed", ha="center", va="center", transform=axes[0].transAxes
            )
            axes[0].set_axis_off()
        for ax, name in zip(axes, names):
            rows = candidate_rows(entries[name])[::-1]
            causes = [r["cause"] for r in rows]
            scores = np.array([r["score"] if r["score"] is not None else np.nan for r in rows], dtype=float)
            labels = [
                f"none ({r['model']}, baseline)" if r["cause"] == "none" else f"{r['cause']} ({r['model']})"
                for r in rows
            ]
            positions = np.arange(len(rows))
            finite = np.isfinite(scores)
            for position, row, score in zip(positions, rows, scores):
                if not np.isfinite(score):
                    continue
                verdict = row["verdict"]
                ax.plot(
                    score,
                    position,
                    "o",
                    ms=10 if verdict else 6,
                    color="0.55" if row["cause"] == "none" else "tab:blue",
                    mec="black" if verdict else "none",
                    mew=2.0 if verdict else 0.0,
                )
            if "none" in causes and np.isfinite(scores[causes.index("none")]):
                ax.axvline(scores[causes.index("none")], color="tab:red", ls="--", lw=1)
            if finite.any():
                ax.set_xscale("log")
                plain_log_axis(ax.xaxis)
                low, high = np.nanmin(scores), np.nanmax(scores)
                ax.set_xlim(low / 1.3, high * 1.3)
                if high * 1.3 / (low / 1.3) < 10**0.5:
                    # within half a decade the log ticks (1, 2, 5 ...) may leave every dot
                    # between two labels (small washer: 1.07-1.12 between 1 and 2): plain steps
                    ax.xaxis.set_major_locator(ticker.MaxNLocator(8, steps=[1, 2, 5, 10]))
                    ax.xaxis.set_minor_locator(ticker.NullLocator())
            else:
                ax.text(0.5, 0.5, "no candidate scored", ha="center", va="center", transform=ax.transAxes)
            ax.set_yticks(positions, labels)
            ax.set_ylim(-0.6, len(causes) - 0.4)
            ax.set_title(
                f"{plot_text(name)}: verdict {next((r['cause'] for r in rows if r['verdict']), '?')} "
                "(large outlined dot)",
                loc="left",
            )
        axes[-1].set_xlabel(ERROR_LABEL + "; dashed: baseline")
        lay_out(fig)
    return fig


def heldout_figure(document: Mapping, units: UnitSystem = INCH_SECOND) -> plt.Figure:
    """Across configurations: error predicting a left-out bearing area, per configuration.

    Parameters
    ----------
    document : mapping
        The campaign's diagnosis document (``across_configurations``).
    units : UnitSystem
        The unit of the bearing areas on the axis.

    Returns
    -------
    Figure
        Bars of the baseline's and the extended model's error for each left-out
        configuration (parameters linear in ln(area), fitted to the others), labelled
        with the area; a "not applicable" panel with the reason otherwise.
    """
    across = document.get("across_configurations") or {}
    with plt.rc_context(STYLE):
        fig, ax = plt.subplots(figsize=(9.0, 4.6))
        if not across.get("applicable"):
            reason = across.get("reason", "no across-configuration prediction in the document")
            _message_panel(
                ax,
                f"Across-configuration prediction not applicable:\n{reason}",
                "Prediction of a left-out bearing area",
            )
            return fig
        models = across.get("models", {})
        configs = across.get("configurations", {})
        names = sorted(configs, key=lambda n: configs[n].get("bearing_area_in2") or 0.0)
        x = np.arange(len(names))
        roles = [r for r in ("baseline", "extended") if r in models]
        markers = {"baseline": "s", "extended": "o"}
        worst = []
        for role in roles:
            errors = [configs[n].get(f"{role}_error") for n in names]
            errors = np.array([e if e is not None else np.nan for e in errors], dtype=float)
            worst.append(errors)
            mean = across.get(f"{role}_mean_error")
            label = f"{role}: {models[role]}" + (f" (mean {fmt(mean)})" if mean is not None else "")
            ax.plot(x, errors, markers[role], ms=8, color=ROLE_COLOURS[role], label=label)
        for position in x:
            values = [errors[position] for errors in worst if np.isfinite(errors[position])]
            if len(values) == 2:
                ax.plot([position, position], values, color="0.6", lw=1, zorder=0)
        ax.axhspan(0, 2, color="0.85", alpha=0.6, lw=0, label="within ±2 scatter")
        areas = [units.per_in2 * (configs[n].get("bearing_area_in2") or float("nan")) for n in names]
        ax.set_xticks(x, [f"{plot_text(n)}\n{area:.3g} {units.area}" for n, area in zip(names, areas)])
        ax.set_xlim(-0.5, len(names) - 0.5)
        ax.set_yscale("log")
        plain_log_axis(ax.yaxis)
        finite = np.concatenate(worst) if worst else np.array([])
        finite = finite[np.isfinite(finite)]
        if finite.size:
            ax.set_ylim(min(0.5, finite.min() / 1.5), finite.max() * 1.5)
        ax.set_xlabel(f"left-out configuration (bearing area, {units.area})")
        ax.set_ylabel("prediction error of the left-out\nconfiguration (RMS residual / scatter, 1)")
        ratio = across.get("ratio")
        title = "Prediction of a left-out bearing area from the others' ln(area) law"
        if ratio is not None:
            title += f"\nextended / baseline mean error = {ratio:.2f}"
        ax.set_title(title, loc="left")
        ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
        caveat = left_out_caveat(np.concatenate(worst)) if worst else None
        notes = [caveat] if caveat else []
        lay_out(fig, notes, width=100)
    return fig

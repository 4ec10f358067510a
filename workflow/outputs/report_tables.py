"""The report's table pages, self-contained HTML: :func:`hypotheses_html`,
:func:`runs_html`, :func:`damping_fits_html`, :func:`model_fits_html`,
:func:`candidates_html`, :func:`rejected_segments_html`, :func:`quality_html`: the key
tables, readable (units in the headers, numbers rounded).

Pure functions of the Parquet tables and ``results/diagnosis.json``; ``rules/report.smk``
marks the pages for ``snakemake --report``, whose HTML viewer shows them beside the
figures.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

import numpy as np
import pandas as pd

from workflow.io.recording_time import run_order
from workflow.io.units import INCH_SECOND, MODEL_PARAMETER_UNITS, UnitSystem
from workflow.outputs.plain_words import uncertainty_note
from workflow.outputs.report_html import amplitude_range, esc, fmt, html_table, page, ratio, tag
from workflow.outputs.report_wording import ERROR_UNIT, cause_name, model_name, verdict_name

__all__ = [
    "hypotheses_in_units",
    "hypotheses_html",
    "runs_in_recorded_order",
    "runs_html",
    "damping_fits_html",
    "model_fits_html",
    "candidates_html",
    "rejected_segments_html",
    "quality_html",
]


_NUMBER = r"\d+(?:\.\d+)?(?:e[+-]?\d+)?"


_IN_S = re.compile(rf"({_NUMBER})(?:-({_NUMBER}))? in/s")


def hypotheses_in_units(hypotheses: pd.DataFrame, units: UnitSystem = INCH_SECOND) -> pd.DataFrame:
    """The hypotheses table (results/tables/hypotheses.parquet, in/s and in²) as shown in
    ``units``: the amplitudes in each ``statistic`` converted, and the estimates and
    intervals of a slope per in² (H2, ``1/in^2``) per ``units.area``.

    Examples
    --------
    >>> from workflow.io.units import SI
    >>> table = pd.DataFrame({"statistic": ["slope of fitted zeta vs bearing area at velocity "
    ...     "amplitude 0.63 in/s, 1/in^2"], "estimate": [0.00064516], "ci_low": [0.0], "ci_high": [0.0]})
    >>> row = hypotheses_in_units(table, SI).iloc[0]
    >>> row["statistic"], round(float(row["estimate"]), 6)
    ('slope of fitted zeta vs bearing area at velocity amplitude 0.016 m/s, 1/m²', 1.0)
    """
    if units.velocity == INCH_SECOND.velocity or hypotheses is None or hypotheses.empty:
        return hypotheses

    def amplitudes(match: re.Match) -> str:
        low = f"{float(match[1]) * units.per_in_s:.3g}"
        high = f"-{float(match[2]) * units.per_in_s:.3g}" if match[2] else ""
        return f"{low}{high} {units.velocity}"

    shown = hypotheses.copy()
    per_area = shown["statistic"].astype(str).str.contains("1/in^2", regex=False)
    for column in ("estimate", "ci_low", "ci_high"):
        shown[column] = shown[column].where(~per_area, shown[column] / units.per_in2)
    shown["statistic"] = (
        shown["statistic"]
        .astype(str)
        .str.replace(_IN_S, amplitudes, regex=True)
        .str.replace("1/in^2", f"1/{units.area}", regex=False)
    )
    return shown


# ------------------------------------------------------------------ tables
def hypotheses_html(hypotheses: pd.DataFrame, units: UnitSystem = INCH_SECOND) -> str:
    """Every hypothesis test, one row per configuration and amplitude, in ``units``."""
    hypotheses = hypotheses_in_units(hypotheses, units)
    rows = [
        [
            esc(r.hypothesis),
            esc(r.configuration),
            tag(r.verdict, r.verdict),
            esc(r.statistic),
            fmt(r.estimate),
            f"{fmt(r.ci_low)} – {fmt(r.ci_high)}",
            fmt(100 * r.confidence, 3),
            esc(amplitude_range(r.amplitude_low_in_s, r.amplitude_high_in_s, units)),
            str(r.n_runs),
            esc(r.note or ""),
        ]
        for r in hypotheses.itertuples()
    ]
    body = (
        "<h1>The paper's hypotheses</h1>"
        "<p>H1: damping rises with amplitude at low amplitude (per configuration). "
        "H2: damping rises with bearing area (across configurations, at amplitudes all "
        "reach). Supported: the confidence interval excludes zero on the predicted side; "
        "contradicted: it excludes zero on the other side; inconclusive: it contains zero.</p>"
        + html_table(
            [
                "hypothesis",
                "configuration",
                "verdict",
                "statistic",
                "estimate",
                "confidence interval",
                "confidence (%)",
                "amplitudes",
                "runs",
                "note",
            ],
            rows,
            numeric=(4, 5, 6, 8),
        )
    )
    return page("Hypotheses", body)


def runs_in_recorded_order(runs: pd.DataFrame) -> tuple[pd.DataFrame, dict[str, str]]:
    """The runs table with each configuration's rows in run order, and which order that is.

    Run order is the order of the recording start times (``record_start``) when every
    file of the configuration states one, else of the file names
    (:func:`workflow.io.recording_time.run_order`); rows that are not run files (a glob
    that matched nothing) keep their place after the runs.
    """
    starts = runs["record_start"] if "record_start" in runs else pd.Series("", index=runs.index)
    parts, orders = [], {}
    for name, part in runs.groupby("configuration", sort=False):
        names = part["run"].astype(str)
        ordered, orders[name] = run_order(list(names), dict(zip(names, starts[part.index].fillna(""))))
        rank = {run: i for i, run in enumerate(ordered)}
        parts.append(part.iloc[np.argsort(names.map(rank).to_numpy(), kind="stable")])
    return (pd.concat(parts) if parts else runs), orders


def runs_html(runs: pd.DataFrame) -> str:
    """Every run file: used or excluded, and why; each configuration's runs in run order."""
    runs, orders = runs_in_recorded_order(runs)
    counts = runs.groupby("configuration", sort=False)["status"].value_counts().unstack(fill_value=0)
    summary = html_table(
        ["configuration", "used", "excluded"],
        [
            [esc(name), str(int(row.get("used", 0))), str(int(row.get("excluded", 0)))]
            for name, row in counts.iterrows()
        ],
        numeric=(1, 2),
    )
    recorded = runs["record_start"].fillna("") if "record_start" in runs else pd.Series("", index=runs.index)
    rows = [
        [
            esc(r.configuration),
            esc(r.run),
            esc(r.path),
            esc(recorded[r.Index]),
            tag(r.status, r.status),
            esc(r.reason),
        ]
        for r in runs.itertuples()
    ]
    order_notes = "".join(f"<li>{esc(name)}: run order: {esc(order)}</li>" for name, order in orders.items())
    body = (
        "<h1>Runs and quality checks</h1>"
        + summary
        + f"<ul>{order_notes}</ul>"
        + html_table(
            ["configuration", "run", "file", "recording start", "status", "reason"],
            rows,
            row_classes=["excluded" if r.status == "excluded" else "" for r in runs.itertuples()],
        )
    )
    return page("Runs", body)


def damping_fits_html(fits: pd.DataFrame) -> str:
    """Polynomial damping fits per configuration."""
    rows = []
    for r in fits.itertuples():
        coefficients = ", ".join(fmt(c, 4) for c in (r.coefficients if r.coefficients is not None else []))
        rows.append(
            [
                esc(r.configuration),
                fmt(r.bearing_area_in2),
                str(r.degree),
                esc(coefficients),
                esc(r.x_transform),
                fmt(r.cv_rmse_at_degree),
                str(r.n_runs),
                str(r.n_segments),
                esc(amplitude_range(r.amplitude_low_in_s, r.amplitude_high_in_s)),
                esc(r.cv_scheme),
            ]
        )
    body = (
        "<h1>Damping fits</h1><p>ζ (fraction of critical) as a polynomial in "
        "x = log10(velocity amplitude / 1 in/s), coefficients from the constant term up; "
        "degree chosen by cross-validation.</p>"
        + html_table(
            [
                "configuration",
                "bearing area (in²)",
                "degree",
                "coefficients (ζ, constant first)",
                "x",
                "CV RMSE of ζ",
                "runs",
                "segments",
                "amplitude range",
                "degree chosen by",
            ],
            rows,
            numeric=(1, 2, 5, 6, 7),
        )
    )
    return page("Damping fits", body)


def _parameter_line(name: str, value: float, std: float, units: UnitSystem) -> str:
    """``sigma = 2891 ± 61 lbf/in`` (HTML), in ``units``, with a word when the uncertainty
    leaves the value undetermined (:func:`~workflow.outputs.plain_words.uncertainty_note`)."""
    unit, unit_si, factor_si = MODEL_PARAMETER_UNITS.get(name, ("", "", 1.0))
    if units.name == "si":
        unit, value, std = unit_si, value * factor_si, std * factor_si
    unit = "" if unit in ("", "1") else f" {unit}"
    note = uncertainty_note(value, std)
    return f"{esc(name)} = {fmt(value, 4)} ± {fmt(std, 2)}{esc(unit)}" + (
        f" <i>({esc(note)})</i>" if note else ""
    )


def model_fits_html(fits: pd.DataFrame, units: UnitSystem = INCH_SECOND) -> str:
    """Dahl and LuGre parameters per configuration, value ± one sigma with its unit (in
    ``units``), fit quality."""
    rows = []
    for (configuration, model), part in fits.groupby(["configuration", "model"], sort=False):
        first = part.iloc[0]
        params = "<br>".join(_parameter_line(p.parameter, p.value, p.std, units) for p in part.itertuples())
        rows.append(
            [
                esc(configuration),
                esc(model_name(model)),
                params,
                fmt(first["rms_log_zeta"]),
                fmt(100 * first["rms_rel_frequency"]),
                esc(first.get("modal_coordinate", "")),
            ]
        )
    body = (
        "<h1>Friction model fits</h1><p>Each model simulated through the same band-pass, "
        "envelope and log decrement as the data; parameters ± one sigma from the Jacobian.</p>"
        + html_table(
            [
                "configuration",
                "model",
                "parameters (± 1σ)",
                "RMS error of ln ζ",
                "RMS error of frequency (%)",
                "modal coordinate",
            ],
            rows,
            numeric=(3, 4),
        )
    )
    return page("Friction model fits", body)


def candidates_html(document: Mapping) -> str:
    """Every model tried by the diagnosis, per configuration: held-out errors, BIC, params."""
    parts = [
        "<h1>Diagnosis: every candidate</h1>",
        f'<p class="note">{esc(ERROR_UNIT)}. ΔBIC is against the baseline (negative: better '
        "after paying for the extra parameters).</p>",
    ]
    for name, entry in (document.get("configurations") or {}).items():
        evidence = entry.get("evidence") or {}
        parts.append(f"<h2>{esc(name)}: {tag(verdict_name(entry), 'cause')}</h2>")
        rows = []
        for model, b in (evidence.get("baselines") or {}).items():
            rows.append(
                [
                    esc(
                        f"paper's model ({'baseline' if model == entry['baseline']['model'] else 'not used'})"
                    ),
                    esc(model_name(model)),
                    fmt(b.get("heldout_error")),
                    fmt(b.get("heldout_error_zeta")),
                    fmt(b.get("heldout_error_frequency")),
                    "–",
                    fmt(b.get("bic")),
                    "–",
                    "",
                ]
            )
        for cause, c in (evidence.get("candidates") or {}).items():
            params = ", ".join(f"{esc(k)} = {fmt(v)}" for k, v in (c.get("params") or {}).items())
            rows.append(
                [
                    esc(cause_name(cause)),
                    esc(model_name(c.get("model"))),
                    fmt(c.get("heldout_error")),
                    fmt(c.get("heldout_error_zeta")),
                    fmt(c.get("heldout_error_frequency")),
                    ratio(c.get("ratio_to_baseline")),
                    fmt(c.get("bic")),
                    fmt(c.get("delta_bic")),
                    params,
                ]
            )
        parts.append(
            html_table(
                [
                    "cause",
                    "model",
                    "held-out error",
                    "… damping",
                    "… frequency",
                    "ratio to baseline",
                    "BIC",
                    "ΔBIC",
                    "parameters",
                ],
                rows,
                numeric=(2, 3, 4, 5, 6, 7),
            )
        )
        parts.append(f"<p>{esc(entry.get('discrepancy', ''))}</p>")
    return page("Diagnosis candidates", "\n".join(parts))


def rejected_segments_html(rejected: pd.DataFrame) -> str:
    """Count of dropped segments per configuration and rule."""
    if rejected is None or rejected.empty:
        return page("Rejected segments", "<h1>Rejected segments</h1><p>No segment was dropped.</p>")
    frame = rejected[~rejected["kept"].astype(bool)] if "kept" in rejected else rejected
    exploded = frame.assign(rule=frame["reject_reason"].astype(str).str.split(",")).explode("rule")
    table = exploded.groupby(["configuration", "rule"], sort=False).size().unstack(fill_value=0)
    header = ["configuration", *[esc(c) for c in table.columns], "segments dropped"]
    totals = frame.groupby("configuration", sort=False).size()
    rows = [
        [esc(name), *[str(int(v)) for v in row.values], str(int(totals.get(name, 0)))]
        for name, row in table.iterrows()
    ]
    body = (
        "<h1>Rejected segments</h1><p>Segments dropped by each rule "
        "(a segment can be dropped by several; see docs/decay_analysis.md).</p>"
        + html_table(header, rows, numeric=tuple(range(1, len(header))))
    )
    return page("Rejected segments", body)


def quality_html(quality: pd.DataFrame) -> str:
    """The quality checks of every run: one row per run, one column per check.

    ``quality`` is ``results/tables/quality.parquet``: ``configuration``, ``run`` and
    one row per check with ``check``, ``applied``, ``passed``, ``value``,
    ``threshold``, ``unit``, ``reason``. A failed check is shaded and its reason
    shown on hover; a check that does not apply shows '-'.
    """
    if quality is None or quality.empty:
        return page("Quality checks", "<h1>Quality checks</h1><p>No quality check was recorded.</p>")
    checks = list(dict.fromkeys(quality["check"]))
    header = ["configuration", "run"]
    for check in checks:
        rows = quality[quality["check"] == check]
        unit = str(rows["unit"].iloc[0]) if "unit" in rows else ""
        threshold = rows["threshold"].iloc[0] if "threshold" in rows else None
        detail = "; ".join(
            part for part in (esc(unit), f"limit {fmt(threshold)}" if fmt(threshold) != "–" else "") if part
        )
        header.append(f'{esc(check)}<br><span class="note">{detail}</span>' if detail else esc(check))
    body_rows, classes = [], []
    for (configuration, run), part in quality.groupby(["configuration", "run"], sort=False):
        by_check = {r.check: r for r in part.itertuples()}
        cells, failed_any = [esc(configuration), esc(run)], False
        for check in checks:
            r = by_check.get(check)
            if r is None or not bool(r.applied):
                cells.append("–")
            elif bool(r.passed):
                cells.append(fmt(r.value))
            else:
                failed_any = True
                cells.append(f'<span class="tag excluded" title="{esc(r.reason)}">{fmt(r.value)} ✗</span>')
        body_rows.append(cells)
        classes.append("excluded" if failed_any else "")
    failed = quality[quality["applied"].astype(bool) & ~quality["passed"].astype(bool)]
    reasons = ""
    if len(failed):
        reasons = "<h2>Failed checks</h2>" + html_table(
            ["configuration", "run", "check", "value", "limit", "reason"],
            [
                [
                    esc(r.configuration),
                    esc(r.run),
                    esc(r.check),
                    fmt(r.value),
                    fmt(r.threshold),
                    esc(r.reason),
                ]
                for r in failed.itertuples()
            ],
            numeric=(3, 4),
        )
    body = (
        "<h1>Quality checks</h1><p>The measured value of every check for every run, with "
        "the limit from config.yaml (quality). Shaded: a check failed and the run was "
        "excluded; '–': the check does not apply (no force column, pre-trigger not stated, "
        "...).</p>"
        + html_table(header, body_rows, numeric=tuple(range(2, len(header))), row_classes=classes)
        + reasons
    )
    return page("Quality checks", body)

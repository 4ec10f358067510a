"""The campaign's diagnosis: ``results/diagnosis.json`` from its configurations', the
residual table, and the held-out prediction across bearing areas."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from workflow.discovery.confidence import verdict_causes, verdict_key
from workflow.discovery.configuration import (
    ConfigurationDiagnosis,
    diagnose_configuration_segments,
    json_safe,
    record_starts,
)
from workflow.discovery.decision import CAUSE_MODELS, cause_fractions
from workflow.discovery.heldout import HELD_OUT_METRIC, HELD_OUT_SCALE, heldout_weights, weighted_rms
from workflow.measured.settings import AnalysisSettings
from workflow.models.averaged import MODELS
from workflow.models.averaged_fit import (
    FitContext,
    FitResult,
    fixed_params,
    model_residuals,
    to_physical,
)
from workflow.models.settings import DiscoverySettings

__all__ = [
    "across_configurations",
    "configuration_outcomes",
    "campaign_verdict",
    "campaign_confidence",
    "diagnose_configurations",
    "diagnose_campaign",
    "RESIDUAL_COLUMNS",
    "residual_table",
    "CAMPAIGN_RULE",
    "campaign_fit_context",
    "campaign_document",
]


def across_configurations(
    diagnoses: Mapping[str, ConfigurationDiagnosis], context: FitContext, extended_model: str | None
) -> dict:
    """Parameters as functions of bearing area; each configuration predicted from the rest.

    Every fit coordinate (ln value for scale parameters) of a model is taken as
    linear in ``ln(bearing area)`` (a constant with two configurations left); the
    left-out configuration's curves are predicted from those lines and scored
    with its own scatter (RMS normalised residual, both curves).

    Returns
    -------
    dict
        ``applicable`` False (with ``reason``) when fewer than 3 configurations have
        areas; else per configuration the baseline's and the extended model's
        prediction errors and their ratio, and their means.
    """
    with_area = {
        n: d
        for n, d in diagnoses.items()
        if d.data.bearing_area_in2 is not None and d.data.bearing_area_in2 > 0
    }
    if len(with_area) < 3:
        return {
            "applicable": False,
            "reason": f"{len(with_area)} configuration(s) with a bearing area; 3 are needed",
        }
    baselines = {d.document["baseline"]["model"] for d in with_area.values()}
    base_model = "dahl" if "dahl" in baselines or len(baselines) != 1 else baselines.pop()
    models = {"baseline": base_model}
    if extended_model and extended_model != base_model:
        models["extended"] = extended_model
    out = {
        "applicable": True,
        "parametrisation": "fit coordinates linear in ln(bearing area)",
        "metric": HELD_OUT_METRIC,
        "models": models,
        "configurations": {},
    }
    names = list(with_area)
    log_area = np.log([with_area[n].data.bearing_area_in2 for n in names])
    for role, m in models.items():
        model = MODELS[m]
        if any(m not in with_area[n].fits for n in names):
            out["models"].pop(role)
            continue
        coords = np.array([with_area[n].fits[m].coords for n in names])
        for i, n in enumerate(names):
            keep = np.arange(len(names)) != i
            design = np.vstack([np.ones(keep.sum()), log_area[keep]]).T
            beta, *_ = np.linalg.lstsq(design, coords[keep], rcond=None)
            pred = np.array([1.0, log_area[i]]) @ beta
            d = with_area[n]
            params = {p.name: float(v[0, 0]) for p, v in zip(model.params, to_physical(model, pred).values())}
            params.update(fixed_params(model, d.data, context))
            fit = FitResult(m, pred, params, np.nan)
            res = model_residuals(fit, d.data, d.scatter, context)
            err = weighted_rms(
                0.5 * (res[f"z_{HELD_OUT_SCALE}"] ** 2 + res[f"f_{HELD_OUT_SCALE}"] ** 2),
                heldout_weights(d.data, d.scatter.noise_ln_zeta, d.scatter.noise_rel_f),
            )
            entry = out["configurations"].setdefault(n, {"bearing_area_in2": d.data.bearing_area_in2})
            entry[f"{role}_error"] = err
            entry[f"{role}_params"] = params
    for entry in out["configurations"].values():
        if "extended_error" in entry and "baseline_error" in entry:
            entry["ratio"] = entry["extended_error"] / entry["baseline_error"]
    errs = out["configurations"].values()
    out["baseline_mean_error"] = float(np.mean([e["baseline_error"] for e in errs]))
    if "extended" in out["models"]:
        out["extended_mean_error"] = float(np.mean([e["extended_error"] for e in errs]))
        out["ratio"] = out["extended_mean_error"] / out["baseline_mean_error"]
    return json_safe(out)


def configuration_outcomes(outcomes: Sequence) -> tuple[dict[str, ConfigurationDiagnosis], dict[str, str]]:
    """The diagnoses and the skipped configurations (name -> why) of the configurations'
    outcomes (:class:`workflow.discovery.diagnosis_files.DiagnosedConfiguration`), in the order of the
    segments table; a configuration with no segment in it (``order`` -1: every run
    excluded, or every segment rejected) comes last among the skipped, never dropped."""
    ordered = sorted(outcomes, key=lambda o: (o.order < 0, o.order))
    diagnoses = {o.configuration: o.diagnosis for o in ordered if o.diagnosis is not None}
    skipped = {o.configuration: o.skipped for o in ordered if o.diagnosis is None}
    return diagnoses, skipped


def campaign_verdict(causes: Sequence[str], ratios: Sequence[float]) -> str:
    """Campaign cause: the most frequent configuration cause other than ``none``.

    Ties go to the cause with the lowest mean gain ratio; ``none`` only when every
    configuration is ``none`` (or there is none).

    Examples
    --------
    >>> campaign_verdict(["none", "run_drift", "quadratic_damping", "run_drift"], [1.0, 0.5, 0.4, 0.6])
    'run_drift'
    >>> campaign_verdict(["none", "none"], [1.0, 1.0])
    'none'
    """
    named = [(c, r) for c, r in zip(causes, ratios) if c != "none"]
    if not named:
        return "none"
    counts: dict[str, list[float]] = {}
    for c, r in named:
        counts.setdefault(c, []).append(r)
    return min(counts, key=lambda c: (-len(counts[c]), float(np.mean(counts[c]))))


CAMPAIGN_DRAWS_PER_REWEIGHTING = 20
"""Verdict sets drawn from each reweighting's probabilities for the campaign's confidence
(its Monte Carlo error is then below 0.01 with 100 reweightings)."""


def campaign_confidence(diagnoses: Mapping[str, ConfigurationDiagnosis], seed: int = 0) -> dict[str, float]:
    """Share of joint draws whose campaign verdict names each verdict (cause, or a
    combination's ``+``-joined causes).

    Reweighting ``b`` of every configuration (of its own runs) gives each configuration's
    verdict probabilities and gain ratio; :data:`CAMPAIGN_DRAWS_PER_REWEIGHTING` sets of
    configuration verdicts are drawn from them, and :func:`campaign_verdict` turns each
    set into one campaign verdict. With one configuration this is its confidence."""
    counts = {len(d.resamples) for d in diagnoses.values()}
    if not diagnoses or len(counts) != 1 or 0 in counts:
        return {}
    if len(diagnoses) == 1:
        return dict(next(iter(diagnoses.values())).document["confidence"])
    rng = np.random.default_rng(seed)
    verdicts = []
    for b in range(counts.pop()):
        ratios = [d.resamples[b]["ratio"] for d in diagnoses.values()]
        tables = [d.resamples[b]["probabilities"] for d in diagnoses.values()]
        drawn = [
            rng.choice(
                list(t), size=CAMPAIGN_DRAWS_PER_REWEIGHTING, p=np.array(list(t.values())) / sum(t.values())
            )
            for t in tables
        ]
        verdicts += [
            campaign_verdict([str(c[k]) for c in drawn], ratios)
            for k in range(CAMPAIGN_DRAWS_PER_REWEIGHTING)
        ]
    return cause_fractions(verdicts)


def diagnose_configurations(
    segments: pd.DataFrame,
    *,
    response_quantity: str | Mapping[str, str] = "acceleration",
    settings: DiscoverySettings | None = None,
    segment_cycles: float = AnalysisSettings.segment_cycles,
    segment_overlap: float = AnalysisSettings.segment_overlap,
    runs: pd.DataFrame | None = None,
) -> tuple[FitContext, dict[str, ConfigurationDiagnosis], dict[str, str]]:
    """Every configuration's diagnosis in one process (the workflow runs one job each).

    Parameters
    ----------
    segments : DataFrame
        The kept segments (results/tables/segments.parquet): ``configuration``,
        ``run``, ``velocity_amplitude_in_s``, ``zeta``, ``frequency_hz``,
        ``bearing_area_in2``.
    response_quantity : str or mapping
        Recorded quantity, for all configurations or per configuration, where the
        segments have no ``response_quantity`` column (the segments table's says each
        segment's): the envelope of an acceleration record decays differently from a
        displacement's when the frequency changes.
    settings : DiscoverySettings, optional
    segment_cycles, segment_overlap : float
        Log-decrement segment length in cycles and overlap (config
        ``analysis.segment_cycles``, ``analysis.segment_overlap``), for the
        envelope-structure check.
    runs : DataFrame, optional
        The runs table (results/tables/runs.parquet): its ``record_start`` orders each
        configuration's runs for the run-order tests; without it, file-name order.

    Returns
    -------
    context, diagnoses, skipped
        The campaign's :class:`FitContext`, configuration -> :class:`ConfigurationDiagnosis`
        in campaign order, and configuration -> why it was not diagnosed.
    """
    settings = settings or DiscoverySettings()
    context = campaign_fit_context(segments)
    diagnoses: dict[str, ConfigurationDiagnosis] = {}
    skipped = {}
    for name in dict.fromkeys(segments["configuration"].astype(str)):
        quantity = (
            response_quantity
            if isinstance(response_quantity, str)
            else response_quantity.get(name, "acceleration")
        )
        outcome = diagnose_configuration_segments(
            segments,
            name,
            context,
            response_quantity=quantity,
            settings=settings,
            segment_cycles=segment_cycles,
            segment_overlap=segment_overlap,
            record_start=record_starts(runs, name),
        )
        if isinstance(outcome, str):
            skipped[name] = outcome
        else:
            diagnoses[name] = outcome
    return context, diagnoses, skipped


def diagnose_campaign(segments: pd.DataFrame, campaign_name: str, **options) -> dict:
    """The ``results/diagnosis.json`` document of a campaign, in one process.

    ``options`` are those of :func:`diagnose_configurations`.

    Returns
    -------
    dict
        ``campaign``, ``cause``, ``configurations`` (per the output contract) and
        ``across_configurations``; all numbers finite (None where not applicable).
    """
    context, diagnoses, skipped = diagnose_configurations(segments, **options)
    return campaign_document(campaign_name, context, diagnoses, skipped)


RESIDUAL_COLUMNS = [
    "configuration",
    "run",
    "segment",
    "role",
    "model",
    "velocity_amplitude_in_s",
    "curve",
    "measured",
    "predicted",
    "scatter",
    "residual",
]


def residual_table(diagnoses: Mapping[str, ConfigurationDiagnosis]) -> pd.DataFrame:
    """Residuals of the baseline and the extended model at every measured segment.

    Parameters
    ----------
    diagnoses : mapping
        Configuration -> :class:`ConfigurationDiagnosis` (:func:`diagnose_configurations`).

    Returns
    -------
    DataFrame
        One row per configuration x segment x model role x curve: ``configuration``,
        ``run``, ``segment`` (index of the segment among the configuration's usable
        ones), ``role`` ("baseline" or "extended"), ``model`` (model id; for cause
        ``none`` the extended model is the baseline), ``velocity_amplitude_in_s``,
        ``curve`` ("zeta" or "frequency_hz"), ``measured``, ``predicted`` (the fitted
        model's curve at the segment's amplitude, all-data fit), ``scatter`` (the
        measured run-to-run scatter: in ``ln zeta``, or in relative frequency) and
        ``residual`` (``ln(measured / predicted)`` or ``measured / predicted - 1``,
        divided by ``scatter``; the same normalisation as the held-out error).
    """
    frames = []
    for name, d in diagnoses.items():
        roles = {
            "baseline": d.document["baseline"]["model"],
            "extended": d.document["extended_model"]["model"],
        }
        data = d.data
        runs = np.array(data.run_names, dtype=object)[data.run_index] if data.n else []
        for role, m in roles.items():
            res = d.residuals[m]
            for curve, measured, predicted, scatter, residual in (
                ("zeta", data.zeta, res["zeta_model"], d.scatter.noise_ln_zeta, res["z_noise"]),
                ("frequency_hz", data.frequency_hz, res["f_model"], d.scatter.noise_rel_f, res["f_noise"]),
            ):
                frames.append(
                    pd.DataFrame(
                        {
                            "configuration": name,
                            "run": runs,
                            "segment": np.arange(data.n),
                            "role": role,
                            "model": m,
                            "velocity_amplitude_in_s": data.velocity_in_s,
                            "curve": curve,
                            "measured": measured,
                            "predicted": predicted,
                            "scatter": scatter,
                            "residual": residual,
                        }
                    )
                )
    if not frames:
        return pd.DataFrame(
            {
                c: pd.Series(
                    dtype=float
                    if c in ("velocity_amplitude_in_s", "measured", "predicted", "scatter", "residual")
                    else object
                )
                for c in RESIDUAL_COLUMNS
            }
        )
    return pd.concat(frames, ignore_index=True)[RESIDUAL_COLUMNS]


CAMPAIGN_RULE = (
    "most frequent configuration cause other than none (ties: lowest mean "
    "gain ratio); none only when every configuration is none"
)


def campaign_fit_context(segments: pd.DataFrame) -> FitContext:
    """The campaign's :class:`FitContext`: reference velocity = 0.9 quantile of every
    configuration's segment velocity amplitudes (in/s; 1 when there are none).

    It is computed from all segments even when one configuration is diagnosed, so that a
    configuration's fits do not depend on which job fitted them.
    """
    v_all = segments["velocity_amplitude_in_s"].to_numpy(float)
    v_all = v_all[np.isfinite(v_all) & (v_all > 0)]
    return FitContext(float(np.quantile(v_all, 0.9)) if v_all.size else 1.0)


def campaign_document(
    campaign_name: str,
    context: FitContext,
    diagnoses: Mapping[str, ConfigurationDiagnosis],
    skipped: Mapping[str, str],
) -> dict:
    """The ``results/diagnosis.json`` document from the configurations' diagnoses.

    Parameters
    ----------
    campaign_name : str
    context : FitContext
        The campaign's (:func:`campaign_fit_context`).
    diagnoses : mapping
        Configuration -> :class:`ConfigurationDiagnosis`, in campaign order.
    skipped : mapping
        Configuration -> why it was not diagnosed.

    Returns
    -------
    dict
        ``campaign``, ``cause``, ``confidence``, ``configurations`` (per the output
        contract), ``across_configurations``, ``skipped_configurations`` and the
        reference velocity; all numbers finite (None where not applicable).
    """
    configurations = {n: d.document for n, d in diagnoses.items()}
    keys = [verdict_key(d.get("causes") or [d["cause"]]) for d in configurations.values()]
    verdict = campaign_verdict(keys, [d["gain"]["ratio"] for d in configurations.values()])
    # the causes in the order of the first configuration with that verdict (largest share first)
    causes = next(
        (
            list(d.get("causes") or [d["cause"]])
            for k, d in zip(keys, configurations.values())
            if k == verdict
        ),
        verdict_causes(verdict),
    )
    cause = causes[0]
    document = {
        "campaign": campaign_name,
        "cause": cause,
        "causes": causes,
        "confidence": campaign_confidence(diagnoses),
        "campaign_rule": CAMPAIGN_RULE,
        "configurations": configurations,
        "across_configurations": across_configurations(diagnoses, context, CAUSE_MODELS.get(cause)),
        "skipped_configurations": dict(skipped),
        "reference_velocity_in_s": context.reference_velocity_in_s,
    }
    return json_safe(document)

"""One configuration's diagnosis: baselines, candidates, verdict, confidence and its document."""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from workflow.discovery.combined import (
    UNTOUCHED_CURVE,
    combination_causes,
    combination_parts,
    combination_starts,
    combination_test,
    combinations_to_try,
    one_curve_scatter,
    term_from_residuals,
)
from workflow.discovery.confidence import VerdictOption, beyond_accuracy, verdict_causes, verdict_key
from workflow.discovery.decision import (
    BASELINE_MODELS,
    BETWEEN_RUN_CAUSES,
    CAUSE_MODELS,
    CLEAR_GAIN,
    RESIDUAL_GAIN,
    RUN_ORDER_TESTS,
    ModelEvidence,
    confidence_draws,
    evaluate_decision,
    extended_model_of,
    predicts_as_well,
    verdict_options,
)
from workflow.discovery.heldout import HELD_OUT_METRIC, cross_validate
from workflow.discovery.microslip import refine_microslip, threshold_cells, threshold_distribution
from workflow.discovery.misfit import (
    binned_discrepancy,
    envelope_structure,
    envelope_structure_draws,
    explains_data,
    microslip_signature,
    run_order_trend,
    stiffness_signature,
    threshold_signature,
)
from workflow.discovery.wording import discrepancy_sentence
from workflow.measured.settings import AnalysisSettings
from workflow.models.averaged import COMBINED_MODELS, MODELS, RESPONSE_ORDER, AveragedModel
from workflow.models.averaged_fit import (
    FitContext,
    FitResult,
    at_bounds,
    fit_model,
    model_residuals,
)
from workflow.models.configuration_data import (
    TOL_LN_ZETA,
    TOL_REL_F,
    ConfigurationData,
    Scatter,
    mean_unbiased_damping,
    prepare_configuration,
    scatter_of,
)
from workflow.models.settings import DiscoverySettings

__all__ = [
    "NESTED_DAHL",
    "json_safe",
    "ConfigurationDiagnosis",
    "bound_flags",
    "diagnose_configuration",
    "record_starts",
    "diagnose_configuration_segments",
    "add_threshold_cells",
    "fit_combinations",
    "judge_combinations",
    "needs_threshold_cells",
    "passes_departure_gate",
    "friction_explains_softening",
    "friction_checked_stiffness",
    "conclude",
    "curve_led_start",
    "most_probable_verdict",
]

log = logging.getLogger(__name__)


NESTED_DAHL = {
    "lugre": lambda d: {
        "stiction_ratio": 1e-3,
        "micro_damping_ratio": 0.0,
        "stribeck_velocity_in_s": float(np.median(d.velocity_in_s)),
    },
    "dahl_quadratic": lambda d: {
        "quadratic_zeta_per_in_s": 2e-3 * float(np.min(d.zeta)) / float(np.max(d.velocity_in_s))
    },
    "dahl_stiffness": lambda d: {"stiffness_shift": 0.0, "stiffness_exponent": 2.0},
    "dahl_drift": lambda d: {"drift": 0.0},
}
"""Extension parameters that reduce each model to Dahl (the nested start)."""


def _finite(x):
    """JSON-safe float (None for non-finite)."""
    if x is None:
        return None
    x = float(x)
    return x if np.isfinite(x) else None


def json_safe(obj):
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return _finite(obj)
    return obj


@dataclass
class ConfigurationDiagnosis:
    """Everything computed for one configuration (the document plus the fits)."""

    document: dict
    fits: dict[str, FitResult]
    data: ConfigurationData
    scatter: Scatter
    residuals: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    resamples: list[dict] = field(default_factory=list)
    """Per Bayesian-bootstrap reweighting of the runs, the verdicts' probabilities, one
    verdict drawn from them and the gain ratio (:func:`confidence_draws`)."""
    evidence: dict[str, ModelEvidence] = field(default_factory=dict)
    """What the decision was taken on (:func:`evaluate_decision`), per model; not kept in
    the interim files."""


def bound_flags(model: AveragedModel | str, coords: np.ndarray, data: ConfigurationData) -> list[str]:
    """Parameters of a fit that sit on an edge of their fit range (not identified there)."""
    model = MODELS[model] if isinstance(model, str) else model
    flags = []
    for spec, edge, c in zip(model.params, at_bounds(model, coords, data), coords):
        if edge:
            value = float(np.exp(c)) if spec.scale == "log" else float(c)
            if spec.name == "joint_stiffness_fraction" and edge > 0:
                flags.append(
                    f"{spec.name} = {value:.3g} at its physical limit: the data ask for a joint "
                    "carrying more of the modal stiffness than a lap joint's contact does "
                    "(docs/discovery.md, fit ranges)"
                )
                continue
            side = "lower" if edge < 0 else "upper"
            flags.append(
                f"{spec.name} = {value:.3g} at the {side} edge of its fit range: not identified by the data"
            )
    return flags


def add_threshold_cells(
    data: ConfigurationData,
    scatter: Scatter,
    context: FitContext,
    *,
    fits: dict[str, FitResult],
    cv: dict[str, dict],
    residuals: dict[str, dict[str, np.ndarray]],
    evidence: dict[str, ModelEvidence],
    settings: DiscoverySettings,
) -> str:
    """Fit and cross-validate the Iwan joint with the slip thresholds from the data
    (:func:`refine_microslip`, from the power-law fit) and add it to ``fits``, ``cv``,
    ``residuals`` and ``evidence``; returns its model id."""
    name = f"iwan_cells_{threshold_cells(data)}"
    fits[name], cv[name] = refine_microslip(data, scatter, context, fits["iwan"], settings=settings)
    residuals[name] = model_residuals(fits[name], data, scatter, context)
    signature = threshold_signature(fits[name], fits["iwan"], data)["shows_signature"]
    evidence[name] = ModelEvidence(residuals[name], cv[name], len(MODELS[name].params), signature)
    return name


def fit_combinations(
    data: ConfigurationData,
    scatter: Scatter,
    context: FitContext,
    *,
    fits: dict[str, FitResult],
    cv: dict[str, dict],
    residuals: dict[str, dict[str, np.ndarray]],
    evidence: dict[str, ModelEvidence],
    settings: DiscoverySettings,
    tried: list[str],
) -> None:
    """Fit and cross-validate the combined models ``tried`` (:func:`combinations_to_try`)
    from both single fits and from each mechanism's own curve; the fits, held-out errors,
    residuals and evidence are added to ``fits``, ``cv``, ``residuals`` and ``evidence``
    (the micro-slip joint with the slip thresholds from the data first, where missing)."""
    if tried and combination_parts(tried[0])[0] not in fits:
        add_threshold_cells(
            data,
            scatter,
            context,
            fits=fits,
            cv=cv,
            residuals=residuals,
            evidence=evidence,
            settings=settings,
        )
    for model in tried:
        started = time.perf_counter()
        extension = combination_parts(model)[1]
        starts = combination_starts(model, fits, NESTED_DAHL[extension](data))
        starts += curve_led_start(model, data, scatter, context, fits, settings)
        fits[model] = fit_model(model, data, scatter, context, settings=settings, nested_start=starts)
        cv[model] = cross_validate(model, data, scatter, context, fits[model], settings=settings)
        residuals[model] = model_residuals(fits[model], data, scatter, context)
        # beside a stiffness term, which shares the frequency curve with the joint, each
        # mechanism must show its signature; a velocity-squared loss leaves the frequency
        # to the joint alone, and the paired test against Dahl with the loss decides
        signature = "stiffness_shift" not in fits[model].params or (
            microslip_signature(fits[model], data)["shows_signature"]
            and stiffness_signature(fits[model], data)["shows_signature"]
        )
        evidence[model] = ModelEvidence(residuals[model], cv[model], len(MODELS[model].params), signature)
        log.info(
            "%s %s: fitted and cross-validated in %.1f s (held-out error %.3g)",
            data.name,
            model,
            time.perf_counter() - started,
            cv[model]["error"],
        )


def passes_departure_gate(result: Mapping, model: str) -> bool:
    """Whether ``model`` passes, on all the data, the gate a candidate passes to depart from
    the baseline without a significant misfit (:func:`workflow.discovery.decision.decide`):
    its held-out error below ``CLEAR_GAIN`` of the baseline's, or what it removes beyond the
    models' accuracy (:func:`~workflow.discovery.confidence.beyond_accuracy`)."""
    base, errors = result["baseline"], result["errors"]
    if errors[model]["error"] < CLEAR_GAIN * errors[base]["error"]:
        return True
    curve_squares = result["unit_curve_squares"]
    all_units = np.ones((1, len(result["unit_weights"])))
    return bool(
        beyond_accuracy(curve_squares[base], curve_squares[model], result["unit_tolerance"], all_units)[0]
    )


def judge_combinations(
    data: ConfigurationData, result: dict, evidence: Mapping[str, ModelEvidence]
) -> tuple[dict[str, dict], list[VerdictOption]]:
    """The combinations fitted (those of ``evidence``), each judged by
    :func:`workflow.discovery.combined.combination_test`; one may replace the single verdict.

    A combination becomes the verdict (``result["verdict"]``, its ``confidence`` key) when
    it passes the test, lowers the BIC of the baseline, passes the gate of a departure from
    the baseline where the single verdict is ``none``, shows, where it has a stiffness term,
    the stiffness signature and micro-slip's on its joint, predicts held-out data better
    than the single verdict's model, and does not leave a significant misfit with less than
    ``RESIDUAL_GAIN`` of the baseline's error; among several, the lower held-out error, and
    among those within one standard error of the best's
    (:func:`~workflow.discovery.decision.predicts_as_well`), the lower BIC, as between
    single causes.

    Returns
    -------
    combinations, options
        Per combination tried (its key) the evidence, and the combinations as
        :class:`VerdictOption`.
    """
    verdict = result["verdict"]
    base, errors, bic = result["baseline"], result["errors"], result["bic"]
    combinations, options = {}, []
    for model in (m for m in COMBINED_MODELS.values() if m in evidence):
        causes = combination_causes(model)
        # micro-slip alone: the better predictor of the power law and the combination's own joint
        microslip = min(("iwan", combination_parts(model)[0]), key=lambda m: errors[m]["error"])
        part_models = {causes[0]: microslip, causes[1]: result["extended_models"][causes[1]]}
        parts = {c: result["unit_squares"][m] for c, m in part_models.items()}
        test = combination_test(
            result["unit_squares"][model], parts, result["unit_squares"][base], result["unit_weights"]
        )
        bins = binned_discrepancy(data, evidence[model].residuals)
        trend = run_order_trend(data, evidence[model].residuals, n_tests=RUN_ORDER_TESTS)
        significant = any(b["significant"] for b in bins) or bool(trend and trend["significant"])
        ratio = errors[model]["error"] / errors[base]["error"]
        # where no single cause departs from the baseline, a combination must pass the same
        # gate as a single cause does (decision.decide): its own clear gain or accuracy margin
        departs = verdict != "none" or result["baseline_fails"] or passes_departure_gate(result, model)
        eligible = test["named"] and departs and bic[model] < bic[base] and evidence[model].shows_signature
        key = verdict_key(causes)
        combinations[key] = {
            "model": model,
            "parts": part_models,
            **test,
            "heldout_error": errors[model]["error"],
            "ratio_to_baseline": ratio,
            "bic": bic[model],
            "delta_bic": bic[model] - bic[base],
            "shows_signature": evidence[model].shows_signature,
            "residual_significant": bool(significant),
            "eligible": bool(eligible),
        }
        # the confidence re-takes the parsimony test on every reweighting of the units
        rest = bic[model] < bic[base] and evidence[model].shows_signature
        options.append(VerdictOption(key, model, bool(rest), bool(significant), parts=part_models))
    # a combination replaces the single verdict only where it also predicts better than it
    single = errors[result["extended_models"][verdict]]["error"] if verdict in CAUSE_MODELS else np.inf
    named = [
        k
        for k, v in combinations.items()
        if v["eligible"]
        and v["heldout_error"] < single
        and not (v["residual_significant"] and v["ratio_to_baseline"] >= RESIDUAL_GAIN)
    ]
    if named:
        # the rule decide() chooses among candidates by: the lowest held-out error, and among
        # those that predict as well as far as the data can tell, the lowest BIC
        leader = min(named, key=lambda k: combinations[k]["heldout_error"])
        squares = result["unit_squares"][combinations[leader]["model"]]
        near = [
            k
            for k in named
            if predicts_as_well(
                combinations[leader]["heldout_error"],
                squares,
                result["unit_weights"],
                combinations[k]["heldout_error"],
            )
        ]
        best = min(near, key=lambda k: combinations[k]["bic"])
        result["verdict"] = best
        result["reason"] = (
            f"{result['reason']}; two mechanisms, {combinations[best]['model']}, predict better still "
            f"({combinations[best]['rule']})"
        )
    return combinations, options


def needs_threshold_cells(
    data: ConfigurationData, result: Mapping, evidence: Mapping[str, ModelEvidence]
) -> bool:
    """Whether micro-slip may be represented by the Iwan joint with the slip thresholds
    from the data: the power law does not explain the data, predicts held-out data no
    better than the baseline (then it is no candidate, however closely it follows the
    data it was fitted to), or leaves a significant misfit while cutting the baseline's
    error by less than :data:`RESIDUAL_GAIN` (then the decision reads it as ``unknown``:
    the misfit several pooled sensors find below 2 scatters), and micro-slip is the verdict, the baseline's misfit is
    significant, or the thresholds from the data, where already fitted (for the
    combinations), predict held-out data better than the baseline and pass
    :func:`passes_departure_gate`, the gate every candidate passes to depart from
    ``none``. A patch joint's micro-slip is not one power law over the measured decades:
    at the edge of its visible range the power law can lose to a candidate of another
    cause, to none, or to the baseline itself where the thresholds from the data beat them
    all; :func:`conclude` adopts them only where they lower both the held-out
    error and the BIC of the power law and show its signature."""
    cells = f"iwan_cells_{threshold_cells(data)}"
    errors = result["errors"]
    baseline_error = errors[result["baseline"]]["error"]
    clear = (
        cells in errors and errors[cells]["error"] < baseline_error and passes_departure_gate(result, cells)
    )
    power_law = result.get("candidates", {}).get("microslip_power_law", {})
    power_law_falls_short = (
        errors["iwan"]["error"] >= baseline_error
        or not (explains_data(data, evidence["iwan"].residuals)["explains_data"])
        # decide() would read it as unknown: a significant misfit left, most of it
        or (
            power_law.get("residual_significant")
            and errors["iwan"]["error"] >= RESIDUAL_GAIN * baseline_error
        )
    )
    return bool(
        (result["cause"] == "microslip_power_law" or result["baseline_fails"] or clear)
        and power_law_falls_short
    )


def friction_explains_softening(decision: Mapping, cells: str) -> bool:
    """Whether the Iwan joint with the slip thresholds from the data (``cells``, where
    fitted) predicts held-out data at least as well as the stiffness candidate, by the
    rule :func:`~workflow.discovery.decision.decide` chooses between candidates with: the
    lower held-out error, and where the two predict as well as far as the data can tell
    (:func:`~workflow.discovery.decision.predicts_as_well`), the lower BIC.

    The contract's signature of a stiffness nonlinearity is a frequency shift far more
    than the friction that fits the damping can explain. The stiffness candidate's own
    check (:func:`~workflow.discovery.misfit.stiffness_signature`) measures it against its
    single-state (Dahl) friction; a joint of Jenkins elements with free thresholds is a
    friction whose damping and softening follow one backbone (Masing), and where it
    predicts both curves as well as the spring does, the softening is what the friction
    that fits the damping explains. A tie in held-out error is no such evidence: there
    the fewer parameters for the same fit decide, as between any two candidates.

    Parameters
    ----------
    decision : mapping
        :func:`~workflow.discovery.decision.evaluate_decision`'s result (``errors``,
        ``bic``, ``unit_squares``, ``unit_weights``).
    cells : str
        The thresholds' model id.
    """
    stiffness = CAUSE_MODELS["stiffness_nonlinearity"]
    errors, bic = decision["errors"], decision["bic"]
    if cells not in errors or stiffness not in errors:
        return False
    cells_error, stiffness_error = errors[cells]["error"], errors[stiffness]["error"]
    best = cells if cells_error <= stiffness_error else stiffness
    other_error = stiffness_error if best == cells else cells_error
    squares, weights = decision["unit_squares"][best], decision["unit_weights"]
    if predicts_as_well(errors[best]["error"], squares, weights, other_error):
        return bool(bic[cells] <= bic[stiffness])
    return best == cells


def friction_checked_stiffness(
    evidence: Mapping[str, ModelEvidence], decision: Mapping, cells: str
) -> Mapping[str, ModelEvidence]:
    """``evidence`` with the stiffness candidate's signature withdrawn where
    :func:`friction_explains_softening` (``decision``: the decision on ``evidence``)."""
    stiffness = CAUSE_MODELS["stiffness_nonlinearity"]
    if stiffness not in evidence or not evidence[stiffness].shows_signature:
        return evidence
    if not friction_explains_softening(decision, cells):
        return evidence
    return {**evidence, stiffness: replace(evidence[stiffness], shows_signature=False)}


ENVELOPE_STREAM = 2
"""Random stream of the envelope test's reweightings, apart from the held-out units'."""


def conclude(
    data: ConfigurationData,
    evidence: Mapping[str, ModelEvidence],
    *,
    envelope_significant: bool,
    settings: DiscoverySettings = DiscoverySettings(),
    segment_cycles: float = AnalysisSettings.segment_cycles,
    segment_overlap: float = AnalysisSettings.segment_overlap,
) -> tuple[dict, dict[str, dict], dict[str, float], list[dict]]:
    """The verdict and its confidence on every model fitted (no fit is made here).

    :func:`evaluate_decision` on ``evidence``; where :func:`needs_threshold_cells`, the
    Iwan joint with the slip thresholds from the data (``iwan_cells_N`` in ``evidence``)
    becomes micro-slip's extended model when it lowers both the held-out error and the BIC
    of ``iwan``; the combinations in ``evidence`` are judged (:func:`judge_combinations`);
    the confidence (:func:`confidence_draws`, the envelope test re-taken on reweightings
    of each run's segments, :func:`envelope_structure_draws`, with the log decrement's
    ``segment_cycles`` and ``segment_overlap``); the verdict is the most probable one of
    the confidence (:func:`most_probable_verdict`).

    Returns
    -------
    result, combinations, confidence, resamples
        The decision (``verdict``: its ``confidence`` key; ``threshold_cells``: the
        refinement's model id where it was considered, else None), the combinations'
        evidence, the confidence and its per-draw decisions.
    """
    refined = f"iwan_cells_{threshold_cells(data)}"
    result = evaluate_decision(data, evidence, envelope_significant=envelope_significant)
    checked = friction_checked_stiffness(evidence, result, refined)
    if checked is not evidence:
        evidence = checked
        result = evaluate_decision(data, evidence, envelope_significant=envelope_significant)
    errors, bic = result["errors"], result["bic"]
    considered = refined in evidence and needs_threshold_cells(data, result, evidence)
    if (
        considered
        and errors[refined]["error"] < errors["iwan"]["error"]
        and bic[refined] < bic["iwan"]
        and evidence[refined].shows_signature
    ):
        # micro-slip is then the thresholds from the data, in the decision as in its model
        result = evaluate_decision(
            data,
            evidence,
            envelope_significant=envelope_significant,
            extended_models={"microslip_power_law": refined},
        )
    result["threshold_cells"] = refined if considered else None
    result["verdict"] = result["cause"]
    combinations, combination_options = judge_combinations(data, result, evidence)
    structure = envelope_structure_draws(
        data,
        settings.resamples,
        np.random.default_rng([settings.seed, ENVELOPE_STREAM]),
        segment_cycles=segment_cycles,
        segment_overlap=segment_overlap,
    )
    confidence, resamples = confidence_draws(
        result,
        verdict_options(result, combination_options),
        envelope_significant=structure,
        n_draws=settings.resamples,
        seed=settings.seed,
    )
    verdict = most_probable_verdict(result["verdict"], confidence, resamples)
    likeliest = max(confidence, key=confidence.get, default=verdict)
    if verdict != result["verdict"]:
        result["reason"] = (
            f"{verdict}, the most probable verdict over reweightings of the runs "
            f"({confidence[verdict]:.2f}; on all the data: {result['verdict']}, {result['reason']})"
        )
    elif confidence.get(likeliest, 0.0) > confidence.get(verdict, 0.0):
        result["reason"] = (
            f"{result['reason']}; {likeliest} ({confidence[likeliest]:.2f}) is as probable within the "
            "Monte Carlo error of the reweightings, so the decision on all the data stands"
        )
    result["verdict"] = verdict
    return result, combinations, confidence, resamples


def curve_led_start(
    model: str,
    data: ConfigurationData,
    scatter: Scatter,
    context: FitContext,
    fits: Mapping[str, FitResult],
    settings: DiscoverySettings,
) -> list[dict[str, float]]:
    """A start of a combined model from each mechanism's own curve.

    The extension's term leaves one curve alone (:data:`UNTOUCHED_CURVE`: a stiffness
    term dissipates nothing, a velocity-squared loss stores nothing), so the joint is
    fitted to that curve alone (from its fit to both), and the extension's term read off
    what the joint leaves on the other (:func:`term_from_residuals`). Where the two
    mechanisms pull the shared curve opposite ways (micro-slip's softening against a
    hardening spring) the fit to both curves starts from a joint that explains neither,
    and the extension's fit from a Dahl joint, which cannot carry micro-slip. Empty where
    the term would be unphysical (a negative loss).
    """
    joint_model, extension_model = combination_parts(model)
    joint = fit_model(
        joint_model,
        data,
        one_curve_scatter(scatter, UNTOUCHED_CURVE[extension_model]),
        context,
        settings=settings,
        nested_start=fits[joint_model].params,
    )
    residuals = model_residuals(joint, data, scatter, context)
    term = term_from_residuals(
        extension_model, data.velocity_in_s, residuals, scatter, context.reference_velocity_in_s
    )
    return [] if term is None else [{**joint.params, **term}]


MONTE_CARLO_MARGIN = 2.0
"""Standard errors of the reweightings' Monte Carlo mean by which another verdict must be
more probable than the decision on all the data to replace it (a 95 % band)."""


def most_probable_verdict(
    verdict: str, confidence: Mapping[str, float], draws: Sequence[Mapping] = ()
) -> str:
    """The verdict with the largest confidence, where it is more probable than ``verdict``
    (the decision on all the data) beyond the Monte Carlo error of the reweightings.

    The confidence re-takes the decision on reweightings of the runs, sharing ties
    between candidates by their held-out evidence: where the decision on all the data
    sits at one of its margins (a gain ratio at ``CLEAR_GAIN``, a near-tie broken by the
    BIC), the verdict is the one most of the reweightings take. With ``draws`` (each
    draw's ``probabilities``, :func:`~workflow.discovery.decision.confidence_draws`) the
    difference must exceed :data:`MONTE_CARLO_MARGIN` standard errors of its mean over
    the draws: a difference the draws' own sampling makes is no evidence, and the
    decision on all the data stands (a tie among six verdicts at 0.16-0.18 does not
    turn on the random numbers).

    Examples
    --------
    >>> most_probable_verdict("unknown", {"stiffness_nonlinearity": 0.6, "unknown": 0.4})
    'stiffness_nonlinearity'
    >>> most_probable_verdict("none", {"none": 0.5, "run_drift": 0.5})
    'none'
    >>> draws = [{"probabilities": {"unknown": 1.0}}, {"probabilities": {"none": 1.0}}] * 5
    >>> most_probable_verdict("none", {"unknown": 0.52, "none": 0.48}, draws)
    'none'
    >>> most_probable_verdict("none", {"unknown": 0.6, "none": 0.4}, [{"probabilities": {"unknown": 0.6, "none": 0.4}}] * 10)
    'unknown'
    """
    best = max(confidence, key=confidence.get, default=verdict)
    if confidence.get(best, 0.0) <= confidence.get(verdict, 0.0):
        return verdict
    if len(draws) >= 2:
        difference = np.array(
            [d["probabilities"].get(best, 0.0) - d["probabilities"].get(verdict, 0.0) for d in draws]
        )
        if difference.mean() <= MONTE_CARLO_MARGIN * difference.std(ddof=1) / np.sqrt(difference.size):
            return verdict
    return best


def diagnose_configuration(
    data: ConfigurationData,
    context: FitContext,
    *,
    settings: DiscoverySettings = DiscoverySettings(),
    segment_cycles: float = AnalysisSettings.segment_cycles,
    segment_overlap: float = AnalysisSettings.segment_overlap,
) -> ConfigurationDiagnosis:
    """Baselines, discrepancy, candidates, verdict and its confidence for one configuration
    (``segment_cycles``, ``segment_overlap``: the log decrement's segments, for the
    envelope test)."""
    scatter = scatter_of(data)
    # every model is fitted and judged on mean-unbiased ln zeta (noisy segments' logarithms
    # average low: log_damping_bias)
    data = mean_unbiased_damping(data, scatter)
    fits: dict[str, FitResult] = {}
    cv: dict[str, dict] = {}
    for name in BASELINE_MODELS + tuple(CAUSE_MODELS.values()):
        if name == "dahl_drift" and data.n_runs < 3:
            continue
        nested = None
        if name != "dahl" and name in NESTED_DAHL and "dahl" in fits:
            nested = {**fits["dahl"].params, **NESTED_DAHL[name](data)}
        started = time.perf_counter()
        fits[name] = fit_model(name, data, scatter, context, settings=settings, nested_start=nested)
        cv[name] = cross_validate(name, data, scatter, context, fits[name], settings=settings)
        log.info(
            "%s %s: fitted and cross-validated in %.1f s (held-out error %.3g)",
            data.name,
            name,
            time.perf_counter() - started,
            cv[name]["error"],
        )
    residuals = {m: model_residuals(f, data, scatter, context) for m, f in fits.items()}
    evidence = {m: ModelEvidence(residuals[m], cv[m], len(MODELS[m].params)) for m in fits}
    stiffness_model = CAUSE_MODELS["stiffness_nonlinearity"]
    signature = stiffness_signature(fits[stiffness_model], data)
    evidence[stiffness_model].shows_signature = signature["shows_signature"]
    envelope = envelope_structure(data, segment_cycles=segment_cycles)
    envelope_significant = bool(envelope and envelope["significant"])
    first = evaluate_decision(data, evidence, envelope_significant=envelope_significant)
    if needs_threshold_cells(data, first, evidence):
        started = time.perf_counter()
        name = add_threshold_cells(
            data,
            scatter,
            context,
            fits=fits,
            cv=cv,
            residuals=residuals,
            evidence=evidence,
            settings=settings,
        )
        log.info(
            "%s %s (slip thresholds from the data): fitted and cross-validated in %.1f s "
            "(held-out error %.3g, iwan %.3g)",
            data.name,
            name,
            time.perf_counter() - started,
            cv[name]["error"],
            cv["iwan"]["error"],
        )
    baseline_error = first["errors"][first["baseline"]]["error"]
    departs = first["cause"] == "none" and (
        any(
            v["heldout_error"] < baseline_error and v["beyond_accuracy"]
            for c, v in first["candidates"].items()
            if c not in BETWEEN_RUN_CAUSES
        )
        or not explains_data(data, evidence[first["baseline"]].residuals)["explains_data"]
    )
    tried = (
        []
        if envelope_significant
        else combinations_to_try(first["cause"], f"iwan_cells_{threshold_cells(data)}", departs)
    )
    fit_combinations(
        data,
        scatter,
        context,
        fits=fits,
        cv=cv,
        residuals=residuals,
        evidence=evidence,
        settings=settings,
        tried=tried,
    )
    result, combinations, confidence, resamples = conclude(
        data,
        evidence,
        envelope_significant=envelope_significant,
        settings=settings,
        segment_cycles=segment_cycles,
        segment_overlap=segment_overlap,
    )
    refinement = None
    if result["threshold_cells"]:
        name, errors, bic = result["threshold_cells"], result["errors"], result["bic"]
        refinement = {
            "model": name,
            "adopted": result["extended_models"]["microslip_power_law"] == name,
            "rule": (
                "adopted as the extended model when it lowers both the held-out error and the BIC of "
                "iwan and shows micro-slip's signature"
            ),
            "heldout_error": errors[name]["error"],
            "bic": bic[name],
            "iwan_heldout_error": errors["iwan"]["error"],
            "iwan_bic": bic["iwan"],
            "cells": threshold_distribution(fits[name], data, scatter, context),
            "signature": threshold_signature(fits[name], fits["iwan"], data),
            "standard_error": "Gauss-Newton, scaled by the fit cost and residuals over effective observations",
        }
    for entry in combinations.values():
        m = entry["model"]
        entry.update(
            in_sample_rms=float(np.sqrt(fits[m].cost)),
            params=fits[m].params,
            flags=bound_flags(m, fits[m].coords, data),
        )
    causes = combinations[result["verdict"]]["causes"] if result["verdict"] in combinations else None
    causes = causes or verdict_causes(result["verdict"])
    result["cause"] = causes[0]
    cause, reason, base = result["cause"], result["reason"], result["baseline"]
    errors, bins, trend, candidates = result["errors"], result["bins"], result["trend"], result["candidates"]
    candidates["stiffness_nonlinearity"]["signature"] = signature
    candidates["stiffness_nonlinearity"]["friction_explains_softening"] = friction_explains_softening(
        result, f"iwan_cells_{threshold_cells(data)}"
    )
    for entry in candidates.values():
        m = entry["model"]
        entry["in_sample_rms"] = float(np.sqrt(fits[m].cost))
        entry["params"] = fits[m].params
        entry["flags"] = bound_flags(m, fits[m].coords, data)
    ranking = [{"cause": "none", "score": errors[base]["error"]}]
    ranking += [{"cause": c, "score": v["heldout_error"]} for c, v in candidates.items()]
    # a combination is a candidate cause once it passes the parsimony rule; until then a check
    ranking += [{"cause": k, "score": v["heldout_error"]} for k, v in combinations.items() if v["eligible"]]
    ranking.sort(key=lambda r: r["score"])
    ext_model = combinations[result["verdict"]]["model"] if result["verdict"] in combinations else None
    ext_model = ext_model or extended_model_of(result)
    ext_err = errors[ext_model]["error"]
    explained = explains_data(data, residuals[ext_model])
    sentence = discrepancy_sentence(base, bins, trend, data.n_runs)
    if envelope_significant:
        sentence = (
            f"The ring-downs are not single-mode decays: even at each run's highest "
            f"amplitudes the envelope departs from an exponential within a segment by "
            f"{100 * envelope['departure_ratio']:.0f} % of its decay across the segment "
            f"(median over runs; limit {100 * envelope['limit']:.0f} %), which no {base} "
            f"fit or candidate can follow; {data.n_dropped} segments had zeta <= 0. " + sentence
        )
    run_spread = {}
    if data.n_runs >= 2:
        run_spread = {
            "relative_frequency_std": float(np.std(residuals[base]["delta_f"], ddof=1)),
            "zeta0_std": float(np.std(residuals[base]["delta_zeta0"], ddof=1)),
        }
    document = {
        "baseline": {
            "model": base,
            "params": fits[base].params,
            "error": {"metric": HELD_OUT_METRIC, "value": errors[base]["error"]},
            "flags": bound_flags(base, fits[base].coords, data),
        },
        "discrepancy": sentence,
        "cause": cause,
        "evidence": {
            "decision_rule": reason,
            "n_runs": data.n_runs,
            "n_segments": data.n,
            "n_segments_dropped": data.n_dropped,
            "effective_observations": result["n_eff"],
            "scatter": {
                "ln_zeta_median": float(np.median(scatter.noise_ln_zeta)),
                "relative_frequency_median": float(np.median(scatter.noise_rel_f)),
                "model_tolerance_ln_zeta": TOL_LN_ZETA,
                "model_tolerance_relative_frequency": TOL_REL_F,
            },
            "run_offsets": run_spread,
            "baselines": {
                m: {
                    "heldout_error": errors[m]["error"],
                    "heldout_error_zeta": errors[m]["error_zeta"],
                    "heldout_error_frequency": errors[m]["error_frequency"],
                    "in_sample_rms": float(np.sqrt(fits[m].cost)),
                    "bic": result["bic"][m],
                }
                for m in BASELINE_MODELS
            },
            "baseline_misfit_significant": result["baseline_fails"],
            "binned_residuals": bins,
            "run_order_trend": trend,
            "envelope_structure": envelope,
            "candidates": candidates,
            "combinations": combinations,
            "clear_gain_threshold": CLEAR_GAIN,
            "residual_gain_threshold": RESIDUAL_GAIN,
            "explains_data": explained,
            "threshold_distribution": refinement,
            "resamples": len(resamples),
        },
        "ranking": ranking,
        "extended_model": {
            "model": ext_model,
            "params": fits[ext_model].params,
            "removes_misfit": cause != "unknown" and explained["explains_data"],
            "flags": bound_flags(ext_model, fits[ext_model].coords, data),
        },
        "gain": {
            "metric": HELD_OUT_METRIC,
            "baseline": errors[base]["error"],
            "extended": ext_err,
            "ratio": 1.0 if cause == "none" else ext_err / errors[base]["error"],
        },
        "explains_data": explained["explains_data"],
        "confidence": confidence,
        "causes": causes,
    }
    return ConfigurationDiagnosis(json_safe(document), fits, data, scatter, residuals, resamples, evidence)


def record_starts(runs: pd.DataFrame | None, name: str) -> dict[str, str]:
    """Run name -> ISO 8601 recording start of configuration ``name``'s runs, from the runs
    table (results/tables/runs.parquet; empty where a file states none, or no table)."""
    if runs is None or "record_start" not in runs:
        return {}
    rows = runs[runs["configuration"].astype(str) == name]
    return dict(zip(rows["run"].astype(str), rows["record_start"].fillna("").astype(str)))


def diagnose_configuration_segments(
    segments: pd.DataFrame,
    name: str,
    context: FitContext,
    *,
    response_quantity: str = "acceleration",
    settings: DiscoverySettings | None = None,
    segment_cycles: float = AnalysisSettings.segment_cycles,
    segment_overlap: float = AnalysisSettings.segment_overlap,
    record_start: Mapping[str, str] | None = None,
) -> ConfigurationDiagnosis | str:
    """:func:`diagnose_configuration` of configuration ``name`` of the segments table, or
    why it is skipped (too few usable segments or amplitudes to fit and validate models).

    Parameters
    ----------
    segments : DataFrame
        The campaign's kept segments (results/tables/segments.parquet).
    name : str
    context : FitContext
        The campaign's (:func:`~workflow.discovery.campaign.campaign_fit_context`).
    response_quantity : str
        The configuration's recorded quantity where the segments have no
        ``response_quantity`` column (the segments table's says each segment's).
    settings : DiscoverySettings, optional
    segment_cycles, segment_overlap : float
        Log-decrement segment length (cycles) and overlap (fraction).
    record_start : mapping, optional
        Run name -> recording start (:func:`record_starts`): the run order.
    """
    data = prepare_configuration(segments, name, RESPONSE_ORDER[response_quantity], record_start)
    if data.n < 12 or np.unique(np.round(np.log10(data.velocity_in_s), 2)).size < 4:
        return f"only {data.n} usable segments: too few to fit and validate models"
    return diagnose_configuration(
        data,
        context,
        settings=settings or DiscoverySettings(),
        segment_cycles=segment_cycles,
        segment_overlap=segment_overlap,
    )

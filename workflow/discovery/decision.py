"""The decision: ``none``, a named cause, or ``unknown``, and how sure the data let one be.

:func:`decide` is the rule; :func:`evaluate_decision` computes what it needs (held-out
errors, BIC, the baseline's misfit tests) on all segments;
:func:`confidence_draws` re-takes it, softly, on Bayesian-bootstrap reweightings of the
runs for the confidence (:mod:`workflow.discovery.confidence`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from workflow.discovery.combined import paired_critical_value, paired_t, squared_error_log_ratio
from workflow.discovery.confidence import (
    HeldoutEvidence,
    VerdictOption,
    beyond_accuracy,
    dirichlet_unit_weights,
    mean_probabilities,
    soft_decisions,
    unseen,
)
from workflow.discovery.heldout import (
    effective_observations,
    heldout_standard_error,
    heldout_units,
    heldout_weights,
    information_criterion,
    weighted_rms,
)
from workflow.discovery.misfit import (
    binned_discrepancy,
    departure_ruled_out_by_channels,
    failure_draws,
    run_order_trend,
)
from workflow.models.configuration_data import TOL_LN_ZETA, TOL_REL_F, ConfigurationData

__all__ = [
    "CAUSE_MODELS",
    "BASELINE_MODELS",
    "RUN_ORDER_TESTS",
    "BETWEEN_RUN_CAUSES",
    "predicts_as_well",
    "heldout_gain_t",
    "parsimonious",
    "CLEAR_GAIN",
    "RESIDUAL_GAIN",
    "decide",
    "ModelEvidence",
    "evaluate_decision",
    "verdict_options",
    "confidence_draws",
    "extended_model_of",
    "cause_fractions",
]


CAUSE_MODELS: dict[str, str] = {
    "microslip_power_law": "iwan",
    "quadratic_damping": "dahl_quadratic",
    "stiffness_nonlinearity": "dahl_stiffness",
    "run_drift": "dahl_drift",
}
"""Cause id -> the extended model that represents it."""


BASELINE_MODELS = ("dahl", "lugre")
"""The paper's models (each + linear viscous damping)."""


RUN_ORDER_TESTS = 2
"""The run-order test is significant at ``p < misfit.ALPHA / RUN_ORDER_TESTS``: it is one
question on its own axis (run order, not amplitude), so it is not diluted by the number
of amplitude bins."""


BETWEEN_RUN_CAUSES = ("run_drift",)
"""Causes whose extension acts between runs, not along a ring-down's amplitudes: each run's
own frequency and linear-damping offsets, fitted to all its segments, absorb part of what
the extension explains in sample, so its BIC cannot show its gain, while a held-out run,
its offsets set by its stuck-joint calibration segments alone, shows it. Such a candidate
also pays for its parameter by its held-out gain across runs, or by removing the
baseline's significant run-order trend (:func:`parsimonious`)."""


CLEAR_GAIN = 0.7
"""Without a significant baseline misfit, a candidate is named when its held-out error is
below this fraction of the baseline's (the same margin as ``RESIDUAL_GAIN``), or when it
removes more held-out misfit than the models' accuracy (:func:`~workflow.discovery.confidence.beyond_accuracy`).
On no-effect (Dahl-joint) campaigns the averaged models' own bias, a few 1e-6 in
relative frequency, let an extension reach 0.62-0.87 of the baseline's error where the
scatter is small (bench/hit_rate.py, seeds 1-40); 0.85 named a cause in 18 % of them."""


RESIDUAL_GAIN = 0.7
"""With a significant baseline misfit, a candidate that leaves a significant misfit
is still accepted when its held-out error is below this fraction of the baseline's
(it removes most of the misfit); otherwise the verdict is ``unknown``."""


def decide(
    baseline_error: float,
    baseline_bic: float,
    baseline_fails: bool,
    candidates: Mapping[str, dict],
    envelope_structure: bool = False,
    unit_squares: Mapping[str, np.ndarray] | None = None,
    unit_weights: np.ndarray | None = None,
) -> tuple[str, str]:
    """The decision rule.

    Parameters
    ----------
    baseline_error, baseline_bic : float
        Held-out error and BIC of the best baseline.
    baseline_fails : bool
        Whether the baseline shows a significant misfit (binned or run-order).
    candidates : mapping
        cause -> dict with ``heldout_error``, ``bic``, ``residual_significant`` and
        optionally ``shows_signature`` (default true), ``gain_across_runs`` (whether its
        held-out gain over the baseline passes the paired test over the runs,
        :func:`heldout_gain_t`; default false; counts for :data:`BETWEEN_RUN_CAUSES` only,
        :func:`parsimonious`), ``removes_run_trend`` (the baseline's run-order trend
        significant and the candidate's not; default false; the same) and
        ``beyond_accuracy`` (whether it
        removes more held-out misfit than the models' accuracy,
        :func:`~workflow.discovery.confidence.beyond_accuracy`; default false).

    envelope_structure : bool
        Whether the ring-downs are not single-mode decays (:func:`~workflow.discovery.misfit.envelope_structure`).
    unit_squares, unit_weights : optional
        Per candidate, its held-out weighted squared residuals summed over each
        independent unit of evidence (a run; with one run, a held-out amplitude block,
        :func:`heldout_units`), and the units' weights: they give the standard error of
        the best candidate's held-out error. Without them only equal errors tie.

    Returns
    -------
    cause, reason : str
        ``none``, a cause id, or ``unknown``; and the rule that fired.

    Rule
    ----
    * ``unknown`` when the envelopes are not single-mode free decays: no model of a
      single mode (baseline or candidate) can remove that misfit.
    * A candidate is *eligible* when its held-out error is below the baseline's, it pays
      for its parameters (:func:`parsimonious`: its BIC below the baseline's; a run drift
      also by its held-out gain across runs or by removing the baseline's run-order
      trend), and its fit shows its cause's signature
      (:func:`~workflow.discovery.misfit.stiffness_signature`).
    * ``none`` when the baseline has no significant misfit and no eligible candidate
      cuts the held-out error below ``CLEAR_GAIN`` x the baseline's or removes more
      held-out misfit than the models' accuracy (``beyond_accuracy``).
    * Otherwise the best eligible candidate by held-out error; candidates whose squared
      held-out error is within one standard error of the best's (the one-standard-error
      rule of cross-validation, :func:`heldout_standard_error`) predict as well as far
      as the data can tell, and the one with the lowest BIC (fewest parameters for the
      same fit) is taken. ``unknown`` when no
      candidate is eligible, or when the best
      leaves a significant misfit and does not cut the held-out error below
      ``RESIDUAL_GAIN`` x the baseline's.

    Examples
    --------
    >>> candidate = {"heldout_error": 0.5, "bic": 5.0, "residual_significant": False}
    >>> decide(1.0, 10.0, True, {"quadratic_damping": candidate})[0]
    'quadratic_damping'
    >>> weak = {"heldout_error": 0.9, "bic": 9.0, "residual_significant": False}
    >>> decide(1.0, 10.0, False, {"quadratic_damping": weak})[0]
    'none'
    """
    if envelope_structure:
        return "unknown", (
            "even at the runs' highest amplitudes the segment envelopes depart from "
            "exponential decays by more than ENVELOPE_DEPARTURE_LIMIT of their decay: "
            "a disturbance outside every single-mode model (e.g. a second mode "
            "beating in the band)"
        )
    eligible = {
        c: v
        for c, v in candidates.items()
        if v["heldout_error"] < baseline_error
        and parsimonious(c, v, baseline_bic)
        and v.get("shows_signature", True)
    }
    clear = {
        c: v
        for c, v in eligible.items()
        if v["heldout_error"] < CLEAR_GAIN * baseline_error or v.get("beyond_accuracy", False)
    }
    if not baseline_fails and not clear:
        return "none", (
            "no significant misfit of the baseline and no candidate reduces the "
            f"held-out error below {CLEAR_GAIN} of the baseline's or removes more held-out "
            "misfit than the models' accuracy"
        )
    if not eligible:
        return "unknown", (
            "the baseline misfit is significant but no candidate lowers the held-out error, pays for its "
            "parameters (BIC, or a run drift's held-out gain across runs or its removal of the run-order "
            "trend) and shows its cause's signature"
        )
    leader = min(eligible, key=lambda c: eligible[c]["heldout_error"])
    best_squares = None if unit_squares is None else unit_squares[leader]
    near = {
        c: v
        for c, v in eligible.items()
        if predicts_as_well(eligible[leader]["heldout_error"], best_squares, unit_weights, v["heldout_error"])
    }
    best = min(near, key=lambda c: near[c]["bic"])
    v = eligible[best]
    if v["residual_significant"] and v["heldout_error"] >= RESIDUAL_GAIN * baseline_error:
        return "unknown", (
            f"the best eligible candidate ({best}) leaves a significant misfit and cuts the "
            f"held-out error only to {v['heldout_error'] / baseline_error:.2f} of "
            "the baseline's"
        )
    why = "baseline misfit significant" if baseline_fails else "clear held-out gain"
    return best, (
        f"{why}; {best} has the lowest held-out error among candidates that also pay for their parameters"
    )


def predicts_as_well(
    best_error: float,
    best_unit_squares: np.ndarray | None,
    unit_weights: np.ndarray | None,
    error: float,
) -> bool:
    """Whether a model whose held-out error is ``error`` predicts as well as the best one
    as far as the data can tell: its squared error within one standard error of the
    best's squared error (the one-standard-error rule of cross-validation,
    :func:`heldout_standard_error` over the units of evidence). Without the units only
    equal errors tie.

    Examples
    --------
    >>> predicts_as_well(1.0, np.array([1.0, 1.4, 0.6]), np.ones(3), 1.1)
    True
    >>> predicts_as_well(1.0, np.array([1.0, 1.4, 0.6]), np.ones(3), 1.2)
    False
    """
    reach = best_error**2
    if best_unit_squares is not None and unit_weights is not None:
        reach += heldout_standard_error(best_unit_squares, unit_weights)
    return error**2 <= reach


def heldout_gain_t(
    baseline_squares: np.ndarray, candidate_squares: np.ndarray, unit_weights: np.ndarray
) -> float:
    """Paired t over the units of evidence (runs) of the log ratio of the baseline's
    squared held-out error in each unit to the candidate's: how consistently, against
    its scatter over the runs, the candidate predicts a held-out run better (the
    scale-free comparison of :func:`~workflow.discovery.combined.combination_test`).

    Examples
    --------
    >>> round(heldout_gain_t(np.array([2.0, 3.0, 4.0]), np.array([1.0, 1.0, 1.0]), np.ones(3)), 2)
    5.27
    """
    present = unit_weights > 0
    return float(paired_t(squared_error_log_ratio(baseline_squares[present], candidate_squares[present]))[0])


def parsimonious(cause: str, candidate: Mapping, baseline_bic: float) -> bool:
    """Whether a candidate pays for its parameters: its BIC below the baseline's, or, for a
    cause that acts between runs (:data:`BETWEEN_RUN_CAUSES`), its held-out gain across
    runs beyond their scatter (``gain_across_runs``: :func:`heldout_gain_t` above Student's
    one-sided 2.5 % quantile, :func:`~workflow.discovery.combined.paired_critical_value`),
    or the removal of the baseline's significant run-order trend (``removes_run_trend``:
    the trend test, :func:`~workflow.discovery.misfit.run_order_trend`, is the drift's own
    test at a stated false-alarm rate, the same parameter's evidence by another route).

    The BIC judges a parameter by what it adds to the in-sample fit. A run drift's
    parameter says how the runs differ, and in sample each run's two offsets already say
    that for every run: on the lab's run-drift campaigns seen near a node they take up
    most of it (seed 728 of bench/hit_rate.py: held-out error 0.81 of the baseline's,
    in-sample cost 0.94, BIC +1.0). Held out, a run's offsets come from its
    lowest-amplitude segments, where the joint is stuck and no drift of its friction
    limit shows, so there the drift's parameter is judged by what it predicts of a run it
    was not fitted to, unit by unit, at a stated false-alarm rate.

    Examples
    --------
    >>> parsimonious("run_drift", {"bic": 11.0, "gain_across_runs": True}, 10.0)
    True
    >>> parsimonious("quadratic_damping", {"bic": 11.0, "gain_across_runs": True}, 10.0)
    False
    >>> parsimonious("run_drift", {"bic": 11.0, "removes_run_trend": True}, 10.0)
    True
    """
    if candidate["bic"] < baseline_bic:
        return True
    return cause in BETWEEN_RUN_CAUSES and bool(
        candidate.get("gain_across_runs", False) or candidate.get("removes_run_trend", False)
    )


@dataclass
class ModelEvidence:
    """What the decision needs of one fitted model, per segment.

    ``residuals`` are the all-data fit's (:func:`~workflow.models.averaged_fit.model_residuals`); ``heldout`` the
    cross-validation's (:func:`~workflow.discovery.heldout.cross_validate`); ``n_params`` the fitted parameters;
    ``shows_signature`` whether a candidate's fit shows its cause's signature
    (:func:`~workflow.discovery.misfit.stiffness_signature`; true where there is no such check).
    """

    residuals: dict[str, np.ndarray]
    heldout: dict
    n_params: int
    shows_signature: bool = True


def evaluate_decision(
    data: ConfigurationData,
    evidence: Mapping[str, ModelEvidence],
    *,
    envelope_significant: bool,
    extended_models: Mapping[str, str] | None = None,
) -> dict:
    """Held-out errors, BIC, discrepancy tests and the decision on all the data.

    Parameters
    ----------
    data : ConfigurationData
    evidence : mapping
        Model id -> :class:`ModelEvidence`.
    envelope_significant : bool
        :func:`~workflow.discovery.misfit.envelope_structure`'s verdict (not resampled).
    extended_models : mapping, optional
        Cause -> the model that represents it, as candidate and once named, where that is
        not the one of :data:`CAUSE_MODELS` (the recovered threshold distribution,
        :func:`~workflow.discovery.microslip.refine_microslip`).

    Returns
    -------
    dict
        ``cause``, ``reason``, ``baseline`` (model id), ``errors`` and ``bic`` per model,
        ``bins`` and ``trend`` of the baseline, ``baseline_fails``, ``candidates``,
        ``extended_models``, and per unit of held-out evidence (:func:`heldout_units`)
        ``unit_squares`` (per model), ``unit_curve_squares`` (per model, shape (2, U):
        damping, frequency), ``unit_tolerance`` (shape (2, U): the models' accuracy over
        the scale the baseline's held-out residuals are scored in,
        :func:`~workflow.discovery.heldout.heldout_scales`, squared, summed alike) and ``unit_weights``, for the confidence.
    """
    view = data
    n_runs_view = view.n_runs
    any_residuals = next(iter(evidence.values())).residuals
    weights = heldout_weights(view, any_residuals["scatter_ln_zeta"], any_residuals["scatter_rel_f"])
    n_eff = effective_observations(view)
    units = heldout_units(view)
    n_units = int(units.max()) + 1 if units.size else 0
    # the scored segments are the data's (calibration segments are not), the same for every model
    scored = next(iter(evidence.values())).heldout["scored"]

    def per_unit(values: np.ndarray) -> np.ndarray:
        return np.bincount(units[scored], weights=(weights * values)[scored], minlength=n_units)

    unit_weights = per_unit(np.ones(view.n))
    errors, bic, residuals, unit_squares, unit_curve_squares = {}, {}, {}, {}, {}
    for m, ev in evidence.items():
        square = 0.5 * (ev.heldout["squared_zeta"] + ev.heldout["squared_frequency"])
        unit_curve_squares[m] = np.array(
            [per_unit(ev.heldout["squared_zeta"]), per_unit(ev.heldout["squared_frequency"])]
        )
        unit_squares[m] = unit_curve_squares[m].mean(axis=0)
        errors[m] = {
            "error": weighted_rms(square[scored], weights[scored]),
            "error_zeta": weighted_rms(ev.heldout["squared_zeta"][scored], weights[scored]),
            "error_frequency": weighted_rms(ev.heldout["squared_frequency"][scored], weights[scored]),
        }
        res = {
            k: ev.residuals[k]
            for k in (
                "ln_zeta",
                "rel_f",
                "ln_zeta_shared",
                "ln_zeta_calibrated",
                "ln_zeta_slope",
                "calibration",
                "scatter_ln_zeta",
                "scatter_rel_f",
                "z_noise",
                "f_noise",
            )
        }
        residuals[m] = res
        in_sample = weighted_rms(0.5 * (res["z_noise"] ** 2 + res["f_noise"] ** 2), weights) ** 2
        offsets = 2 * (n_runs_view - 1) if n_runs_view >= 2 else 0  # frequency and zeta0 per run
        bic[m] = information_criterion(in_sample, ev.n_params + offsets, n_eff)
    base = min((m for m in BASELINE_MODELS if m in evidence), key=lambda m: errors[m]["error"])
    # the models' accuracy in the units the held-out residuals are scored in (the baseline's)
    unit_tolerance = np.array(
        [
            per_unit((TOL_LN_ZETA / evidence[base].heldout["scale_zeta"]) ** 2),
            per_unit((TOL_REL_F / evidence[base].heldout["scale_frequency"]) ** 2),
        ]
    )
    bins = binned_discrepancy(view, residuals[base])
    trend = run_order_trend(view, residuals[base], n_tests=RUN_ORDER_TESTS)
    baseline_fails = (
        any(b["significant"] for b in bins) or bool(trend and trend["significant"]) or envelope_significant
    )
    candidates = {}
    all_units = np.ones((1, n_units))
    critical_t = paired_critical_value(int(np.count_nonzero(unit_weights > 0)))
    extended_models = {**CAUSE_MODELS, **(extended_models or {})}
    for cause, m in extended_models.items():
        if m not in evidence:
            continue
        gain_t = heldout_gain_t(unit_squares[base], unit_squares[m], unit_weights)
        cb = binned_discrepancy(view, residuals[m])
        ct = run_order_trend(view, residuals[m], n_tests=RUN_ORDER_TESTS)
        candidates[cause] = {
            "model": m,
            "heldout_error": errors[m]["error"],
            "heldout_error_zeta": errors[m]["error_zeta"],
            "heldout_error_frequency": errors[m]["error_frequency"],
            "ratio_to_baseline": errors[m]["error"] / errors[base]["error"],
            "bic": bic[m],
            "delta_bic": bic[m] - bic[base],
            "residual_significant": bool(
                any(b["significant"] for b in cb) or (ct is not None and ct["significant"])
            ),
            "significant_bins": int(sum(b["significant"] for b in cb)),
            "shows_signature": evidence[m].shows_signature,
            "heldout_gain_t": gain_t,
            "gain_across_runs": bool(n_runs_view >= 2 and gain_t > critical_t),
            # the baseline's run-order trend significant, the candidate's not
            "removes_run_trend": bool(
                trend is not None and trend["significant"] and (ct is None or not ct["significant"])
            ),
            "beyond_accuracy": bool(
                beyond_accuracy(unit_curve_squares[base], unit_curve_squares[m], unit_tolerance, all_units)[0]
            ),
        }
    cause, reason = decide(
        errors[base]["error"],
        bic[base],
        baseline_fails,
        candidates,
        envelope_structure=envelope_significant,
        unit_squares={c: unit_squares[v["model"]] for c, v in candidates.items()},
        unit_weights=unit_weights,
    )
    return {
        "cause": cause,
        "reason": reason,
        "baseline": base,
        "errors": errors,
        "bic": bic,
        "n_eff": n_eff,
        "bins": bins,
        "trend": trend,
        "baseline_fails": baseline_fails,
        "ruled_out": departure_ruled_out_by_channels(view, residuals[base], bins),
        "candidates": candidates,
        "extended_models": extended_models,
        "unit_squares": unit_squares,
        "unit_curve_squares": unit_curve_squares,
        "unit_tolerance": unit_tolerance,
        "unit_weights": unit_weights,
    }


def verdict_options(result: Mapping, combinations: Sequence[VerdictOption] = ()) -> list[VerdictOption]:
    """The named verdicts the confidence shares the departure from the baseline among:
    every candidate cause (represented by its extended model), eligible when it pays for
    its parameters (:func:`parsimonious`) and its fit shows its cause's signature, and the
    combinations."""
    base_bic = result["bic"][result["baseline"]]
    options = [
        VerdictOption(
            cause,
            result["extended_models"][cause],
            eligible=bool(parsimonious(cause, v, base_bic) and v["shows_signature"]),
            residual_significant=v["residual_significant"],
        )
        for cause, v in result["candidates"].items()
    ]
    return options + list(combinations)


def confidence_draws(
    result: Mapping,
    options: Sequence[VerdictOption],
    *,
    envelope_significant: bool | np.ndarray,
    n_draws: int,
    seed: int,
) -> tuple[dict[str, float], list[dict]]:
    """The verdict's confidence and its per-draw decisions (:mod:`workflow.discovery.confidence`).

    Parameters
    ----------
    result : mapping
        :func:`evaluate_decision` on all the data (its ``unit_squares``, ``unit_weights``,
        ``n_eff``, ``baseline_fails``).
    options : sequence of VerdictOption
        :func:`verdict_options`.
    envelope_significant : bool or ndarray of bool, shape (n_draws,)
        :func:`~workflow.discovery.misfit.envelope_structure`'s verdict, or its verdict per
        draw (:func:`~workflow.discovery.misfit.envelope_structure_draws`).
    n_draws, seed : int
        Bayesian-bootstrap reweightings of the units, and their random seed.

    Returns
    -------
    confidence : dict
        Verdict key -> mean probability over the draws (sums to 1, largest first).
    draws : list of dict
        Per draw: ``probabilities`` (verdict key -> probability) and ``ratio`` (the
        probability-weighted gain ratio); the campaign's confidence combines the
        configurations' draws.
    """
    rng = np.random.default_rng(seed)
    evidence = HeldoutEvidence(
        result["unit_curve_squares"], result["unit_tolerance"], result["unit_weights"], result["n_eff"]
    )
    weights = dirichlet_unit_weights(n_draws, evidence.unit_weights.size, rng)
    probabilities, ratio = soft_decisions(
        evidence,
        [m for m in BASELINE_MODELS if m in result["errors"]],
        options,
        baseline_fails=failure_draws(result["bins"], result["trend"], weights),
        envelope_structure=envelope_significant,
        clear_gain=CLEAR_GAIN,
        residual_gain=RESIDUAL_GAIN,
        draws=weights,
    )
    unseen(probabilities, options, result["ruled_out"])
    keys = list(probabilities)
    table = np.array([probabilities[k] for k in keys]).T
    draws = [
        {"ratio": float(r), "probabilities": {k: float(v) for k, v in zip(keys, row) if v > 0}}
        for row, r in zip(table, ratio)
    ]
    return mean_probabilities(probabilities), draws


def extended_model_of(result: Mapping) -> str:
    """Model id that represents the decision's cause (the baseline for ``none``; for
    ``unknown`` the candidate with the lowest held-out error)."""
    cause, candidates = result["cause"], result["candidates"]
    if cause == "none" or (cause == "unknown" and not candidates):
        return result["baseline"]
    if cause == "unknown":
        return candidates[min(candidates, key=lambda c: candidates[c]["heldout_error"])]["model"]
    return result["extended_models"][cause]


def cause_fractions(causes: Sequence[str]) -> dict[str, float]:
    """Fraction of ``causes`` naming each cause, largest first (sums to 1).

    Examples
    --------
    >>> cause_fractions(["none", "run_drift", "none", "none"])
    {'none': 0.75, 'run_drift': 0.25}
    """
    if not causes:
        return {}
    names, counts = np.unique(np.asarray(causes, dtype=object), return_counts=True)
    order = np.argsort(-counts, kind="stable")
    return {str(names[i]): float(counts[i] / len(causes)) for i in order}

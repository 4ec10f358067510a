"""Two mechanisms at once: a micro-slip joint with a velocity-squared loss or a stiffness term.

Real joints often show two mechanisms (micro-slip with a stiffness term, micro-slip with a
velocity-squared loss). The combined models (:data:`workflow.models.averaged.COMBINED_MODELS`)
are fitted from both single fits (the micro-slip fit with the extension switched off, and
the micro-slip joint with the single extension fit's term), and a combination is named
only when it passes :func:`combination_test`: it predicts held-out data better than each
of its parts, run by run, by more than their scatter (:func:`combination_test`), and each
mechanism removes at least :data:`MIN_REMOVED_SHARE` of what the other leaves.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from workflow.discovery.heldout import heldout_standard_error
from workflow.models.averaged import COMBINED_MODELS, MODELS
from workflow.models.averaged_fit import FitResult
from workflow.models.configuration_data import Scatter

__all__ = [
    "EXTENSION_CAUSES",
    "combination_parts",
    "combination_causes",
    "PAIRED_FALSE_ALARM",
    "paired_critical_value",
    "paired_t",
    "squared_error_log_ratio",
    "reweighted_combination_test",
    "MIN_REMOVED_SHARE",
    "combinations_to_try",
    "combination_starts",
    "combination_test",
    "UNTOUCHED_CURVE",
    "one_curve_scatter",
    "term_from_residuals",
]

EXTENSION_CAUSES: dict[str, str] = {
    "dahl_quadratic": "quadratic_damping",
    "dahl_stiffness": "stiffness_nonlinearity",
}
"""Extension model -> the cause its term stands for, beside micro-slip in a combination."""

PAIRED_FALSE_ALARM = 0.025
"""One-sided false-alarm rate of each part's paired test (:func:`paired_critical_value`)
when the added mechanism does nothing and the units of evidence are independent."""


def paired_critical_value(n_units: int, false_alarm: float = PAIRED_FALSE_ALARM) -> float:
    """The t a combination's paired test over the units must exceed for each part: Student's
    t quantile ``1 - false_alarm`` with ``n_units - 1`` degrees of freedom.

    The standard error is estimated from the same few units (8 runs, or 5-7 amplitude
    blocks of one run), so a fixed 2 would let a mechanism that does nothing through 4.3 %
    of the time with 8 units, 6 % with 5, instead of 2.5 %.

    >>> round(paired_critical_value(8), 2), round(paired_critical_value(5), 2)
    (2.36, 2.78)
    """
    # stdtrit is what scipy.stats.t.ppf calls (importing scipy.stats would cost every job
    # that imports the discovery 0.25 s); imported here, as the jobs that only assemble or
    # draw the diagnosis never call this
    from scipy import special

    return float(special.stdtrit(max(n_units - 1, 1), 1.0 - false_alarm))


MIN_REMOVED_SHARE = 0.2
"""Each mechanism of a named combination removes at least this share of the squared
held-out error the other mechanism alone leaves (:func:`combination_test`): a second
mechanism that only polishes the first's fit is not a second cause. Measured against what
the other leaves, not against the gain over the baseline: where the baseline is far off
(a clean record, a large effect) a second mechanism that takes the error the first leaves
from 36 scatter units to 1.3 is a small share of the gain and still the whole of what is
left."""


def combination_parts(model: str) -> tuple[str, str]:
    """A combined model's two parts: (its micro-slip joint model, its extension model)."""
    return next(parts for parts, name in COMBINED_MODELS.items() if name == model)


def combination_causes(model: str) -> tuple[str, str]:
    """A combined model's two causes, micro-slip first."""
    return ("microslip_power_law", EXTENSION_CAUSES[combination_parts(model)[1]])


def combinations_to_try(cause: str, joint_model: str, departs: bool = True) -> list[str]:
    """The combined models worth fitting after a single-cause decision, on the micro-slip
    joint ``joint_model`` (``iwan_cells_<n>``, the slip thresholds from the data): every one
    after a cause of the joint's physics (micro-slip, quadratic damping, stiffness: two
    mechanisms at once are often called by a third, the single candidate that mimics their
    sum best) or after ``unknown``; after ``none`` where the data depart from the baseline
    without a single cause being named (``departs``: the baseline does not explain the
    data, or a single cause's candidate removes more held-out misfit than the models'
    accuracy): micro-slip with a hardening spring that cancels its softening leaves each
    mechanism alone part of the curves; none after ``run_drift``."""
    if cause == "run_drift" or (cause == "none" and not departs):
        return []
    return [COMBINED_MODELS[(joint_model, extension)] for extension in EXTENSION_CAUSES]


def combination_starts(
    model: str, fits: Mapping[str, FitResult], extension_off: Mapping[str, float]
) -> list[dict[str, float]]:
    """Starts of a combined model from both single fits.

    The joint's fit with the extension switched off (``extension_off``, values that make
    the term vanish) reproduces the joint model exactly, so the combination never fits
    worse than it; the joint's fit with the single extension fit's term added starts
    where the extension's fit put the term.
    """
    joint_model, extension_model = combination_parts(model)
    joint, extension = fits[joint_model].params, fits[extension_model].params
    added = [p.name for p in MODELS[model].params if p.name not in MODELS[joint_model].param_names]
    return [{**joint, **extension_off}, {**joint, **{name: extension[name] for name in added}}]


UNTOUCHED_CURVE: dict[str, str] = {"dahl_stiffness": "zeta", "dahl_quadratic": "frequency"}
"""Extension model -> the curve its term leaves alone: a stiffness term dissipates nothing
(the damping is the joint's), a velocity-squared loss stores nothing (the frequency is the
joint's)."""

STIFFNESS_EXPONENTS = (0.5, 1.0, 2.0, 4.0)
"""Exponents tried when a stiffness term is read off a frequency residual: the fit range's
edges (``stiffness_exponent`` in [0.5, 4]) and the quadratic and cubic springs between."""

IGNORED_CURVE_SCALE = 1e6
"""Factor on the uncertainty of a curve a fit is to ignore (:func:`one_curve_scatter`)."""


def one_curve_scatter(scatter: Scatter, curve: str) -> Scatter:
    """``scatter`` with the other curve's uncertainties made so large that a fit weighted
    by it follows ``curve`` (``"zeta"`` or ``"frequency"``) alone."""
    if curve == "zeta":
        return replace(scatter, rel_f=scatter.rel_f * IGNORED_CURVE_SCALE)
    return replace(scatter, ln_zeta=scatter.ln_zeta * IGNORED_CURVE_SCALE)


def term_from_residuals(
    extension_model: str,
    velocity_in_s: np.ndarray,
    residuals: Mapping[str, np.ndarray],
    scatter: Scatter,
    reference_velocity_in_s: float,
) -> dict[str, float] | None:
    """The extension's term that a joint fitted to the other curve leaves to explain.

    A velocity-squared loss adds ``q V`` to the damping ratio: ``q`` is the weighted
    least-squares slope of the damping the joint leaves (``zeta - zeta_model``) on ``V``.
    A stiffness term ``stiffness_shift (V / V_ref)^p`` changes ``omega^2``, so the
    relative frequency by half of it: for each of :data:`STIFFNESS_EXPONENTS` the shift
    is the weighted least-squares fit of the frequency residual, and the exponent the one
    that leaves the least. None where the loss would have to be negative.

    Parameters
    ----------
    extension_model : str
        ``dahl_quadratic`` or ``dahl_stiffness``.
    velocity_in_s : ndarray
        The segments' velocity amplitudes, in/s.
    residuals : mapping
        :func:`~workflow.models.averaged_fit.model_residuals` of the joint's fit.
    scatter : Scatter
        The segments' uncertainties (weights).
    reference_velocity_in_s : float
        The stiffness term's reference velocity amplitude, in/s.

    Examples
    --------
    >>> from workflow.models.configuration_data import Scatter
    >>> v = np.geomspace(0.1, 3.0, 30)
    >>> ones = np.ones(v.size)
    >>> s = Scatter(0.01 * ones, 1e-5 * ones, 0.01 * ones, 1e-5 * ones)
    >>> term = term_from_residuals("dahl_stiffness", v, {"rel_f": 0.002 * v**2}, s, 1.0)
    >>> {k: round(x, 6) for k, x in term.items()}
    {'stiffness_shift': 0.004, 'stiffness_exponent': 2.0}
    """
    if extension_model == "dahl_quadratic":
        zeta_model = residuals["zeta_model"]
        excess = zeta_model * np.expm1(residuals["ln_zeta"])
        weight = 1.0 / (zeta_model * scatter.ln_zeta) ** 2
        slope = float(np.sum(weight * velocity_in_s * excess) / np.sum(weight * velocity_in_s**2))
        return {"quadratic_zeta_per_in_s": slope} if slope > 0 else None
    weight = 1.0 / scatter.rel_f**2
    best = None
    for exponent in STIFFNESS_EXPONENTS:
        shape = 0.5 * (velocity_in_s / reference_velocity_in_s) ** exponent
        shift = float(np.sum(weight * shape * residuals["rel_f"]) / np.sum(weight * shape**2))
        left = float(np.sum(weight * (residuals["rel_f"] - shift * shape) ** 2))
        if best is None or left < best[0]:
            best = (left, {"stiffness_shift": shift, "stiffness_exponent": exponent})
    return best[1]


def squared_error_log_ratio(worse_squares: np.ndarray, better_squares: np.ndarray) -> np.ndarray:
    """Per unit of evidence, ``ln(worse / better)`` of two models' squared held-out errors
    (both floored at the smallest positive double): the scale-free comparison that
    :func:`paired_t` tests.

    >>> squared_error_log_ratio(np.array([np.e, 0.0]), np.array([1.0, 0.0])).tolist()
    [1.0, 0.0]
    """
    floor = np.finfo(float).tiny
    return np.log(np.maximum(worse_squares, floor) / np.maximum(better_squares, floor))


def paired_t(values: np.ndarray, draws: np.ndarray | None = None) -> np.ndarray:
    """Student's t of the weighted mean of paired values against 0, per row of unit weights.

    Parameters
    ----------
    values : ndarray, shape (U,)
        One value per unit of evidence (e.g. a run's log ratio of two squared errors).
    draws : ndarray, shape (B, U), optional
        Unit weights (e.g. Bayesian-bootstrap ones), each row scaled to sum to U; default
        one row of ones (the data as it is).

    Returns
    -------
    ndarray, shape (B,)
        Weighted mean over its weighted standard error; ``inf`` (``-inf``) where the values
        do not scatter and their mean is positive (negative), 0 with fewer than two units.

    Examples
    --------
    >>> round(float(paired_t(np.array([1.0, 2.0, 3.0]))[0]), 3)
    3.464
    """
    n = values.size
    a = np.ones((1, n)) if draws is None else draws
    a = a * (n / np.maximum(a.sum(axis=1, keepdims=True), np.finfo(float).tiny))
    mean = (a @ values) / max(n, 1)
    spread = np.sqrt(np.sum(a * (values[None, :] - mean[:, None]) ** 2, axis=1) / max(n - 1, 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(spread > 0, mean / (spread / np.sqrt(max(n, 1))), np.copysign(np.inf, mean))
    return np.where((n < 2) | ((spread == 0) & (mean == 0)), 0.0, t)


def reweighted_combination_test(
    combined_squares: np.ndarray,
    part_squares: Mapping[str, np.ndarray],
    unit_weights: np.ndarray,
    draws: np.ndarray,
    *,
    critical_t: float | None = None,
    min_removed: float = MIN_REMOVED_SHARE,
) -> dict:
    """The statistics of :func:`combination_test` on reweightings of the units of evidence.

    Per row of ``draws`` (unit weights, e.g. Bayesian-bootstrap ones; a row of ones is the
    data): each part's paired t of the units' log ratios of its squared held-out error to
    the combination's (weighted mean over its weighted standard error, as
    :func:`workflow.discovery.misfit.failure_draws` re-takes the baseline's tests), the
    share of what the other part alone leaves that each mechanism removes (reweighted
    squared errors), and whether both pass. A combination whose test sits at its limit
    passes in about half of the reweightings.

    Parameters
    ----------
    combined_squares, part_squares, unit_weights, critical_t, min_removed
        As :func:`combination_test`.
    draws : ndarray, shape (B, U)
        Unit weights.

    Returns
    -------
    dict
        ``log_ratio_t`` and ``removed`` (cause -> array (B,)) and ``named`` (array (B,) of
        bool). A t is ``inf`` (``-inf``) where the log ratios do not scatter and their mean
        is positive (negative), 0 with fewer than two units.

    Examples
    --------
    >>> combined = np.ones(3)
    >>> parts = {"a": np.exp([1.0, 2.0, 3.0]), "b": np.full(3, 2.0)}
    >>> test = reweighted_combination_test(combined, parts, np.ones(3), np.ones((1, 3)), critical_t=4.0)
    >>> round(float(test["log_ratio_t"]["b"][0]), 3), bool(test["named"][0])
    (3.464, False)
    """
    causes = list(part_squares)
    present = unit_weights > 0
    n = int(np.count_nonzero(present))
    if critical_t is None:
        critical_t = paired_critical_value(n)
    a = draws[:, present]
    a = a * (n / np.maximum(a.sum(axis=1, keepdims=True), np.finfo(float).tiny))
    total = a @ unit_weights[present]
    combined = (a @ combined_squares[present]) / total
    floor = np.finfo(float).tiny
    removed, log_t = {}, {}
    for cause, other in ((causes[0], causes[1]), (causes[1], causes[0])):
        other_squares = part_squares[other][present]
        other_alone = (a @ other_squares) / total
        removed[cause] = np.where(
            other_alone > 0, np.maximum(other_alone - combined, 0.0) / np.maximum(other_alone, floor), 0.0
        )
        log_t[cause] = paired_t(squared_error_log_ratio(other_squares, combined_squares[present]), a)
    named = np.logical_and.reduce([(log_t[c] > critical_t) & (removed[c] >= min_removed) for c in causes])
    return {"log_ratio_t": log_t, "removed": removed, "named": named, "critical_t": critical_t}


def combination_test(
    combined_squares: np.ndarray,
    part_squares: Mapping[str, np.ndarray],
    baseline_squares: np.ndarray,
    unit_weights: np.ndarray,
    *,
    critical_t: float | None = None,
    min_removed: float = MIN_REMOVED_SHARE,
) -> dict:
    """Whether two mechanisms together predict held-out data better than either alone.

    Each part is compared with the combination unit by unit (run; with one run, half
    decade of amplitude): the log of the ratio of the part's squared held-out error in
    the unit to the combination's, a paired t test over the units that it is above 0.
    A unit's squared error scales with its own level (a run hit harder, a noisier
    record), and so does a difference of two of them: a paired test of the differences
    is dominated by the runs with the largest errors, and a mechanism that divides every
    run's error by 16 reads as 2 standard errors when one run's share of it is large. The
    log ratio is the scale-free comparison (variance-stabilising for quantities on a
    ratio scale): how consistently, against its scatter over the units, the combination
    predicts better.

    Parameters
    ----------
    combined_squares : ndarray, shape (U,)
        The combined model's amplitude-weighted squared held-out residuals summed per
        unit of evidence (run; with one run, held-out amplitude block).
    part_squares : mapping
        Each of the two causes -> the same sums of the model of that cause alone.
    baseline_squares : ndarray, shape (U,)
        The same sums of the baseline.
    unit_weights : ndarray, shape (U,)
        The units' summed weights (``E^2 = sum S / sum W``).
    critical_t : float, optional
        The t each part's paired test must exceed; default :func:`paired_critical_value`
        of the units that carry weight.

    Returns
    -------
    dict
        ``contributions`` (cause -> what the cause adds to the other alone: the other's
        squared held-out error minus the combination's), ``standard_errors`` (of those
        paired differences over the units), ``log_ratio_t`` (the paired t of the units'
        log ratios of the other's squared error to the combination's), ``shares`` (each
        contribution over the combination's gain, the baseline's squared held-out error
        minus its own; the largest first is the order of ``causes``), ``removed`` (each
        contribution over the other part alone's squared held-out error: the share of what
        the other leaves that this mechanism removes), ``named`` (each ``log_ratio_t``
        above ``critical_t`` and each ``removed`` at least ``min_removed``) and ``rule``.
        A share may exceed 1 where the other part alone predicts worse than the baseline.

    Examples
    --------
    >>> w = np.ones(6)
    >>> combined = np.full(6, 1.0) + 0.05 * np.sin(np.arange(6))
    >>> parts = {"a": np.full(6, 3.0) + 0.1 * np.arange(6), "b": np.full(6, 2.0)}
    >>> result = combination_test(combined, parts, np.full(6, 4.0), w)
    >>> result["named"], result["causes"]
    (True, ['b', 'a'])
    """
    causes = list(part_squares)
    test = reweighted_combination_test(
        combined_squares,
        part_squares,
        unit_weights,
        np.ones((1, unit_weights.size)),
        critical_t=critical_t,
        min_removed=min_removed,
    )
    critical_t = test["critical_t"]
    total = float(np.sum(unit_weights))
    combined = float(np.sum(combined_squares)) / total
    contributions, errors = {}, {}
    for cause, other in ((causes[0], causes[1]), (causes[1], causes[0])):
        contributions[cause] = float(np.sum(part_squares[other])) / total - combined
        errors[cause] = heldout_standard_error(part_squares[other] - combined_squares, unit_weights)
    removed = {c: float(test["removed"][c][0]) for c in causes}
    log_t = {c: float(test["log_ratio_t"][c][0]) for c in causes}
    gain = float(np.sum(baseline_squares)) / total - combined
    shares = {c: (max(v, 0.0) / gain if gain > 0 else 0.0) for c, v in contributions.items()}
    named = bool(test["named"][0])
    return {
        "contributions": contributions,
        "standard_errors": errors,
        "shares": shares,
        "removed": removed,
        "log_ratio_t": log_t,
        "causes": sorted(causes, key=lambda c: -contributions[c]),
        "named": bool(named),
        "rule": (
            f"named when it predicts held-out data better than each part alone, unit by unit of "
            f"evidence, by more than their scatter (paired t of the log ratio of squared held-out "
            f"errors above {critical_t:.3g}: one-sided {PAIRED_FALSE_ALARM:g} false alarms per part) and each "
            f"mechanism removes at least {min_removed:g} of the squared held-out error the other alone leaves"
        ),
    }

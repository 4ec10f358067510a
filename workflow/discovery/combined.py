"""Two mechanisms at once: a micro-slip joint with a velocity-squared loss or a stiffness term.

Real joints often show two mechanisms (micro-slip with a stiffness term, micro-slip with a
velocity-squared loss). The combined models (:data:`workflow.models.averaged.COMBINED_MODELS`)
are fitted from both single fits (the micro-slip fit with the extension switched off, and
the micro-slip joint with the single extension fit's term), and a combination is named
only when it passes :func:`combination_test`: it predicts held-out data better than each
of its parts by more than :data:`PAIRED_STANDARD_ERRORS` paired standard errors, and each
mechanism carries at least :data:`MIN_GAIN_SHARE` of its gain over the baseline.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from workflow.discovery.heldout import heldout_standard_error
from workflow.models.averaged import COMBINED_MODELS, MODELS
from workflow.models.averaged_fit import FitResult

__all__ = [
    "COMBINATION_CAUSES",
    "PAIRED_STANDARD_ERRORS",
    "MIN_GAIN_SHARE",
    "combinations_to_try",
    "combination_starts",
    "combination_test",
]

COMBINATION_CAUSES: dict[str, tuple[str, str]] = {
    "iwan_quadratic": ("microslip_power_law", "quadratic_damping"),
    "iwan_stiffness": ("microslip_power_law", "stiffness_nonlinearity"),
}
"""Combined model -> its two causes (the joint's first)."""

PAIRED_STANDARD_ERRORS = 2.0
"""A combination must predict held-out data better than each of its parts by more than
this many standard errors of the paired difference of their squared held-out errors
over the units of evidence (runs): about a 2.5 % one-sided false-alarm rate per part
when the added mechanism does nothing and the units are independent."""

MIN_GAIN_SHARE = 0.2
"""Each mechanism of a named combination carries at least this share of the combination's
gain over the baseline, measured as what it adds to the other mechanism alone
(:func:`combination_test`): a second mechanism that only polishes the first's fit is not a
second cause."""


def combinations_to_try(cause: str) -> list[str]:
    """The combined models worth fitting after a single-cause decision: every one after a
    cause of the joint's physics (micro-slip, quadratic damping, stiffness: two mechanisms
    at once are often called by a third, the single candidate that mimics their sum best)
    or after ``unknown``; none after ``none`` or ``run_drift``."""
    if cause in ("none", "run_drift"):
        return []
    return list(COMBINATION_CAUSES)


def combination_starts(
    model: str, fits: Mapping[str, FitResult], extension_off: Mapping[str, float]
) -> list[dict[str, float]]:
    """Starts of a combined model from both single fits.

    The joint's fit with the extension switched off (``extension_off``, values that make
    the term vanish) reproduces the joint model exactly, so the combination never fits
    worse than it; the joint's fit with the single extension fit's term added starts
    where the extension's fit put the term.
    """
    joint_model, extension_model = next(parts for parts, name in COMBINED_MODELS.items() if name == model)
    joint, extension = fits[joint_model].params, fits[extension_model].params
    added = [p.name for p in MODELS[model].params if p.name not in MODELS[joint_model].param_names]
    return [{**joint, **extension_off}, {**joint, **{name: extension[name] for name in added}}]


def combination_test(
    combined_squares: np.ndarray,
    part_squares: Mapping[str, np.ndarray],
    baseline_squares: np.ndarray,
    unit_weights: np.ndarray,
    *,
    paired_standard_errors: float = PAIRED_STANDARD_ERRORS,
    min_share: float = MIN_GAIN_SHARE,
) -> dict:
    """Whether two mechanisms together predict held-out data better than either alone.

    Parameters
    ----------
    combined_squares : ndarray, shape (U,)
        The combined model's amplitude-weighted squared held-out residuals summed per
        unit of evidence (run; with one run, half decade of amplitude).
    part_squares : mapping
        Each of the two causes -> the same sums of the model of that cause alone.
    baseline_squares : ndarray, shape (U,)
        The same sums of the baseline.
    unit_weights : ndarray, shape (U,)
        The units' summed weights (``E^2 = sum S / sum W``).

    Returns
    -------
    dict
        ``contributions`` (cause -> what the cause adds to the other alone: the other's
        squared held-out error minus the combination's), ``standard_errors`` (of those
        paired differences over the units), ``shares`` (each contribution over the
        combination's gain, the baseline's squared held-out error minus its own),
        ``causes`` (largest contribution first), ``named`` (both contributions
        above ``paired_standard_errors`` standard errors and each share at least
        ``min_share``) and ``rule``. A share may exceed 1 where the other part alone predicts
    worse than the baseline.

    Examples
    --------
    >>> w = np.ones(6)
    >>> combined = np.full(6, 1.0)
    >>> parts = {"a": np.full(6, 3.0) + 0.1 * np.arange(6), "b": np.full(6, 2.0)}
    >>> result = combination_test(combined, parts, np.full(6, 4.0), w)
    >>> result["named"], result["causes"]
    (True, ['b', 'a'])
    """
    causes = list(part_squares)
    total = float(np.sum(unit_weights))
    combined = float(np.sum(combined_squares)) / total
    contributions, errors = {}, {}
    for cause, other in ((causes[0], causes[1]), (causes[1], causes[0])):
        difference = part_squares[other] - combined_squares
        contributions[cause] = float(np.sum(part_squares[other])) / total - combined
        errors[cause] = heldout_standard_error(difference, unit_weights)
    gain = float(np.sum(baseline_squares)) / total - combined
    shares = {c: (max(v, 0.0) / gain if gain > 0 else 0.0) for c, v in contributions.items()}
    named = all(
        contributions[c] > paired_standard_errors * errors[c] and shares[c] >= min_share for c in causes
    )
    return {
        "contributions": contributions,
        "standard_errors": errors,
        "shares": shares,
        "causes": sorted(causes, key=lambda c: -contributions[c]),
        "named": bool(named),
        "rule": (
            f"named when it predicts held-out data better than each part alone by more than "
            f"{paired_standard_errors:g} paired standard errors over the units of evidence and each "
            f"mechanism carries at least {min_share:g} of the combination's gain over the baseline"
        ),
    }

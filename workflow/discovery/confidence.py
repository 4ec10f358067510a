"""Calibrated confidence of a verdict: how sure the held-out evidence lets one be.

The verdict (:func:`workflow.discovery.decision.decide`) is one decision on all the data.
Its confidence carries the two uncertainties behind it:

* **Is there a departure from the baseline at all?** The decision's gate (a significant
  baseline misfit, or a candidate predicting held-out data better than ``CLEAR_GAIN`` of
  the baseline's error or removing more held-out misfit than the models' accuracy,
  :func:`beyond_accuracy`) is re-taken on Bayesian-bootstrap reweightings of the
  independent units of held-out evidence (runs; with one run, its held-out amplitude
  blocks): every unit keeps a Dirichlet(1, ..., 1) weight, so no unit is ever left out (a
  multinomial resample of five amplitude blocks leaves the top one out in a third of
  the draws). The accuracy margin carries the data's power: where the scatter is many
  times the models' accuracy, a small gain passes it in the reweightings that show it, so
  a scatter too large to show an effect does not make ``none`` sure.
* **Could these data show a departure?** ``none`` is right only as far as the data rule
  out a mechanism beyond the models' accuracy
  (:func:`workflow.discovery.misfit.departure_ruled_out`, from the baseline's binned
  residuals); the rest of its probability is spread evenly over ``none`` and the single
  causes (:func:`unseen`): a sensor near a node may see nothing, never be sure of nothing.
* **Are these single-mode decays?** The envelope test is re-taken on reweightings of each
  run's segments (:func:`workflow.discovery.misfit.envelope_structure_draws`); the draws
  in which it fails are ``unknown``.
* **Which mechanism?** Within each reweighting the candidates share the departure by
  pseudo-BMA+ weights (Yao et al. 2018): the held-out log predictive density of each
  candidate, a Gaussian with the candidate's own discrepancy variance (its squared
  held-out error, in scatter units), over the configuration's effective number of
  independent observations ``n_eff`` (:func:`workflow.discovery.heldout.effective_observations`):
  ``elpd = -n_eff / 2 (ln E^2 + 1)``. Candidates whose held-out errors differ by less
  than their scatter over the units share the confidence; one that leads in every
  reweighting takes it.

Several channels (sensors) of one hit are pooled before this point into one
configuration's data (:mod:`workflow.discovery.joint`: each channel in its own scatter
units, the runs shared), so their evidence reaches the confidence as one
:class:`HeldoutEvidence` whose units and ``n_eff`` are the runs and cells of the hit, not
one per sensor: nothing is voted or multiplied across sensors, and a duplicated sensor
adds no evidence.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from workflow.discovery.combined import reweighted_combination_test

__all__ = [
    "HeldoutEvidence",
    "VerdictOption",
    "verdict_key",
    "verdict_causes",
    "dirichlet_unit_weights",
    "log_density",
    "beyond_accuracy",
    "combination_passes",
    "soft_decisions",
    "unseen",
    "mean_probabilities",
]

CAUSE_ORDER = ("microslip_power_law", "quadratic_damping", "stiffness_nonlinearity", "run_drift")
"""Canonical order of the causes inside a combination's key."""


def verdict_key(causes: Sequence[str]) -> str:
    """The ``confidence`` key of a verdict: its cause, or a combination's causes joined by
    ``+`` in the vocabulary's order (the same key whichever carries more of the gain).

    Examples
    --------
    >>> verdict_key(["quadratic_damping", "microslip_power_law"])
    'microslip_power_law+quadratic_damping'
    >>> verdict_key(["none"])
    'none'
    """
    rank = {c: i for i, c in enumerate(CAUSE_ORDER)}
    return "+".join(sorted(causes, key=lambda c: (rank.get(c, len(rank)), c)))


def verdict_causes(key: str) -> list[str]:
    """The causes of a ``confidence`` key (:func:`verdict_key`)."""
    return key.split("+")


@dataclass(frozen=True)
class HeldoutEvidence:
    """A configuration's held-out evidence, summed over its independent units (runs; with
    one run, its held-out amplitude blocks). Pooled channels of one hit are one evidence:
    the units are the hit's runs, every channel's residuals in its own scatter.

    Attributes
    ----------
    unit_curve_squares : mapping
        Model id -> array (2, U): per curve (damping, frequency), the unit's
        amplitude-weighted squared held-out residuals over the measured scatter, summed
        over its scored segments.
    unit_tolerance : ndarray, shape (2, U)
        The same sums of the models' accuracy over the measured scatter, squared
        (``(TOL_LN_ZETA / scatter)^2``, ``(TOL_REL_F / scatter)^2``).
    unit_weights : ndarray, shape (U,)
        The units' summed amplitude weights (``E^2 = sum S / sum W``).
    effective_observations : int
        Independent observations (2 x occupied run x half-decade cells).
    """

    unit_curve_squares: Mapping[str, np.ndarray]
    unit_tolerance: np.ndarray
    unit_weights: np.ndarray
    effective_observations: int


@dataclass(frozen=True)
class VerdictOption:
    """A verdict other than ``none``/``unknown`` that the evidence may name.

    Attributes
    ----------
    key : str
        Its ``confidence`` key (:func:`verdict_key`).
    model : str
        The model that represents it (the extended model once named).
    eligible : bool
        Whether the rule lets it be named at all (BIC below the baseline's, its cause's
        signature, for a combination the parsimony rule), decided on all the data.
    residual_significant : bool
        Whether it leaves a significant binned misfit (then it needs a clear gain).
    parts : mapping
        For a combination, each cause -> the model of that cause alone (its micro-slip
        joint, its extension): its parsimony test
        (:func:`workflow.discovery.combined.reweighted_combination_test`) is re-taken on
        every reweighting, and ``eligible`` is then the rest of the rule (BIC, signatures).
    """

    key: str
    model: str
    eligible: bool = True
    residual_significant: bool = False
    parts: Mapping[str, str] = field(default_factory=dict)


def dirichlet_unit_weights(n_draws: int, n_units: int, rng: np.random.Generator) -> np.ndarray:
    """Bayesian-bootstrap weights of the units, shape (n_draws, n_units), rows summing to
    the number of units (scaled so that the all-ones row is the data).

    The weights are Dirichlet with concentration ``alpha = (n - 2) / n`` for ``n`` units
    (at least ``1 / n``): a reweighted mean of the units' values then varies by
    ``sum (x - mean)^2 / (n (n - 1))``, the squared standard error the held-out tests
    take (:func:`workflow.discovery.heldout.heldout_standard_error`). The flat Dirichlet
    (``alpha = 1``) gives ``(n - 1) / (n + 1)`` of it: a fifth too narrow a spread of the
    held-out errors over eight runs, a third over five amplitude blocks of one hit.
    """
    n = max(n_units, 1)
    alpha = max(n - 2, 1) / n if n >= 2 else 1.0
    return rng.dirichlet(np.full(n, alpha), size=n_draws) * n


def log_density(
    evidence: HeldoutEvidence, models: Sequence[str], draws: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Held-out log predictive density of each model under each reweighting of the units.

    Parameters
    ----------
    evidence : HeldoutEvidence
    models : sequence of str
    draws : ndarray, shape (B, U)
        Unit weights (:func:`dirichlet_unit_weights`).

    Returns
    -------
    elpd : ndarray, shape (M, B)
        ``-n_eff / 2 (ln E^2 + 1)`` with ``E^2`` the reweighted squared held-out error,
        both curves (the Gaussian's discrepancy variance fitted per model).
    error : ndarray, shape (M, B)
        The held-out error ``E``.
    """
    weight = np.maximum(draws @ evidence.unit_weights, 1e-300)
    squared = np.array([(draws @ evidence.unit_curve_squares[m].mean(axis=0)) / weight for m in models])
    n = evidence.effective_observations
    elpd = -0.5 * n * (np.log(np.maximum(squared, 1e-300)) + 1.0)
    return elpd, np.sqrt(squared)


def beyond_accuracy(
    base_curve_squares: np.ndarray,
    option_curve_squares: np.ndarray,
    unit_tolerance: np.ndarray,
    draws: np.ndarray,
) -> np.ndarray:
    """Whether an option removes more held-out misfit than the models' accuracy, per
    reweighting of the units.

    On either curve, the baseline's squared held-out error minus the option's (both over
    the scale held-out residuals are scored in: the measured scatter and a held-out run's
    offset uncertainty, :func:`~workflow.discovery.heldout.heldout_scales`) exceeds the
    squared accuracy of the averaged models over the same scale (``TOL_LN_ZETA``,
    ``TOL_REL_F``), amplitude weighted alike: what the option
    explains is more than a misfit of the models' own accuracy at every amplitude could be.
    This margin scales with the data: where the scatter is large (a sensor near a node)
    an effect several times the accuracy moves the held-out error by a few percent, far
    less than ``CLEAR_GAIN`` asks, and this is what shows it; where the scatter is small
    the accuracy is many scatters and the relative margin decides.

    Parameters
    ----------
    base_curve_squares, option_curve_squares : ndarray, shape (2, U)
        :attr:`HeldoutEvidence.unit_curve_squares` of the baseline and of the option.
    unit_tolerance : ndarray, shape (2, U)
        :attr:`HeldoutEvidence.unit_tolerance`.
    draws : ndarray, shape (B, U)

    Returns
    -------
    ndarray of bool, shape (B,)

    Examples
    --------
    A damping misfit of twice the accuracy removed, on two units:

    >>> tolerance = np.ones((2, 2))
    >>> base, option = np.array([[5.0, 5.0], [1.0, 1.0]]), np.array([[1.0, 1.0], [1.0, 1.0]])
    >>> beyond_accuracy(base, option, tolerance, np.ones((1, 2))).tolist()
    [True]
    >>> beyond_accuracy(base, base - 0.5, tolerance, np.ones((1, 2))).tolist()
    [False]
    """
    removed = draws @ (base_curve_squares - option_curve_squares).T
    return np.any(removed > draws @ unit_tolerance.T, axis=1)


def soft_decisions(
    evidence: HeldoutEvidence,
    baselines: Sequence[str],
    options: Sequence[VerdictOption],
    *,
    baseline_fails: bool | np.ndarray,
    envelope_structure: bool | np.ndarray,
    clear_gain: float,
    residual_gain: float,
    draws: np.ndarray,
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The decision's probabilities on every reweighting of the units.

    Per reweighting ``b``: the baseline is the better of ``baselines``; the options that
    are eligible and predict better than it share the departure by their pseudo-BMA+
    weights (softmax of ``elpd``); the departure is certain when the baseline fails its
    misfit tests (``baseline_fails``: one verdict, or one per reweighting,
    :func:`workflow.discovery.misfit.failure_draws`), else it happens when an option
    predicts clearly better: its error below ``clear_gain`` of the baseline's, or what it
    removes beyond the models' accuracy (:func:`beyond_accuracy`). An option that leaves a
    significant misfit and does not reach ``residual_gain`` passes its share to
    ``unknown``. Not single-mode decays (``envelope_structure``: one verdict, or one per
    draw, :func:`~workflow.discovery.misfit.envelope_structure_draws`): ``unknown``. The same rule as
    :func:`workflow.discovery.decision.decide`, with the tie-break by BIC replaced by the
    weights.

    Returns
    -------
    probabilities : dict
        ``none``, ``unknown`` and every option's key -> array (B,), summing to 1 per draw.
    ratio : ndarray, shape (B,)
        Per draw, the probability-weighted gain ratio: 1 for ``none``, an option's
        error over the baseline's for the option, the lowest of every option's for
        ``unknown`` (its extended model is the best candidate tried).
    """
    n_draws = draws.shape[0]
    keys = ["none", "unknown"] + [o.key for o in options]
    p = {k: np.zeros(n_draws) for k in keys}
    models = list(dict.fromkeys([*baselines, *(o.model for o in options)]))
    elpd, error = log_density(evidence, models, draws)
    row = {m: i for i, m in enumerate(models)}
    base_errors = error[[row[m] for m in baselines]]
    base = base_errors.min(axis=0)
    base_choice = base_errors.argmin(axis=0)
    usable = [o for o in options if o.eligible]
    fails = np.broadcast_to(np.asarray(baseline_fails, dtype=bool), (n_draws,))
    all_errors = np.array([error[row[o.model]] for o in options]) if options else base[None, :]
    unknown_ratio = all_errors.min(axis=0) / base
    structure = np.broadcast_to(np.asarray(envelope_structure, dtype=bool), (n_draws,))
    if structure.all():
        p["unknown"][:] = 1.0
        return p, unknown_ratio

    def no_single_mode(ratio: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
        for k in p:
            p[k] = np.where(structure, 1.0 if k == "unknown" else 0.0, p[k])
        return p, np.where(structure, unknown_ratio, ratio)

    if not usable:
        p["unknown"] += fails
        p["none"] += ~fails
        return no_single_mode(p["none"] + p["unknown"] * unknown_ratio)
    opt_error = np.array([error[row[o.model]] for o in usable])  # (K, B)
    better = opt_error < base
    for k, o in enumerate(usable):
        if o.parts:
            # a combination is an option only where its parsimony test passes: elsewhere its
            # weight goes where the rule puts it, to the single causes by their predictive density
            better[k] &= combination_passes(evidence, o, draws)
    beyond = np.array(
        [
            np.choose(
                base_choice,
                [
                    beyond_accuracy(
                        evidence.unit_curve_squares[b],
                        evidence.unit_curve_squares[o.model],
                        evidence.unit_tolerance,
                        draws,
                    )
                    for b in baselines
                ],
            )
            for o in usable
        ]
    )
    clear = better & ((opt_error < clear_gain * base) | beyond)
    log_w = np.where(better, np.array([elpd[row[o.model]] for o in usable]), -np.inf)
    any_better = better.any(axis=0)
    top = np.where(any_better, log_w.max(axis=0), 0.0)
    w = np.where(better, np.exp(log_w - top), 0.0)
    w /= np.maximum(w.sum(axis=0), 1e-300)
    departs = any_better & (fails | clear.any(axis=0))
    # no option better: the baseline stands where it fits, nothing removes its misfit where it fails
    p["unknown"] += ~any_better & fails
    p["none"] += ~any_better & ~fails
    p["none"] += any_better & ~departs
    ratio = np.zeros(n_draws)
    for k, o in enumerate(usable):
        share = np.where(departs, w[k], 0.0)
        ratio_k = opt_error[k] / base
        to_unknown = o.residual_significant & (ratio_k >= residual_gain)
        p["unknown"] += np.where(to_unknown, share, 0.0)
        p[o.key] += np.where(to_unknown, 0.0, share)
        ratio += np.where(to_unknown, 0.0, share * ratio_k)
    return no_single_mode(ratio + p["none"] + p["unknown"] * unknown_ratio)


def unseen(p: dict[str, np.ndarray], options: Sequence[VerdictOption], ruled_out: float) -> None:
    """``none`` is the baseline explaining the data within their scatter; it is right only as
    far as the data rule out a mechanism beyond the models' accuracy (``ruled_out``,
    :func:`workflow.discovery.misfit.departure_ruled_out`). The share ``1 - ruled_out`` of
    :func:`soft_decisions`' ``p["none"]`` is spread evenly over ``none`` and the single
    causes of ``options`` (in place): a mechanism the data cannot show is as likely any of
    them (a sensor near a node may see nothing, never be sure of nothing). It gains nothing
    on these data: the draws' gain ratio stays as :func:`soft_decisions` gave it."""
    single = [o.key for o in options if not o.parts]
    if ruled_out >= 1.0 or not single:
        return
    share = p["none"] * (1.0 - ruled_out) / (len(single) + 1)
    p["none"] -= share * len(single)
    for key in single:
        p[key] += share


def combination_passes(evidence: HeldoutEvidence, option: VerdictOption, draws: np.ndarray) -> np.ndarray:
    """Whether a combination passes its parsimony test on each reweighting of the units
    (:func:`workflow.discovery.combined.reweighted_combination_test` on the units' squared
    held-out errors, both curves), shape (B,)."""
    squares = {m: v.mean(axis=0) for m, v in evidence.unit_curve_squares.items()}
    parts = {cause: squares[model] for cause, model in option.parts.items()}
    return reweighted_combination_test(squares[option.model], parts, evidence.unit_weights, draws)["named"]


REPORTED_PROBABILITY = 1e-3
"""Smallest mean probability reported: below a thousandth (one draw in a thousand) a
verdict is not listed, and the rest are renormalised to sum to 1."""


def mean_probabilities(probabilities: Mapping[str, np.ndarray]) -> dict[str, float]:
    """Mean over the draws of each verdict's probability, those of at least
    :data:`REPORTED_PROBABILITY`, largest first (sums to 1).

    Examples
    --------
    >>> mean_probabilities({"none": np.array([1.0, 0.5]), "run_drift": np.array([0.0, 0.5])})
    {'none': 0.75, 'run_drift': 0.25}
    """
    mean = {k: float(np.mean(v)) for k, v in probabilities.items()}
    kept = {k: v for k, v in mean.items() if v >= REPORTED_PROBABILITY} or mean
    total = sum(kept.values()) or 1.0
    return dict(sorted(((k, v / total) for k, v in kept.items()), key=lambda kv: -kv[1]))

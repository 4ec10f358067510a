"""Calibrated confidence (workflow/discovery/confidence.py) and the combination rule
(workflow/discovery/combined.py), against cases whose answer is known."""

import numpy as np
import pytest

from workflow.discovery.combined import PAIRED_FALSE_ALARM, combination_test
from workflow.discovery.confidence import (
    HeldoutEvidence,
    VerdictOption,
    beyond_accuracy,
    dirichlet_unit_weights,
    log_density,
    mean_probabilities,
    soft_decisions,
    unseen,
    verdict_causes,
    verdict_key,
)
from workflow.discovery.heldout import heldout_standard_error

N_UNITS = 8
RULE = {"clear_gain": 0.7, "residual_gain": 0.7, "envelope_structure": False}


def with_squares(squares: dict[str, np.ndarray], tolerance: float, n_eff: int = 40) -> HeldoutEvidence:
    """Evidence of ``N_UNITS`` runs of unit weight whose per-run squared held-out errors
    are ``squares`` on the damping curve, the frequency curve fitted exactly (0) by every
    model, and the models' accuracy ``tolerance`` (squared, in scatter units) per run."""
    curves = {m: np.array([2.0 * v, np.zeros(N_UNITS)]) for m, v in squares.items()}
    return HeldoutEvidence(curves, np.full((2, N_UNITS), tolerance), np.ones(N_UNITS), n_eff)


def channel(
    errors: dict[str, float], spread: float, seed: int, n_eff: int = 40, tolerance: float = 100.0
) -> HeldoutEvidence:
    """Held-out sums of ``N_UNITS`` runs of unit weight: model ``m``'s squared error per run
    (both curves) is ``errors[m]^2`` times a common run factor and its own lognormal scatter
    ``spread``. The default ``tolerance``, far above every error, is data whose scatter is
    small against the models' accuracy: the relative margin alone decides."""
    rng = np.random.default_rng(seed)
    common = rng.lognormal(0.0, 0.3, N_UNITS)
    squares = {m: e**2 * common * rng.lognormal(0.0, spread, N_UNITS) for m, e in errors.items()}
    return with_squares(squares, tolerance, n_eff)


def squares_of(ev: HeldoutEvidence) -> dict[str, np.ndarray]:
    """Per model, the per-run squared held-out error of both curves."""
    return {m: v.mean(axis=0) for m, v in ev.unit_curve_squares.items()}


def decide_softly(evidence, options, *, baseline_fails=False, n_draws=400, seed=0):
    draws = dirichlet_unit_weights(n_draws, N_UNITS, np.random.default_rng(seed))
    p, ratio = soft_decisions(evidence, ["dahl"], options, baseline_fails=baseline_fails, draws=draws, **RULE)
    return mean_probabilities(p), p, ratio


def test_dirichlet_weights_keep_every_unit_and_average_to_the_data():
    w = dirichlet_unit_weights(2000, 5, np.random.default_rng(1))
    assert np.all(w > 0)
    np.testing.assert_allclose(w.sum(axis=1), 5.0)
    # the mean reweighting is the data itself; Monte Carlo error of the mean ~ 1/sqrt(2000 * 6)
    np.testing.assert_allclose(w.mean(axis=0), 1.0, atol=0.04)


@pytest.mark.parametrize("n_units", [3, 5, 8, 14])
def test_reweighted_means_spread_by_the_heldout_standard_error(n_units):
    """Over the reweightings, a weighted mean of the units' values varies as much as the
    held-out tests' standard error of their mean says (``s^2 / n``, ``s`` the sample
    standard deviation). Monte Carlo: the variance of 20000 draws is within 2 % (its
    relative standard error ~ sqrt(2 / 20000) for a near-Gaussian mean, 1 %, widened for
    the Dirichlet's heavier tails at three units)."""
    values = np.random.default_rng(n_units).lognormal(0.0, 0.5, n_units)
    w = dirichlet_unit_weights(20000, n_units, np.random.default_rng(2))
    means = w @ values / n_units
    expected = heldout_standard_error(values, np.ones(n_units)) ** 2
    assert np.var(means) == pytest.approx(expected, rel=0.02 if n_units > 3 else 0.04)


def test_log_density_returns_the_heldout_error():
    ev = channel({"dahl": 2.0, "iwan": 1.0}, 0.1, seed=3)
    elpd, error = log_density(ev, ["dahl", "iwan"], np.ones((1, N_UNITS)))
    direct = np.sqrt([squares_of(ev)[m].sum() / N_UNITS for m in ("dahl", "iwan")])
    np.testing.assert_allclose(error[:, 0], direct, rtol=1e-12)
    # Gaussian with its own variance E^2: elpd = -n/2 (ln E^2 + 1)
    np.testing.assert_allclose(elpd[:, 0], -0.5 * 40 * (np.log(direct**2) + 1.0), rtol=1e-12)


def test_tied_candidates_share_the_confidence():
    """Two candidates whose held-out errors differ by less than their run-to-run scatter:
    neither may be sure, and together they carry the departure."""
    ev = channel({"dahl": 1.0, "dahl_quadratic": 0.5, "dahl_stiffness": 0.505}, 0.15, seed=5)
    options = [
        VerdictOption("quadratic_damping", "dahl_quadratic"),
        VerdictOption("stiffness_nonlinearity", "dahl_stiffness"),
    ]
    confidence, p, _ = decide_softly(ev, options)
    assert 0.2 < confidence["quadratic_damping"] < 0.8
    assert 0.2 < confidence["stiffness_nonlinearity"] < 0.8
    assert sum(confidence.values()) == pytest.approx(1.0)
    for b in range(400):  # every draw is a probability vector
        assert sum(v[b] for v in p.values()) == pytest.approx(1.0)


def test_a_clear_leader_takes_the_confidence():
    ev = channel({"dahl": 1.0, "iwan": 0.3, "dahl_stiffness": 0.8}, 0.1, seed=7)
    options = [
        VerdictOption("microslip_power_law", "iwan"),
        VerdictOption("stiffness_nonlinearity", "dahl_stiffness"),
    ]
    confidence, _, ratio = decide_softly(ev, options)
    assert confidence["microslip_power_law"] > 0.99
    # the gain ratio of the draws is the leader's, 0.3 up to the run scatter
    assert np.median(ratio) == pytest.approx(0.3, rel=0.15)


def test_a_small_gain_without_a_baseline_misfit_is_not_confident_of_an_effect():
    """No-effect campaigns: an extension absorbs the models' own bias to ~0.85 of the
    baseline's error. Without a significant misfit the gate (0.7) is rarely passed."""
    ev = channel({"dahl": 1.0, "dahl_drift": 0.85}, 0.1, seed=11)
    confidence, _, _ = decide_softly(ev, [VerdictOption("run_drift", "dahl_drift")])
    assert confidence["none"] > 0.9


def test_a_gain_at_the_margin_is_uncertain():
    """A gain ratio at the margin itself: about half of the reweightings pass it."""
    ev = channel({"dahl": 1.0, "dahl_drift": 0.7}, 0.2, seed=13)
    squares = squares_of(ev)  # the all-data ratio exactly at the margin
    squares["dahl_drift"] = (
        squares["dahl_drift"] * 0.7**2 * squares["dahl"].sum() / squares["dahl_drift"].sum()
    )
    ev = with_squares(squares, 100.0)
    confidence, _, _ = decide_softly(ev, [VerdictOption("run_drift", "dahl_drift")])
    assert 0.2 < confidence["none"] < 0.8


def test_beyond_accuracy_is_the_removed_misfit_against_the_models_accuracy():
    """Removed squared error per curve against the tolerance, reweighted per draw."""
    tolerance = np.array([[0.1, 0.1], [4.0, 4.0]])
    base = np.array([[1.5, 1.0], [9.0, 9.0]])
    # damping: 0.25 removed per unit against 0.1 (beyond); frequency: 3 against 4 (within)
    option = np.array([[1.25, 0.75], [6.0, 6.0]])
    assert beyond_accuracy(base, option, tolerance, np.ones((1, 2))).tolist() == [True]
    assert beyond_accuracy(base, option, tolerance * 3.0, np.ones((1, 2))).tolist() == [False]
    # one unit removes 0.05 only: the draw that weighs it alone is within the accuracy
    option = np.array([[1.0, 0.95], [9.0, 9.0]])
    assert beyond_accuracy(base, option, tolerance, np.array([[2.0, 0.0], [0.0, 2.0]])).tolist() == [
        True,
        False,
    ]


def test_a_small_gain_in_a_large_scatter_is_an_effect_when_it_exceeds_the_accuracy():
    """A sensor near a node of the mode: the scatter is 13 times the models' accuracy
    (tolerance (1/13)^2 = 0.006 in squared scatter units), so a joint effect of a few times
    the accuracy lowers the held-out error only to 0.86 of the baseline's, far from the
    relative margin (0.7). That gain is 40 times the accuracy: the departure is sure,
    where the relative margin alone reads it as none."""
    errors = {"dahl": 1.0, "dahl_drift": 0.86}
    noisy = channel(errors, 0.1, seed=29, tolerance=(1 / 13) ** 2)
    confidence, _, _ = decide_softly(noisy, [VerdictOption("run_drift", "dahl_drift")])
    assert confidence["run_drift"] > 0.9
    precise = channel(errors, 0.1, seed=29)
    confidence, _, _ = decide_softly(precise, [VerdictOption("run_drift", "dahl_drift")])
    assert confidence["none"] > 0.9


def test_a_gain_at_the_models_accuracy_is_uncertain():
    """What an option removes, across the runs, about equal to the models' accuracy: the
    data cannot tell an effect from the models' own inaccuracy, so neither is sure."""
    ev = channel({"dahl": 1.0, "dahl_drift": 0.95}, 0.3, seed=31)
    damping = {m: v[0] for m, v in ev.unit_curve_squares.items()}
    removed = float(np.mean(damping["dahl"] - damping["dahl_drift"]))
    ev = HeldoutEvidence(ev.unit_curve_squares, np.full((2, N_UNITS), removed), ev.unit_weights, 40)
    confidence, _, _ = decide_softly(ev, [VerdictOption("run_drift", "dahl_drift")])
    assert 0.2 < confidence["none"] < 0.8


def test_ineligible_and_misfitting_options():
    ev = channel({"dahl": 1.0, "dahl_stiffness": 0.3, "iwan": 0.8}, 0.1, seed=17)
    vetoed = [VerdictOption("stiffness_nonlinearity", "dahl_stiffness", eligible=False)]
    confidence, _, _ = decide_softly(ev, vetoed, baseline_fails=True)
    assert confidence == {"unknown": 1.0}
    misfit = [VerdictOption("microslip_power_law", "iwan", residual_significant=True)]
    confidence, _, _ = decide_softly(ev, misfit, baseline_fails=True)
    assert confidence["unknown"] > 0.95  # 0.8 of the baseline's error does not reach 0.7


def test_verdict_keys_do_not_depend_on_the_order_of_causes():
    assert verdict_key(["stiffness_nonlinearity", "microslip_power_law"]) == verdict_key(
        ["microslip_power_law", "stiffness_nonlinearity"]
    )


def test_verdict_keys_follow_the_vocabulary_and_give_their_causes_back():
    """The contract's key of two causes is the vocabulary's order joined by ``+`` (micro-slip,
    quadratic, stiffness, run drift), not the alphabet's, and reads back into its causes."""
    assert verdict_key(["run_drift", "stiffness_nonlinearity"]) == "stiffness_nonlinearity+run_drift"
    assert (
        verdict_key(["quadratic_damping", "microslip_power_law"]) == "microslip_power_law+quadratic_damping"
    )
    for causes in (["microslip_power_law", "stiffness_nonlinearity"], ["none"], ["unknown"]):
        assert verdict_causes(verdict_key(causes)) == causes


def test_not_single_mode_decays_are_unknown_in_every_reweighting():
    """Envelopes that are not single-mode decays: ``unknown`` in every draw, whatever the
    options predict; its gain ratio is the best option's error over the baseline's."""
    ev = with_squares({"dahl": np.full(N_UNITS, 4.0), "iwan": np.full(N_UNITS, 1.0)}, 100.0)
    draws = dirichlet_unit_weights(50, N_UNITS, np.random.default_rng(2))
    rule = {**RULE, "envelope_structure": True}
    p, ratio = soft_decisions(
        ev, ["dahl"], [VerdictOption("microslip_power_law", "iwan")], baseline_fails=True, draws=draws, **rule
    )
    np.testing.assert_array_equal(p["unknown"], 1.0)
    np.testing.assert_array_equal(p["none"] + p["microslip_power_law"], 0.0)
    np.testing.assert_allclose(ratio, 0.5, rtol=1e-12)  # sqrt(1 / 4) in every draw


@pytest.mark.parametrize("baseline_fails", [True, False])
def test_without_an_eligible_option_the_baseline_stands_or_nothing_explains_its_misfit(baseline_fails):
    """No option the rule lets name: ``none`` where the baseline fits (gain ratio 1),
    ``unknown`` where it fails (gain ratio of the best model tried, here 0.5)."""
    ev = with_squares({"dahl": np.full(N_UNITS, 4.0), "iwan": np.full(N_UNITS, 1.0)}, 100.0)
    draws = dirichlet_unit_weights(50, N_UNITS, np.random.default_rng(4))
    vetoed = [VerdictOption("microslip_power_law", "iwan", eligible=False)]
    p, ratio = soft_decisions(ev, ["dahl"], vetoed, baseline_fails=baseline_fails, draws=draws, **RULE)
    np.testing.assert_array_equal(p["unknown"], 1.0 if baseline_fails else 0.0)
    np.testing.assert_array_equal(p["none"], 0.0 if baseline_fails else 1.0)
    np.testing.assert_array_equal(p["microslip_power_law"], 0.0)
    np.testing.assert_allclose(ratio, 0.5 if baseline_fails else 1.0, rtol=1e-12)


@pytest.mark.parametrize("second_error, leaves_misfit", [(0.42, False), (0.8, True)])
def test_better_options_share_a_departure_by_their_pseudo_bma_weights(second_error, leaves_misfit):
    """Two options that predict better: on the data (one draw of ones) their shares are
    ``exp(elpd)`` normalised, ``(E2^2 / E1^2)^(n_eff / 2)`` apart. One that leaves a
    significant misfit at 0.8 of a failing baseline's error passes its share to
    ``unknown`` (whose ratio is the best model tried); the gain ratio is the shares' mean
    of their ratios."""
    n_eff = 6
    errors = {"dahl": 1.0, "iwan": 0.40, "dahl_quadratic": second_error}
    ev = with_squares({m: np.full(N_UNITS, e**2) for m, e in errors.items()}, 1e-6, n_eff)
    options = [
        VerdictOption("microslip_power_law", "iwan"),
        VerdictOption("quadratic_damping", "dahl_quadratic", residual_significant=leaves_misfit),
    ]
    p, ratio = soft_decisions(
        ev, ["dahl"], options, baseline_fails=leaves_misfit, draws=np.ones((1, N_UNITS)), **RULE
    )
    odds = (second_error**2 / 0.40**2) ** (n_eff / 2)
    share = odds / (1.0 + odds)
    second = "unknown" if leaves_misfit else "quadratic_damping"
    assert p["microslip_power_law"][0] == pytest.approx(share, rel=1e-12)
    assert p[second][0] == pytest.approx(1.0 - share, rel=1e-12)
    assert sum(p[k][0] for k in p if k not in ("microslip_power_law", second)) == 0.0
    second_ratio = 0.40 if leaves_misfit else second_error
    assert ratio[0] == pytest.approx(share * 0.40 + (1.0 - share) * second_ratio, rel=1e-12)


def test_log_density_does_not_depend_on_the_scale_of_the_unit_weights():
    """``E^2 = sum S / sum W``: amplitude weights far below 1 (a channel of few segments)
    give the same error as the same sums scaled up."""
    ev = channel({"dahl": 2.0, "iwan": 1.0}, 0.1, seed=3)
    small = HeldoutEvidence(
        {m: v * 1e-6 for m, v in ev.unit_curve_squares.items()},
        ev.unit_tolerance * 1e-6,
        ev.unit_weights * 1e-6,
        ev.effective_observations,
    )
    draws = dirichlet_unit_weights(5, N_UNITS, np.random.default_rng(0))
    for a, b in zip(log_density(ev, ["dahl", "iwan"], draws), log_density(small, ["dahl", "iwan"], draws)):
        np.testing.assert_allclose(a, b, rtol=1e-12)


def test_one_unit_of_evidence_keeps_its_weight():
    """One unit (one run of one half decade): every reweighting is the data."""
    np.testing.assert_array_equal(dirichlet_unit_weights(4, 1, np.random.default_rng(0)), np.ones((4, 1)))


def test_mean_probabilities_drop_the_negligible_and_sum_to_one_largest_first():
    mean = mean_probabilities(
        {
            "microslip_power_law": np.array([0.2, 0.3]),
            "unknown": np.array([0.0, 0.001]),  # mean 5e-4: below the reported thousandth
            "none": np.array([0.8, 0.699]),
        }
    )
    assert list(mean) == ["none", "microslip_power_law"]
    total = 0.25 + 0.7495
    assert mean["none"] == pytest.approx(0.7495 / total, rel=1e-12)
    assert mean["microslip_power_law"] == pytest.approx(0.25 / total, rel=1e-12)


@pytest.mark.parametrize("baseline_fails", [True, False])
def test_where_an_eligible_option_predicts_worse_the_baseline_stands_or_nothing_explains_it(baseline_fails):
    """An option the rule lets name but that predicts held-out data worse than the
    baseline in every reweighting takes nothing: ``none`` where the baseline fits (gain
    ratio 1), ``unknown`` where it fails (the ratio of the best model tried, per draw)."""
    ev = channel({"dahl": 1.0, "dahl_stiffness": 1.6}, 0.1, seed=19)
    draws = dirichlet_unit_weights(50, N_UNITS, np.random.default_rng(6))
    options = [VerdictOption("stiffness_nonlinearity", "dahl_stiffness")]
    p, ratio = soft_decisions(ev, ["dahl"], options, baseline_fails=baseline_fails, draws=draws, **RULE)
    _, error = log_density(ev, ["dahl", "dahl_stiffness"], draws)
    assert np.all(error[1] > error[0])
    np.testing.assert_array_equal(p["unknown"], 1.0 if baseline_fails else 0.0)
    np.testing.assert_array_equal(p["none"], 0.0 if baseline_fails else 1.0)
    np.testing.assert_array_equal(p["stiffness_nonlinearity"], 0.0)
    np.testing.assert_allclose(ratio, error[1] / error[0] if baseline_fails else 1.0, rtol=1e-12)


def test_without_any_option_a_failing_baseline_is_unknown_at_its_own_error():
    ev = channel({"dahl": 1.0}, 0.1, seed=23)
    draws = dirichlet_unit_weights(20, N_UNITS, np.random.default_rng(8))
    p, ratio = soft_decisions(ev, ["dahl"], [], baseline_fails=True, draws=draws, **RULE)
    np.testing.assert_array_equal(p["unknown"], 1.0)
    np.testing.assert_allclose(ratio, 1.0)


@pytest.mark.parametrize("baseline_fails", [False, True])
def test_an_option_better_in_some_reweightings_departs_in_those_only(baseline_fails):
    """An option that predicts half the runs far better and the other half worse: in each
    reweighting it takes the departure where its reweighted error is below the
    baseline's; elsewhere ``none``, or ``unknown`` where the baseline fails; an option
    worse in every draw never takes a share; at a realistic ``n_eff`` (the elpd in the
    thousands) the shares stay finite."""
    runs = np.arange(N_UNITS)
    squares = {
        "dahl": np.full(N_UNITS, 1.0),
        "iwan": np.where(runs < N_UNITS // 2, 0.01, 1.9),
        "dahl_stiffness": np.full(N_UNITS, 3.0),
    }
    ev = with_squares(squares, 1e-6, n_eff=4000)
    draws = dirichlet_unit_weights(400, N_UNITS, np.random.default_rng(10))
    options = [
        VerdictOption("microslip_power_law", "iwan"),
        VerdictOption("stiffness_nonlinearity", "dahl_stiffness"),
    ]
    p, ratio = soft_decisions(ev, ["dahl"], options, baseline_fails=baseline_fails, draws=draws, **RULE)
    _, error = log_density(ev, ["dahl", "iwan"], draws)
    better = error[1] < error[0]
    assert 0.2 < better.mean() < 0.8  # both kinds of draw occur
    np.testing.assert_array_equal(p["microslip_power_law"], np.where(better, 1.0, 0.0))
    np.testing.assert_array_equal(p["unknown" if baseline_fails else "none"], np.where(better, 0.0, 1.0))
    np.testing.assert_array_equal(p["none" if baseline_fails else "unknown"], 0.0)
    np.testing.assert_array_equal(p["stiffness_nonlinearity"], 0.0)
    # unknown's ratio is the best model tried (iwan, the stiffness term predicting worse still)
    expected = np.where(better | baseline_fails, error[1] / error[0], 1.0)
    np.testing.assert_allclose(ratio, expected, rtol=1e-12)


def test_a_combination_worse_than_the_baseline_takes_nothing_even_where_it_beats_its_parts():
    """A combination whose parts both predict far worse than the baseline passes its own
    parsimony test against them, yet predicts worse than the baseline: it takes nothing
    of a failing baseline's misfit (``unknown``)."""
    squares = {
        "dahl": np.full(N_UNITS, 1.0),
        "iwan_cells_5_quadratic": np.full(N_UNITS, 1.2) + 0.01 * np.arange(N_UNITS),
        "iwan_cells_5": np.full(N_UNITS, 20.0),
        "dahl_quadratic": np.full(N_UNITS, 30.0),
    }
    ev = with_squares(squares, 1e-6)
    combination = VerdictOption(
        "microslip_power_law+quadratic_damping",
        "iwan_cells_5_quadratic",
        parts={"microslip_power_law": "iwan_cells_5", "quadratic_damping": "dahl_quadratic"},
    )
    draws = dirichlet_unit_weights(50, N_UNITS, np.random.default_rng(12))
    p, _ = soft_decisions(ev, ["dahl"], [combination], baseline_fails=True, draws=draws, **RULE)
    np.testing.assert_array_equal(p["unknown"], 1.0)


def test_combination_named_only_when_both_parts_add_more_than_their_scatter():
    rng = np.random.default_rng(21)
    w = np.ones(N_UNITS)
    combined = 1.0 + 0.05 * rng.standard_normal(N_UNITS)
    baseline = combined + 3.0  # the two mechanisms' effects add: 1 + 2
    parts = {"a": combined + 2.0, "b": combined + 1.0}  # each part misses what the other adds
    result = combination_test(combined, parts, baseline, w)
    assert result["named"] and result["causes"] == ["b", "a"]
    assert result["shares"]["b"] == pytest.approx(2.0 / 3.0)
    # one part alone as good as the combination (up to noise): the second mechanism adds nothing
    parts = {"a": combined + 0.05 * rng.standard_normal(N_UNITS), "b": combined + 1.0}
    assert not combination_test(combined, parts, baseline, w)["named"]
    # both add, but one only a twentieth of the gain: not a second cause
    parts = {"a": combined + 2.85, "b": combined + 0.15}
    assert not combination_test(combined, parts, baseline, w, critical_t=0.0)["named"]


def test_a_second_mechanism_is_judged_by_what_it_removes_of_what_the_first_leaves():
    """The lab's micro-slip + velocity-squared case seen by three sensors (base seed, squared
    held-out errors in scatter units): the baseline at 6700, the threshold-distribution joint
    alone at 1290, the loss alone at 2210, both at 1.7. The loss carries only 0.19 of the
    gain over the baseline, but removes all but a 700th of what micro-slip alone leaves: two
    mechanisms. Micro-slip that removes a tenth of what the loss leaves only polishes it."""
    rng = np.random.default_rng(5)
    w = np.ones(N_UNITS)
    combined = 1.7 * (1.0 + 0.3 * rng.standard_normal(N_UNITS))
    spread = 1.0 + 0.3 * rng.standard_normal(N_UNITS)
    parts = {"microslip": combined + 1290.0 * spread, "loss": combined + 2210.0 * spread}
    result = combination_test(combined, parts, combined + 6700.0, w)
    assert result["shares"]["loss"] < 0.2  # what the old share-of-gain rule refused
    assert result["removed"]["loss"] > 0.99
    assert result["named"] and result["causes"] == ["microslip", "loss"]
    polish = {"microslip": combined + 1290.0 * spread, "loss": combined + 0.1 * 1.7 * spread}
    assert not combination_test(combined, polish, combined + 6700.0, w, critical_t=0.0)["named"]


def test_a_mechanism_that_does_nothing_is_named_at_the_stated_false_alarm_rate():
    """Eight runs, a second term that adds nothing (each run's paired difference of squared
    held-out errors drawn around zero): each part's test fires at its one-sided 2.5 %, not at
    the 4.3 % of a fixed 2 standard errors estimated from the same eight runs. Binomial
    sd of the rate over 4000 draws: 0.0025; the band is 4 sd."""
    rng = np.random.default_rng(31)
    w = np.ones(N_UNITS)
    fired = 0
    draws = 4000
    for _ in range(draws):
        combined = np.full(N_UNITS, 1.0)
        parts = {"a": combined + 0.1 * rng.standard_normal(N_UNITS), "b": np.full(N_UNITS, 100.0)}
        fired += combination_test(combined, parts, np.full(N_UNITS, 200.0), w, min_removed=0.0)["named"]
    assert abs(fired / draws - PAIRED_FALSE_ALARM) < 0.01


def test_a_mechanism_that_divides_every_runs_error_is_named_whatever_the_runs_levels():
    """Micro-slip + hardening spring (lab, seed 620): the combination divides every run's
    squared held-out error of the stiffness term alone by a large factor (16.9^2 to 1.0^2
    in scatter units overall). A run hit harder has larger errors, both models' alike: the
    verdict must not change when one run's level is 30 times the others'. The paired
    differences then scatter as widely as that run (1.4 standard errors: refused);
    the runs' log ratios do not move."""
    rng = np.random.default_rng(8)
    w = np.ones(N_UNITS)
    combined = 0.3 * np.exp(0.3 * rng.standard_normal(N_UNITS))
    stiffness_alone = 285.0 * 0.3 * np.exp(0.7 * rng.standard_normal(N_UNITS))
    level = np.ones(N_UNITS)
    level[0] = 30.0
    for scale in (np.ones(N_UNITS), level):
        parts = {"microslip": stiffness_alone * scale, "stiffness": 30.0 * combined * scale}
        result = combination_test(combined * scale, parts, 2.0 * stiffness_alone * scale, w)
        assert result["named"], result
        assert result["log_ratio_t"]["microslip"] > 10.0
    difference_t = result["contributions"]["microslip"] / result["standard_errors"]["microslip"]
    assert difference_t < 2.0  # what a paired test of the differences reads


def test_failure_draws_with_equal_weights_are_the_tests_on_the_data():
    """All-ones weights are the data: the bin's t test and the trend's regression p value
    (scipy's linregress) decide as on the data; reweightings then spread around it."""
    from scipy import stats

    from workflow.discovery.misfit import failure_draws

    rng = np.random.default_rng(23)
    y = 0.01 + 0.004 * rng.standard_normal(N_UNITS)  # a bin mean 0.01, t ~ 7
    t = y.mean() / (y.std(ddof=1) / np.sqrt(N_UNITS))
    p = 2 * stats.t.sf(abs(t), N_UNITS - 1)
    row = {"run_ids": list(range(N_UNITS)), "run_means": y.tolist(), "tolerance": 0.005}
    ones = np.ones((1, N_UNITS))
    for limit in (p * 1.01, p * 0.99):  # just above and just below the data's p value
        assert failure_draws([{**row, "p_limit": limit}], None, ones)[0] == (p < limit)
    x = np.arange(N_UNITS, dtype=float)
    projections = -0.03 * x + 0.02 * rng.standard_normal(N_UNITS)
    fit = stats.linregress(x, projections)
    trend = {
        "run_ids": list(range(N_UNITS)),
        "run_positions": x.tolist(),
        "run_projections": projections.tolist(),
        "largest_shape": 1.0,
    }
    for limit in (fit.pvalue * 1.01, fit.pvalue * 0.99):
        assert failure_draws([], {**trend, "p_limit": limit}, ones)[0] == (fit.pvalue < limit)
    # at its limit, about half of the reweightings fail
    draws = dirichlet_unit_weights(400, N_UNITS, rng)
    share = failure_draws([], {**trend, "p_limit": fit.pvalue}, draws).mean()
    assert 0.2 < share < 0.8


def combination_at_its_limit(t_micro: float, seed: int = 41) -> HeldoutEvidence:
    """Eight runs: the baseline far off, the loss alone leaving 30 times the combination's
    squared error in every run, micro-slip alone (``iwan``) beaten by the combination by
    log ratios whose paired t is exactly ``t_micro`` (mean 0.9 in ln, about 2.5 times the
    combination's squared error: micro-slip removes ~0.9 of what the loss leaves, the loss
    ~0.6 of what micro-slip leaves)."""
    rng = np.random.default_rng(seed)
    z = rng.standard_normal(N_UNITS)
    z = (z - z.mean()) / z.std(ddof=1)
    spread = 0.9 * np.sqrt(N_UNITS) / t_micro
    combined = np.exp(0.2 * rng.standard_normal(N_UNITS))
    squares = {
        "dahl": 200.0 * combined,
        "iwan": combined * np.exp(0.9 + spread * z),
        "dahl_quadratic": 30.0 * combined * np.exp(0.1 * rng.standard_normal(N_UNITS)),
        "combined": combined,
    }
    return with_squares(squares, 0.01)


COMBINATION_OPTIONS = [
    VerdictOption("microslip_power_law", "iwan"),
    VerdictOption("quadratic_damping", "dahl_quadratic"),
    VerdictOption(
        "microslip_power_law+quadratic_damping",
        "combined",
        parts={"microslip_power_law": "iwan", "quadratic_damping": "dahl_quadratic"},
    ),
]


def test_a_combination_at_the_limit_of_its_test_shares_the_confidence_with_its_better_part():
    """The combination predicts best in every reweighting, but its test over the runs
    against micro-slip alone sits at Student's quantile: about half of the reweightings
    pass it, and where it fails the rule names the better part alone. Neither is sure."""
    from workflow.discovery.combined import paired_critical_value

    key = "microslip_power_law+quadratic_damping"
    at_limit = combination_at_its_limit(paired_critical_value(N_UNITS))
    squares = squares_of(at_limit)
    test = combination_test(
        squares["combined"],
        {k: squares[m] for k, m in COMBINATION_OPTIONS[2].parts.items()},
        squares["dahl"],
        np.ones(N_UNITS),
    )
    assert test["log_ratio_t"]["quadratic_damping"] == pytest.approx(paired_critical_value(N_UNITS))
    assert min(test["removed"].values()) > 0.5  # the removed shares do not decide here
    confidence, _, _ = decide_softly(at_limit, COMBINATION_OPTIONS, baseline_fails=True)
    assert 0.2 < confidence[key] < 0.8
    assert 0.2 < confidence["microslip_power_law"] < 0.8
    assert confidence[key] + confidence["microslip_power_law"] == pytest.approx(1.0, abs=0.01)
    # the same runs twice as consistent: the test passes in (nearly) every reweighting
    clear = combination_at_its_limit(2.0 * paired_critical_value(N_UNITS))
    confidence, _, _ = decide_softly(clear, COMBINATION_OPTIONS, baseline_fails=True)
    assert confidence[key] > 0.95


def test_the_reweighted_combination_test_on_the_data_is_the_test():
    """A row of ones is the data: the reweighted statistics equal combination_test's."""
    from workflow.discovery.combined import reweighted_combination_test

    ev = combination_at_its_limit(3.0)
    squares = squares_of(ev)
    parts = {"microslip_power_law": squares["iwan"], "quadratic_damping": squares["dahl_quadratic"]}
    test = combination_test(squares["combined"], parts, squares["dahl"], np.ones(N_UNITS))
    again = reweighted_combination_test(squares["combined"], parts, np.ones(N_UNITS), np.ones((1, N_UNITS)))
    for cause in parts:
        assert again["log_ratio_t"][cause][0] == pytest.approx(test["log_ratio_t"][cause], rel=1e-12)
        assert again["removed"][cause][0] == pytest.approx(test["removed"][cause], rel=1e-12)
    assert bool(again["named"][0]) == test["named"]


@pytest.mark.parametrize("ruled_out", [1.0, 0.6, 0.0])
def test_none_is_as_sure_as_the_data_rule_out_a_departure(ruled_out):
    """A baseline that fits, two options no better: ``none`` in every reweighting where the
    data rule out a departure (``ruled_out`` 1); otherwise the share they cannot rule out
    is a mechanism as likely as none or either cause (a third each), and it gains nothing
    on these data (gain ratio 1). A combination takes none of it."""
    ev = with_squares({"dahl": np.full(N_UNITS, 1.0), "iwan": np.full(N_UNITS, 1.2)}, 100.0)
    options = [
        VerdictOption("microslip_power_law", "iwan"),
        VerdictOption("quadratic_damping", "iwan", eligible=False),
        VerdictOption(
            "microslip_power_law+quadratic_damping",
            "iwan",
            eligible=False,
            parts={"microslip_power_law": "iwan", "quadratic_damping": "iwan"},
        ),
    ]
    draws = dirichlet_unit_weights(50, N_UNITS, np.random.default_rng(5))
    p, ratio = soft_decisions(ev, ["dahl"], options, baseline_fails=False, draws=draws, **RULE)
    unseen(p, options, ruled_out)
    moved = 1.0 - ruled_out
    np.testing.assert_allclose(p["none"], ruled_out + moved / 3, rtol=1e-12)
    np.testing.assert_allclose(p["microslip_power_law"], moved / 3, rtol=1e-12)
    np.testing.assert_allclose(p["quadratic_damping"], moved / 3, rtol=1e-12)
    np.testing.assert_array_equal(p["microslip_power_law+quadratic_damping"], 0.0)
    np.testing.assert_allclose(sum(p.values()), 1.0, rtol=1e-12)
    np.testing.assert_allclose(ratio, 1.0, rtol=1e-12)


def test_draws_whose_envelopes_are_no_single_mode_decay_are_unknown_and_the_others_decide():
    """Per-draw envelope verdicts: in the draws where the envelopes are no single-mode
    decay every probability goes to ``unknown`` at the best tried model's ratio; the other
    draws are decided as without the envelope test, to the bit."""
    ev = channel({"dahl": 1.0, "dahl_stiffness": 0.4}, 0.1, seed=31)
    draws = dirichlet_unit_weights(60, N_UNITS, np.random.default_rng(9))
    options = [VerdictOption("stiffness_nonlinearity", "dahl_stiffness")]
    structure = np.arange(60) % 3 == 0
    rule = {**RULE, "envelope_structure": structure}
    p, ratio = soft_decisions(ev, ["dahl"], options, baseline_fails=False, draws=draws, **rule)
    free, free_ratio = soft_decisions(ev, ["dahl"], options, baseline_fails=False, draws=draws, **RULE)
    _, error = log_density(ev, ["dahl", "dahl_stiffness"], draws)
    assert free["stiffness_nonlinearity"].min() == 1.0
    np.testing.assert_array_equal(p["unknown"], np.where(structure, 1.0, free["unknown"]))
    np.testing.assert_array_equal(p["stiffness_nonlinearity"], np.where(structure, 0.0, 1.0))
    np.testing.assert_allclose(ratio, np.where(structure, error[1] / error[0], free_ratio), rtol=1e-12)
    assert mean_probabilities(p)["unknown"] == pytest.approx(structure.mean())

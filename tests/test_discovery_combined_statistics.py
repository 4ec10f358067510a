"""The statistics of the combination rule (workflow/discovery/combined.py) against
textbook values: Student's quantiles, the one-sample t of SciPy, weighted least squares
solved by NumPy, and the invariances the held-out sums must have."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from workflow.discovery.combined import (
    IGNORED_CURVE_SCALE,
    STIFFNESS_EXPONENTS,
    combination_test,
    one_curve_scatter,
    paired_critical_value,
    paired_t,
    reweighted_combination_test,
    term_from_residuals,
)
from workflow.discovery.heldout import heldout_standard_error
from workflow.models.configuration_data import Scatter

# Student's t, one-sided 2.5 % (two-sided 5 %) quantiles, from the printed tables
STUDENT_975 = {1: 12.706, 4: 2.776, 7: 2.365}


@pytest.mark.parametrize("n_units, degrees", [(8, 7), (5, 4), (2, 1), (1, 1)])
def test_the_critical_value_is_students_quantile_with_one_degree_less_than_the_units(n_units, degrees):
    assert paired_critical_value(n_units) == pytest.approx(STUDENT_975[degrees], abs=5e-4)


def test_a_looser_false_alarm_rate_lowers_the_critical_value():
    assert paired_critical_value(8, 0.05) == pytest.approx(1.895, abs=5e-4)  # t(0.95, 7)


def test_paired_t_on_the_data_is_the_one_sample_t():
    values = np.array([0.3, -0.1, 0.8, 0.45, 0.2, 0.05, 0.6])
    expected = stats.ttest_1samp(values, 0.0).statistic
    assert paired_t(values).shape == (1,)  # one row: the data
    assert paired_t(values)[0] == pytest.approx(expected, rel=1e-12)
    assert paired_t(values[:2])[0] == pytest.approx(stats.ttest_1samp(values[:2], 0.0).statistic, rel=1e-12)


def test_paired_t_with_whole_unit_weights_is_the_t_of_the_units_repeated():
    """A reweighting by counts that sum to the number of units is a resample: its t is the
    one-sample t of the units repeated that often, whatever the row's scale."""
    values = np.array([0.3, -0.1, 0.8, 0.45, 0.2])
    counts = np.array([[2.0, 0.0, 1.0, 1.0, 1.0], [0.0, 3.0, 0.0, 1.0, 1.0]])
    t = paired_t(values, counts)
    for row, value in zip(counts, t, strict=True):
        expected = stats.ttest_1samp(np.repeat(values, row.astype(int)), 0.0).statistic
        assert value == pytest.approx(expected, rel=1e-12)
    np.testing.assert_allclose(paired_t(values, 7.0 * counts), t, rtol=1e-12)


def test_paired_t_where_the_units_agree_exactly_or_are_too_few():
    assert paired_t(np.full(4, 0.2))[0] == np.inf
    assert paired_t(np.full(4, -0.2))[0] == -np.inf
    assert paired_t(np.zeros(4))[0] == 0.0
    assert paired_t(np.array([0.7]))[0] == 0.0


def test_one_curve_scatter_makes_the_other_curve_weightless():
    scatter = Scatter(np.full(3, 0.01), np.full(3, 2e-5), np.full(3, 0.02), np.full(3, 3e-5))
    damping = one_curve_scatter(scatter, "zeta")
    np.testing.assert_array_equal(damping.ln_zeta, scatter.ln_zeta)
    np.testing.assert_array_equal(damping.rel_f, scatter.rel_f * IGNORED_CURVE_SCALE)
    frequency = one_curve_scatter(scatter, "frequency")
    np.testing.assert_array_equal(frequency.rel_f, scatter.rel_f)
    np.testing.assert_array_equal(frequency.ln_zeta, scatter.ln_zeta * IGNORED_CURVE_SCALE)


def heteroscedastic(v: np.ndarray) -> Scatter:
    """Scatters that differ from segment to segment, so that weights matter."""
    ln_zeta = 0.01 * (1.0 + 3.0 * (np.arange(v.size) % 3))
    rel_f = 2e-5 * (1.0 + 4.0 * (np.arange(v.size) % 2))
    return Scatter(ln_zeta, rel_f, ln_zeta, rel_f)


def test_a_loss_read_off_noisy_damping_is_the_weighted_least_squares_slope():
    """The loss is the slope through the origin of the damping the joint leaves against
    ``V``, each segment weighted by its own scatter of ``zeta`` (``zeta_model x scatter
    of ln zeta``): the least-squares solution of the whitened system."""
    rng = np.random.default_rng(3)
    v = np.geomspace(0.05, 3.0, 30)
    zeta_model = 1e-3 * (1 + 0.3 * np.log(v / 0.05))
    scatter = heteroscedastic(v)
    excess = 2e-4 * v + zeta_model * scatter.ln_zeta * rng.standard_normal(v.size)
    residuals = {"zeta_model": zeta_model, "ln_zeta": np.log1p(excess / zeta_model)}
    term = term_from_residuals("dahl_quadratic", v, residuals, scatter, 1.0)
    sigma = zeta_model * scatter.ln_zeta
    expected = np.linalg.lstsq((v / sigma)[:, None], excess / sigma, rcond=None)[0][0]
    assert term["quadratic_zeta_per_in_s"] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("exponent", STIFFNESS_EXPONENTS)
@pytest.mark.parametrize("seed", range(8))
def test_a_stiffness_term_read_off_noisy_frequency_is_the_best_weighted_power(exponent, seed):
    """Of the tried exponents, the one whose weighted least-squares shift leaves the least
    weighted squared frequency residual, and that shift (a term ``shift (V / V_ref)^p``
    of ``omega^2`` moves the relative frequency by half of it); with a term of 2-10
    scatters and one scatter of noise that is the true exponent."""
    rng = np.random.default_rng(seed)
    v = np.geomspace(0.1, 3.0, 40)
    reference = 1.3
    scatter = heteroscedastic(v)
    rel_f = 0.5 * 4e-4 * (v / reference) ** exponent + scatter.rel_f * rng.standard_normal(v.size)
    term = term_from_residuals("dahl_stiffness", v, {"rel_f": rel_f}, scatter, reference)
    fits = {}
    for p in STIFFNESS_EXPONENTS:
        column = 0.5 * (v / reference) ** p / scatter.rel_f
        shift, left, *_ = np.linalg.lstsq(column[:, None], rel_f / scatter.rel_f, rcond=None)
        fits[p] = (float(left[0]), float(shift[0]))
    best = min(fits, key=lambda p: fits[p][0])
    assert best == exponent
    assert term["stiffness_exponent"] == best
    assert term["stiffness_shift"] == pytest.approx(fits[best][1], rel=1e-9)


def units_with(rng: np.random.Generator, n: int = 8) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A combination's and its parts' per-unit squared held-out errors: a part alone
    3 and 5 times the combination's, run to run scatter 20 %."""
    combined = rng.lognormal(0.0, 0.2, n)
    parts = {
        "microslip_power_law": 3.0 * combined * rng.lognormal(0.0, 0.2, n),
        "quadratic_damping": 5.0 * combined * rng.lognormal(0.0, 0.2, n),
    }
    return combined, parts


def test_the_combination_test_does_not_depend_on_the_scale_of_the_errors_or_the_draws():
    """Squared errors in other units (a scatter twice as large: a quarter of the sums) and
    unit weights scaled alike, or a reweighting row scaled, leave every statistic as it is."""
    combined, parts = units_with(np.random.default_rng(7))
    weights = np.ones(combined.size)
    draws = np.vstack(
        [np.ones(combined.size), np.random.default_rng(8).dirichlet(np.ones(combined.size)) * 8]
    )
    test = reweighted_combination_test(combined, parts, weights, draws)
    scaled = reweighted_combination_test(
        combined * 1e-3, {c: v * 1e-3 for c, v in parts.items()}, weights * 1e-3, draws * 5.0
    )
    for key in ("log_ratio_t", "removed"):
        for cause in parts:
            np.testing.assert_allclose(scaled[key][cause], test[key][cause], rtol=1e-10)
    np.testing.assert_array_equal(scaled["named"], test["named"])
    assert test["named"].all()
    # the sums alone in other units (weights kept): errors of a few thousandths of a scatter
    small = reweighted_combination_test(
        combined * 1e-3, {c: v * 1e-3 for c, v in parts.items()}, weights, draws
    )
    for cause in parts:
        np.testing.assert_allclose(small["removed"][cause], test["removed"][cause], rtol=1e-10)


def test_a_unit_without_weight_adds_no_evidence():
    """A unit of no weight (a run with no scored segment) is left out of every statistic,
    whatever its sums hold."""
    combined, parts = units_with(np.random.default_rng(9))
    weights = np.ones(combined.size)
    with_empty = reweighted_combination_test(
        np.append(combined, 50.0),
        {c: np.append(v, 1e-6) for c, v in parts.items()},
        np.append(weights, 0.0),
        np.ones((1, combined.size + 1)),
    )
    alone = reweighted_combination_test(combined, parts, weights, np.ones((1, combined.size)))
    for cause in parts:
        assert with_empty["log_ratio_t"][cause][0] == pytest.approx(alone["log_ratio_t"][cause][0], rel=1e-12)
        assert with_empty["removed"][cause][0] == pytest.approx(alone["removed"][cause][0], rel=1e-12)
    assert with_empty["critical_t"] == pytest.approx(paired_critical_value(combined.size))


def test_a_part_that_predicts_perfectly_leaves_nothing_for_the_other_to_remove():
    combined, parts = units_with(np.random.default_rng(11))
    parts["quadratic_damping"] = np.zeros(combined.size)
    test = reweighted_combination_test(combined, parts, np.ones(combined.size), np.ones((1, combined.size)))
    assert test["removed"]["microslip_power_law"][0] == 0.0  # what the loss's part alone leaves: nothing
    assert not test["named"][0]


def test_the_combination_tests_figures_on_the_data():
    """Contributions, their standard errors, the shares of the gain and what each
    mechanism removes, computed from the sums by hand; the critical value passed on."""
    combined, parts = units_with(np.random.default_rng(13))
    parts = {
        "quadratic_damping": parts["quadratic_damping"],
        "microslip_power_law": parts["microslip_power_law"],
    }
    baseline = 10.0 * combined
    w = np.ones(combined.size)
    result = combination_test(combined, parts, baseline, w)
    n = combined.size
    mean = {m: float(np.sum(v)) / n for m, v in {**parts, "combined": combined, "baseline": baseline}.items()}
    gain = mean["baseline"] - mean["combined"]
    other = {"microslip_power_law": "quadratic_damping", "quadratic_damping": "microslip_power_law"}
    for cause, part in other.items():
        contribution = mean[part] - mean["combined"]
        assert result["contributions"][cause] == pytest.approx(contribution, rel=1e-12)
        assert result["standard_errors"][cause] == pytest.approx(
            heldout_standard_error(parts[part] - combined, w), rel=1e-12
        )
        assert result["shares"][cause] == pytest.approx(contribution / gain, rel=1e-12)
        assert result["removed"][cause] == pytest.approx(contribution / mean[part], rel=1e-12)
    # the larger contribution first: micro-slip's, what the loss alone (5 x) leaves over the pair
    assert result["causes"] == ["microslip_power_law", "quadratic_damping"]
    assert result["named"]
    assert f"{paired_critical_value(n):.3g}" in result["rule"]
    small = combination_test(combined * 1e-3, {c: v * 1e-3 for c, v in parts.items()}, baseline * 1e-3, w)
    for key in ("shares", "removed", "log_ratio_t"):
        for cause in parts:
            assert small[key][cause] == pytest.approx(result[key][cause], rel=1e-10)
    # a t of 2 passes a critical value of 1.5 passed on, not the default 2.36
    weak = {c: combined * np.exp(0.3 + 0.4 * np.resize([1.0, -1.0], n)) for c in parts}
    t = combination_test(combined, weak, baseline, w)["log_ratio_t"]["microslip_power_law"]
    assert 1.5 < t < paired_critical_value(n)
    assert not combination_test(combined, weak, baseline, w)["named"]
    assert combination_test(combined, weak, baseline, w, critical_t=1.5)["named"]


def test_without_a_gain_over_the_baseline_no_share_is_claimed():
    combined, parts = units_with(np.random.default_rng(17))
    result = combination_test(combined, parts, 0.5 * combined, np.ones(combined.size))
    assert result["shares"] == {"microslip_power_law": 0.0, "quadratic_damping": 0.0}

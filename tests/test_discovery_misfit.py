"""The baseline's misfit tests (workflow/discovery/misfit.py) against textbook statistics:
each amplitude bin's mean residual is a one-sample t test over the runs' means (SciPy's),
the run-order trend an ordinary least-squares slope over the runs' projections (SciPy's
``linregress``), both at their Bonferroni limits and the models' accuracy."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats
from support.discovery import segments_data

from workflow.discovery.misfit import (
    ALPHA,
    MIN_BIN_RUNS,
    MIN_BIN_SEGMENTS_ONE_RUN,
    bin_is_judged,
    bin_observations,
    binned_discrepancy,
    channel_weighted_observations,
    departure_ruled_out,
    departure_ruled_out_by_channels,
    explains_data,
    run_order_trend,
)
from workflow.models.configuration_data import TOL_LN_ZETA, TOL_REL_F, ConfigurationData

ANCHOR_IN_S = 8.0
TOP_EDGE_IN_S = ANCHOR_IN_S / np.sqrt(10.0)
# three half decades below the anchor (not a power of ten: bins and amplitude weights count
# from it): (2.53, 8], (0.8, 2.53], (0.253, 0.8]
BIN_VELOCITIES_IN_S = (6.0, 2.0, 0.6)


def campaign(n_runs: int, per_bin: int = 5) -> ConfigurationData:
    """``n_runs`` runs, each with ``per_bin`` segments in each of three half decades."""
    velocity = np.tile(np.repeat(BIN_VELOCITIES_IN_S, per_bin), n_runs) * np.tile(
        np.linspace(1.0, 1.2, per_bin), 3 * n_runs
    )
    return segments_data(velocity, np.repeat(np.arange(n_runs), 3 * per_bin), ANCHOR_IN_S)


def residuals_of(ln_zeta: np.ndarray, rel_f: np.ndarray, scatter=(0.01, 2e-5)) -> dict[str, np.ndarray]:
    """Residuals with the measured scatter ``scatter`` (of ``ln zeta`` and of the relative
    frequency: numbers, or arrays of one per segment)."""
    zeta_scatter, f_scatter = (np.broadcast_to(np.asarray(s, dtype=float), ln_zeta.shape) for s in scatter)
    return {
        "ln_zeta": ln_zeta,
        "rel_f": rel_f,
        "z_noise": ln_zeta / zeta_scatter,
        "f_noise": rel_f / f_scatter,
        "scatter_ln_zeta": zeta_scatter,
        "scatter_rel_f": f_scatter,
    }


def two_sensors(one: ConfigurationData) -> ConfigurationData:
    """The segments of ``one`` seen by two sensors: the same runs and amplitudes twice."""
    return segments_data(
        np.tile(one.velocity_in_s, 2),
        np.tile(one.run_index, 2),
        ANCHOR_IN_S,
        channel_index=np.repeat([0, 1], one.n),
    )


def test_a_bins_misfit_is_the_t_test_of_the_runs_means_at_the_bonferroni_limit():
    rng = np.random.default_rng(1)
    data = campaign(6)
    top = data.velocity_in_s > TOP_EDGE_IN_S
    # a 0.05 offset of ln zeta in the top half decade (2.5 x the models' accuracy), runs scatter 0.01
    ln_zeta = 0.01 * rng.standard_normal(data.n) + np.where(top, 0.05, 0.0)
    rel_f = 2e-5 * rng.standard_normal(data.n)
    rows = binned_discrepancy(data, residuals_of(ln_zeta, rel_f))
    assert len(rows) == 6  # three bins, two curves
    assert sorted(row["curve"] for row in rows) == ["damping"] * 3 + ["frequency"] * 3
    for row in rows:
        values, tolerance = (ln_zeta, TOL_LN_ZETA) if row["curve"] == "damping" else (rel_f, TOL_REL_F)
        in_bin = (data.velocity_in_s >= row["v_low_in_s"]) & (data.velocity_in_s <= row["v_high_in_s"])
        run_means = np.array([values[in_bin & (data.run_index == r)].mean() for r in range(6)])
        test = stats.ttest_1samp(run_means, 0.0)
        assert row["mean"] == pytest.approx(run_means.mean(), rel=1e-12)
        assert row["standard_error"] == pytest.approx(stats.sem(run_means), rel=1e-12)
        assert row["t"] == pytest.approx(test.statistic, rel=1e-10)
        assert row["p"] == pytest.approx(test.pvalue, rel=1e-8)
        assert row["p_limit"] == pytest.approx(ALPHA / 12)  # half of alpha over 6 tests
        assert (row["n_runs"], row["n_segments"]) == (6, 30)
        assert row["tolerance"] == tolerance
        assert row["run_ids"] == list(range(6))
        assert row["run_means"] == pytest.approx(run_means.tolist(), rel=1e-12)
        # the half decade's edges, cut to the measured amplitudes
        low, high = data.velocity_in_s[in_bin].min(), data.velocity_in_s[in_bin].max()
        edges = ANCHOR_IN_S * 10.0 ** (np.arange(-6, 1) / 2.0)
        assert row["v_low_in_s"] == pytest.approx(max(edges[edges <= low].max(), data.velocity_in_s.min()))
        assert row["v_high_in_s"] == pytest.approx(min(edges[edges >= high].min(), data.velocity_in_s.max()))
        assert row["mean_over_scatter"] == pytest.approx(
            run_means.mean() / (0.01 if tolerance == TOL_LN_ZETA else 2e-5)
        )
        assert row["significant"] == (row["curve"] == "damping" and row["v_high_in_s"] > 3.0)


def test_a_clear_misfit_smaller_than_the_models_accuracy_is_not_significant():
    """A 0.015 offset of ln zeta (below the 0.02 accuracy) measured to 1e-4: p far below its
    limit, yet no misfit of the model."""
    rng = np.random.default_rng(2)
    data = campaign(6)
    ln_zeta = 1e-4 * rng.standard_normal(data.n) + 0.015
    rows = binned_discrepancy(data, residuals_of(ln_zeta, np.zeros(data.n)))
    damping = [row for row in rows if row["curve"] == "damping"]
    assert all(row["p"] < 1e-10 and not row["significant"] for row in damping)


def test_a_bin_of_too_few_runs_is_not_judged():
    """The lowest half decade reached by two runs only: left out, the others tested on six."""
    data = campaign(6)
    low = data.velocity_in_s < 0.8
    reached = ~low | (data.run_index < MIN_BIN_RUNS - 1)
    data = segments_data(data.velocity_in_s[reached], data.run_index[reached], ANCHOR_IN_S)
    rng = np.random.default_rng(3)
    residuals = residuals_of(rng.standard_normal(data.n), rng.standard_normal(data.n))
    rows = binned_discrepancy(data, residuals)
    assert len(rows) == 4
    assert all(row["v_low_in_s"] >= 0.79 and row["n_runs"] == 6 for row in rows)
    assert [(b["v_low_in_s"] >= 0.79, b["n_runs"]) for b in explains_data(data, residuals)["bins"]] == [
        (True, 6)
    ] * 4
    assert bin_is_judged(MIN_BIN_RUNS, 1, 6) and not bin_is_judged(MIN_BIN_RUNS - 1, 100, 6)
    assert bin_is_judged(1, MIN_BIN_SEGMENTS_ONE_RUN, 1)
    assert not bin_is_judged(1, MIN_BIN_SEGMENTS_ONE_RUN - 1, 1)
    # two runs never make three: a two-run campaign's bins are not judged, however many segments
    assert not bin_is_judged(2, 40, 2)


def test_the_observations_of_a_bin_are_the_runs_means_or_one_runs_segments():
    values = np.array([1.0, 3.0, 10.0, 20.0, 7.0])
    in_bin = np.array([True, True, True, True, False])
    runs, means = bin_observations(values, np.array([0, 0, 2, 2, 1]), in_bin, 3)
    assert runs.tolist() == [0, 2] and means.tolist() == [2.0, 15.0]
    runs, means = bin_observations(values, np.array([0, 0, 1, 1, 1]), in_bin, 2)
    assert runs.tolist() == [0, 1] and means.tolist() == [2.0, 15.0]
    runs, segments = bin_observations(values, np.zeros(5, dtype=int), in_bin, 1)
    assert runs.tolist() == [0] and runs.dtype.kind == "i" and segments.tolist() == [1.0, 3.0, 10.0, 20.0]


def test_one_run_tests_its_segments_with_their_serial_correlation():
    """One run: the bin's segments in order of amplitude are the observations; independent
    ones (no lag-1 correlation) give the plain t test; correlated ones fewer effective
    observations, a smaller |t|."""
    data = campaign(1, per_bin=12)
    independent = np.resize([0.03, -0.01, 0.02, 0.0, 0.04, -0.02], data.n) + 0.01
    rows = binned_discrepancy(data, residuals_of(independent, np.zeros(data.n)))
    damping = [row for row in rows if row["curve"] == "damping"]
    for row in damping:
        in_bin = (data.velocity_in_s >= row["v_low_in_s"]) & (data.velocity_in_s <= row["v_high_in_s"])
        segments = independent[in_bin][np.argsort(data.velocity_in_s[in_bin])]
        c = segments - segments.mean()
        assert np.sum(c[1:] * c[:-1]) <= 0  # no positive lag-1 correlation: n_eff = n
        test = stats.ttest_1samp(segments, 0.0)
        assert row["t"] == pytest.approx(test.statistic, rel=1e-10)
        assert row["p"] == pytest.approx(test.pvalue, rel=1e-8)
        assert row["n_runs"] == 1 and "run_ids" not in row
    drifting = np.tile(np.linspace(0.0, 0.04, 12), 3)  # each bin's segments rise steadily
    correlated = binned_discrepancy(data, residuals_of(drifting, np.zeros(data.n)))[0]
    segments = drifting[:12]
    c = segments - segments.mean()
    rho = min(np.sum(c[1:] * c[:-1]) / np.sum(c * c), 0.95)
    n_eff = max(1.0, 12 * (1 - rho) / (1 + rho))  # AR(1)'s effective number
    t = segments.mean() / (segments.std(ddof=1) / np.sqrt(n_eff))
    assert correlated["t"] == pytest.approx(t, rel=1e-10)
    assert correlated["t"] < stats.ttest_1samp(segments, 0.0).statistic
    # at least one degree of freedom, however few effective observations
    assert correlated["p"] == pytest.approx(2 * stats.t.sf(t, max(n_eff - 1.0, 1.0)), rel=1e-8)
    assert n_eff < 2.0  # the ramp's lag-1 correlation 0.75: one degree of freedom, not fewer
    long = campaign(1, per_bin=100)
    ramp = np.tile(np.linspace(0.0, 0.04, 100), 3)  # lag-1 correlation 0.97, taken as 0.95
    row = binned_discrepancy(long, residuals_of(ramp, np.zeros(long.n)))[0]
    segments = ramp[:100]
    n_eff = 100 * 0.05 / 1.95
    assert row["t"] == pytest.approx(segments.mean() / (segments.std(ddof=1) / np.sqrt(n_eff)), rel=1e-10)
    assert row["p"] == pytest.approx(2 * stats.t.sf(row["t"], n_eff - 1.0), rel=1e-8)
    # four segments are enough for the lag-1 estimate (fewer count as independent)
    one_run = explains_data(data, residuals_of(drifting, np.zeros(data.n)))
    assert len(one_run["bins"]) == 6 and all(b["n_runs"] == 1 for b in one_run["bins"])
    few = campaign(1, per_bin=4)
    rising = np.tile([0.0, 0.01, 0.02, 0.03], 3) + 0.01
    row = binned_discrepancy(few, residuals_of(rising, np.zeros(few.n)))[0]
    assert row["t"] < stats.ttest_1samp(rising[:4], 0.0).statistic


def trend_campaign(n_runs: int, change_per_run: float, seed: int) -> tuple[ConfigurationData, dict]:
    rng = np.random.default_rng(seed)
    data = campaign(n_runs)
    ln_zeta = change_per_run * data.run_index + 0.002 * rng.standard_normal(data.n)
    return data, {"ln_zeta": ln_zeta}


def test_the_run_order_trend_is_the_least_squares_slope_of_the_runs_levels():
    """Without a shape, each run's level of ln zeta (amplitude-weighted mean) against its
    position: SciPy's linregress of those levels, its p at ``alpha / n_tests``, and the
    change over the sequence as slope x (runs - 1)."""
    data, residuals = trend_campaign(8, 0.01, seed=4)
    trend = run_order_trend(data, residuals, n_tests=2)
    # each run has as many segments in each quarter decade (one per group of amplitudes):
    # equal amplitude weights, its level the plain mean
    levels = np.array([residuals["ln_zeta"][data.run_index == r].mean() for r in range(8)])
    fit = stats.linregress(np.arange(8.0), levels)
    assert trend["slope_per_run"] == pytest.approx(fit.slope, rel=1e-9)
    assert trend["t"] == pytest.approx(fit.slope / fit.stderr, rel=1e-9)
    assert trend["p"] == pytest.approx(fit.pvalue, rel=1e-6)
    assert trend["p_limit"] == pytest.approx(ALPHA / 2)
    assert trend["change_over_sequence"] == pytest.approx(7 * fit.slope, rel=1e-9)
    assert trend["significant"]  # 0.07 over the sequence, 3.5 x the accuracy
    assert trend["runs"] == data.run_names and trend["run_ids"] == list(range(8))


def test_a_steady_change_within_the_models_accuracy_is_not_a_drift():
    data, residuals = trend_campaign(8, 0.002, seed=5)  # 0.014 over the sequence
    trend = run_order_trend(data, residuals, n_tests=2)
    assert trend["p"] < 1e-6 and not trend["significant"]


def test_no_run_order_trend_from_fewer_than_four_runs():
    data, residuals = trend_campaign(3, 0.05, seed=6)
    assert run_order_trend(data, residuals, n_tests=2) is None
    data, residuals = trend_campaign(4, 0.05, seed=6)
    assert run_order_trend(data, residuals, n_tests=2)["run_positions"] == [0.0, 1.0, 2.0, 3.0]


def test_a_trend_between_its_limit_and_a_looser_one_is_not_a_drift():
    """A change of 0.04 over the sequence (twice the accuracy) with p between the limit
    ``alpha / n_tests`` and ten times it: not significant."""
    rng = np.random.default_rng(8)
    data = campaign(8)
    ln_zeta = 0.04 / 7 * data.run_index + np.repeat(0.02 * rng.standard_normal(8), 15)
    trend = run_order_trend(data, {"ln_zeta": ln_zeta}, n_tests=2)
    assert trend["p_limit"] < trend["p"] < 10 * trend["p_limit"]
    assert abs(trend["change_over_sequence"]) > TOL_LN_ZETA
    assert not trend["significant"]


def test_the_trend_takes_the_calibrated_residual_weighted_by_its_variance_off_the_calibration():
    """Each run's projection is its weighted least-squares level of the calibrated residual
    (``ln_zeta_calibrated`` before ``ln_zeta_shared`` before ``ln_zeta``) on the friction
    limit's shape (``-ln_zeta_slope``), its calibration segments left out, every segment
    weighted by its amplitude weight over its variance; the change over the sequence is the
    slope times the runs' span times the shape's largest value."""
    from workflow.discovery.heldout import amplitude_weights

    rng = np.random.default_rng(9)
    data = campaign(8)
    slope = -np.log(data.velocity_in_s) * 0.05 - 0.02  # the damping's d ln(zeta) / d ln(Fc)
    calibration = data.velocity_in_s < 1.0
    scatter = np.where(data.velocity_in_s > TOP_EDGE_IN_S, 0.01, 0.05)
    calibrated = -slope * 0.03 * data.run_index + scatter * rng.standard_normal(data.n)
    calibrated = np.where(calibration, 5.0, calibrated)  # what the calibration segments hold is not used
    residuals = {
        "ln_zeta": np.full(data.n, 9.0),
        "ln_zeta_shared": np.full(data.n, 7.0),
        "ln_zeta_calibrated": calibrated,
        "calibration": calibration,
        "scatter_ln_zeta": scatter,
        "ln_zeta_slope": slope,
    }
    trend = run_order_trend(data, residuals, n_tests=2)
    w = amplitude_weights(data.velocity_in_s, ANCHOR_IN_S) * ~calibration / scatter**2
    shape = -slope
    levels = np.array(
        [
            np.sum((w * shape * calibrated)[data.run_index == r])
            / np.sum((w * shape * shape)[data.run_index == r])
            for r in range(8)
        ]
    )
    assert trend["run_projections"] == pytest.approx(levels.tolist(), rel=1e-10)
    fit = stats.linregress(np.arange(8.0), levels)
    assert trend["slope_per_run"] == pytest.approx(fit.slope, rel=1e-9)
    assert abs(trend["slope_per_run"] - 0.03) < 3.0 * fit.stderr  # the injected drift of ln Fc
    largest = shape[~calibration][np.argmax(np.abs(shape[~calibration]))]
    assert trend["largest_shape"] == pytest.approx(largest)
    assert trend["change_over_sequence"] == pytest.approx(fit.slope * 7 * largest, rel=1e-9)
    assert trend["order"] == data.run_order
    # without a calibrated residual the shared one, without it the plain one
    shared = {k: v for k, v in residuals.items() if k != "ln_zeta_calibrated"}
    shared["ln_zeta_shared"] = calibrated
    assert run_order_trend(data, shared, n_tests=2)["run_projections"] == pytest.approx(
        levels.tolist(), rel=1e-10
    )
    plain = {k: v for k, v in shared.items() if k != "ln_zeta_shared"}
    plain["ln_zeta"] = calibrated
    assert run_order_trend(data, plain, n_tests=2)["run_projections"] == pytest.approx(
        levels.tolist(), rel=1e-10
    )


def test_a_damping_curve_flatter_than_the_accuracy_gives_no_shape():
    """Where the model's damping moves by less than the models' accuracy over the scored
    amplitudes, the projection is the runs' plain weighted level."""
    data, residuals = trend_campaign(8, 0.01, seed=10)
    flat = {
        **residuals,
        "ln_zeta_slope": np.full(data.n, 0.9 * TOL_LN_ZETA / np.ptp(np.log(data.velocity_in_s))),
    }
    steep = {
        **residuals,
        "ln_zeta_slope": np.full(data.n, 2.0 * TOL_LN_ZETA / np.ptp(np.log(data.velocity_in_s))),
    }
    level = run_order_trend(data, residuals, n_tests=2)
    assert run_order_trend(data, flat, n_tests=2)["run_projections"] == pytest.approx(
        level["run_projections"]
    )
    assert run_order_trend(data, flat, n_tests=2)["largest_shape"] == 1.0
    shaped = run_order_trend(data, steep, n_tests=2)
    # a constant shape -s: the projection is the level over -s
    s = 2.0 * TOL_LN_ZETA / np.ptp(np.log(data.velocity_in_s))
    assert shaped["run_projections"] == pytest.approx([-y / s for y in level["run_projections"]], rel=1e-9)
    assert shaped["largest_shape"] == pytest.approx(-s)


def test_explains_data_is_every_judged_bin_within_two_scatters():
    """Binned means of ``z_noise``/``f_noise`` within 2 measured scatters everywhere: true;
    one half decade 2.5 scatters off on the damping: false, and that bin is named."""
    data = campaign(6)
    rng = np.random.default_rng(7)
    ln_zeta, rel_f = 0.002 * rng.standard_normal(data.n), 4e-6 * rng.standard_normal(data.n)
    assert explains_data(data, residuals_of(ln_zeta, rel_f))["explains_data"]
    top = data.velocity_in_s > TOP_EDGE_IN_S
    off = explains_data(data, residuals_of(ln_zeta + np.where(top, 0.025, 0.0), rel_f))
    assert not off["explains_data"]
    (failing,) = off["failing_bins"]
    assert failing["curve"] == "damping" and failing["v_high_in_s"] > 3.0
    assert failing["mean_over_scatter"] == pytest.approx(2.5, abs=0.1)
    assert (failing["n_runs"], failing["n_segments"]) == (6, 30)
    assert off["worst"] == failing and len(off["bins"]) == 6 and off["limit"] == 2.0
    # several failing bins: by curve, then amplitude
    low = data.velocity_in_s < 1.0
    many = explains_data(
        data,
        residuals_of(ln_zeta + np.where(top | low, 0.025, 0.0), rel_f + np.where(low, -1e-4, 0.0)),
    )
    order = [(b["curve"], b["v_low_in_s"] < 1.0) for b in many["failing_bins"]]
    assert order == [("damping", True), ("damping", False), ("frequency", True)]
    assert many["worst"]["curve"] == "frequency"  # 5 scatters
    # two runs: no half decade is judged, nothing fails, no worst bin
    two = campaign(2)
    none = explains_data(two, residuals_of(np.full(two.n, 0.1), np.zeros(two.n)))
    assert none == {"explains_data": True, "limit": 2.0, "bins": [], "worst": None, "failing_bins": []}


def test_a_run_without_scored_segments_is_no_point_of_the_trend_and_the_shape_is_the_scored_ones():
    """A run whose segments all calibrate it (none scored) is left out of the trend; the
    shape's largest value is taken over the scored segments only."""
    rng = np.random.default_rng(11)
    data = campaign(8)
    calibration = (data.velocity_in_s < 0.8) | (data.run_index == 3)
    slope = -0.08 / data.velocity_in_s  # the shape 0.08 / V: largest at the calibration's amplitudes
    residuals = {
        "ln_zeta_calibrated": 0.08 / data.velocity_in_s * 0.03 * data.run_index
        + 0.01 * rng.standard_normal(data.n),
        "ln_zeta": np.zeros(data.n),
        "calibration": calibration,
        "ln_zeta_slope": slope,
    }
    trend = run_order_trend(data, residuals, n_tests=2)
    assert trend["run_ids"] == [0, 1, 2, 4, 5, 6, 7]
    assert trend["run_positions"] == [0.0, 1.0, 2.0, 4.0, 5.0, 6.0, 7.0]
    assert trend["largest_shape"] == pytest.approx(0.08 / data.velocity_in_s[~calibration].min())


def test_the_data_rule_out_a_departure_as_far_as_their_standard_errors_allow():
    """Per bin, the probability that the true mean residual is within the models' accuracy
    (Student t around the bin's mean): 2 Phi(1) - 1 for a standard error of one accuracy
    (many degrees of freedom), 1/2 for a mean at the accuracy measured exactly; independent
    bins multiply; a bin without a standard error says nothing."""
    row = {"mean": 0.0, "standard_error": TOL_LN_ZETA, "tolerance": TOL_LN_ZETA, "degrees_of_freedom": 1e9}
    one_sigma = 2.0 * stats.norm.cdf(1.0) - 1.0
    assert departure_ruled_out([row]) == pytest.approx(one_sigma, rel=1e-9)
    assert departure_ruled_out([row, row]) == pytest.approx(one_sigma**2, rel=1e-9)
    at_limit = {**row, "mean": TOL_LN_ZETA, "standard_error": 1e-9 * TOL_LN_ZETA}
    assert departure_ruled_out([at_limit]) == pytest.approx(0.5, rel=1e-9)
    assert departure_ruled_out([{**row, "standard_error": float("nan")}]) == 1.0
    few_runs = {**row, "degrees_of_freedom": 2.0}
    assert departure_ruled_out([few_runs]) == pytest.approx(
        stats.t.cdf(1.0, 2) - stats.t.cdf(-1.0, 2), rel=1e-9
    )


def test_a_noisy_sensor_rules_out_less_than_a_quiet_one():
    """The same campaign without misfit (six runs, five segments per half decade) seen with
    a scatter of a tenth of the models' accuracy and of five times it: the quiet data rule a
    departure out (each bin's standard error ~0.02 accuracy), the noisy ones cannot (~0.9
    accuracy per bin, six bins). The bins carry their degrees of freedom (runs - 1)."""
    data = campaign(6)
    rng = np.random.default_rng(7)
    noise = rng.standard_normal((2, data.n))
    quiet = binned_discrepancy(data, residuals_of(0.1 * TOL_LN_ZETA * noise[0], 0.1 * TOL_REL_F * noise[1]))
    noisy = binned_discrepancy(data, residuals_of(5.0 * TOL_LN_ZETA * noise[0], 5.0 * TOL_REL_F * noise[1]))
    assert all(row["degrees_of_freedom"] == 5.0 for row in quiet + noisy)
    assert departure_ruled_out(quiet) > 0.999
    assert departure_ruled_out(noisy) < 0.2


def test_pooled_sensors_rule_out_what_their_quietest_sensor_rules_out():
    """Two sensors of the same runs pooled, one with a tenth of the models' accuracy as
    scatter and one with five times it: the damping and frequency are the mode's, so the
    quiet sensor's power stands for both. The bins' run means weigh each sensor by its
    inverse variance, so they rule out about as much as the quiet sensor alone; the
    plain mean of the pooled segments, the noisy sensor's spread in every run's mean,
    rules out less than 0.9."""
    one = campaign(6)
    rng = np.random.default_rng(9)
    noise = rng.standard_normal((2, 2, one.n))
    scales = (0.1, 5.0)
    pooled = two_sensors(one)
    ln_zeta = np.concatenate([s * TOL_LN_ZETA * noise[i, 0] for i, s in enumerate(scales)])
    rel_f = np.concatenate([s * TOL_REL_F * noise[i, 1] for i, s in enumerate(scales)])
    scatter = (np.repeat(scales, one.n) * TOL_LN_ZETA, np.repeat(scales, one.n) * TOL_REL_F)
    quiet_alone = residuals_of(
        ln_zeta[: one.n], rel_f[: one.n], (scales[0] * TOL_LN_ZETA, scales[0] * TOL_REL_F)
    )
    quiet = departure_ruled_out(binned_discrepancy(one, quiet_alone))
    assert quiet > 0.999
    pooled_residuals = residuals_of(ln_zeta, rel_f, scatter)
    pooled_bins = binned_discrepancy(pooled, pooled_residuals)
    assert departure_ruled_out(pooled_bins) > 0.99
    unweighted = binned_discrepancy(replace(pooled, channel_index=None), pooled_residuals)
    assert departure_ruled_out(unweighted) < 0.9
    assert departure_ruled_out_by_channels(pooled, pooled_residuals, pooled_bins) == pytest.approx(
        quiet, rel=1e-12
    )
    assert departure_ruled_out_by_channels(one, quiet_alone, binned_discrepancy(one, quiet_alone)) == quiet


def test_pooled_sensors_bin_means_weigh_each_sensor_by_its_inverse_variance():
    """Per run, each sensor's plain mean in the bin, weighted by its segments' count squared
    over their summed variances; one sensor alone gives the run means unchanged."""
    values = np.array([1.0, 3.0, 10.0, 20.0, 5.0, 7.0])
    variances = np.array([1.0, 1.0, 4.0, 4.0, 1.0, 9.0])
    runs = np.array([0, 0, 0, 0, 1, 1])
    channels = np.array([0, 0, 1, 1, 0, 1])
    in_bin = np.ones(6, dtype=bool)
    ids, means = channel_weighted_observations(values, variances, runs, channels, in_bin, 2)
    # run 0: means 2 and 15, variances 2/4 and 8/4; run 1: 5 and 7, variances 1 and 9
    assert ids.tolist() == [0, 1]
    assert means == pytest.approx(
        [(2.0 / 0.5 + 15.0 / 2.0) / (1 / 0.5 + 1 / 2.0), (5.0 + 7.0 / 9.0) / (1 + 1 / 9.0)]
    )
    same = np.zeros(6, dtype=int)
    ids, alone = channel_weighted_observations(values, variances, runs, same, in_bin, 2)
    assert alone == pytest.approx(bin_observations(values, runs, in_bin, 2)[1], rel=1e-14)


def test_a_node_sensors_noise_floor_skew_is_no_misfit_of_the_pooled_bins():
    """A sensor near a node of the mode: its log decrements scatter 15 times the models'
    accuracy and its noise floor shifts their mean by 6 accuracies in every run, while the
    reference sensor beside it reads the model to a tenth of the accuracy (100 segments of
    each per run and half decade, as a real hit gives). Pooled, the bins weigh each sensor
    by what it knows: no misfit, where their plain mean (the node sensor's shift over two,
    measured to a quarter of an accuracy) is a significant one in every bin; a real
    departure of 2.5 accuracies in the top half decade, seen by both, is still found."""
    one = campaign(8, per_bin=100)
    pooled = two_sensors(one)
    rng = np.random.default_rng(11)
    quiet = 0.1 * TOL_LN_ZETA * rng.standard_normal(one.n)
    node = -6.0 * TOL_LN_ZETA + 15.0 * TOL_LN_ZETA * rng.standard_normal(one.n)
    scatter = (np.repeat([0.1, 15.0], one.n) * TOL_LN_ZETA, np.full(pooled.n, 2e-5))
    rel_f = 2e-5 * rng.standard_normal(pooled.n)
    residuals = residuals_of(np.concatenate([quiet, node]), rel_f, scatter)
    damping = [row for row in binned_discrepancy(pooled, residuals) if row["curve"] == "damping"]
    assert not any(row["significant"] for row in damping)
    assert all(abs(row["mean"]) < TOL_LN_ZETA for row in damping)
    plain = binned_discrepancy(replace(pooled, channel_index=None), residuals)
    assert all(row["significant"] for row in plain if row["curve"] == "damping")
    top = np.tile(one.velocity_in_s > TOP_EDGE_IN_S, 2)
    departed = residuals_of(
        np.concatenate([quiet, node]) + np.where(top, 2.5 * TOL_LN_ZETA, 0.0), rel_f, scatter
    )
    found = [row for row in binned_discrepancy(pooled, departed) if row["significant"]]
    assert [(row["curve"], row["v_high_in_s"] > TOP_EDGE_IN_S) for row in found] == [("damping", True)]

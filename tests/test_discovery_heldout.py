"""Held-out statistics (workflow/discovery/heldout.py) on cases whose answer is known: the
folds, the amplitude bins and weights, the effective observations, the information
criterion, the units of evidence and the standard error of a ratio estimator."""

from __future__ import annotations

import numpy as np
import pytest
from support.discovery import segments_data

from workflow.discovery.heldout import (
    MIN_BIN_SEGMENTS,
    amplitude_bin,
    amplitude_blocks,
    amplitude_weights,
    effective_observations,
    folds_of,
    heldout_scales,
    heldout_standard_error,
    heldout_units,
    information_criterion,
    weighted_rms,
)
from workflow.models.configuration_data import ConfigurationData, Scatter


def data_of(velocity_in_s, run_index, anchor_in_s=10.0, channel_index=None) -> ConfigurationData:
    return segments_data(velocity_in_s, run_index, anchor_in_s, channel_index)


def test_folds_hold_out_whole_runs_spread_over_the_run_order():
    data = data_of(np.geomspace(0.1, 10.0, 40), np.repeat(np.arange(8), 5))
    folds = folds_of(data, 3)
    assert len(folds) == 3
    for j, fold in enumerate(folds):
        assert sorted(set(data.run_index[fold].tolist())) == [r for r in range(8) if r % 3 == j]
    np.testing.assert_array_equal(np.sum(folds, axis=0), 1)  # every segment held out once
    assert len(folds_of(data_of(np.ones(6), np.repeat([0, 1, 2], 2)), 5)) == 3  # no more folds than runs
    two_runs = folds_of(data_of([9.0, 1.0, 5.0, 0.5], np.array([0, 0, 1, 1])), 5)  # two runs: two folds
    assert [fold.tolist() for fold in two_runs] == [[True, True, False, False], [False, False, True, True]]


QUARTER_DECADES = {9.0: 2, 4.0: 5, 2.5: 8, 1.5: 3, 0.8: 3, 0.4: 1}
"""Segments of one hit in six quarter decades below a 10 in/s anchor (5.6-10, 3.2-5.6,
1.8-3.2, 1-1.8, 0.56-1, 0.32-0.56 in/s)."""


def one_hit(counts=QUARTER_DECADES, channels=1, seed=1) -> ConfigurationData:
    velocity = np.repeat(list(counts), [n * channels for n in counts.values()])
    order = np.random.default_rng(seed).permutation(velocity.size)
    return data_of(
        velocity[order], np.zeros(velocity.size, dtype=int), channel_index=np.arange(velocity.size) % channels
    )


def test_one_hit_is_held_out_by_quarter_decades_merged_down_to_six_instants():
    """The top quarter decade (2 segments) joins the next (7), 8 stand alone, 3 + 3 make
    six, and the last one joins them: three contiguous blocks, the top one first."""
    data = one_hit()
    block = amplitude_blocks(data)
    expected = {9.0: 0, 4.0: 0, 2.5: 1, 1.5: 2, 0.8: 2, 0.4: 2}
    np.testing.assert_array_equal(block, [expected[v] for v in data.velocity_in_s])
    folds = folds_of(data, 5)  # the folds over runs do not set the blocks
    assert [f.tolist() for f in folds] == [(block == j).tolist() for j in range(3)]
    np.testing.assert_array_equal(heldout_units(data), block)
    # two channels: the same instants, the same blocks (twelve segments are six instants)
    two = one_hit(channels=2)
    np.testing.assert_array_equal(amplitude_blocks(two), [expected[v] for v in two.velocity_in_s])


def test_a_block_closes_on_the_instants_of_the_channel_that_has_most():
    """Two channels at the top quarter decade, one with 6 segments, the other with 5 (one
    lost to its noise): six instants of the hit, a block of its own."""
    velocity = np.array([9.0] * 11 + [4.0] * 14)
    channel = np.array([0] * 6 + [1] * 5 + [0, 1] * 7)
    data = data_of(velocity, np.zeros(velocity.size, dtype=int), channel_index=channel)
    np.testing.assert_array_equal(amplitude_blocks(data), (velocity < 5.0).astype(int))


def test_one_hit_within_one_block_is_split_at_its_median():
    data = one_hit({9.0: 3, 8.0: 2, 7.0: 2})
    folds = folds_of(data, 5)
    assert len(folds) == 2
    assert data.velocity_in_s[folds[1]].max() < data.velocity_in_s[folds[0]].min()


def test_amplitude_bins_count_down_from_the_anchor_which_tops_the_first():
    anchor = 8.0
    edges = anchor * 10.0 ** (-np.arange(4) / 2.0)  # 8, 2.53, 0.8, 0.253
    just_below = edges * (1 - 1e-6)
    assert amplitude_bin(edges, anchor, 2).tolist() == [-1, -2, -3, -4]  # an edge tops its bin
    assert amplitude_bin(just_below, anchor, 2).tolist() == [-1, -2, -3, -4]
    assert amplitude_bin(edges[1:] * (1 + 1e-6), anchor, 2).tolist() == [-1, -2, -3]
    assert amplitude_bin(np.array([8.0, 6.0, 4.4]), anchor, 4).tolist() == [-1, -1, -2]


def test_every_occupied_quarter_decade_has_the_same_say_and_a_sparse_one_less():
    """Bins of 120 and 60 segments carry equal total weight; one of 10 segments carries
    10 / MIN_BIN_SEGMENTS of it; pooled channels raise the floor by their number."""
    velocity = np.concatenate(
        [np.full(120, 9.0), np.full(60, 4.0), np.full(10, 2.0)]
    )  # three quarter decades
    w = amplitude_weights(velocity, 10.0)
    totals = [w[velocity == v].sum() for v in (9.0, 4.0, 2.0)]
    assert totals[0] == pytest.approx(1.0) and totals[1] == pytest.approx(1.0)
    assert totals[2] == pytest.approx(10 / MIN_BIN_SEGMENTS)
    w2 = amplitude_weights(velocity, 10.0, channels=2)
    assert w2[velocity == 9.0].sum() == pytest.approx(1.0)
    assert w2[velocity == 4.0].sum() == pytest.approx(60 / (2 * MIN_BIN_SEGMENTS))


def test_weighted_rms():
    assert weighted_rms(np.array([1.0, 9.0]), np.array([3.0, 1.0])) == pytest.approx(np.sqrt(12.0 / 4.0))
    assert weighted_rms(np.array([4.0]), np.array([0.0])) == 0.0
    assert weighted_rms(np.array([1.0, 9.0]), np.array([0.3, 0.1])) == pytest.approx(np.sqrt(12.0 / 4.0))


def test_effective_observations_are_two_per_occupied_run_and_half_decade():
    # run 0 in two half decades (9 and 4 share one), run 1 in one: three cells
    data = data_of([9.0, 4.0, 2.0, 9.5], [0, 0, 0, 1])
    assert effective_observations(data) == 6
    assert effective_observations(data_of([9.0, 8.5], [0, 0])) == 4  # at least two cells


def test_information_criterion_is_bic_on_the_normalised_residuals():
    assert information_criterion(0.5, 3, 20) == pytest.approx(20 * np.log(0.5) + 3 * np.log(20))
    assert information_criterion(0.0, 1, 10) == pytest.approx(10 * np.log(1e-300) + np.log(10))


def test_units_are_runs_with_several_runs():
    runs = data_of([9.0, 2.0, 9.0], [0, 0, 1])
    np.testing.assert_array_equal(heldout_units(runs), [0, 0, 1])


def test_the_standard_error_of_a_ratio_estimator():
    """``E^2 = sum S / sum W``; to first order its variance is ``n/(n-1) sum (S - E^2
    W)^2 / W^2`` over the units (the delta method for a ratio of sums); units without
    weight are no units; fewer than two units give none."""
    squares = np.array([1.0, 3.0, 2.5, 0.5])
    weights = np.array([1.0, 2.0, 1.5, 0.5])
    ratio = squares.sum() / weights.sum()
    variance = 4 / 3 * np.sum((squares - ratio * weights) ** 2) / weights.sum() ** 2
    assert heldout_standard_error(squares, weights) == pytest.approx(np.sqrt(variance), rel=1e-12)
    assert heldout_standard_error(np.append(squares, 99.0), np.append(weights, 0.0)) == pytest.approx(
        np.sqrt(variance), rel=1e-12
    )
    assert heldout_standard_error(squares[:1], weights[:1]) == 0.0
    two = 2 * np.sum((squares[:2] - squares[:2].sum() / 3.0 * weights[:2]) ** 2) / 3.0**2
    assert heldout_standard_error(squares[:2], weights[:2]) == pytest.approx(np.sqrt(two), rel=1e-12)
    # weights in other units (a tenth): the same error, the same standard error
    assert heldout_standard_error(0.1 * squares, 0.1 * weights) == pytest.approx(np.sqrt(variance), rel=1e-12)
    assert heldout_standard_error(squares, np.zeros(4)) == 0.0


def test_held_out_residuals_are_scored_in_the_scatter_and_the_offsets_uncertainty():
    scatter = Scatter(np.full(2, 0.1), np.full(2, 1e-4), np.array([0.03, 0.04]), np.array([3e-5, 4e-5]))
    residuals = {
        "offset_variance_ln_zeta": np.array([0.04**2, 0.03**2]),
        "offset_variance_rel_f": np.array([4e-5**2, 0.0]),
    }
    ln_zeta, rel_f = heldout_scales(residuals, scatter)
    np.testing.assert_allclose(ln_zeta, [0.05, 0.05])
    np.testing.assert_allclose(rel_f, [5e-5, 4e-5])


def test_a_held_out_run_is_scored_up_to_a_quarter_decade_above_the_runs_it_is_predicted_from():
    """Three runs to 1, 2 and 8 in/s: held out, the third is predicted from runs that reach
    2 in/s, so its segments above 2 x 10^(1/4) = 3.56 in/s measure an extrapolation and are
    not scored; the others reach below the rest's top. Each channel on its own scale: a
    second channel seeing the same run at a tenth is judged against its own runs."""
    from workflow.discovery.heldout import beyond_reach

    velocity = np.concatenate(
        [np.geomspace(1.0, 0.1, 10), np.geomspace(2.0, 0.1, 10), np.geomspace(8.0, 0.1, 10)]
    )
    run = np.repeat([0, 1, 2], 10)
    data = data_of(velocity, run)
    held = run == 2
    expected = held & (velocity > 2.0 * 10**0.25)
    np.testing.assert_array_equal(beyond_reach(data, held), expected)
    assert not beyond_reach(data, run == 1).any() and not beyond_reach(data, run == 0).any()
    pooled = data_of(
        np.concatenate([velocity, 0.1 * velocity]), np.tile(run, 2), channel_index=np.repeat([0, 1], 30)
    )
    np.testing.assert_array_equal(beyond_reach(pooled, np.tile(held, 2)), np.tile(expected, 2))

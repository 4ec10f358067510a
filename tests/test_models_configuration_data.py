"""The measured curves' uncertainties: the mean bias of noisy segments' ln zeta."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from workflow.models.configuration_data import (
    ConfigurationData,
    log_damping_bias,
    mean_unbiased_damping,
    prepare_configuration,
    scatter_of,
)


@pytest.mark.parametrize("spread", [0.005, 0.02, 0.05])
def test_small_noise_lowers_the_mean_log_by_half_its_variance(spread):
    """``E[ln(1 + r z)] = -r^2/2 - 3 r^4/4 - ...`` and the robust spread is ``r`` to the
    same order: within 2 % of ``-spread^2 / 2`` up to a spread of 0.05 (the next term is
    ``1.5 r^2`` of it, 0.4 %)."""
    bias = float(log_damping_bias(np.array([spread]))[0])
    assert bias == pytest.approx(-0.5 * spread**2, rel=0.02)


@pytest.mark.parametrize("relative_noise", [0.15, 0.3, 0.45])
def test_the_bias_is_the_mean_of_sampled_logs_at_their_measured_spread(relative_noise):
    """Damping estimates with a Gaussian relative error, the non-positive ones dropped as
    prepare_configuration drops them: the bias read at their logarithms' robust spread is
    their logarithms' mean, within 4 standard errors of a million draws (plus the spread's
    own sampling error times the bias's slope, a tenth of that)."""
    rng = np.random.default_rng(11)
    estimates = 1.0 + relative_noise * rng.standard_normal(1_000_000)
    logs = np.log(estimates[estimates > 0.0])
    spread = 1.4826 * np.median(np.abs(logs - np.median(logs)))
    standard_error = logs.std() / np.sqrt(logs.size)
    assert float(log_damping_bias(np.array([spread]))[0]) == pytest.approx(
        logs.mean(), abs=4.4 * standard_error
    )


def test_noisy_low_amplitudes_show_no_damping_trend_once_the_bias_is_removed():
    """A constant damping measured with a relative error growing from 2 % at the top to
    40 % at the lowest amplitudes (a sensor near a node of the mode): the lowest decade's
    mean ln zeta lies 0.09 below the truth, 7 standard errors, which a mean-based fit
    reads as damping rising with amplitude; with the bias the data's own scatter implies
    removed, it lies within 3 standard errors of the truth."""
    rng = np.random.default_rng(3)
    n = 8000
    velocity = 10.0 ** rng.uniform(-2.0, 0.0, n)
    relative_noise = 0.02 + 0.38 * (-np.log10(velocity) / 2.0) ** 2
    zeta = 0.002 * (1.0 + relative_noise * rng.standard_normal(n))
    kept = zeta > 0
    data = ConfigurationData(
        name="node",
        velocity_in_s=velocity[kept],
        zeta=zeta[kept],
        frequency_hz=np.full(kept.sum(), 100.0),
        run_index=np.zeros(kept.sum(), dtype=int),
        run_names=["r1"],
        bearing_area_in2=0.5,
    )
    unbiased = mean_unbiased_damping(data, scatter_of(data))
    lowest = data.velocity_in_s < 0.02
    for curve, expected_below in ((data, True), (unbiased, False)):
        residual = np.log(curve.zeta[lowest] / 0.002)
        standard_error = residual.std() / np.sqrt(residual.size)
        if expected_below:
            assert residual.mean() < -5.0 * standard_error
        else:
            assert abs(residual.mean()) < 3.0 * standard_error
    top = data.velocity_in_s > 0.5
    np.testing.assert_allclose(unbiased.zeta[top], data.zeta[top], rtol=1e-3)


def test_the_segments_quantity_column_gives_each_segment_its_response_order():
    frame = pd.DataFrame(
        {
            "configuration": "c",
            "run": ["r1"] * 6,
            "channel": ["acc1", "laser", "acc1", "laser", "acc2", "acc1"],
            "response_quantity": ["acceleration", "velocity"] * 2 + ["acceleration"] * 2,
            "velocity_amplitude_in_s": [1.0, 0.9, 0.5, 0.45, 0.3, 0.2],
            "zeta": [0.003, 0.003, -0.001, 0.002, 0.002, 0.002],
            "frequency_hz": 100.0,
        }
    )
    data = prepare_configuration(frame, "c", response_order=0)
    # the growing envelope's row is dropped with its order
    assert data.response_order.tolist() == [2, 1, 1, 2, 2]
    assert data.grid_response_order == 2
    one = prepare_configuration(frame.assign(response_quantity="velocity"), "c", response_order=0)
    assert (one.response_order, one.grid_response_order) == (1, 1)
    assert prepare_configuration(frame.drop(columns="response_quantity"), "c", 0).response_order == 0

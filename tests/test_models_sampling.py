"""The fits' scrambled Sobol points are SciPy's, to the bit."""

import warnings

import numpy as np
import pytest
from scipy.stats import qmc

from workflow.models.averaged import MODELS
from workflow.models.sampling import (
    BITS,
    MAX_DIMENSIONS,
    direction_numbers,
    scrambled_sobol_points,
    sobol_integers,
)


def scipy_points(count: int, dimensions: int, seed: int) -> np.ndarray:
    """The reference: the engine and call the fits used before they had their own points."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # SciPy's warnings on a count not a power of two
        return qmc.Sobol(dimensions, scramble=True, seed=seed).random(count)


@pytest.mark.parametrize("dimensions", [1, 2, 4, 9, 14, MAX_DIMENSIONS])
@pytest.mark.parametrize("seed", [0, 1976, 2**31 - 1])
def test_the_points_are_scipys_scrambled_sobol_points_to_the_bit(dimensions, seed):
    for count in (1, 2, 3, 256, 1024):
        np.testing.assert_array_equal(
            scrambled_sobol_points(count, dimensions, seed), scipy_points(count, dimensions, seed)
        )


def test_unscrambled_direction_numbers_give_scipys_unscrambled_sequence():
    integers = sobol_integers(direction_numbers(MAX_DIMENSIONS), 512)
    reference = qmc.Sobol(MAX_DIMENSIONS, scramble=False).random(512)
    np.testing.assert_array_equal(integers.astype(float) * 2.0**-BITS, reference)


def test_the_first_256_points_are_stratified_on_every_axis():
    points = scrambled_sobol_points(256, 8, seed=1976)
    assert np.all((points >= 0.0) & (points < 1.0))
    for axis in points.T:  # a (0, 8)-net in every dimension: one point in each 1/256
        assert np.array_equal(np.sort(np.floor(axis * 256)), np.arange(256.0))


def test_every_averaged_model_has_few_enough_parameters():
    # the most parameters: the Iwan joint with the most slip-threshold cells
    assert max(len(model.params) for model in MODELS.values()) <= MAX_DIMENSIONS


def test_out_of_range_requests_are_refused():
    with pytest.raises(ValueError, match="dimensions must be 1 to"):
        scrambled_sobol_points(8, MAX_DIMENSIONS + 1, seed=0)
    with pytest.raises(ValueError, match="count must be"):
        scrambled_sobol_points(0, 2, seed=0)

"""Scrambled Sobol points in the unit box, for the global stage of the fits.

The fits (:func:`workflow.models.averaged_fit.fit_model`,
:func:`workflow.models.fitting.fit_friction_model`) evaluate a model on a few hundred
parameter sets spread over their box and refine the best ones locally. The points are
the first points of a Sobol sequence (Joe and Kuo's direction numbers, Bratley and Fox's
recurrence, Gray-code order) scrambled as ``scipy.stats.qmc.Sobol(d, scramble=True,
seed=seed)`` scrambles it: a random lower-triangular linear matrix scramble of every
coordinate's bits and a random digital shift, their bits drawn in that order from
``numpy.random.default_rng(seed)``. The points are SciPy's to the bit (tested), so the
fits are the same; importing ``scipy.stats`` for them cost each fitting job half a
second of CPU.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "BITS",
    "DIRECTION_POLYNOMIALS",
    "MAX_DIMENSIONS",
    "direction_numbers",
    "sobol_integers",
    "scrambled_sobol_points",
]


BITS = 30
"""Bits of every coordinate (SciPy's default): resolution ``2^-30``, up to ``2^30`` points."""

DIRECTION_POLYNOMIALS = (
    (1, 0, (1,)),
    (2, 1, (1, 3)),
    (3, 1, (1, 3, 1)),
    (3, 2, (1, 1, 1)),
    (4, 1, (1, 1, 3, 3)),
    (4, 4, (1, 3, 5, 13)),
    (5, 2, (1, 1, 5, 5, 17)),
    (5, 4, (1, 1, 5, 5, 5)),
    (5, 7, (1, 1, 7, 11, 19)),
    (5, 11, (1, 1, 5, 1, 1)),
    (5, 13, (1, 1, 1, 3, 11)),
    (5, 14, (1, 3, 5, 5, 31)),
    (6, 1, (1, 3, 3, 9, 7, 49)),
    (6, 13, (1, 1, 1, 15, 21, 21)),
    (6, 16, (1, 3, 1, 13, 27, 49)),
    (6, 19, (1, 1, 1, 15, 7, 5)),
    (6, 22, (1, 3, 1, 15, 13, 25)),
    (6, 25, (1, 1, 5, 5, 19, 61)),
    (7, 1, (1, 3, 7, 11, 23, 15, 103)),
    (7, 4, (1, 3, 7, 13, 13, 15, 69)),
    (7, 7, (1, 1, 3, 13, 7, 35, 63)),
    (7, 8, (1, 3, 5, 9, 1, 25, 53)),
    (7, 14, (1, 3, 1, 13, 9, 35, 107)),
    (7, 19, (1, 3, 1, 5, 27, 61, 31)),
    (7, 21, (1, 1, 5, 11, 19, 41, 61)),
    (7, 28, (1, 3, 5, 3, 3, 13, 69)),
    (7, 31, (1, 1, 7, 13, 1, 19, 1)),
)
"""Dimensions 2, 3, ... (Joe and Kuo's table ``new-joe-kuo-6.21201``): degree ``s`` of the
primitive polynomial over GF(2), its inner coefficients ``a`` (bits ``a_1 .. a_(s-1)``,
``a_1`` the highest) and the initial direction integers ``m_1 .. m_s``. The first
dimension is the van der Corput sequence in base 2."""

MAX_DIMENSIONS = len(DIRECTION_POLYNOMIALS) + 1


def direction_numbers(dimensions: int) -> np.ndarray:
    """Unscrambled direction numbers ``v_(j,k) = m_(j,k) 2^(BITS-1-k)``, k = 0 .. BITS-1.

    ``m_k = 2 a_1 m_(k-1) ^ 4 a_2 m_(k-2) ^ ... ^ 2^s m_(k-s) ^ m_(k-s)`` beyond the
    initial ones (``^``: exclusive or).

    Returns
    -------
    ndarray of uint64, shape (dimensions, BITS)
    """
    if not 1 <= dimensions <= MAX_DIMENSIONS:
        raise ValueError(f"Sobol points: dimensions must be 1 to {MAX_DIMENSIONS}, got {dimensions}")
    m = np.ones((dimensions, BITS), dtype=np.uint64)
    for j, (degree, inner, initial) in enumerate(DIRECTION_POLYNOMIALS[: dimensions - 1], start=1):
        row = list(initial)
        for k in range(degree, BITS):
            new = row[k - degree] ^ (row[k - degree] << degree)
            for i in range(1, degree):
                if (inner >> (degree - 1 - i)) & 1:
                    new ^= row[k - i] << i
            row.append(new)
        m[j] = row
    return m << (BITS - 1 - np.arange(BITS, dtype=np.uint64))


def _bit_columns(values: np.ndarray) -> np.ndarray:
    """Bits of ``values`` along a new last axis, the highest (``2^(BITS-1)``) first."""
    return (values[..., None] >> (BITS - 1 - np.arange(BITS, dtype=np.uint64))) & np.uint64(1)


def sobol_integers(directions: np.ndarray, count: int) -> np.ndarray:
    """The first ``count`` points of a Sobol sequence as integers in ``[0, 2^BITS)``: point
    ``i`` is the exclusive or of the direction numbers whose bits are set in the Gray code
    of ``i``.

    Parameters
    ----------
    directions : ndarray of uint64, shape (dimensions, BITS)
        Direction numbers, scrambled or not (:func:`direction_numbers`).
    count : int

    Returns
    -------
    ndarray of uint64, shape (count, dimensions)
    """
    index = np.arange(count, dtype=np.uint64)
    gray = index ^ (index >> np.uint64(1))
    integers = np.zeros((count, directions.shape[0]), dtype=np.uint64)
    for k in range(BITS):
        integers ^= ((gray >> np.uint64(k)) & np.uint64(1))[:, None] * directions[:, k]
    return integers


def scrambled_sobol_points(count: int, dimensions: int, seed: int) -> np.ndarray:
    """The first ``count`` points of the scrambled Sobol sequence in ``[0, 1)^dimensions``.

    Parameters
    ----------
    count : int
        Number of points (1 to ``2^BITS``); a power of two keeps the net's balance.
    dimensions : int
        Dimensions of the box (1 to :data:`MAX_DIMENSIONS`).
    seed : int
        Seed of the scramble: the same seed gives the same points, and the points of
        ``scipy.stats.qmc.Sobol(dimensions, scramble=True, seed=seed).random(count)``.

    Returns
    -------
    ndarray, shape (count, dimensions)

    Examples
    --------
    Eight points in two dimensions: one in each eighth of either axis (a (0, 3, 2)-net):

    >>> points = scrambled_sobol_points(8, 2, seed=1976)
    >>> [sorted(np.floor(8 * points[:, axis]).astype(int).tolist()) for axis in range(2)]
    [[0, 1, 2, 3, 4, 5, 6, 7], [0, 1, 2, 3, 4, 5, 6, 7]]
    """
    if not 1 <= count <= 2**BITS:
        raise ValueError(f"Sobol points: count must be 1 to 2^{BITS}, got {count}")
    v = direction_numbers(dimensions)
    rng = np.random.default_rng(seed)
    shift_bits = rng.integers(0, 2, size=(dimensions, BITS), dtype=np.uint32).astype(np.uint64)
    shift = shift_bits @ (np.uint64(1) << np.arange(BITS, dtype=np.uint64))
    scramble = np.tril(rng.integers(0, 2, size=(dimensions, BITS, BITS), dtype=np.uint32)).astype(np.uint64)
    scramble[:, np.arange(BITS), np.arange(BITS)] = 1
    # output bit p of every direction number: row p of the scramble times its bits, mod 2
    scrambled_bits = np.einsum("dpk,djk->djp", scramble, _bit_columns(v)) & np.uint64(1)
    v = scrambled_bits @ (np.uint64(1) << (BITS - 1 - np.arange(BITS, dtype=np.uint64)))
    return (sobol_integers(v, count) ^ shift).astype(float) * 2.0**-BITS

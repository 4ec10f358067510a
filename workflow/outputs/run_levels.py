"""The change of the measured damping between two amplitude ranges, each run against its own level.

Runs of one configuration sit at levels of their own (figure 12); when only some runs reach
one end of the range, the medians of the segments there compare different runs, and the
difference of their levels reads as a trend no run shows. :func:`within_run_change` fits
``ln zeta = level of the run + shape of the amplitude bin`` by least squares, so that the
change between the ends is measured where runs overlap, with its standard error.
"""

from __future__ import annotations

import numpy as np

__all__ = ["within_run_change"]


def within_run_change(
    run_ids: np.ndarray,
    bin_codes: np.ndarray,
    ln_zeta: np.ndarray,
    low_bins: np.ndarray,
    high_bins: np.ndarray,
) -> tuple[float, float]:
    """Change of ``ln zeta`` from the ``low_bins`` to the ``high_bins`` with each run's level removed.

    Parameters
    ----------
    run_ids : ndarray
        Run of each segment.
    bin_codes : ndarray of int
        Amplitude bin of each segment (quarter decades of in/s).
    ln_zeta : ndarray
        Natural log of each segment's damping ratio (fraction of critical).
    low_bins, high_bins : ndarray of int
        The bins making up the low and the high end.

    Returns
    -------
    change : float
        Mean bin shape over ``high_bins`` minus that over ``low_bins`` (a change of ``ln zeta``);
        nan when no chain of overlapping runs links the two ends.
    standard_error : float
        Its standard error from the segments' scatter about the fit (nan with no residual
        degree of freedom).

    Examples
    --------
    Two runs at levels 0.1 apart, each flat; only the lower run reaches the top bin:

    >>> runs = np.array(["a"] * 4 + ["b"] * 6)
    >>> bins = np.array([0, 0, 1, 1, 0, 0, 1, 1, 2, 2])
    >>> ln_zeta = np.where(runs == "a", 0.1, 0.0) + np.tile([0.01, -0.01], 5)
    >>> change, error = within_run_change(runs, bins, ln_zeta, np.array([0]), np.array([2]))
    >>> abs(change) < 1e-12, round(error, 4)
    (True, 0.0121)
    """
    run_names, run_index = np.unique(np.asarray(run_ids).astype(str), return_inverse=True)
    codes, bin_index = np.unique(np.asarray(bin_codes), return_inverse=True)
    n = len(ln_zeta)
    design = np.zeros((n, len(run_names) + len(codes) - 1))
    design[np.arange(n), run_index] = 1.0
    shaped = bin_index > 0  # the first bin is the reference of the shapes
    design[np.flatnonzero(shaped), len(run_names) + bin_index[shaped] - 1] = 1.0
    contrast = np.zeros(design.shape[1])
    for ends, sign in ((low_bins, -1.0), (high_bins, 1.0)):
        positions = np.flatnonzero(np.isin(codes, ends))
        for position in positions[positions > 0]:
            contrast[len(run_names) + position - 1] += sign / len(positions)
    normal_inverse = np.linalg.pinv(design.T @ design)
    # estimable only if the contrast lies in the design's row space (runs link the two ends)
    if not np.allclose(design.T @ design @ normal_inverse @ contrast, contrast, atol=1e-8):
        return float("nan"), float("nan")
    coefficients = normal_inverse @ design.T @ ln_zeta
    dof = n - np.linalg.matrix_rank(design)
    if dof <= 0:
        return float(contrast @ coefficients), float("nan")
    variance = float(np.sum((ln_zeta - design @ coefficients) ** 2)) / dof
    return float(contrast @ coefficients), float(np.sqrt(variance * contrast @ normal_inverse @ contrast))

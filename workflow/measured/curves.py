"""Damping curves: polynomial fits of damping vs amplitude and area, bands, hypothesis tests.

Input everywhere is the set of measured segments of one configuration, as three
aligned arrays: ``velocity_amplitude_in_s`` (velocity amplitude of the segment,
in/s, > 0), ``zeta`` (local equivalent damping ratio, fraction of critical) and
``run`` (run labels).

Runs are the independent units. Segments of one ring-down are correlated
(overlapping windows, a common assembly state, a common hammer hit), so every
resampling and every cross-validation in this module is over runs, never over
segments. With a single run there is no between-run information; the functions
say so in their results instead of pretending.

Conventions
-----------
* The fit variable is ``x = log10(velocity amplitude / (1 in/s))`` when
  ``log_amplitude`` is true (the default; amplitudes span decades), else
  ``x = velocity amplitude`` in in/s.
* Polynomials are pooled ordinary least squares over all segments, coefficients
  in :func:`numpy.polyfit` order (highest power first) in ``x``.
* No curve is ever extrapolated: outside the amplitude range of the data that
  made it, a curve is NaN.

The tests of the paper's two hypotheses on these curves are in
:mod:`workflow.measured.hypotheses`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "LOG10",
    "IDENTITY",
    "PolynomialFit",
    "validated_damping_data",
    "fit_variable",
    "can_fit",
    "fit_damping_polynomial",
    "evaluate",
    "run_indices",
    "bootstrap_band",
]


LOG10 = "log10"
"""``x_transform`` of a fit against log10 of the velocity amplitude (in/s)."""

IDENTITY = "identity"
"""``x_transform`` of a fit against the velocity amplitude itself (in/s)."""


# --------------------------------------------------------------------------- fit


@dataclass(frozen=True)
class PolynomialFit:
    """A polynomial fit of damping ratio against (log) velocity amplitude.

    Attributes
    ----------
    degree : int
        Selected polynomial degree.
    coefficients : numpy.ndarray
        Polynomial coefficients in :func:`numpy.polyfit` order (highest power
        first) in the transformed amplitude ``x``; the value is a damping ratio
        (dimensionless).
    x_transform : str
        ``"log10"``: ``x = log10(v / (1 in/s))``; ``"identity"``: ``x = v`` in in/s.
    cv_rmse : numpy.ndarray
        Cross-validated root-mean-square prediction error of ``zeta`` for each
        degree ``0 .. max_degree`` (index = degree), dimensionless; NaN for a
        degree that was skipped (too few points) or when no cross-validation
        was possible. It is the mean over folds of each fold's RMSE, so every
        held-out run counts equally.
    cv_rmse_se : numpy.ndarray
        Standard error of ``cv_rmse`` over the folds (std / sqrt(n_folds)).
    cv_excess_se : numpy.ndarray
        Standard error of each degree's fold-by-fold excess over the best degree's
        error (std / sqrt(n_folds) of the paired differences; 0 at the best degree).
    cv_scheme : str
        How the degree was chosen, in words (leave-one-run-out, blocked K-fold
        for a single run, or none).
    n_runs : int
        Number of distinct runs in the data.
    n_points : int
        Number of segments fitted.
    amplitude_range_in_s : tuple of float
        Smallest and largest velocity amplitude fitted, in/s; the fit is only
        evaluated inside this range.
    """

    degree: int
    coefficients: np.ndarray
    x_transform: str
    cv_rmse: np.ndarray
    cv_rmse_se: np.ndarray
    cv_excess_se: np.ndarray
    cv_scheme: str
    n_runs: int
    n_points: int
    amplitude_range_in_s: tuple[float, float]


def validated_damping_data(
    velocity_amplitude_in_s: np.ndarray, zeta: np.ndarray, run: Sequence | np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the three inputs as aligned 1-D arrays, or raise ``ValueError``."""
    amplitude = np.asarray(velocity_amplitude_in_s, dtype=float).ravel()
    damping = np.asarray(zeta, dtype=float).ravel()
    labels = np.asarray(run).ravel()
    if not (amplitude.size == damping.size == labels.size):
        raise ValueError(
            "velocity_amplitude_in_s, zeta and run must have the same length, got "
            f"{amplitude.size}, {damping.size} and {labels.size}"
        )
    if amplitude.size == 0:
        raise ValueError("no segments to fit")
    if not np.all(np.isfinite(amplitude)) or np.any(amplitude <= 0):
        raise ValueError("velocity_amplitude_in_s must be finite and > 0 in/s")
    if not np.all(np.isfinite(damping)):
        raise ValueError("zeta must be finite")
    return amplitude, damping, labels


def fit_variable(velocity_amplitude_in_s: np.ndarray, x_transform: str) -> np.ndarray:
    """Map velocity amplitude (in/s) to the fit variable ``x``."""
    amplitude = np.asarray(velocity_amplitude_in_s, dtype=float)
    if x_transform == LOG10:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log10(amplitude)
    if x_transform == IDENTITY:
        return amplitude
    raise ValueError(f"unknown x_transform {x_transform!r} (expected 'log10' or 'identity')")


def can_fit(x: np.ndarray, degree: int) -> bool:
    """Whether a degree-``degree`` least-squares fit to ``x`` is determined.

    It needs ``degree + 1`` distinct abscissae and at least one residual degree
    of freedom (``degree + 2`` points).
    """
    return x.size >= degree + 2 and np.unique(x).size >= degree + 1


def _polyfit(x: np.ndarray, y: np.ndarray, degree: int) -> np.ndarray:
    """Least-squares polynomial coefficients (numpy.polyfit order)."""
    return np.polyfit(x, y, degree)


def _fold_rmse(
    x: np.ndarray, y: np.ndarray, folds: list[tuple[np.ndarray, np.ndarray]], degree: int
) -> np.ndarray | None:
    """RMSE of held-out predictions for every fold, or None if a fold cannot be fitted.

    A fold is scored only on its held-out points inside the amplitude range of its
    training points (folds with none are left out): the curves are used within the
    measured range, and a held-out run that reaches past the others would otherwise
    reward whichever degree extrapolates most tamely (a straight line through curved
    data), not the one that follows the data.
    """
    errors = []
    for train, test in _interpolating_folds(x, folds):
        if not can_fit(x[train], degree):
            return None
        coefficients = _polyfit(x[train], y[train], degree)
        residual = y[test] - np.polyval(coefficients, x[test])
        errors.append(np.sqrt(np.mean(residual**2)))
    return np.array(errors)


def _interpolating_folds(
    x: np.ndarray, folds: list[tuple[np.ndarray, np.ndarray]]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The folds with their test masks cut to the training range of ``x`` (empty ones dropped)."""
    kept = []
    for train, test in folds:
        if not train.any():
            continue
        inside = test & (x >= x[train].min()) & (x <= x[train].max())
        if inside.any():
            kept.append((train, inside))
    return kept


def _run_folds(labels: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Leave-one-run-out folds as (train mask, test mask)."""
    return [(labels != name, labels == name) for name in np.unique(labels)]


def _block_folds(x: np.ndarray, n_blocks: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Folds for a single run: contiguous amplitude blocks, interior blocks held out.

    The segments are sorted by amplitude and cut into ``n_blocks`` blocks of
    (nearly) equal count. Only interior blocks are held out: holding out the
    lowest or highest block would score extrapolation, which the fits are
    never used for.
    """
    order = np.argsort(x, kind="stable")
    blocks = np.array_split(order, n_blocks)
    folds = []
    for block in blocks[1:-1]:
        test = np.zeros(x.size, dtype=bool)
        test[block] = True
        folds.append((~test, test))
    return folds


def _paired_standard_errors(fold_errors: Mapping[int, np.ndarray], max_degree: int) -> np.ndarray:
    """Standard error of every degree's fold-by-fold excess over the best degree's error.

    Paired by fold: runs differ in level and noise far more than degrees differ on one
    run, so the spread of the folds' own errors would hide a gain that every fold shows.
    """
    se = np.full(max_degree + 1, np.nan)
    best = min(fold_errors, key=lambda d: fold_errors[d].mean())
    for degree, errors in fold_errors.items():
        difference = errors - fold_errors[best]
        se[degree] = difference.std(ddof=1) / np.sqrt(difference.size) if difference.size > 1 else 0.0
    return se


def fit_damping_polynomial(
    velocity_amplitude_in_s: np.ndarray,
    zeta: np.ndarray,
    run: Sequence | np.ndarray,
    *,
    max_degree: int = 3,
    log_amplitude: bool = True,
    n_blocks: int = 6,
) -> PolynomialFit:
    """Fit damping ratio vs velocity amplitude with a cross-validated polynomial degree.

    Parameters
    ----------
    velocity_amplitude_in_s : array_like
        Segment velocity amplitudes, in/s (> 0).
    zeta : array_like
        Segment damping ratios (fraction of critical, dimensionless).
    run : array_like
        Run label of every segment.
    max_degree : int, optional
        Highest degree tried (degrees ``0 .. max_degree``).
    log_amplitude : bool, optional
        Fit against ``log10(v)`` (True) or ``v`` in in/s (False).
    n_blocks : int, optional
        Number of contiguous amplitude blocks for the single-run fallback.

    Returns
    -------
    PolynomialFit
        The fit at the selected degree, with the cross-validation record.

    Notes
    -----
    Degree selection:

    * With two or more runs, leave-one-run-out cross-validation: each run in
      turn is held out, the polynomial is fitted to the others and the held-out
      run's RMSE recorded. ``cv_rmse`` is the mean of these fold RMSEs.
    * With one run, blocked K-fold: the segments are cut into ``n_blocks``
      contiguous amplitude blocks and each interior block is held out in turn
      (see ``cv_scheme``). Segments within a run are correlated, so a random
      K-fold would be optimistic.
    * A degree is skipped (NaN) when some training fold has fewer than
      ``degree + 2`` points or ``degree + 1`` distinct amplitudes.
    * One-standard-error rule (Hastie, Tibshirani & Friedman, *Elements of
      Statistical Learning*, sec. 7.10): the smallest degree whose ``cv_rmse``
      is within one standard error of the minimum is chosen. Degrees that the
      data cannot tell apart from the best are not worth their extra wiggle.
      A degree that fold after fold predicts worse than the best (excess beyond two
      standard errors of the paired differences, ``cv_excess_se``) is not taken even
      so: runs differing in level and noise inflate the folds' spread and would
      otherwise let a straight line pass for curved data.
    * Held-out points outside their training folds' amplitude range are not
      scored (no extrapolation); when fewer than two runs keep points so, the
      runs' segments are pooled into contiguous amplitude blocks as for one run.
    * When no cross-validation is possible (fewer than three points, or no
      degree could be scored), degree 0 (a constant) is used.

    The final polynomial is pooled least squares over all segments.

    Examples
    --------
    Three runs of a damping ratio linear in log10(amplitude) with 1e-5 of noise: degree 1,
    chosen by leave-one-run-out cross-validation, and no value outside the measured range:

    >>> rng = np.random.default_rng(0)
    >>> velocity_in_s = np.tile(np.geomspace(0.1, 10.0, 30), 3)
    >>> zeta = 0.002 + 0.001 * np.log10(velocity_in_s) + 1e-5 * rng.standard_normal(velocity_in_s.size)
    >>> fit = fit_damping_polynomial(velocity_in_s, zeta, np.repeat(["run01", "run02", "run03"], 30))
    >>> fit.degree, np.round(evaluate(fit, np.array([0.1, 1.0, 10.0, 20.0])), 5).tolist()
    (1, [0.001, 0.002, 0.003, nan])
    """
    amplitude, damping, labels = validated_damping_data(velocity_amplitude_in_s, zeta, run)
    if max_degree < 0:
        raise ValueError(f"max_degree must be >= 0, got {max_degree}")
    x_transform = LOG10 if log_amplitude else IDENTITY
    x = fit_variable(amplitude, x_transform)
    n_runs = int(np.unique(labels).size)

    run_folds = _interpolating_folds(x, _run_folds(labels)) if n_runs >= 2 else []
    if len(run_folds) >= 2:
        folds = _run_folds(labels)
        scheme = (
            f"leave-one-run-out cross-validation over {n_runs} runs, each held-out run scored "
            "within the others' amplitude range, one-SE rule"
        )
    elif x.size >= 3 and n_blocks >= 3:
        blocks = min(n_blocks, x.size)
        folds = _block_folds(x, blocks)
        scheme = (
            ("single run" if n_runs == 1 else "runs over disjoint amplitude ranges")
            + ": blocked cross-validation over contiguous amplitude blocks "
            f"({blocks} blocks, the {len(folds)} interior ones held out in turn), one-SE rule"
        )
    else:
        folds = []
        scheme = "none: too few runs and points to cross-validate; constant fit"

    cv_rmse = np.full(max_degree + 1, np.nan)
    cv_rmse_se = np.full(max_degree + 1, np.nan)
    cv_excess_se = np.full(max_degree + 1, np.nan)
    fold_errors: dict[int, np.ndarray] = {}
    if folds:
        for degree in range(max_degree + 1):
            errors = _fold_rmse(x, damping, folds, degree)
            if errors is None or errors.size == 0:
                continue
            fold_errors[degree] = errors
            cv_rmse[degree] = errors.mean()
            cv_rmse_se[degree] = errors.std(ddof=1) / np.sqrt(errors.size) if errors.size > 1 else 0.0

    if fold_errors:
        cv_excess_se = _paired_standard_errors(fold_errors, max_degree)
        best = int(np.nanargmin(cv_rmse))
        excess = cv_rmse - cv_rmse[best]
        within = np.isfinite(cv_rmse) & (excess <= cv_rmse_se[best]) & (excess <= 2.0 * cv_excess_se)
        degree = int(np.flatnonzero(within)[0])
    else:
        degree = 0
        if folds:
            scheme += "; no degree could be scored, constant fit"

    while degree > 0 and not can_fit(x, degree):
        degree -= 1
    coefficients = _polyfit(x, damping, degree)
    return PolynomialFit(
        degree=degree,
        coefficients=coefficients,
        x_transform=x_transform,
        cv_rmse=cv_rmse,
        cv_rmse_se=cv_rmse_se,
        cv_excess_se=cv_excess_se,
        cv_scheme=scheme,
        n_runs=n_runs,
        n_points=int(x.size),
        amplitude_range_in_s=(float(amplitude.min()), float(amplitude.max())),
    )


def evaluate(
    fit: PolynomialFit, velocity_amplitude_in_s: np.ndarray, *, extrapolate: bool = False
) -> np.ndarray:
    """Damping ratio predicted by a fit.

    Parameters
    ----------
    fit : PolynomialFit
        Result of :func:`fit_damping_polynomial`.
    velocity_amplitude_in_s : array_like
        Velocity amplitudes, in/s.
    extrapolate : bool, optional
        False (default): NaN outside ``fit.amplitude_range_in_s``.

    Returns
    -------
    numpy.ndarray
        Damping ratio (dimensionless), same shape as the input.
    """
    amplitude = np.asarray(velocity_amplitude_in_s, dtype=float)
    value = np.polyval(fit.coefficients, fit_variable(amplitude, fit.x_transform))
    if not extrapolate:
        low, high = fit.amplitude_range_in_s
        inside = (amplitude >= low) & (amplitude <= high)
        value = np.where(inside, value, np.nan)
    return value


# --------------------------------------------------------------------- bootstrap


def run_indices(labels: np.ndarray) -> list[np.ndarray]:
    """Segment indices of every run (runs in sorted label order)."""
    return [np.flatnonzero(labels == name) for name in np.unique(labels)]


def _bootstrap_curves(
    x: np.ndarray,
    y: np.ndarray,
    runs: list[np.ndarray],
    degree: int,
    x_grid: np.ndarray,
    n_boot: int,
    rng: np.random.Generator,
) -> np.ndarray:
    """Refitted curves on ``x_grid`` for run-bootstrap resamples.

    Each row is one resample (runs drawn with replacement, all their segments
    kept, a run drawn twice counts twice), NaN outside the ``x`` range of the
    resample and everywhere when the resample cannot determine the degree.
    """
    curves = np.full((n_boot, x_grid.size), np.nan)
    n_runs = len(runs)
    for b in range(n_boot):
        chosen = np.concatenate([runs[k] for k in rng.integers(0, n_runs, n_runs)])
        xb = x[chosen]
        if not can_fit(xb, degree):
            continue
        coefficients = _polyfit(xb, y[chosen], degree)
        inside = (x_grid >= xb.min()) & (x_grid <= xb.max())
        curves[b, inside] = np.polyval(coefficients, x_grid[inside])
    return curves


def _percentile_band(
    curves: np.ndarray, confidence: float, min_coverage: float
) -> tuple[np.ndarray, np.ndarray]:
    """Pointwise percentile interval of bootstrap curves; NaN where too few cover."""
    alpha = (1.0 - confidence) / 2.0
    finite = np.isfinite(curves)
    enough = finite.sum(axis=0) >= max(2, int(np.ceil(min_coverage * curves.shape[0])))
    lower = np.full(curves.shape[1], np.nan)
    upper = np.full(curves.shape[1], np.nan)
    if np.any(enough):
        lower[enough] = np.nanquantile(curves[:, enough], alpha, axis=0)
        upper[enough] = np.nanquantile(curves[:, enough], 1.0 - alpha, axis=0)
    return lower, upper


def bootstrap_band(
    velocity_amplitude_in_s: np.ndarray,
    zeta: np.ndarray,
    run: Sequence | np.ndarray,
    degree: int,
    amplitude_grid_in_s: np.ndarray,
    *,
    n_boot: int = 400,
    confidence: float = 0.95,
    seed: int = 0,
    log_amplitude: bool = True,
    min_coverage: float = 0.5,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pointwise confidence band of the damping curve by bootstrapping runs.

    Parameters
    ----------
    velocity_amplitude_in_s, zeta, run : array_like
        Segments of one configuration (in/s, dimensionless, labels).
    degree : int
        Polynomial degree, held fixed in every resample (normally the one
        chosen by :func:`fit_damping_polynomial`).
    amplitude_grid_in_s : array_like
        Velocity amplitudes at which the band is evaluated, in/s.
    n_boot : int, optional
        Number of run resamples.
    confidence : float, optional
        Pointwise coverage of the band, e.g. 0.95.
    seed : int, optional
        Seed of the random generator (results are reproducible).
    log_amplitude : bool, optional
        Fit against ``log10(v)`` (True) or ``v`` (False).
    min_coverage : float, optional
        A grid point gets a band only where at least this fraction of the
        resampled curves reach it; elsewhere NaN.

    Returns
    -------
    lower, centre, upper : numpy.ndarray
        Damping ratio on the grid (dimensionless). ``centre`` is the fit to all
        segments; ``lower``/``upper`` are the ``(1 -/+ confidence) / 2``
        percentiles of the resampled curves. All three are NaN outside the
        amplitude range of the data; ``lower``/``upper`` are NaN everywhere
        with fewer than two runs (no between-run variability to resample).

    Notes
    -----
    Each resample draws as many runs as there are, with replacement, and keeps
    all segments of the drawn runs. Its curve is restricted to the amplitude
    range that the resample covers, so the band never rests on extrapolated
    polynomials. Percentile bands from few runs are somewhat too narrow
    (the bootstrap variance is biased by about ``(n_runs - 1) / n_runs``).
    """
    amplitude, damping, labels = validated_damping_data(velocity_amplitude_in_s, zeta, run)
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    x_transform = LOG10 if log_amplitude else IDENTITY
    x = fit_variable(amplitude, x_transform)
    grid = np.asarray(amplitude_grid_in_s, dtype=float)
    x_grid = fit_variable(grid, x_transform)
    inside = (grid >= amplitude.min()) & (grid <= amplitude.max())

    centre = np.full(grid.shape, np.nan)
    if can_fit(x, degree):
        centre[inside] = np.polyval(_polyfit(x, damping, degree), x_grid[inside])
    runs = run_indices(labels)
    if len(runs) < 2:
        nan = np.full(grid.shape, np.nan)
        return nan, centre, nan.copy()
    curves = _bootstrap_curves(x, damping, runs, degree, x_grid.ravel(), n_boot, np.random.default_rng(seed))
    lower, upper = _percentile_band(curves, confidence, min_coverage)
    return lower.reshape(grid.shape), centre, upper.reshape(grid.shape)

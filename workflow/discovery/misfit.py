"""Misfit tests: where a fitted model is wrong, and whether that is more than the scatter.

Per half decade of amplitude and per curve, each run's mean residual, then a t test over
runs (Bonferroni-corrected, familywise :data:`ALPHA`) that also asks the misfit to exceed
the models' accuracy; a trend of the runs' damping with run order; whether the segments
are single-mode decays at all; whether a model explains the data; and the stiffness
candidate's signature.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

# scipy is imported in the functions that test: the jobs that assemble, word or draw the
# diagnosis import this module without calling them (scipy.optimize costs them 0.3 s)
from workflow.discovery.heldout import amplitude_bin, amplitude_weights
from workflow.measured.settings import AnalysisSettings
from workflow.models.averaged import model_curves
from workflow.models.averaged_fit import FitResult
from workflow.models.configuration_data import TOL_LN_ZETA, TOL_REL_F, ConfigurationData, robust_trend

__all__ = [
    "failure_draws",
    "departure_ruled_out",
    "departure_ruled_out_by_channels",
    "ALPHA",
    "misfit_significant",
    "bin_observations",
    "channel_weighted_observations",
    "MIN_BIN_RUNS",
    "MIN_BIN_SEGMENTS_ONE_RUN",
    "bin_is_judged",
    "binned_discrepancy",
    "run_order_trend",
    "ENVELOPE_DEPARTURE_LIMIT",
    "proportional_departure",
    "envelope_structure",
    "weighted_nonnegative_line",
    "envelope_structure_draws",
    "EXPLAINS_LIMIT",
    "explains_data",
    "stiffness_signature",
    "OWN_SHAPE_SHARE",
    "MICROSLIP_ONSET",
    "microslip_signature",
    "threshold_signature",
    "bin_span_in_s",
]


ALPHA = 0.01
"""Familywise false-alarm probability of the discrepancy tests: half of it is shared by
the amplitude bins (Bonferroni over bins and curves), half goes to the run-order test."""


def misfit_significant(p: float, p_limit: float, size: float, tolerance: float) -> bool:
    """The one rule by which a misfit (a bin's mean residual, a run-order change) is real.

    Real means statistically clear, ``p < p_limit`` (the corrected limit), *and* larger
    than the models' accuracy, ``|size| > tolerance`` (same unit as ``size``). ``|t|``
    alone decides nothing: its ``p`` depends on the runs behind it.

    Examples
    --------
    >>> misfit_significant(1e-6, 1e-3, 0.05, 0.02), misfit_significant(1e-6, 1e-3, 0.01, 0.02)
    (True, False)
    >>> misfit_significant(0.0013, 0.00083, 0.05, 0.02)
    False
    """
    return bool(p < p_limit and abs(size) > tolerance)


def bin_span_in_s(velocity_in_s: np.ndarray, anchor_velocity_in_s: float, b: int) -> dict:
    """Amplitudes of half-decade bin ``b`` (of :func:`amplitude_bin`), in/s: its edges,
    cut to the measured range so that a sentence or table never places a misfit at
    amplitudes no segment reached.

    Examples
    --------
    >>> bin_span_in_s(np.array([0.5, 2.0, 10.0]), 10.0, -3)
    {'v_low_in_s': 0.5, 'v_high_in_s': 1.0}
    """
    low = anchor_velocity_in_s * 10 ** (b / 2.0)
    high = anchor_velocity_in_s * 10 ** ((b + 1) / 2.0)
    return {
        "v_low_in_s": float(max(low, velocity_in_s.min())),
        "v_high_in_s": float(min(high, velocity_in_s.max())),
    }


def _lag1_effective(r: np.ndarray) -> float:
    """Effective sample size of a serially correlated sequence (AR(1))."""
    n = r.size
    if n < 4:
        return float(n)
    c = r - r.mean()
    rho = float(np.sum(c[1:] * c[:-1]) / max(np.sum(c * c), 1e-300))
    rho = min(max(rho, 0.0), 0.95)
    return max(1.0, n * (1.0 - rho) / (1.0 + rho))


def bin_observations(
    values: np.ndarray, run_index: np.ndarray, in_bin: np.ndarray, n_runs: int
) -> tuple[np.ndarray, np.ndarray]:
    """The observations of one amplitude bin: each run's mean of ``values`` there.

    With several runs, one observation per run with segments in the bin (its mean);
    with one run, the bin's segments in order of amplitude (its observations are
    segments). Their mean is the bin's mean, the number the binned verdicts and the
    residual figure's binned means use (the discrepancy test of pooled channels weighs
    each channel by what it knows, :func:`channel_weighted_observations`).

    Returns
    -------
    runs : ndarray of int
        The runs behind the observations (``[0]`` with one run).
    observations : ndarray

    Examples
    --------
    >>> bin_observations(np.array([1.0, 3.0, 10.0, 0.0]), np.array([0, 0, 1, 1]),
    ...                  np.array([True, True, True, False]), 2)
    (array([0, 1]), array([ 2., 10.]))
    """
    if n_runs >= 2:
        counts = np.bincount(run_index[in_bin], minlength=n_runs)
        runs = np.flatnonzero(counts)
        sums = np.bincount(run_index[in_bin], weights=values[in_bin], minlength=n_runs)
        return runs, sums[runs] / counts[runs]
    return np.zeros(1, dtype=int), values[in_bin]


def channel_weighted_observations(
    values: np.ndarray,
    variances: np.ndarray,
    run_index: np.ndarray,
    channel_index: np.ndarray,
    in_bin: np.ndarray,
    n_runs: int,
) -> tuple[np.ndarray, np.ndarray]:
    """The observations of one amplitude bin of pooled channels (sensors of the same runs):
    per run, each channel's mean of ``values`` there, weighted by the inverse of that
    mean's variance (its segments' ``variances`` summed, over their count squared).

    The channels see one joint: a run's bin mean is one estimate of the same residual from
    each sensor, and a sensor near a node, whose log decrements scatter tens of times more
    than the reference's and are skewed by its noise floor, weighs as little as it knows
    (the weighting of the joint fit and of :func:`run_order_trend`). An unweighted mean of
    the pooled segments would carry that sensor's noise-floor skew into every bin: on a
    no-effect campaign seen at x0.06 beside two sensors at x2-3 (bench/hit_rate.py
    ``--sensors 3``, seed 2044), its mean of -0.08 in ``ln zeta`` made the bin's mean
    -0.026 over the seven runs reaching it (t -7), beyond the models' accuracy, where the
    other two sensors read 0.0004 and 0.0001. With one channel each run's
    observation is its plain mean, as :func:`bin_observations` gives it.

    Examples
    --------
    A quiet channel reading 0 and a noisy one reading -1, both in one run:

    >>> values, variances = np.array([0.0, 0.0, -1.0, -1.0]), np.array([0.01, 0.01, 1.0, 1.0])
    >>> runs, means = channel_weighted_observations(
    ...     values, variances, np.zeros(4, dtype=int), np.array([0, 0, 1, 1]), np.ones(4, dtype=bool), 2)
    >>> runs.tolist(), round(float(means[0]), 4)
    ([0], -0.0099)
    """
    n_channels = int(channel_index.max()) + 1
    cell = run_index[in_bin] * n_channels + channel_index[in_bin]
    size = n_runs * n_channels
    counts = np.bincount(cell, minlength=size).reshape(n_runs, n_channels)
    sums = np.bincount(cell, weights=values[in_bin], minlength=size).reshape(n_runs, n_channels)
    spread = np.bincount(cell, weights=variances[in_bin], minlength=size).reshape(n_runs, n_channels)
    occupied = counts > 0
    weight = np.where(occupied, counts**2 / np.maximum(spread, np.finfo(float).tiny), 0.0)
    means = np.where(occupied, sums / np.maximum(counts, 1), 0.0)
    runs = np.flatnonzero(occupied.any(axis=1))
    return runs, (weight * means).sum(axis=1)[runs] / weight.sum(axis=1)[runs]


MIN_BIN_RUNS = 3
"""Fewest runs with segments in an amplitude bin for its mean to be judged (one run: the
segments, at least :data:`MIN_BIN_SEGMENTS_ONE_RUN`): a mean over fewer is one or two
runs' draws of the run-to-run spread, not a misfit of the model."""

MIN_BIN_SEGMENTS_ONE_RUN = 4
"""With one run, fewest segments in an amplitude bin for its mean to be judged."""


def bin_is_judged(n_bin_runs: int, n_bin_segments: int, n_runs: int) -> bool:
    """Whether an amplitude bin holds enough observations for its mean to be judged: at
    least :data:`MIN_BIN_RUNS` runs, or with one run :data:`MIN_BIN_SEGMENTS_ONE_RUN`
    segments (both the misfit test and ``explains_data``).

    >>> bin_is_judged(2, 40, 8), bin_is_judged(3, 3, 8), bin_is_judged(1, 4, 1)
    (False, True, True)
    """
    if n_runs >= 2:
        return n_bin_runs >= MIN_BIN_RUNS
    return n_bin_segments >= MIN_BIN_SEGMENTS_ONE_RUN


def binned_discrepancy(
    data: ConfigurationData, residuals: Mapping[str, np.ndarray], *, alpha: float = ALPHA
) -> list[dict]:
    """Mean residual per half decade of amplitude and per curve, with its significance.

    For each bin and curve, each run's mean residual in the bin is one
    observation (:func:`bin_observations`; with pooled channels, each channel's mean
    weighted by its inverse variance, :func:`channel_weighted_observations`); the mean
    over runs, its standard error over
    runs and a t test (``n_runs - 1`` degrees of freedom) follow. With one run, the
    segments are the observations and the standard error uses their AR(1) effective
    number. A bin counts as a real misfit when ``p < p_limit = alpha / (2 n)``, ``n``
    the number of bins x curves tested (Bonferroni with half of ``alpha``; the
    run-order test has the other half), and ``|mean|`` exceeds the model accuracy
    (``TOL_LN_ZETA`` or ``TOL_REL_F``). Bins with fewer than 3 runs (one run: 4
    segments) are not tested (:func:`bin_is_judged`).

    Returns
    -------
    list of dict
        One per tested (bin, curve): ``curve`` ("damping"/"frequency"), ``v_low_in_s``,
        ``v_high_in_s``, ``mean`` (ln zeta or relative f), ``mean_over_scatter`` (the
        runs' plain mean of the residuals divided by the measured scatter, ``z_noise`` or
        ``f_noise``: the binned mean the residual figure draws), ``standard_error``,
        ``t``, ``p``, ``p_limit`` (``alpha / n_tests``), ``n_runs``, ``n_segments``,
        ``tolerance``, ``significant``; with several runs also ``run_ids`` and
        ``run_means`` (the observations, for :func:`failure_draws`).
    """
    from scipy import special

    code = amplitude_bin(data.velocity_in_s, data.anchor_velocity_in_s, 2)
    channels = data.channel_index
    pooled = data.n_runs >= 2 and data.n_channels > 1
    rows = []
    for curve, key, scaled, spread, tol in (
        ("damping", "ln_zeta", "z_noise", "scatter_ln_zeta", TOL_LN_ZETA),
        ("frequency", "rel_f", "f_noise", "scatter_rel_f", TOL_REL_F),
    ):
        r = residuals[key]
        for b in np.unique(code):
            in_bin = code == b
            if pooled:
                runs, observations = channel_weighted_observations(
                    r, residuals[spread] ** 2, data.run_index, channels, in_bin, data.n_runs
                )
            else:
                runs, observations = bin_observations(r, data.run_index, in_bin, data.n_runs)
            if not bin_is_judged(runs.size, observations.size, data.n_runs):
                continue
            if data.n_runs >= 2:
                m = float(observations.mean())
                se = float(observations.std(ddof=1) / np.sqrt(observations.size))
                dof = observations.size - 1
                per_run = {"run_ids": runs.tolist(), "run_means": observations.tolist()}
            else:
                per_run = {}
                seg = observations[np.argsort(data.velocity_in_s[in_bin])]
                m = float(seg.mean())
                n_eff = _lag1_effective(seg)
                se = float(seg.std(ddof=1) / np.sqrt(n_eff))
                dof = max(n_eff - 1.0, 1.0)
            t = m / max(se, 1e-300)
            rows.append(
                {
                    "curve": curve,
                    **bin_span_in_s(data.velocity_in_s, data.anchor_velocity_in_s, b),
                    "mean": m,
                    "mean_over_scatter": float(
                        bin_observations(residuals[scaled], data.run_index, in_bin, data.n_runs)[1].mean()
                    ),
                    "standard_error": se,
                    "t": float(t),
                    "p": float(2.0 * special.stdtr(dof, -abs(t))),
                    "n_runs": int(runs.size),
                    "n_segments": int(in_bin.sum()),
                    "degrees_of_freedom": float(dof),
                    "tolerance": tol,
                    "significant": False,
                    **per_run,
                }
            )
    n_tests = 2 * max(len(rows), 1)  # the other half of alpha goes to the run-order test
    for row in rows:
        row["p_limit"] = alpha / n_tests
        row["significant"] = misfit_significant(row["p"], row["p_limit"], row["mean"], row["tolerance"])
    return rows


def run_order_trend(
    data: ConfigurationData,
    residuals: Mapping[str, np.ndarray],
    *,
    n_tests: int,
    alpha: float = ALPHA,
) -> dict | None:
    """Linear trend with run order of the runs' shift of the damping curve.

    Each run's residual is the shared model's, with the run's own frequency and linear
    damping set by its lowest-amplitude segments (``ln_zeta_calibrated`` and
    ``calibration`` when present, as for a held-out run; else ``ln_zeta_shared``, else
    ``ln_zeta``). Of that residual the test takes the amount of the shape a change of the
    joint's friction limit leaves (``-ln_zeta_slope``, :func:`~workflow.models.averaged_fit.damping_curve_slope`; a
    constant shape without it, or where the model's damping changes by less than its
    accuracy ``TOL_LN_ZETA`` over the scored amplitudes), a weighted least-squares
    projection over the run's other segments with every quarter decade of amplitude
    weighted equally (:func:`amplitude_weights`) and every segment by the inverse of its
    measured variance (``scatter_ln_zeta`` when present): the run's relative change of
    friction limit against the shared model. Without the variance, the noisy low end of a
    sensor near a node of the mode (its amplitudes 1/20 of the reference's, the noise
    the same, a scatter of 0.3 in ln zeta against 0.05 at the top) weighed as much as the
    top, where the joint shows its change: a drift of 0.29 in ln zeta over the runs went
    from t = -11 to t = -3.3. Projecting on the shape weighs each amplitude by how
    much a change of the joint shows there, where a plain mean would dilute the change at
    the top of the range with the stuck joint's segments below. The calibration takes out the random
    spread of the runs' linear damping; a random spread of the joint left over only widens
    the scatter of the runs' projections, which the t test counts, while a steady change
    with run order tilts them. Offsets fitted to all of a run's segments would absorb a
    trend.

    Parameters
    ----------
    n_tests : int
        The test is significant at ``p < alpha / n_tests``.

    Returns None with fewer than 4 runs with scored segments; else ``slope_per_run`` (of
    the projection, per run: ``ln Fc``, or ``ln zeta`` without a slope),
    ``change_over_sequence`` (the change of ``ln zeta`` the trend makes from the first run
    to the last, at the scored amplitude where it is largest), ``t``, ``p``,
    ``significant`` (``p < alpha / n_tests`` and the change over the sequence larger than
    the model accuracy), ``order`` (which run order, ``data.run_order``) and ``runs`` (the
    run names in that order).
    """
    from scipy import special

    x = np.arange(data.n_runs, dtype=float)
    r = residuals.get("ln_zeta_calibrated", residuals.get("ln_zeta_shared", residuals["ln_zeta"]))
    w = amplitude_weights(data.velocity_in_s, data.anchor_velocity_in_s, data.n_channels)
    if "calibration" in residuals:
        w = w * ~residuals["calibration"]
    if "scatter_ln_zeta" in residuals:
        # inverse variance: a sensor near a node sees its low amplitudes through noise
        w = w / residuals["scatter_ln_zeta"] ** 2
    shape = np.ones(data.n)
    if "ln_zeta_slope" in residuals and np.any(w > 0):
        curve_slope = residuals["ln_zeta_slope"]
        # a curve flatter than the models' accuracy over the scored amplitudes defines no
        # shape (its slope is rounding): a change of the damping is then read as a level
        span = float(np.ptp(np.log(data.velocity_in_s[w > 0])))
        if float(np.max(np.abs(curve_slope[w > 0]))) * span >= TOL_LN_ZETA:
            shape = -curve_slope
    counts = np.bincount(data.run_index, weights=w * shape * shape, minlength=data.n_runs)
    means = np.bincount(data.run_index, weights=w * shape * r, minlength=data.n_runs) / np.maximum(
        counts, 1e-300
    )
    keep = counts > 0
    x, y = x[keep], means[keep]
    if x.size < 4 or np.unique(x).size < 3:  # runs with scored segments
        return None
    dx = x - x.mean()
    slope = float(np.sum(dx * (y - y.mean())) / np.sum(dx * dx))
    dof = x.size - 2
    stderr = float(np.sqrt(np.sum((y - y.mean() - slope * dx) ** 2) / dof / np.sum(dx * dx)))
    t = slope / max(stderr, 1e-300)
    p = float(2.0 * special.stdtr(dof, -abs(t)))
    scored_shape = shape[w > 0]
    largest = float(scored_shape[np.argmax(np.abs(scored_shape))]) if scored_shape.size else 0.0
    change = slope * float(np.ptp(x)) * largest
    return {
        "slope_per_run": slope,
        "change_over_sequence": change,
        "t": float(t),
        "p": p,
        "significant": misfit_significant(p, alpha / n_tests, change, TOL_LN_ZETA),
        "p_limit": alpha / n_tests,
        "order": data.run_order,
        "runs": list(data.run_names),
        "run_ids": np.flatnonzero(keep).tolist(),
        "run_positions": x.tolist(),
        "run_projections": y.tolist(),
        "largest_shape": largest,
    }


def departure_ruled_out(bins: Sequence[Mapping]) -> float:
    """Probability that the baseline departs from the data by no more than the models'
    accuracy in every tested bin: how far the data can rule out a mechanism the
    baseline misses.

    Per bin of :func:`binned_discrepancy`, the true mean residual given its estimate and
    standard error (Student t, the bin's degrees of freedom) lies within the accuracy
    (``TOL_LN_ZETA``, ``TOL_REL_F``) with probability
    ``T((tol - mean) / se) - T((-tol - mean) / se)``; the bins are independent
    observations, so the probabilities multiply. Where the scatter is small against the
    accuracy each factor is close to 1; a sensor near a node of the mode, whose standard
    errors are several accuracies, cannot tell a departure from none.

    Examples
    --------
    >>> row = {"mean": 0.0, "standard_error": 0.001, "tolerance": 0.02, "degrees_of_freedom": 9.0}
    >>> round(departure_ruled_out([row, row]), 6)
    1.0
    >>> round(departure_ruled_out([{**row, "standard_error": 0.02}]), 2)
    0.66
    """
    from scipy import special

    probability = 1.0
    for row in bins:
        se, dof = float(row["standard_error"]), float(row["degrees_of_freedom"])
        if np.isfinite(se) and se > 0.0:
            low, high = (-row["tolerance"] - row["mean"]) / se, (row["tolerance"] - row["mean"]) / se
            probability *= float(special.stdtr(dof, high) - special.stdtr(dof, low))
    return probability


def departure_ruled_out_by_channels(
    data: ConfigurationData, residuals: Mapping[str, np.ndarray], bins: Sequence[Mapping]
) -> float:
    """:func:`departure_ruled_out` of the baseline's residuals, whose
    :func:`binned_discrepancy` on all the data is ``bins``; with pooled channels (sensors
    of one hit), that of the channel that rules most out.

    The channels share the joint's physics (damping and relative frequency are the mode's,
    whatever the sensor), so what the quietest sensor rules out is ruled out for all of
    them; pooling its segments with a noisier sensor's in one bin mean would only widen the
    bin's standard error. Each channel's bins are counted from the same top amplitude.
    """
    channels = data.channel_index
    if data.n_channels < 2:
        return departure_ruled_out(bins)
    best = 0.0
    for channel in np.unique(channels):
        rows = channels == channel
        view = replace(
            data,
            velocity_in_s=data.velocity_in_s[rows],
            zeta=data.zeta[rows],
            frequency_hz=data.frequency_hz[rows],
            run_index=data.run_index[rows],
            response_order=data.response_order_of(rows),
            fit_rms=None,
            response_amplitude=None,
            channel_index=None,
        )
        own = {key: residuals[key][rows] for key in ("ln_zeta", "rel_f", "z_noise", "f_noise")}
        best = max(best, departure_ruled_out(binned_discrepancy(view, own)))
    return best


def failure_draws(bins: Sequence[Mapping], trend: Mapping | None, draws: np.ndarray) -> np.ndarray:
    """Whether the baseline fails its misfit tests on each Bayesian-bootstrap reweighting
    of the runs.

    The tests of :func:`binned_discrepancy` and :func:`run_order_trend` re-taken with
    the runs' observations (a bin's run means, the runs' projections on the drift shape)
    weighted by ``draws``: weighted mean and its standard error, weighted least-squares
    slope and its standard error, the same limits. A bin tested on the segments of one run
    keeps its verdict (its observations are not runs).

    Parameters
    ----------
    bins : sequence of mapping
        :func:`binned_discrepancy` rows.
    trend : mapping or None
        :func:`run_order_trend`'s result.
    draws : ndarray, shape (B, n_runs)
        Run weights, each row summing to the number of runs.

    Returns
    -------
    ndarray of bool, shape (B,)
    """
    from scipy import special

    fails = np.zeros(draws.shape[0], dtype=bool)
    for row in bins:
        if "run_means" not in row:
            fails |= bool(row["significant"])
            continue
        y = np.asarray(row["run_means"])
        a = draws[:, row["run_ids"]]
        a = a * (y.size / a.sum(axis=1, keepdims=True))
        mean = (a @ y) / y.size
        variance = np.sum(a * (y - mean[:, None]) ** 2, axis=1) / (y.size - 1)
        t = mean / np.maximum(np.sqrt(variance / y.size), 1e-300)
        p = 2.0 * special.stdtr(y.size - 1, -np.abs(t))
        fails |= (p < row["p_limit"]) & (np.abs(mean) > row["tolerance"])
    if trend is not None and "run_projections" in trend:
        x, y = np.asarray(trend["run_positions"]), np.asarray(trend["run_projections"])
        a = draws[:, trend["run_ids"]]
        a = a * (y.size / a.sum(axis=1, keepdims=True))
        x_mean = (a @ x) / y.size
        y_mean = (a @ y) / y.size
        dx = x[None, :] - x_mean[:, None]
        sxx = np.sum(a * dx * dx, axis=1)
        slope = np.sum(a * dx * (y[None, :] - y_mean[:, None]), axis=1) / np.maximum(sxx, 1e-300)
        residual = y[None, :] - y_mean[:, None] - slope[:, None] * dx
        stderr = np.sqrt(np.sum(a * residual**2, axis=1) / (y.size - 2) / np.maximum(sxx, 1e-300))
        t = slope / np.maximum(stderr, 1e-300)
        p = 2.0 * special.stdtr(y.size - 2, -np.abs(t))
        change = slope * float(np.ptp(x)) * trend["largest_shape"]
        fails |= (p < trend["p_limit"]) & (np.abs(change) > TOL_LN_ZETA)
    elif trend is not None:
        fails |= bool(trend["significant"])
    return fails


ENVELOPE_DEPARTURE_LIMIT = 0.05
"""Largest acceptable departure of a segment's ln-envelope from a straight line (RMS of
the line fit, ``fit_rms``), as a fraction of the decay of ln-envelope across the segment
(``2 pi N zeta`` for ``N`` cycles): its part that does not fade with the noise, in each
run's upper half of amplitudes (:func:`proportional_departure`)."""


def proportional_departure(amplitude: np.ndarray, departure: np.ndarray) -> float:
    """The part of a run's envelope departures that does not fade with the noise.

    Additive noise of level ``n`` on an envelope of amplitude ``A`` moves its logarithm by
    about ``n / A``: its share of a segment's departure falls as the amplitude rises. A
    disturbance proportional to the signal (a second mode beating in the band) departs by
    the same fraction at every amplitude. With both independent, ``departure^2 = d^2 +
    k / A^2``; ``d`` is found by non-negative least squares over the segments.

    Parameters
    ----------
    amplitude : ndarray
        The segments' envelope amplitudes, any one unit.
    departure : ndarray
        Their departures from a straight ln-envelope, over the decay across the segment.

    Returns
    -------
    float
        ``d``, in the unit of ``departure``.

    Examples
    --------
    Noise alone (departure 0.02 at the top, ten times more a decade below) against a
    steady 0.2:

    >>> a = np.geomspace(1.0, 0.1, 20)
    >>> round(proportional_departure(a, 0.02 / a), 6), round(proportional_departure(a, np.full(20, 0.2)), 6)
    (0.0, 0.2)
    """
    scale = (amplitude.max() / amplitude) ** 2
    return float(np.sqrt(weighted_nonnegative_line(scale, departure**2, np.ones((1, scale.size)))[0]))


def _upper_halves(data: ConfigurationData, segment_cycles: float) -> list[tuple[np.ndarray, float]]:
    """Each run of each channel with 3 segments or more: the indices of its upper half of
    amplitudes (3 at least) and the median decay of ln-envelope across a segment there."""
    x = np.log10(data.velocity_in_s)
    fall = 2.0 * np.pi * segment_cycles * np.exp(robust_trend(x, np.log(data.zeta), 3))
    channel = np.zeros(data.n, dtype=int) if data.channel_index is None else data.channel_index
    halves = []
    # each run of each channel: pooled sensors see one decay, each through its own noise
    for group in np.unique(np.column_stack([data.run_index, channel]), axis=0):
        m = np.flatnonzero((data.run_index == group[0]) & (channel == group[1]))
        if m.size < 3:
            continue
        top = m[np.argsort(data.velocity_in_s[m])[::-1][: max(3, m.size // 2)]]
        halves.append((top, float(np.median(fall[top]))))
    return halves


def _majority(over: np.ndarray) -> np.ndarray:
    """Whether the runs over the limit are at least half of those tested (axis 0)."""
    return over.sum(axis=0) >= max(1, int(np.ceil(over.shape[0] / 2)))


def envelope_structure(
    data: ConfigurationData, *, segment_cycles: float = AnalysisSettings.segment_cycles
) -> dict | None:
    """Whether the log-decrement segments measure a decay at all.

    Every model of the vocabulary is a single mode whose damping changes slowly with
    amplitude: over a segment of ``N`` cycles its ln-envelope is a straight line that
    falls by ``2 pi N zeta``, up to additive noise (largest at the run's low end) and
    a curvature far smaller than that fall. The departure ``fit_rms`` must therefore
    be a small fraction of the fall once the noise's share is taken out: in each run's
    upper half of amplitudes, the part of the departure that does not fade as ``1 / A``
    (:func:`proportional_departure`). A disturbance proportional to the signal (a second
    mode beating in the band, an amplitude modulation) keeps it large at every amplitude:
    then the segments' damping and frequency are dominated by that disturbance and no
    single-mode model applies. A sensor near a node of the mode sees it through noise even
    at its highest amplitudes (there the departure of a plain decay grew from 0.01 to 0.3
    of the fall over the upper half): noise, not structure. How sure that verdict is:
    :func:`envelope_structure_draws`.

    Parameters
    ----------
    data : ConfigurationData
    segment_cycles : float
        Segment length of the log decrement, cycles (config ``analysis.segment_cycles``).

    Returns
    -------
    dict or None
        ``departure_ratio`` (median over runs, each channel's run on its own, of each
        run's proportional departure over ``2 pi N zeta_trend``), ``runs_over_limit``,
        ``limit``, ``significant`` (ratio above the limit in at least half the runs). None
        when the table has no ``fit_rms``.
    """
    if data.fit_rms is None:
        return None
    halves = _upper_halves(data, segment_cycles)
    if not halves:
        return None
    per_run = np.array(
        [proportional_departure(data.velocity_in_s[top], data.fit_rms[top]) / fall for top, fall in halves]
    )
    over = per_run > ENVELOPE_DEPARTURE_LIMIT
    return {
        "departure_ratio": float(np.median(per_run)),
        "runs_over_limit": int(np.sum(over)),
        "runs_tested": int(per_run.size),
        "limit": ENVELOPE_DEPARTURE_LIMIT,
        "segment_cycles": float(segment_cycles),
        "median_fit_rms": float(np.median(data.fit_rms)),
        "significant": bool(_majority(over[:, None])[0]),
    }


def weighted_nonnegative_line(s: np.ndarray, y: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Intercepts of the non-negative weighted least-squares lines ``y = a + b s``
    (``a, b >= 0``), one per row of ``weights``.

    The two-coefficient problem solved in closed form for many weightings at once: the
    unconstrained solution where both coefficients are non-negative, else the better of
    the two one-coefficient fits (each clipped at 0).

    Parameters
    ----------
    s, y : ndarray, shape (n,)
    weights : ndarray, shape (B, n)
        Non-negative weights, each row with a positive sum.

    Returns
    -------
    ndarray, shape (B,)
        ``a`` per row.

    Examples
    --------
    >>> s = np.array([1.0, 2.0, 4.0])
    >>> weighted_nonnegative_line(s, 0.5 + 0.25 * s, np.ones((1, 3))).round(12).tolist()
    [0.5]
    >>> weighted_nonnegative_line(s, 3.0 - s, np.ones((1, 3))).round(12).tolist()  # b < 0: a alone
    [0.666666666667]
    """
    w_sum, ws, wss = weights.sum(axis=1), weights @ s, weights @ (s * s)
    wy, wsy, wyy = weights @ y, weights @ (s * y), weights @ (y * y)
    det = w_sum * wss - ws * ws
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (wss * wy - ws * wsy) / det
        b = (w_sum * wsy - ws * wy) / det
    a_alone = np.maximum(wy / w_sum, 0.0)
    b_alone = np.maximum(wsy / wss, 0.0)
    # weighted squared residuals of the two one-coefficient fits
    sse_a = wyy - 2.0 * a_alone * wy + a_alone**2 * w_sum
    sse_b = wyy - 2.0 * b_alone * wsy + b_alone**2 * wss
    both = (det > 0) & (a >= 0.0) & (b >= 0.0)
    return np.where(both, a, np.where(sse_a <= sse_b, a_alone, 0.0))


def envelope_structure_draws(
    data: ConfigurationData,
    n_draws: int,
    rng: np.random.Generator,
    *,
    segment_cycles: float = AnalysisSettings.segment_cycles,
    segment_overlap: float = AnalysisSettings.segment_overlap,
) -> np.ndarray:
    """:func:`envelope_structure`'s verdict on Bayesian-bootstrap reweightings of each
    run's segments, shape (n_draws,) of bool.

    The proportional departure of a run's upper half is estimated from a few tens of
    segments whose line-fit residuals, under noise, scatter by a factor of several from
    one segment to the next: at a sensor near a node, whose upper half lies only some
    tens of times above its noise floor, that estimate alone can reach the limit. Each
    draw refits it (:func:`weighted_nonnegative_line` on ``fit_rms^2`` against
    ``(A_max / A)^2``) with Dirichlet weights on the segments of concentration
    ``1 - segment_overlap``: segments overlapping by that fraction carry ``n (1 -
    overlap)`` segments' worth of independent samples, and a reweighted mean then varies
    as one of that many. The verdict (at least half the runs over the limit) is re-taken
    per draw: its share of the draws is how sure the data are of the structure.
    """
    if data.fit_rms is None:
        return np.zeros(n_draws, dtype=bool)
    halves = _upper_halves(data, segment_cycles)
    if not halves:
        return np.zeros(n_draws, dtype=bool)
    concentration = max(1.0 - segment_overlap, 0.05)
    over = []
    for top, fall in halves:
        amplitude = data.velocity_in_s[top]
        weights = rng.dirichlet(np.full(top.size, concentration), size=n_draws)
        square = weighted_nonnegative_line(
            (amplitude.max() / amplitude) ** 2, data.fit_rms[top] ** 2, weights
        )
        over.append(np.sqrt(square) / fall > ENVELOPE_DEPARTURE_LIMIT)
    return _majority(np.array(over))


EXPLAINS_LIMIT = 2.0
"""``explains_data`` (output contract): the model's mean residual in every half decade
of amplitude, in units of the measured scatter, stays within this limit on both curves."""


def explains_data(data: ConfigurationData, residuals: Mapping[str, np.ndarray]) -> dict:
    """Whether a model explains the data: binned residuals within ±2 measured scatter.

    Per half decade of amplitude (counted down from the anchor) and per curve, the mean
    of the residuals over the measured scatter (``z_noise``, ``f_noise``: each run with
    its own offsets), taken as every binned mean is (:func:`bin_observations`: the mean
    over runs of each run's mean). The model explains the data when every such mean is
    within :data:`EXPLAINS_LIMIT`, over the bins the misfit test judges too
    (:func:`bin_is_judged`): a mean over one or two runs at the edge of the measured
    range (one segment, at worst) is their draw of the run-to-run spread, beyond 2
    scatters one time in twenty in each bin, not a misfit the model leaves.

    Returns
    -------
    dict
        ``explains_data`` (bool), ``limit``, ``bins`` (every bin: curve, range,
        ``mean_over_scatter``, ``n_runs``, ``n_segments``; the binned means the residual
        figure draws for this model), ``worst`` (the largest bin) and ``failing_bins``
        (every bin outside the limit, in amplitude order).
    """
    code = amplitude_bin(data.velocity_in_s, data.anchor_velocity_in_s, 2)
    bins = []
    for curve, key in (("damping", "z_noise"), ("frequency", "f_noise")):
        for b in np.unique(code):
            in_bin = code == b
            runs, observations = bin_observations(residuals[key], data.run_index, in_bin, data.n_runs)
            if not bin_is_judged(runs.size, observations.size, data.n_runs):
                continue
            bins.append(
                {
                    "curve": curve,
                    **bin_span_in_s(data.velocity_in_s, data.anchor_velocity_in_s, b),
                    "mean_over_scatter": float(observations.mean()),
                    "n_runs": int(runs.size),
                    "n_segments": int(in_bin.sum()),
                }
            )
    failing = [b for b in bins if abs(b["mean_over_scatter"]) > EXPLAINS_LIMIT]
    failing.sort(key=lambda b: (b["curve"], b["v_low_in_s"]))
    return {
        "explains_data": not failing,
        "limit": EXPLAINS_LIMIT,
        "bins": bins,
        "worst": max(bins, key=lambda b: abs(b["mean_over_scatter"]), default=None),
        "failing_bins": failing,
    }


OWN_SHAPE_SHARE = 0.25
"""Smallest share of a stiffness term's relative frequency change not proportional to the
fitted friction's softening for the term to count as a mechanism of its own
(:func:`stiffness_signature`). Refits of the lab's micro-slip campaigns with a hidden
mechanism (bench/hit_rate.py seeds 1720-1739, random placement): the micro-slip + spring
combination's term is 0.056-0.19 its own beside a velocity-squared loss (20 campaigns, the
term's fitted exponent 0.59-0.99, cancelling 60-70 % of the joint's softening) and
0.33-0.61 beside a cubic spring (14 campaigns, exponents 1.58-2.01)."""


def stiffness_signature(fit: FitResult, data: ConfigurationData, *, n_grid: int = 48) -> dict:
    """Whether a fit with a stiffness term (``dahl_stiffness``, ``iwan_stiffness``) shows
    the stiffness-nonlinearity signature.

    The output contract's signature: the frequency shifts with amplitude more than the
    friction that fits the damping explains. Over the measured amplitudes the relative
    change of the fitted model's damped frequency is compared with that of its friction
    alone (the same fit with the stiffness term switched off); the signature is there
    when the whole change is larger in magnitude, or when the model's frequency rises
    with amplitude anywhere by more than the models' accuracy (``TOL_REL_F``): a
    friction joint (Dahl, LuGre, Iwan: Jenkins elements) only lowers the frequency as
    the amplitude grows, and a velocity-squared loss leaves it put, so a rise is a
    stiffness the friction cannot explain at all.

    Why: Dahl's pre-sliding damping grows in proportion to amplitude, its softening
    with its square, so a stiff Dahl joint deep in pre-sliding, with a stiffness term
    that cancels its softening, reproduces a velocity-squared loss (damping in
    proportion to amplitude, frequency put) as closely as ``dahl_quadratic`` does. Such
    a fit's stiffness term works against the friction's frequency change at every
    amplitude; that of an amplitude-dependent stiffness the data show adds to it,
    outgrows it, or (a hardening spring beside micro-slip, whose softening grows more
    slowly than the spring's stiffening) turns the frequency back up.

    A spring that only lessens the friction's softening, the frequency never turning
    up, still has an amplitude dependence of its own, where a term that cancels part of
    the softening mirrors it: that term is a joint carrying less stiffness, not a second
    mechanism. So the signature is also there when the share of the term's relative
    frequency change that is not proportional to the friction's softening (over the
    measured amplitudes, the sine of the angle between the two curves) reaches
    :data:`OWN_SHAPE_SHARE` and that part changes the frequency somewhere by more than the
    models' accuracy.

    Returns
    -------
    dict
        ``relative_frequency_change`` (model, lowest to highest amplitude),
        ``friction_relative_frequency_change`` (stiffness term off),
        ``frequency_rise`` (the model's largest relative rise of frequency from a lower
        to a higher measured amplitude, 0 where it never rises), ``rise_limit``,
        ``own_shape_share`` (the term's share not proportional to the friction's
        softening; 1 where the friction does not soften, 0 without a term) and
        ``shows_signature`` (bool).
    """
    velocity = np.geomspace(float(np.min(data.velocity_in_s)), float(np.max(data.velocity_in_s)), n_grid)
    curves = []
    for params in (fit.params, {**fit.params, "stiffness_shift": 0.0}):
        _, frequency_hz = model_curves(fit.model, params, velocity, response_order=data.grid_response_order)
        curves.append(frequency_hz)
    whole, friction = (float(f[-1] / f[0] - 1.0) for f in curves)
    rise = float(np.max(curves[0] / np.minimum.accumulate(curves[0]) - 1.0))
    term = curves[0] / curves[1] - 1.0
    softening = curves[1] / curves[1][0] - 1.0
    scale = float(softening @ softening)
    own = term - (float(term @ softening) / scale) * softening if scale > 0 else term
    own_share = float(np.sqrt(own @ own / (term @ term))) if np.any(term) else 0.0
    own_shape = own_share >= OWN_SHAPE_SHARE and float(np.max(np.abs(own))) > TOL_REL_F
    return {
        "relative_frequency_change": whole,
        "friction_relative_frequency_change": friction,
        "frequency_rise": rise,
        "rise_limit": TOL_REL_F,
        "own_shape_share": own_share,
        "shows_signature": bool(abs(whole) > abs(friction) or rise > TOL_REL_F or own_shape),
    }


MICROSLIP_ONSET = 0.1
"""The joint's damping counts from where it first exceeds this share of the linear damping
``zeta0`` (the onset of the lab's micro-slip visibility ranges, docs/discovery.md)."""


def microslip_signature(fit: FitResult, data: ConfigurationData, *, n_grid: int = 48) -> dict:
    """Whether the joint of a combination (``iwan_cells_<n>_*``) shows micro-slip's signature.

    The output contract's signature: damping that grows as a power of amplitude with an
    exponent clearly below the single-state model's 1, over a decade or more. The joint's
    own damping is the fit's with the extension switched off, less ``zeta0``; over the
    measured amplitudes where it exceeds :data:`MICROSLIP_ONSET` of ``zeta0``, its
    log-log slope (least squares) and the decades it spans. The signature is there when the
    slope is below 1 and the span at least a decade.

    Why: the slip-threshold distribution is free in shape, so beside a stiffness term it
    can follow a single-state (Dahl) joint more closely than the fitted Dahl joint does; a
    Dahl joint's damping grows in proportion to amplitude below slip (slope 1) and peaks at
    slip, so it rises less than a decade at a slope near 1, the patch joint's spread of
    thresholds over more than a decade at 0.5-0.8.

    Returns
    -------
    dict
        ``damping_exponent``, ``decades`` and ``shows_signature``.
    """
    velocity = np.geomspace(float(np.min(data.velocity_in_s)), float(np.max(data.velocity_in_s)), n_grid)
    joint_only = {**fit.params}
    for name in ("stiffness_shift", "quadratic_zeta_per_in_s"):
        if name in joint_only:
            joint_only[name] = 0.0
    zeta, _ = model_curves(fit.model, joint_only, velocity, response_order=data.grid_response_order)
    excess = zeta - fit.params["zeta0"]
    rising = excess > MICROSLIP_ONSET * fit.params["zeta0"]
    if np.count_nonzero(rising) < 3:
        return {"damping_exponent": None, "decades": 0.0, "shows_signature": False}
    exponent = float(np.polyfit(np.log(velocity[rising]), np.log(excess[rising]), 1)[0])
    decades = float(np.log10(np.max(velocity[rising]) / np.min(velocity[rising])))
    return {
        "damping_exponent": exponent,
        "decades": decades,
        "shows_signature": bool(exponent < 1.0 and decades >= 1.0),
    }


def threshold_signature(cells: FitResult, power_law: FitResult, data: ConfigurationData) -> dict:
    """Whether the Iwan joint with the slip thresholds from the data (``iwan_cells_<n>``,
    alone) shows micro-slip's signature, read with the power law it refines.

    The exponent is the thresholds' own (:func:`microslip_signature`): below 1, a spread
    of thresholds, not a single-state joint. The span is theirs or the power law's: the
    thresholds' free shape trades ``zeta0`` against the lowest thresholds, so where the
    damping's rise starts near the bottom of the measured range the start of their rise
    (from :data:`MICROSLIP_ONSET` of their ``zeta0``) may be put higher and span less
    than the decade the data show; the power law, one exponent over every measured
    amplitude, reads that span, and counts where it shows the signature itself.

    Returns
    -------
    dict
        ``damping_exponent`` and ``decades`` (the thresholds'), ``power_law`` (the power
        law's :func:`microslip_signature`) and ``shows_signature`` (bool).
    """
    own, rigid = microslip_signature(cells, data), microslip_signature(power_law, data)
    spread = own["damping_exponent"] is not None and own["damping_exponent"] < 1.0
    return {
        "damping_exponent": own["damping_exponent"],
        "decades": own["decades"],
        "power_law": rigid,
        "shows_signature": bool(spread and (own["decades"] >= 1.0 or rigid["shows_signature"])),
    }

"""The measured curves of one configuration and their uncertainties: what the averaged-model
fits (:mod:`workflow.models.averaged_fit`) take.

Input: the rows of ``results/tables/segments.parquet`` of one configuration
(``configuration``, ``run``, ``velocity_amplitude_in_s``, ``zeta``, ``frequency_hz``,
``bearing_area_in2``). The scatter is a smooth trend (robust cubic in ``log10 V``) through
each curve and the robust spread of the segments around it, per amplitude bin, combined
in quadrature with the averaged models' accuracy (:data:`TOL_LN_ZETA`, :data:`TOL_REL_F`),
which pooled channels share (:func:`pooled_total_uncertainty`).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from workflow.io.recording_time import FILE_NAME_ORDER, run_order
from workflow.models.averaged import RESPONSE_ORDER

__all__ = [
    "TOL_LN_ZETA",
    "TOL_REL_F",
    "ConfigurationData",
    "prepare_configuration",
    "Scatter",
    "robust_trend",
    "estimate_scatter",
    "scatter_of",
    "log_damping_bias",
    "mean_unbiased_damping",
    "pooled_precision",
    "pooled_total_uncertainty",
]


TOL_LN_ZETA = 0.02
"""Accuracy of the averaged models in ``ln zeta`` (about 2 %: the largest deviation
from direct integration of the Dahl oscillator through the slip transition, where a
10-cycle segment averages over the curvature of the damping curve)."""


TOL_REL_F = 1.0e-4
"""Accuracy of the averaged models in relative frequency (direct integration: a few
1e-5 away from the transition, 3.6e-4 at its steepest point)."""


@dataclass
class ConfigurationData:
    """The measured curves of one configuration.

    Attributes
    ----------
    name : str
    velocity_in_s, zeta, frequency_hz : ndarray
        Per segment: velocity amplitude (in/s), damping ratio, damped frequency (Hz).
    run_index : ndarray of int
        0-based run of each segment in run order (``run_names``).
    run_names : list of str
        The runs in run order: by recording start when the files give one, else by name.
    run_order : str
        Which order ``run_names`` is, in words (:func:`workflow.io.recording_time.run_order`).
    bearing_area_in2 : float or None
    response_order : int or ndarray of int
        0, 1, 2: the record was displacement, velocity, acceleration; per segment where
        pooled channels record different quantities (accelerometers beside a laser
        vibrometer: each envelope decays in its own quantity's way).
    n_dropped : int
        Segments dropped because ``zeta <= 0`` or a value was not finite.
    fit_rms, response_amplitude : ndarray or None
        Per segment (when the table has them): RMS residual of the ln-envelope line
        of the log decrement, and the envelope amplitude in the record's unit.
    anchor_velocity_in_s : float
        Amplitude the bins are counted from (default: the largest measured).
    channel_index : ndarray of int or None
        Per segment, the response channel (sensor) that measured it, when the segments
        of several channels are pooled (:mod:`workflow.discovery.joint`): each channel
        then has its own scatter (:func:`scatter_of`). None: one channel.
    """

    name: str
    velocity_in_s: np.ndarray
    zeta: np.ndarray
    frequency_hz: np.ndarray
    run_index: np.ndarray
    run_names: list[str]
    bearing_area_in2: float | None
    response_order: int | np.ndarray = 2
    n_dropped: int = 0
    fit_rms: np.ndarray | None = None
    response_amplitude: np.ndarray | None = None
    anchor_velocity_in_s: float = 0.0
    """Top of the measured amplitudes (default: the largest), in/s: amplitude bins are
    counted down from it, so that they do not depend on the sensor's position."""
    run_order: str = FILE_NAME_ORDER
    channel_index: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not self.anchor_velocity_in_s > 0:
            self.anchor_velocity_in_s = float(np.max(self.velocity_in_s)) if self.velocity_in_s.size else 1.0

    def response_order_of(self, rows: np.ndarray) -> int | np.ndarray:
        """:attr:`response_order` of the segments ``rows`` (a mask or indices)."""
        return self.response_order if np.ndim(self.response_order) == 0 else self.response_order[rows]

    @property
    def grid_response_order(self) -> int:
        """The order a model curve on a grid of amplitudes (not at the segments) is drawn
        in: :attr:`response_order`, or where it is per segment the most segments' order."""
        if np.ndim(self.response_order) == 0:
            return int(self.response_order)
        orders, counts = np.unique(self.response_order, return_counts=True)
        return int(orders[np.argmax(counts)])

    @property
    def n_runs(self) -> int:
        return len(self.run_names)

    @property
    def n_channels(self) -> int:
        """Response channels pooled in these segments (1 unless :attr:`channel_index`)."""
        return 1 if self.channel_index is None else int(np.unique(self.channel_index).size)

    @property
    def n(self) -> int:
        return int(self.velocity_in_s.size)

    @property
    def f_ref(self) -> float:
        """Reference frequency (median), Hz: relative frequency residuals use it."""
        return float(np.median(self.frequency_hz))


def prepare_configuration(
    frame: pd.DataFrame, name: str, response_order: int = 2, record_start: Mapping[str, str] | None = None
) -> ConfigurationData:
    """Arrays of one configuration from the segments table.

    Rows with non-finite values or ``zeta <= 0`` (a growing envelope) cannot enter a
    fit in ``ln zeta`` and are dropped (counted in ``n_dropped``). ``record_start``
    (run name -> ISO 8601 recording start, the runs table's ``record_start``) orders
    the runs when every run has one (:func:`workflow.io.recording_time.run_order`).
    A ``response_quantity`` column (the segments table's) gives the response order in
    place of ``response_order``: one order, or one per segment where the channels
    record different quantities.
    A ``channel_index`` column (pooled channels, :func:`workflow.discovery.joint.joint_segments`)
    becomes :attr:`ConfigurationData.channel_index`.

    Examples
    --------
    A growing envelope (``zeta <= 0``) cannot enter a fit in ``ln zeta`` and is dropped:

    >>> frame = pd.DataFrame(
    ...     {
    ...         "configuration": ["a", "a", "a", "a", "b"],
    ...         "run": ["r1", "r1", "r2", "r2", "r1"],
    ...         "velocity_amplitude_in_s": [1.0, 0.5, 1.2, 0.6, 1.0],
    ...         "zeta": [0.003, 0.002, 0.003, -0.001, 0.002],
    ...         "frequency_hz": [99.0, 99.5, 99.1, 99.6, 98.0],
    ...         "bearing_area_in2": 0.5,
    ...     }
    ... )
    >>> data = prepare_configuration(frame, "a")
    >>> data.n, data.n_dropped, data.run_names, data.run_index.tolist(), data.anchor_velocity_in_s
    (3, 1, ['r1', 'r2'], [0, 0, 1], 1.2)
    """
    rows = frame[frame["configuration"] == name]
    v = rows["velocity_amplitude_in_s"].to_numpy(float)
    z = rows["zeta"].to_numpy(float)
    f = rows["frequency_hz"].to_numpy(float)
    ok = np.isfinite(v) & np.isfinite(z) & np.isfinite(f) & (v > 0) & (z > 0) & (f > 0)
    runs = rows["run"].astype(str).to_numpy()
    run_names, order = run_order(sorted(set(runs[ok])), record_start or {})
    index = {r: i for i, r in enumerate(run_names)}
    area = None
    if "bearing_area_in2" in rows and len(rows):
        a = rows["bearing_area_in2"].to_numpy(float)
        a = a[np.isfinite(a)]
        area = float(a[0]) if a.size else None
    extra = {}
    if {"fit_rms", "response_amplitude"} <= set(rows.columns):
        rms = rows["fit_rms"].to_numpy(float)[ok]
        amp = rows["response_amplitude"].to_numpy(float)[ok]
        if np.all(np.isfinite(rms) & (rms > 0) & np.isfinite(amp) & (amp > 0)):
            extra = {"fit_rms": rms, "response_amplitude": amp}
    if "channel_index" in rows:
        extra["channel_index"] = rows["channel_index"].to_numpy(int)[ok]
    if "response_quantity" in rows and ok.any():
        orders = rows["response_quantity"].map(RESPONSE_ORDER).to_numpy(int)[ok]
        response_order = int(orders[0]) if np.all(orders == orders[0]) else orders
    return ConfigurationData(
        name=name,
        velocity_in_s=v[ok],
        zeta=z[ok],
        frequency_hz=f[ok],
        run_index=np.array([index[r] for r in runs[ok]], dtype=int),
        run_names=run_names,
        bearing_area_in2=area,
        response_order=response_order,
        n_dropped=int((~ok).sum()),
        run_order=order,
        **extra,
    )


@dataclass
class Scatter:
    """Per-segment standard uncertainties of the two curves.

    Attributes
    ----------
    ln_zeta, rel_f : ndarray
        Total standard uncertainty (scatter and model accuracy in quadrature; with
        pooled channels the accuracy counted once per amplitude,
        :func:`pooled_total_uncertainty`) of ``ln zeta`` and of ``f / f_model - 1``.
    noise_ln_zeta, noise_rel_f : ndarray
        The scatter part alone (robust, around the smooth trend).
    """

    ln_zeta: np.ndarray
    rel_f: np.ndarray
    noise_ln_zeta: np.ndarray
    noise_rel_f: np.ndarray


def robust_trend(x: np.ndarray, y: np.ndarray, degree: int, groups: np.ndarray | None = None) -> np.ndarray:
    """Robust (soft-L1) polynomial trend of ``y`` in ``x``; returns fitted values.

    With ``groups`` (integer labels), each group gets its own constant level on top
    of the common polynomial.
    """
    degree = int(min(degree, max(np.unique(np.round(x, 6)).size - 1, 0)))
    xc = (x - x.mean()) / (x.std() + 1e-12)
    design = np.vander(xc, degree + 1)
    if groups is not None and np.unique(groups).size > 1:
        labels = np.unique(groups)
        # one level per group beyond the first (the polynomial's constant is the first's)
        design = np.hstack([design, (groups[:, None] == labels[None, 1:]).astype(float)])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    scale = 1.4826 * np.median(np.abs(y - design @ coef)) + 1e-15
    from scipy import optimize  # here: the campaign's diagnose job fits nothing

    fit = optimize.least_squares(lambda c: (design @ c - y) / scale, coef, loss="soft_l1")
    return design @ fit.x


def estimate_scatter(
    velocity_in_s: np.ndarray,
    values: np.ndarray,
    *,
    degree: int = 3,
    min_bin: int = 12,
    runs: np.ndarray | None = None,
) -> np.ndarray:
    """Robust scatter of a curve around its smooth trend, per segment.

    Parameters
    ----------
    velocity_in_s : ndarray
        Amplitudes, in/s.
    values : ndarray
        The curve (``ln zeta``, or relative frequency).
    degree : int
        Degree of the trend polynomial in ``log10 V``.
    min_bin : int
        Fewest segments per amplitude bin; bins are consecutive in amplitude with
        about ``max(min_bin, n / 8)`` segments.
    runs : ndarray of int, optional
        Run of each segment: each run then gets its own level of the trend, so the
        scatter is that of the segments within a ring-down. Differences between runs
        are left to the models and to the run-level tests (a drift with run order is
        a cause, not noise; pooled, it inflated the scatter that normalises every
        error and so hid itself).

    Returns
    -------
    ndarray
        1.4826 * median absolute deviation of the residuals in each bin,
        interpolated in ``log10 V`` to every segment (constant beyond the ends).
    """
    x = np.log10(velocity_in_s)
    resid = values - robust_trend(x, values, degree, groups=runs)
    order = np.argsort(x)
    per_bin = max(min_bin, x.size // 8)
    n_bins = max(1, x.size // per_bin)
    centres, spreads = [], []
    for chunk in np.array_split(order, n_bins):
        r = resid[chunk]
        centres.append(float(np.median(x[chunk])))
        spreads.append(1.4826 * float(np.median(np.abs(r - np.median(r)))))
    spreads = np.maximum(np.array(spreads), 1e-12)
    return np.interp(x, np.array(centres), spreads)


def scatter_of(data: ConfigurationData) -> Scatter:
    """:class:`Scatter` of a configuration's two curves; with pooled channels, each
    channel's own (a sensor near a node of the mode measures noisier curves), and the
    models' accuracy shared by the channels (:func:`pooled_total_uncertainty`)."""
    channels = np.zeros(data.n, dtype=int) if data.channel_index is None else data.channel_index
    noise_z, noise_f = np.empty(data.n), np.empty(data.n)
    rel_f = data.frequency_hz / data.f_ref - 1.0
    for channel in np.unique(channels):
        rows = channels == channel
        v, runs = data.velocity_in_s[rows], data.run_index[rows]
        noise_z[rows] = estimate_scatter(v, np.log(data.zeta[rows]), runs=runs)
        noise_f[rows] = estimate_scatter(v, rel_f[rows], runs=runs)
    if np.unique(channels).size < 2:
        return Scatter(np.hypot(noise_z, TOL_LN_ZETA), np.hypot(noise_f, TOL_REL_F), noise_z, noise_f)
    return Scatter(
        pooled_total_uncertainty(data.velocity_in_s, channels, noise_z, TOL_LN_ZETA),
        pooled_total_uncertainty(data.velocity_in_s, channels, noise_f, TOL_REL_F),
        noise_z,
        noise_f,
    )


RELATIVE_NOISE_GRID = np.linspace(0.0, 1.0, 101)
"""Relative standard deviations ``r`` of a segment's damping estimate at which
:func:`log_damping_bias` is tabulated."""


def _log_noise_spread_and_mean(r: float) -> tuple[float, float]:
    """Robust spread (1.4826 x median absolute deviation) and mean of ``ln(1 + r z)``,
    ``z`` standard normal with ``1 + r z > 0``."""
    from scipy import integrate, optimize, special

    lowest = -1.0 / r
    kept = special.ndtr(-lowest)  # P(1 + r z > 0)
    median = np.log1p(r * special.ndtri(special.ndtr(lowest) + 0.5 * kept))

    def within(m: float) -> float:
        """P(|ln(1 + r z) - median| < m | kept) - 1/2."""
        inside = special.ndtr(np.expm1(median + m) / r) - special.ndtr(np.expm1(median - m) / r)
        return inside / kept - 0.5

    def weighted_log(z: float) -> float:
        return np.log1p(r * z) * np.exp(-0.5 * z * z) / np.sqrt(2.0 * np.pi)

    mad = optimize.brentq(within, 1e-12, 50.0, xtol=1e-14)
    mean = integrate.quad(weighted_log, max(lowest, -40.0), 40.0, limit=200, epsabs=1e-13)[0] / kept
    return 1.4826 * mad, mean


@functools.lru_cache(maxsize=1)
def _log_damping_bias_table() -> tuple[np.ndarray, np.ndarray]:
    """:func:`_log_noise_spread_and_mean` at each ``r`` of :data:`RELATIVE_NOISE_GRID`
    (spreads, means; 0 and 0 at ``r = 0``)."""
    rows = [(0.0, 0.0)] + [_log_noise_spread_and_mean(float(r)) for r in RELATIVE_NOISE_GRID[1:]]
    spreads, means = np.array(rows).T
    return spreads, means


def log_damping_bias(noise_ln_zeta: np.ndarray) -> np.ndarray:
    """Mean of ``ln zeta_hat - ln zeta`` for segments whose ``ln zeta`` scatters by
    ``noise_ln_zeta`` (the robust spread around the trend, :func:`estimate_scatter`).

    A segment's damping is the slope of a line fitted to its log envelope: the estimate
    is the true damping plus a Gaussian error of relative standard deviation ``r``, kept
    only where positive (:func:`prepare_configuration`). Its logarithm is then unbiased
    in the median but not in the mean: ``E[ln(1 + r z)]`` is about ``-r^2 / 2``, and the
    fits and bin tests average ``ln zeta``. Near a node of the mode, where the noise is a
    large part of the signal, ``r`` reaches 0.3-0.4 at the lowest amplitudes, the mean
    falls by 0.05-0.1 there and less above: a mean-based analysis reads that as damping
    rising with amplitude. ``r`` is found from the robust spread of ``ln(1 + r z)``,
    which is what the scatter measures, and the mean of that distribution returned
    (tabulated for ``r`` up to 1 and interpolated in the variance, held beyond).

    Examples
    --------
    >>> bias = log_damping_bias(np.array([0.0, 0.01, 0.3]))
    >>> [round(float(b), 4) for b in bias]
    [0.0, -0.0001, -0.0539]
    """
    spreads, means = _log_damping_bias_table()
    # interpolated in the variance, in which the bias is linear for small noise
    return np.interp(np.asarray(noise_ln_zeta, float) ** 2, spreads**2, means)


def mean_unbiased_damping(data: ConfigurationData, scatter: Scatter) -> ConfigurationData:
    """``data`` with each segment's damping divided by ``exp`` of its
    :func:`log_damping_bias` (from its channel's scatter of ``ln zeta`` at its amplitude,
    ``scatter.noise_ln_zeta``): curves whose ``ln zeta`` the fits, held-out errors and
    bin tests may average. The relative change is ``r^2 / 2``: 1e-4 at a scatter of 1.4 %,
    5 % at 30 %."""
    return replace(data, zeta=data.zeta * np.exp(-log_damping_bias(scatter.noise_ln_zeta)))


def pooled_total_uncertainty(
    velocity_in_s: np.ndarray, channels: np.ndarray, noise: np.ndarray, accuracy: float
) -> np.ndarray:
    """Per segment of pooled channels, the uncertainty its fit weight is taken from: its
    channel's scatter, scaled so that the models' accuracy counts once for every channel.

    Every channel measures the same modal curve, so the averaged models' error at an
    amplitude (``accuracy``) is common to the channels, while their scatter is their own.
    The measurements at amplitude ``V`` then weigh as their precision-weighted mean does,
    whose uncertainty is ``accuracy^2 + 1 / P(V)`` with ``P(V)`` the channels' summed
    precision ``sum_c 1 / noise_c(V)^2``: each segment's total variance is
    ``noise^2 (1 + accuracy^2 P(V))``. With one channel this is ``noise^2 + accuracy^2``;
    with the accuracy counted per segment instead, a channel 15 times noisier than the
    reference in frequency (a sensor near a node of the mode) weighed nearly as much as
    the reference, its distortions pulling the shared fit by more than the scatter of
    the channel that sees the mode.

    Parameters
    ----------
    velocity_in_s : ndarray
        Amplitudes on one scale (the pooled channels'), in/s.
    channels : ndarray of int
        Channel of each segment.
    noise : ndarray
        Each segment's scatter (:func:`estimate_scatter`, per channel), in the curve's unit.
    accuracy : float
        The models' accuracy in that unit (:data:`TOL_LN_ZETA`, :data:`TOL_REL_F`).

    Returns
    -------
    ndarray
        The total standard uncertainty of each segment.

    Examples
    --------
    Two channels at the same amplitudes, scatters 1 and 10 times the accuracy: the
    noisy one counts by its scatter against the clean one's, not by the accuracy.

    >>> v = np.tile([1.0, 2.0, 3.0], 2)
    >>> s = pooled_total_uncertainty(v, np.repeat([0, 1], 3), np.repeat([0.01, 0.1], 3), 0.01)
    >>> np.round(s, 4).tolist()
    [0.0142, 0.0142, 0.0142, 0.1418, 0.1418, 0.1418]
    """
    return noise * np.sqrt(1.0 + accuracy**2 * pooled_precision(velocity_in_s, channels, noise))


def pooled_precision(velocity_in_s: np.ndarray, channels: np.ndarray, noise: np.ndarray) -> np.ndarray:
    """Per segment of pooled channels, ``P(V)``: the summed precision ``sum_c 1 / noise_c^2``
    of every channel at its amplitude, the other channels' interpolated in ``ln V`` where
    their segments reach it.

    ``velocity_in_s``, ``channels`` and ``noise`` as for :func:`pooled_total_uncertainty`.

    Returns
    -------
    ndarray
        ``P(V)`` of each segment, in the inverse square of the curve's unit.

    Examples
    --------
    The second channel reaches only the first two amplitudes:

    >>> v = np.array([1.0, 2.0, 4.0, 1.0, 2.0])
    >>> pooled_precision(v, np.array([0, 0, 0, 1, 1]), np.array([1.0, 1.0, 1.0, 0.5, 0.5])).tolist()
    [5.0, 5.0, 1.0, 5.0, 5.0]
    """
    log_v = np.log(velocity_in_s)
    precision = 1.0 / noise**2
    pooled = precision.copy()
    for channel in np.unique(channels):
        rows = channels == channel
        x, order = np.unique(log_v[rows], return_inverse=True)
        p = np.bincount(order, weights=precision[rows]) / np.bincount(order)
        # the other channels at each segment's amplitude, where that channel reaches it
        others = ~rows & (log_v >= x[0]) & (log_v <= x[-1])
        pooled[others] += np.interp(log_v[others], x, p)
    return pooled

"""Model discovery: where the fitted friction model is wrong, why, and what fixes it.

Input per configuration: its measured log-decrement segments (rows of
``results/tables/segments.parquet``: ``configuration``, ``run``,
``velocity_amplitude_in_s``, ``zeta``, ``frequency_hz``, ``bearing_area_in2``).
Everything is computed from these; nothing is read from truth files.

Steps (docs/discovery.md states the rule with its numbers):

1. **Scatter.** A smooth trend (robust cubic in ``log10 V``) through each curve; the
   scatter of the segments around it, per amplitude bin (1.4826 MAD), combined in
   quadrature with the averaged models' accuracy (:data:`TOL_LN_ZETA`,
   :data:`TOL_REL_F`) gives every segment's standard uncertainty in ``ln zeta`` and in
   relative frequency. Residuals divided by it are the *normalised residuals*.
2. **Fits.** Every model of :mod:`workflow.models.averaged` is fitted by weighted least
   squares on both curves at once: a quasi-random (Sobol) global stage over the
   parameter box (log coordinates for scale parameters), then
   ``scipy.optimize.least_squares`` from the best distinct global points.
3. **Held-out error.** K-fold cross-validation over runs (interleaved in run
   order); with one run, contiguous amplitude blocks are held out. The error is the
   RMS normalised residual over the held-out segments, each quarter decade of
   amplitude weighted equally (:func:`amplitude_weights`).
4. **Discrepancy.** The best baseline's residuals, per half decade of amplitude
   and per curve: each run's mean residual in the bin, then mean and standard error
   over runs. A misfit is real where it is significant (Bonferroni-corrected t test,
   familywise 1 %) *and* larger than the models' accuracy. A linear trend of the
   runs' damping residuals with run order is tested the same way.
5. **Decision** (see :func:`decide`): ``none`` / a named cause / ``unknown``.
6. **Across configurations:** parameters linear in ``ln(bearing area)``, each
   configuration predicted from the others.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import special

from workflow.io.recording_time import FILE_NAME_ORDER, run_order
from workflow.io.settings import AnalysisSettings, DiscoverySettings
from workflow.models.averaged import (
    MAX_THRESHOLD_CELLS,
    MODELS,
    RESPONSE_ORDER,
    AveragedModel,
    CurveGrid,
    model_curves,
    threshold_cell_edges,
)
from workflow.models.sampling import scrambled_sobol_points

__all__ = [
    "CAUSE_MODELS",
    "BASELINE_MODELS",
    "TOL_LN_ZETA",
    "TOL_REL_F",
    "FitSettings",
    "ConfigurationData",
    "Scatter",
    "FitResult",
    "prepare_configuration",
    "estimate_scatter",
    "parameter_box",
    "fit_model",
    "cross_validate",
    "binned_discrepancy",
    "run_order_trend",
    "decide",
    "diagnose_configuration",
    "across_configurations",
    "diagnose_campaign",
    "residual_table",
    "amplitude_weights",
    "amplitude_bin",
    "RunGroups",
    "run_groups",
    "run_offsets",
    "calibration_segments",
    "heldout_standard_error",
    "heldout_units",
]

log = logging.getLogger(__name__)

CAUSE_MODELS: dict[str, str] = {
    "microslip_power_law": "iwan",
    "quadratic_damping": "dahl_quadratic",
    "stiffness_nonlinearity": "dahl_stiffness",
    "run_drift": "dahl_drift",
}
"""Cause id -> the extended model that represents it."""

BASELINE_MODELS = ("dahl", "lugre")
"""The paper's models (each + linear viscous damping)."""

TOL_LN_ZETA = 0.02
"""Accuracy of the averaged models in ``ln zeta`` (about 2 %: the largest deviation
from direct integration of the Dahl oscillator through the slip transition, where a
10-cycle segment averages over the curvature of the damping curve)."""

TOL_REL_F = 1.0e-4
"""Accuracy of the averaged models in relative frequency (direct integration: a few
1e-5 away from the transition, 3.6e-4 at its steepest point)."""

ALPHA = 0.01
"""Familywise false-alarm probability of the discrepancy tests: half of it is shared by
the amplitude bins (Bonferroni over bins and curves), half goes to the run-order test."""

RUN_ORDER_TESTS = 2
"""The run-order test is significant at ``p < ALPHA / RUN_ORDER_TESTS``: it is one
question on its own axis (run order, not amplitude), so it is not diluted by the number
of amplitude bins."""

CLEAR_GAIN = 0.7
"""Without a significant baseline misfit, a candidate is named only when its held-out
error is below this fraction of the baseline's (the same margin as ``RESIDUAL_GAIN``).
On no-effect (Dahl-joint) campaigns the averaged models' own bias, a few 1e-6 in
relative frequency, let an extension reach 0.62-0.87 of the baseline's error
(bench/hit_rate.py, seeds 1-40); 0.85 named a cause in 18 % of them."""

RESIDUAL_GAIN = 0.7
"""With a significant baseline misfit, a candidate that leaves a significant misfit
is still accepted when its held-out error is below this fraction of the baseline's
(it removes most of the misfit); otherwise the verdict is ``unknown``."""

HELD_OUT_METRIC = "heldout_rms_residual_over_scatter_amplitude_weighted"
HELD_OUT_SCALE = "noise"
"""Held-out residuals are divided by the measured scatter alone ("noise"), not by the
scatter combined with the model accuracy used as fit weights ("norm")."""

NESTED_DAHL = {
    "lugre": lambda d: {
        "stiction_ratio": 1e-3,
        "micro_damping_ratio": 0.0,
        "stribeck_velocity_in_s": float(np.median(d.velocity_in_s)),
    },
    "dahl_quadratic": lambda d: {
        "quadratic_zeta_per_in_s": 2e-3 * float(np.min(d.zeta)) / float(np.max(d.velocity_in_s))
    },
    "dahl_stiffness": lambda d: {"stiffness_shift": 0.0, "stiffness_exponent": 2.0},
    "dahl_drift": lambda d: {"drift": 0.0},
}
"""Extension parameters that reduce each model to Dahl (the nested start)."""


@dataclass(frozen=True)
class FitSettings:
    """Optimiser settings: the ``discovery`` section of config.yaml (its defaults are
    :class:`workflow.io.settings.DiscoverySettings`'), then the refinement budgets."""

    global_samples: int = DiscoverySettings.global_samples
    local_starts: int = DiscoverySettings.local_starts
    seed: int = DiscoverySettings.seed
    folds: int = DiscoverySettings.folds
    max_nfev: int = 60
    """Most residual evaluations of one local refinement from a global start."""
    two_stage_models: tuple[str, ...] = ("lugre",)
    """Models refined in two stages (expensive ones): every start briefly, the best fully."""
    screen_nfev: int = 8
    """Evaluations of the short refinement from each start (the best is continued)."""
    fold_nfev: int = 12
    """Most evaluations when refitting a cross-validation fold from the all-data fit."""
    resamples: int = DiscoverySettings.resamples


# ------------------------------------------------------------------------- data
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
    response_order : int
        0, 1, 2: the record was displacement, velocity, acceleration.
    n_dropped : int
        Segments dropped because ``zeta <= 0`` or a value was not finite.
    fit_rms, response_amplitude : ndarray or None
        Per segment (when the table has them): RMS residual of the ln-envelope line
        of the log decrement, and the envelope amplitude in the record's unit.
    anchor_velocity_in_s : float
        Amplitude the bins are counted from (default: the largest measured).
    """

    name: str
    velocity_in_s: np.ndarray
    zeta: np.ndarray
    frequency_hz: np.ndarray
    run_index: np.ndarray
    run_names: list[str]
    bearing_area_in2: float | None
    response_order: int = 2
    n_dropped: int = 0
    fit_rms: np.ndarray | None = None
    response_amplitude: np.ndarray | None = None
    anchor_velocity_in_s: float = 0.0
    """Top of the measured amplitudes (default: the largest), in/s: amplitude bins are
    counted down from it, so that they do not depend on the sensor's position."""
    run_order: str = FILE_NAME_ORDER

    def __post_init__(self) -> None:
        if not self.anchor_velocity_in_s > 0:
            self.anchor_velocity_in_s = float(np.max(self.velocity_in_s)) if self.velocity_in_s.size else 1.0

    @property
    def n_runs(self) -> int:
        return len(self.run_names)

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


# ---------------------------------------------------------------------- scatter
@dataclass
class Scatter:
    """Per-segment standard uncertainties of the two curves.

    Attributes
    ----------
    ln_zeta, rel_f : ndarray
        Total standard uncertainty (scatter and model accuracy in quadrature) of
        ``ln zeta`` and of ``f / f_model - 1``.
    noise_ln_zeta, noise_rel_f : ndarray
        The scatter part alone (robust, around the smooth trend).
    """

    ln_zeta: np.ndarray
    rel_f: np.ndarray
    noise_ln_zeta: np.ndarray
    noise_rel_f: np.ndarray


def _robust_trend(x: np.ndarray, y: np.ndarray, degree: int, groups: np.ndarray | None = None) -> np.ndarray:
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
    resid = values - _robust_trend(x, values, degree, groups=runs)
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
    """:class:`Scatter` of a configuration's two curves."""
    noise_z = estimate_scatter(data.velocity_in_s, np.log(data.zeta), runs=data.run_index)
    noise_f = estimate_scatter(data.velocity_in_s, data.frequency_hz / data.f_ref - 1.0, runs=data.run_index)
    return Scatter(np.hypot(noise_z, TOL_LN_ZETA), np.hypot(noise_f, TOL_REL_F), noise_z, noise_f)


# ------------------------------------------------------------------------ fits
@dataclass
class FitContext:
    """Data-derived quantities shared by the fits of a campaign."""

    reference_velocity_in_s: float


JOINT_SHARE_MAX = 0.1
"""Largest joint share ``beta`` of the small-amplitude modal stiffness a fit may take: a
physical limit, not a range the data set. ``beta`` is the fraction of ``omega^2`` that a
full slip removes, the part of the mode's stiffness carried through the frictional
contact. The data cannot bound it where the joint stays in pre-sliding (common on heavily
clamped washers): Dahl's damping there grows as ``0.21 beta V / V_s`` and its softening as
``0.19 beta (V / V_s)^2``, so a damping that grows in proportion to amplitude with little
softening (a velocity-squared loss) is fitted by a joint as stiff as the softening's
smallness asks, ``beta = 4.2 zeta_joint^2 / softening`` (exact coefficients ``2/(3 pi)``
and ``3/16``). The specimen's contact model
(:mod:`workflow.models.contact`) puts the stuck washers' contact at 3-4 % of the modal
stiffness, and the real campaigns the project was checked on fit 1-2 %; a tenth allows
2.5 times the stiffest (a 5 % frequency drop at full slip). With half (a 29 % drop) a Dahl
baseline absorbed velocity-squared damping of 0.2-0.5 % on the virtual lab's washer
joints. A fit that ends on this limit is flagged on the verdict page."""

SLIP_SCALE_ABOVE_RANGE = 1000.0
"""How far above the top measured amplitude a joint's slip scale may lie. A joint that
never leaves pre-sliding over the measured range (Dahl: damping ``~ 0.21 beta V / V_s``,
frequency loss ``~ 0.19 beta (V / V_s)^2``) is common on heavily clamped washers; with
the joint share ``beta`` at :data:`JOINT_SHARE_MAX`, a slip scale 1000 times the top
amplitude still adds 2e-5 to the damping ratio there, 2-3 % of a typical linear damping. A
bound of 30 forced such joints to show a frequency loss they do not have: on the
virtual lab's washer joints (slip scales 200-2000 times the top amplitude) the misfit,
a few 1e-6 at the top, was taken up by the stiffness or quadratic candidates."""

CELL_FRACTION_BOX = (float(np.log(1e-7)), float(np.log(JOINT_SHARE_MAX)))
"""Fit range of a slip-threshold cell's stiffness share (ln): from nothing the data can
see (a 1e-7 frequency-squared change) to the whole joint's limit."""


def parameter_box(model: AveragedModel, data: ConfigurationData) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of the fit coordinates (ln value for log parameters) from the data.

    Scales follow the data: frequencies around the measured ones, damping around the
    measured damping, velocity scales over the measured amplitude range widened by a
    factor 30 below and :data:`SLIP_SCALE_ABOVE_RANGE` above.
    """
    v_lo, v_hi = float(data.velocity_in_s.min()), float(data.velocity_in_s.max())
    z_lo, z_hi = float(np.min(data.zeta)), float(np.max(data.zeta))
    f_lo, f_hi = float(np.min(data.frequency_hz)), float(np.max(data.frequency_hz))
    boxes = {
        "f_lin_hz": (np.log(f_lo * 0.98), np.log(f_hi * 1.05)),
        "zeta0": (np.log(z_lo / 30.0), np.log(z_hi * 1.5)),
        "joint_stiffness_fraction": (np.log(1e-4), np.log(JOINT_SHARE_MAX)),
        "slip_velocity_in_s": (np.log(v_lo / 30.0), np.log(v_hi * SLIP_SCALE_ABOVE_RANGE)),
        "stiction_ratio": (0.0, 3.0),
        "stribeck_velocity_in_s": (np.log(v_lo / 10.0), np.log(v_hi * 10.0)),
        "micro_damping_ratio": (-0.9, 3.0),
        "chi": (-0.95, 0.5),
        "macro_ratio": (np.log(1e-3), np.log(10.0)),
        "quadratic_zeta_per_in_s": (np.log(1e-3 * z_lo / v_hi), np.log(3.0 * z_hi / v_hi)),
        "stiffness_shift": (-0.1, 0.1),
        "stiffness_exponent": (np.log(0.5), np.log(4.0)),
        "drift": (-1.5, 1.5),
    }
    for name in model.cell_names:
        boxes[name] = CELL_FRACTION_BOX
    lo = np.array([boxes[p.name][0] for p in model.params])
    hi = np.array([boxes[p.name][1] for p in model.params])
    return lo, hi


def to_physical(model: AveragedModel, coords: np.ndarray) -> dict[str, np.ndarray]:
    """Fit coordinates (..., k) -> physical parameter arrays (..., 1)."""
    coords = np.atleast_2d(coords)
    out = {}
    for i, p in enumerate(model.params):
        c = coords[:, i : i + 1]
        out[p.name] = np.exp(c) if p.scale == "log" else c
    return out


def to_coords(model: AveragedModel, params: Mapping[str, float]) -> np.ndarray:
    """Physical parameters -> fit coordinates."""
    return np.array(
        [np.log(params[p.name]) if p.scale == "log" else float(params[p.name]) for p in model.params]
    )


@dataclass
class FitResult:
    """A fitted model.

    Attributes
    ----------
    model : str
    coords : ndarray
        Best fit coordinates (ln for log parameters).
    params : dict of float
        Physical parameters (with fixed ones).
    cost : float
        Mean squared normalised residual on the fitted segments.
    """

    model: str
    coords: np.ndarray
    params: dict[str, float]
    cost: float


RUN_OFFSET_FLOOR = 0.05
"""Smallest ``1 + delta_zeta0 / zeta_model`` kept when a run's linear-damping offset is
applied (a run cannot have negative damping)."""


@dataclass(frozen=True)
class RunGroups:
    """The segments of each run that its offsets are estimated from.

    Built once per set of segments (:func:`run_groups`), so that a fit's residuals,
    evaluated thousands of times, do not rebuild it.

    Attributes
    ----------
    member : ndarray, shape (n, n_runs)
        1.0 where segment ``i`` is of run ``r`` and used, else 0.0.
    present : ndarray of bool, shape (n_runs,)
        Runs with at least one used segment.
    """

    member: np.ndarray
    present: np.ndarray


def run_groups(run_index: np.ndarray, n_runs: int, use: np.ndarray | None = None) -> RunGroups:
    """:class:`RunGroups` of segments of runs ``run_index`` (0-based, ``< n_runs``); only the
    segments in ``use`` (default all) count."""
    use = np.ones(run_index.size, dtype=bool) if use is None else use
    member = (run_index[:, None] == np.arange(n_runs)[None, :]) & use[:, None]
    return RunGroups(member.astype(float), member.any(axis=0))


def run_offsets(
    rel_f: np.ndarray,
    ln_zeta: np.ndarray,
    zeta_model: np.ndarray,
    s_rel_f: np.ndarray,
    s_ln_zeta: np.ndarray,
    groups: RunGroups,
) -> tuple[np.ndarray, np.ndarray]:
    """Each run's own small-amplitude frequency and linear damping, given shared physics.

    Runs of one configuration differ (re-hung, re-struck, a degree warmer): each has its
    own natural frequency, ``f_lin (1 + delta_f)``, and linear damping,
    ``zeta0 + delta_zeta0``, on top of the joint physics they share. Both enter the
    residuals of the shared model almost linearly (``delta_f`` multiplies the model's
    frequency exactly; ``delta_zeta0`` adds ``delta_zeta0 / zeta_model`` to
    ``ln zeta``), so the weighted least-squares offsets of every run have a closed form.

    Parameters
    ----------
    rel_f, ln_zeta : ndarray, shape (..., n)
        Residuals of the shared model: ``f / f_model - 1`` and ``ln zeta - ln zeta_model``.
    zeta_model : ndarray, shape (..., n)
        The shared model's damping ratio at each segment.
    s_rel_f, s_ln_zeta : ndarray, shape (n,)
        Standard uncertainties (the fit weights are their inverse squares).
    groups : RunGroups
        Each segment's run, and the segments the offsets are estimated from
        (:func:`run_groups`).

    Returns
    -------
    delta_f, delta_zeta0 : ndarray, shape (..., n_runs)
        Relative frequency offset and linear-damping offset (damping ratio) of each run;
        0 for a run with no segment used.
    """
    member = groups.member
    w_f = 1.0 / s_rel_f**2
    count_f = w_f @ member
    delta_f = ((rel_f * w_f) @ member) / np.maximum(count_f, 1e-300)
    g = 1.0 / np.maximum(zeta_model, 1e-12)
    w_z = 1.0 / s_ln_zeta**2
    delta_z = ((ln_zeta * g * w_z) @ member) / np.maximum((g * g * w_z) @ member, 1e-300)
    return delta_f, delta_z


def apply_run_offsets(
    rel_f: np.ndarray,
    ln_zeta: np.ndarray,
    zeta_model: np.ndarray,
    delta_f: np.ndarray,
    delta_zeta0: np.ndarray,
    run_index: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Residuals of the shared model with each run's offsets (:func:`run_offsets`) applied."""
    df = np.take(delta_f, run_index, axis=-1)
    dz = np.take(delta_zeta0, run_index, axis=-1)
    rel = (1.0 + rel_f) / (1.0 + df) - 1.0
    ln = ln_zeta - np.log(np.maximum(1.0 + dz / np.maximum(zeta_model, 1e-12), RUN_OFFSET_FLOOR))
    return rel, ln


def centred_run_offsets(
    rel_f, ln_zeta, zeta_model, s_rel_f, s_ln_zeta, groups: RunGroups
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`run_offsets` minus their mean over the runs present, so that the shared
    ``f_lin`` and ``zeta0`` are the runs' mean and stay identifiable."""
    present = groups.present
    n_present = int(np.count_nonzero(present))
    delta_f, delta_z = run_offsets(rel_f, ln_zeta, zeta_model, s_rel_f, s_ln_zeta, groups)
    # the mean as np.mean computes it (sum, then division by the count), without its overhead
    mean_f = np.add.reduce(delta_f[..., present], axis=-1, keepdims=True) / n_present
    mean_z = np.add.reduce(delta_z[..., present], axis=-1, keepdims=True) / n_present
    return np.where(present, delta_f - mean_f, 0.0), np.where(present, delta_z - mean_z, 0.0)


CALIBRATION_FRACTION = 0.25
"""Share of a held-out run's segments, its lowest in amplitude, that set its own
frequency and linear-damping offsets before the rest of the run is scored. Low in
amplitude the joint is stuck and every model of the vocabulary reduces to the same linear
oscillator, so these segments say what the run's beam is without saying which physics
acts above them; they are not scored."""

MIN_CALIBRATION_SEGMENTS = 3


def calibration_segments(velocity_in_s: np.ndarray, run_index: np.ndarray, runs: np.ndarray) -> np.ndarray:
    """Mask of each listed run's lowest-amplitude segments (:data:`CALIBRATION_FRACTION`,
    at least :data:`MIN_CALIBRATION_SEGMENTS`, never the whole run)."""
    mask = np.zeros(velocity_in_s.size, dtype=bool)
    for r in np.atleast_1d(runs):
        members = np.flatnonzero(run_index == r)
        if members.size <= MIN_CALIBRATION_SEGMENTS:
            continue
        k = int(
            np.clip(np.ceil(CALIBRATION_FRACTION * members.size), MIN_CALIBRATION_SEGMENTS, members.size - 1)
        )
        mask[members[np.argsort(velocity_in_s[members])[:k]]] = True
    return mask


def fixed_params(model: AveragedModel, data: ConfigurationData, context: FitContext) -> dict[str, float]:
    """The supplied (not fitted) parameters of a model: the campaign's reference velocity,
    the top of the configuration's measured amplitudes."""
    known = {
        "reference_velocity_in_s": float(context.reference_velocity_in_s),
        "anchor_velocity_in_s": float(data.anchor_velocity_in_s),
    }
    return {name: known[name] for name in model.fixed}


class _Problem:
    """Normalised-residual function of one model on a subset of segments."""

    def __init__(
        self,
        model: AveragedModel,
        data: ConfigurationData,
        scatter: Scatter,
        mask: np.ndarray,
        context: FitContext,
    ):
        self.model = model
        self.mask = mask
        self.grid = CurveGrid(
            data.velocity_in_s[mask],
            run_index=data.run_index[mask],
            n_runs=max(data.n_runs, 1),
            response_order=data.response_order,
            grid_range=(float(data.velocity_in_s.min()), float(data.velocity_in_s.max())),
        )
        self.ln_zeta = np.log(data.zeta[mask])
        self.freq = data.frequency_hz[mask]
        self.s_z = scatter.ln_zeta[mask]
        self.s_f = scatter.rel_f[mask]
        self.run_index = data.run_index[mask]
        self.n_runs = max(data.n_runs, 1)
        self.groups = run_groups(self.run_index, self.n_runs)
        self.per_run = np.count_nonzero(self.groups.present) >= 2
        self.fixed = fixed_params(model, data, context)
        self.lo, self.hi = parameter_box(model, data)

    def physical(self, unit: np.ndarray) -> dict[str, np.ndarray]:
        coords = self.lo + np.atleast_2d(unit) * (self.hi - self.lo)
        p = to_physical(self.model, coords)
        p.update({k: np.array(v) for k, v in self.fixed.items()})
        return p

    def residuals(self, unit: np.ndarray) -> np.ndarray:
        """Normalised residuals, shape (P, 2 n) for unit-box points (P, k)."""
        zeta, freq = self.grid(self.model, self.physical(unit))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            ln_res = self.ln_zeta - np.log(np.maximum(zeta, 1e-12))
            f_res = self.freq / freq - 1.0
            if self.per_run:
                offsets = centred_run_offsets(f_res, ln_res, zeta, self.s_f, self.s_z, self.groups)
                f_res, ln_res = apply_run_offsets(f_res, ln_res, zeta, *offsets, self.run_index)
            r = np.concatenate([ln_res / self.s_z, f_res / self.s_f], axis=-1)
        return np.where(np.isfinite(r), r, 1e6)

    def residuals_and_jacobian(self, unit: np.ndarray, step: float = 1e-5) -> tuple[np.ndarray, np.ndarray]:
        """Residuals at ``unit`` and their forward-difference Jacobian, from one batch."""
        k = unit.size
        points = np.repeat(unit[None, :], k + 1, axis=0)
        steps = np.where(unit + step <= 1.0, step, -step)
        points[np.arange(1, k + 1), np.arange(k)] += steps
        r = self.residuals(points)
        return r[0], ((r[1:] - r[0]) / steps[:, None]).T

    def jacobian(self, unit: np.ndarray, step: float = 1e-5) -> np.ndarray:
        return self.residuals_and_jacobian(unit, step)[1]


class _Evaluations:
    """A problem's residuals and Jacobian for the optimiser, evaluated together: the
    optimiser asks for the Jacobian at the point whose residuals it has just accepted,
    and a batch of the point and its neighbours costs less than the point and then the
    batch."""

    def __init__(self, problem: _Problem):
        self.problem = problem
        self.unit: np.ndarray | None = None
        self.jac: np.ndarray | None = None

    def residuals(self, unit: np.ndarray) -> np.ndarray:
        r, self.jac = self.problem.residuals_and_jacobian(unit)
        self.unit = np.array(unit, copy=True)
        return r

    def jacobian(self, unit: np.ndarray, *_) -> np.ndarray:
        if self.unit is not None and np.array_equal(unit, self.unit):
            return self.jac
        return self.problem.jacobian(unit)


def _local_fit(problem: _Problem, start: np.ndarray, max_nfev: int) -> tuple[np.ndarray, float]:
    from scipy import optimize  # here: the campaign's diagnose job fits nothing

    evaluations = _Evaluations(problem)
    res = optimize.least_squares(
        evaluations.residuals,
        np.clip(start, 1e-6, 1 - 1e-6),
        jac=evaluations.jacobian,
        bounds=(0.0, 1.0),
        method="trf",
        max_nfev=max_nfev,
        x_scale=1.0,
    )
    return res.x, float(np.mean(res.fun**2))


def fit_model(
    model: AveragedModel | str,
    data: ConfigurationData,
    scatter: Scatter,
    context: FitContext,
    *,
    settings: FitSettings = FitSettings(),
    mask: np.ndarray | None = None,
    warm_start: np.ndarray | None = None,
    nested_start: Mapping[str, float] | None = None,
) -> FitResult:
    """Weighted least-squares fit of a model to both curves of (part of) a configuration.

    Parameters
    ----------
    model : AveragedModel or str
    data : ConfigurationData
    scatter : Scatter
        Per-segment uncertainties (weights).
    context : FitContext
    settings : FitSettings
        Global samples, local starts, seed.
    mask : ndarray of bool, optional
        Segments used (default all).
    warm_start : ndarray, optional
        Fit coordinates to refine from (skips the global stage: used for the
        cross-validation folds, started from the all-data fit).
    nested_start : mapping, optional
        Physical parameters of a model this one contains (e.g. the Dahl fit with the
        extension switched off): refined as one more start, so that an extended
        model never fits worse than the model it extends.

    Returns
    -------
    FitResult
    """
    model = MODELS[model] if isinstance(model, str) else model
    mask = np.ones(data.n, dtype=bool) if mask is None else mask
    problem = _Problem(model, data, scatter, mask, context)
    span = problem.hi - problem.lo
    if warm_start is not None:
        starts = [np.clip((warm_start - problem.lo) / span, 0.0, 1.0)]
    else:
        starts = []
        if nested_start is not None:
            starts.append(np.clip((to_coords(model, nested_start) - problem.lo) / span, 0.0, 1.0))
        n = 2 ** int(np.ceil(np.log2(max(settings.global_samples, 2))))
        unit = scrambled_sobol_points(n, len(model.params), settings.seed)
        cost = np.mean(problem.residuals(unit) ** 2, axis=-1)
        order = np.argsort(cost)
        n_nested = len(starts)
        for i in order:  # distinct starts: at least 0.1 apart in the unit box
            if all(np.max(np.abs(unit[i] - s)) > 0.1 for s in starts):
                starts.append(unit[i])
            if len(starts) >= settings.local_starts + n_nested:
                break
    best_u, best_cost = None, np.inf
    if warm_start is not None:
        best_u, best_cost = _local_fit(problem, starts[0], settings.fold_nfev)
    elif model.name not in settings.two_stage_models:
        for start in starts:
            u, c = _local_fit(problem, start, settings.max_nfev)
            if c < best_cost:
                best_u, best_cost = u, c
    else:
        # two stages: a short refinement from every start, then the best one continued
        screened = [_local_fit(problem, start, settings.screen_nfev) for start in starts]
        u0 = min(screened, key=lambda r: r[1])[0]
        best_u, best_cost = _local_fit(problem, u0, settings.max_nfev)
    coords = problem.lo + best_u * span
    params = {p.name: float(v[0, 0]) for p, v in zip(model.params, to_physical(model, coords).values())}
    params.update(problem.fixed)
    return FitResult(model.name, coords, params, best_cost)


def model_residuals(
    fit: FitResult,
    data: ConfigurationData,
    scatter: Scatter,
    context: FitContext,
    *,
    offsets_from: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Raw and normalised residuals of a fit on all segments of a configuration.

    With two runs or more, every run gets its own frequency and linear-damping offset
    (:func:`run_offsets`) estimated from its segments in ``offsets_from`` (default: all
    of them, centred over the runs as in the fit); a run with no segment there keeps
    the shared model.

    Returns ``ln_zeta`` (``ln zeta - ln zeta_model``), ``rel_f`` (``f / f_model - 1``),
    their normalised versions ``z_norm``, ``f_norm`` (total uncertainty) and
    ``z_noise``, ``f_noise`` (scatter alone), the model curves with each run's offsets
    (``zeta_model``, ``f_model``), the offsets ``delta_f``, ``delta_zeta0`` per run,
    ``ln_zeta_shared``, the damping residual of the shared model before the offsets, and
    ``ln_zeta_calibrated``, the damping residual with each run's offsets set by its own
    lowest-amplitude segments (``calibration``, :func:`calibration_segments`) as a
    held-out run's are, and ``ln_zeta_slope``, the shared model's log-log damping slope
    (:func:`damping_curve_slope`).
    """
    model = MODELS[fit.model]
    problem = _Problem(model, data, scatter, np.ones(data.n, dtype=bool), context)
    zeta, freq = problem.grid(model, {k: np.array(v) for k, v in fit.params.items()})
    ln_res = np.log(data.zeta) - np.log(np.maximum(zeta, 1e-12))
    f_res = data.frequency_hz / freq - 1.0
    n_runs = max(data.n_runs, 1)
    delta_f, delta_z = np.zeros(n_runs), np.zeros(n_runs)
    ln_shared, shared_zeta = ln_res, zeta
    calibration = np.zeros(data.n, dtype=bool)
    ln_calibrated = ln_res
    if data.n_runs >= 2:
        calibration = calibration_segments(data.velocity_in_s, data.run_index, np.arange(n_runs))
        calibration_groups = run_groups(data.run_index, n_runs, calibration)
        own = run_offsets(f_res, ln_res, zeta, scatter.rel_f, scatter.ln_zeta, calibration_groups)
        ln_calibrated = apply_run_offsets(f_res, ln_res, zeta, *own, data.run_index)[1]
        offsets = run_offsets if offsets_from is not None else centred_run_offsets
        fitted_groups = run_groups(data.run_index, n_runs, offsets_from)
        delta_f, delta_z = offsets(f_res, ln_res, zeta, scatter.rel_f, scatter.ln_zeta, fitted_groups)
        f_res, ln_res = apply_run_offsets(f_res, ln_res, zeta, delta_f, delta_z, data.run_index)
        zeta = zeta * np.maximum(1.0 + delta_z[data.run_index] / np.maximum(zeta, 1e-12), RUN_OFFSET_FLOOR)
        freq = freq * (1.0 + delta_f[data.run_index])
    return {
        "ln_zeta": ln_res,
        "rel_f": f_res,
        "z_norm": ln_res / scatter.ln_zeta,
        "f_norm": f_res / scatter.rel_f,
        "z_noise": ln_res / scatter.noise_ln_zeta,
        "f_noise": f_res / scatter.noise_rel_f,
        "zeta_model": zeta,
        "f_model": freq,
        "delta_f": delta_f,
        "delta_zeta0": delta_z,
        "ln_zeta_shared": ln_shared,
        "ln_zeta_calibrated": ln_calibrated,
        "ln_zeta_slope": damping_curve_slope(
            data.velocity_in_s, np.log(np.maximum(shared_zeta, 1e-12)), data.run_index
        ),
        "calibration": calibration,
    }


# ----------------------------------------------------------------- validation
def folds_of(data: ConfigurationData, n_folds: int) -> list[np.ndarray]:
    """Held-out masks: interleaved runs (run r in fold r mod K); one run: amplitude blocks.

    With several runs every fold holds out whole runs spread over the run order,
    so a run-order effect is interpolated, not extrapolated. With one run the
    segments are split into ``n_folds`` contiguous amplitude ranges.
    """
    if data.n_runs >= 2:
        k = min(n_folds, data.n_runs)
        return [(data.run_index % k) == j for j in range(k)]
    order = np.argsort(data.velocity_in_s)
    k = max(2, min(n_folds, data.n // 6))
    masks = []
    for chunk in np.array_split(order, k):
        m = np.zeros(data.n, dtype=bool)
        m[chunk] = True
        masks.append(m)
    return masks


AMPLITUDE_BINS_PER_DECADE = 4
"""Bins of the amplitude weighting of held-out errors (quarter decades)."""

MIN_BIN_SEGMENTS = 40
"""A bin with fewer segments carries proportionally less than a full bin's weight: about
5 segments per run of an 8-run campaign. The sparse top bins (a few segments per run,
where the averaged Dahl model's own frequency accuracy, up to 3.6e-4 at the slip
transition, is 10-20 times the frequency scatter) are not inflated beyond their count.
Chosen over 20 seeds per cause (bench/hit_rate.py, seeds 1-20: floor 10 -> Dahl joint
called ``none`` in 0.75, 40 -> 0.85, no weighting -> 0.90; quadratic-damping gain ratio
median 0.34 / 0.50 / 0.66) and validated on seeds 21-40 (docs/discovery.md)."""


def amplitude_bin(velocity_in_s: np.ndarray, anchor_velocity_in_s: float, per_decade: int) -> np.ndarray:
    """Bin of each amplitude, ``per_decade`` bins a decade counted down from the anchor.

    Bins relative to the top of the measured range make every binned quantity the same
    for two sensors that see one decay at different amplitudes (mode shape)."""
    # bin -1 is (anchor / 10**(1/per_decade), anchor]: the anchor itself tops the first bin
    return np.ceil(per_decade * np.log10(velocity_in_s / anchor_velocity_in_s) - 1e-9).astype(int) - 1


def amplitude_weights(velocity_in_s: np.ndarray, anchor_velocity_in_s: float) -> np.ndarray:
    """Weights that give every quarter decade of amplitude the same say in an error.

    Segments are equally spaced in time, so a ring-down leaves segments at each
    amplitude in proportion to the time it spends there, ``1 / (zeta omega)`` per unit
    ``ln V``: the slowly decaying low-amplitude tail, where the joint is stuck and every
    model agrees, holds most segments, and the top of the range, where the friction
    models differ, holds few. An error meant to say how well a model predicts the
    *curves* over the measured amplitude range weights each occupied quarter decade
    equally: each segment gets ``1 / max(n_bin, MIN_BIN_SEGMENTS)`` (a nearly empty
    bin is not inflated).
    """
    code = amplitude_bin(velocity_in_s, anchor_velocity_in_s, AMPLITUDE_BINS_PER_DECADE)
    _, inverse, counts = np.unique(code, return_inverse=True, return_counts=True)
    return 1.0 / np.maximum(counts[inverse], MIN_BIN_SEGMENTS)


def _weighted_rms(squares: np.ndarray, weights: np.ndarray) -> float:
    """``sqrt(sum w r^2 / sum w)``."""
    return float(np.sqrt(np.sum(weights * squares) / max(np.sum(weights), 1e-300)))


def cross_validate(
    model: AveragedModel | str,
    data: ConfigurationData,
    scatter: Scatter,
    context: FitContext,
    full_fit: FitResult,
    *,
    settings: FitSettings = FitSettings(),
) -> dict:
    """Held-out error of a model: refit without each fold, predict the fold.

    With several runs a fold holds out whole runs. What an honest prediction of a
    held-out run may know of it is its own beam, not its physics: the shared parameters
    come from the other runs, and the run's own frequency and linear-damping offsets
    from its lowest-amplitude segments (:func:`calibration_segments`), which are then
    not scored. With one run, contiguous amplitude blocks are held out and predicted
    from the rest.

    Returns
    -------
    dict
        ``error`` (RMS residual over the scatter, scored held-out segments, both curves,
        amplitude weighted by :func:`amplitude_weights`), ``error_zeta``,
        ``error_frequency`` (per curve), ``fold_errors``, per segment its held-out
        squared residuals ``squared_zeta``, ``squared_frequency``, and ``scored``
        (False for the calibration segments).
    """
    model = MODELS[model] if isinstance(model, str) else model
    sq_z, sq_f, fold_errors = np.zeros(data.n), np.zeros(data.n), []
    scored = np.ones(data.n, dtype=bool)
    w = amplitude_weights(data.velocity_in_s, data.anchor_velocity_in_s)
    for held in folds_of(data, settings.folds):
        fit = fit_model(
            model, data, scatter, context, settings=settings, mask=~held, warm_start=full_fit.coords
        )
        offsets_from = None
        if data.n_runs >= 2:
            calibration = calibration_segments(
                data.velocity_in_s, data.run_index, np.unique(data.run_index[held])
            )
            offsets_from = ~held | calibration
            scored &= ~calibration
        res = model_residuals(fit, data, scatter, context, offsets_from=offsets_from)
        part = held & scored
        sq_z[part] = res[f"z_{HELD_OUT_SCALE}"][part] ** 2
        sq_f[part] = res[f"f_{HELD_OUT_SCALE}"][part] ** 2
        fold_errors.append(_weighted_rms(0.5 * (sq_z[part] + sq_f[part]), w[part]))
    return {
        "error": _weighted_rms(0.5 * (sq_z + sq_f)[scored], w[scored]),
        "error_zeta": _weighted_rms(sq_z[scored], w[scored]),
        "error_frequency": _weighted_rms(sq_f[scored], w[scored]),
        "fold_errors": fold_errors,
        "squared_zeta": sq_z,
        "squared_frequency": sq_f,
        "scored": scored,
    }


def effective_observations(data: ConfigurationData) -> int:
    """Independent observations for the information criterion.

    Segments of one ring-down are strongly correlated (overlapping windows, one
    hit), so the count is the number of occupied (run, half-decade of amplitude)
    cells, times two curves.
    """
    cells = set(
        zip(data.run_index.tolist(), amplitude_bin(data.velocity_in_s, data.anchor_velocity_in_s, 2).tolist())
    )
    return 2 * max(len(cells), 2)


def information_criterion(cost: float, n_params: int, n_eff: int) -> float:
    """BIC on the normalised residuals: ``n_eff ln(cost) + k ln(n_eff)``.

    ``cost`` is the mean squared residual over the measured scatter, amplitude weighted
    (the held-out error's normalisation; per amplitude bin, as ``n_eff`` counts cells,
    not segments).
    """
    return float(n_eff * np.log(max(cost, 1e-300)) + n_params * np.log(n_eff))


# --------------------------------------------------------------- discrepancy
def _lag1_effective(r: np.ndarray) -> float:
    """Effective sample size of a serially correlated sequence (AR(1))."""
    n = r.size
    if n < 4:
        return float(n)
    c = r - r.mean()
    rho = float(np.sum(c[1:] * c[:-1]) / max(np.sum(c * c), 1e-300))
    rho = min(max(rho, 0.0), 0.95)
    return max(1.0, n * (1.0 - rho) / (1.0 + rho))


def binned_discrepancy(
    data: ConfigurationData, residuals: Mapping[str, np.ndarray], *, alpha: float = ALPHA
) -> list[dict]:
    """Mean residual per half decade of amplitude and per curve, with its significance.

    For each bin and curve, each run's mean residual in the bin is one
    observation; the mean over runs, its standard error over runs and a t test
    (``n_runs - 1`` degrees of freedom) follow. With one run, the segments are the
    observations and the standard error uses their AR(1) effective number. A bin
    counts as a real misfit when ``p < p_limit = alpha / (2 n)``, ``n`` the number of
    bins x curves tested (Bonferroni with half of ``alpha``; the run-order test has the
    other half), and ``|mean|`` exceeds the model accuracy (``TOL_LN_ZETA`` or
    ``TOL_REL_F``).

    Returns
    -------
    list of dict
        One per (bin, curve): ``curve`` ("damping"/"frequency"), ``v_low_in_s``,
        ``v_high_in_s``, ``mean`` (ln zeta or relative f), ``standard_error``, ``t``,
        ``p``, ``p_limit`` (``alpha / n_tests``), ``n_runs``, ``n_segments``,
        ``tolerance``, ``significant``.
    """
    code = amplitude_bin(data.velocity_in_s, data.anchor_velocity_in_s, 2)
    rows = []
    for curve, key, tol in (("damping", "ln_zeta", TOL_LN_ZETA), ("frequency", "rel_f", TOL_REL_F)):
        r = residuals[key]
        for b in np.unique(code):
            in_bin = code == b
            if data.n_runs >= 2:
                counts = np.bincount(data.run_index[in_bin], minlength=data.n_runs)
                runs = np.flatnonzero(counts)
                if runs.size < 3:
                    continue
                sums = np.bincount(data.run_index[in_bin], weights=r[in_bin], minlength=data.n_runs)
                means = sums[runs] / counts[runs]
                m = float(means.mean())
                se = float(means.std(ddof=1) / np.sqrt(means.size))
                dof = means.size - 1
            else:
                runs = np.zeros(1, dtype=int)
                seg = r[in_bin][np.argsort(data.velocity_in_s[in_bin])]
                if seg.size < 4:
                    continue
                m = float(seg.mean())
                n_eff = _lag1_effective(seg)
                se = float(seg.std(ddof=1) / np.sqrt(n_eff))
                dof = max(n_eff - 1.0, 1.0)
            t = m / max(se, 1e-300)
            rows.append(
                {
                    "curve": curve,
                    "v_low_in_s": float(data.anchor_velocity_in_s * 10 ** (b / 2.0)),
                    "v_high_in_s": float(data.anchor_velocity_in_s * 10 ** ((b + 1) / 2.0)),
                    "mean": m,
                    "standard_error": se,
                    "t": float(t),
                    "p": float(2.0 * special.stdtr(dof, -abs(t))),
                    "n_runs": int(runs.size),
                    "n_segments": int(in_bin.sum()),
                    "tolerance": tol,
                    "significant": False,
                }
            )
    n_tests = 2 * max(len(rows), 1)  # the other half of alpha goes to the run-order test
    for row in rows:
        row["p_limit"] = alpha / n_tests
        row["significant"] = bool(row["p"] < row["p_limit"] and abs(row["mean"]) > row["tolerance"])
    return rows


def damping_curve_slope(
    velocity_in_s: np.ndarray, ln_zeta_model: np.ndarray, run_index: np.ndarray
) -> np.ndarray:
    """Log-log slope ``d ln zeta / d ln V`` of each run's model damping curve at its segments.

    A change of the joint's friction limit moves its damping curve along ``ln V`` (the
    slip velocity scales with it, the linear damping stays), so ``-slope`` is the change of
    ``ln zeta`` per unit change of ``ln Fc``: the shape a run-to-run change of the joint
    leaves in the residuals (:func:`run_order_trend`). Central differences along each
    run's segments sorted by amplitude (one-sided at the ends); 0 where a run has fewer
    than two distinct amplitudes.
    """
    slope = np.zeros(velocity_in_s.size)
    ln_v = np.log(velocity_in_s)
    for run in np.unique(run_index):
        members = np.flatnonzero(run_index == run)
        ordered = members[np.argsort(ln_v[members], kind="stable")]
        x, inverse = np.unique(ln_v[ordered], return_inverse=True)
        if x.size < 2:
            continue
        y = np.bincount(inverse, weights=ln_zeta_model[ordered]) / np.bincount(inverse)
        slope[ordered] = np.gradient(y, x)[inverse]
    return slope


def run_order_trend(
    data: ConfigurationData,
    residuals: Mapping[str, np.ndarray],
    *,
    n_tests: int,
    alpha: float = ALPHA,
    run_position: np.ndarray | None = None,
) -> dict | None:
    """Linear trend with run order of the runs' shift of the damping curve.

    Each run's residual is the shared model's, with the run's own frequency and linear
    damping set by its lowest-amplitude segments (``ln_zeta_calibrated`` and
    ``calibration`` when present, as for a held-out run; else ``ln_zeta_shared``, else
    ``ln_zeta``). Of that residual the test takes the amount of the shape a change of the
    joint's friction limit leaves (``-ln_zeta_slope``, :func:`damping_curve_slope`; a
    constant shape without it, or where the model's damping changes by less than its
    accuracy ``TOL_LN_ZETA`` over the scored amplitudes), a weighted least-squares
    projection over the run's other segments with every quarter decade of amplitude
    weighted equally (:func:`amplitude_weights`): the run's relative change of friction
    limit against the shared model. Projecting on the shape weighs each amplitude by how
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
    run_position : ndarray, optional
        Position in run order of each of the ``data.n_runs`` runs (default ``0 .. n-1``;
        a resample of runs passes the drawn runs' positions).

    Returns None with fewer than 4 runs with scored segments; else ``slope_per_run`` (of
    the projection, per run: ``ln Fc``, or ``ln zeta`` without a slope),
    ``change_over_sequence`` (the change of ``ln zeta`` the trend makes from the first run
    to the last, at the scored amplitude where it is largest), ``t``, ``p``,
    ``significant`` (``p < alpha / n_tests`` and the change over the sequence larger than
    the model accuracy), ``order`` (which run order, ``data.run_order``) and ``runs`` (the
    run names in that order).
    """
    x = np.arange(data.n_runs, dtype=float) if run_position is None else np.asarray(run_position, float)
    r = residuals.get("ln_zeta_calibrated", residuals.get("ln_zeta_shared", residuals["ln_zeta"]))
    w = amplitude_weights(data.velocity_in_s, data.anchor_velocity_in_s)
    if "calibration" in residuals:
        w = w * ~residuals["calibration"]
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
        "significant": bool(p < alpha / n_tests and abs(change) > TOL_LN_ZETA),
        "order": data.run_order,
        "runs": list(data.run_names),
    }


ENVELOPE_DEPARTURE_LIMIT = 0.05
"""Largest acceptable departure of a segment's ln-envelope from a straight line (RMS of
the line fit, ``fit_rms``), as a fraction of the decay of ln-envelope across the segment
(``2 pi N zeta`` for ``N`` cycles), in each run's highest-amplitude third."""


def envelope_structure(
    data: ConfigurationData, *, segment_cycles: float = AnalysisSettings.segment_cycles
) -> dict | None:
    """Whether the log-decrement segments measure a decay at all.

    Every model of the vocabulary is a single mode whose damping changes slowly with
    amplitude: over a segment of ``N`` cycles its ln-envelope is a straight line that
    falls by ``2 pi N zeta``, up to additive noise (largest at the run's low end) and
    a curvature far smaller than that fall. In each run's highest-amplitude third
    (best signal-to-noise) the departure ``fit_rms`` must therefore be a small
    fraction of the fall. A disturbance proportional to the signal (a second mode
    beating in the band, an amplitude modulation) keeps it large at every amplitude:
    then the segments' damping and frequency are dominated by that disturbance and
    no single-mode model applies.

    Parameters
    ----------
    data : ConfigurationData
    segment_cycles : float
        Segment length of the log decrement, cycles (config ``analysis.segment_cycles``).

    Returns
    -------
    dict or None
        ``departure_ratio`` (median over runs of each run's median of
        ``fit_rms / (2 pi N zeta_trend)`` in its top third), ``runs_over_limit``,
        ``limit``, ``significant`` (ratio above the limit in at least half the runs).
        None when the table has no ``fit_rms``.
    """
    if data.fit_rms is None:
        return None
    x = np.log10(data.velocity_in_s)
    zeta_trend = np.exp(_robust_trend(x, np.log(data.zeta), 3))
    ratio = data.fit_rms / (2.0 * np.pi * segment_cycles * zeta_trend)
    per_run = []
    for j in range(data.n_runs):
        m = np.flatnonzero(data.run_index == j)
        if m.size < 3:
            continue
        top = m[np.argsort(data.velocity_in_s[m])[::-1][: max(2, m.size // 3)]]
        per_run.append(float(np.median(ratio[top])))
    if not per_run:
        return None
    per_run = np.array(per_run)
    over = int(np.sum(per_run > ENVELOPE_DEPARTURE_LIMIT))
    return {
        "departure_ratio": float(np.median(per_run)),
        "runs_over_limit": over,
        "runs_tested": int(per_run.size),
        "limit": ENVELOPE_DEPARTURE_LIMIT,
        "segment_cycles": float(segment_cycles),
        "median_fit_rms": float(np.median(data.fit_rms)),
        "significant": bool(over >= max(1, int(np.ceil(per_run.size / 2)))),
    }


def _fmt_v(v: float) -> str:
    return f"{v:.3g}"


def format_percent(value_percent: float) -> str:
    """A signed percentage to two significant digits, never rounded to zero.

    ``-0.0042`` gives ``"-0.0042 %"``, ``31.4`` gives ``"+31 %"``; exactly zero gives ``"0 %"``.
    """
    if value_percent == 0 or not np.isfinite(value_percent):
        return f"{value_percent:g} %"
    rounded = float(f"{value_percent:.2g}")
    decimals = max(0, 1 - int(np.floor(np.log10(abs(rounded)))))
    return f"{rounded:+.{decimals}f} %"


def _misfit_percent(curve: str, mean: float) -> float:
    """A bin's mean residual as a percentage of the model: damping residuals are in
    ln zeta, frequency residuals relative."""
    return 100 * float(np.expm1(mean)) if curve == "damping" else 100 * float(mean)


def _misfit_words(model_name: str, row: Mapping) -> str:
    """``the measured damping lies 4.2 % above the lugre fit at 1-3.2 in/s``."""
    size = _misfit_percent(row["curve"], row["mean"])
    side = "above" if size > 0 else "below" if size < 0 else "on"
    return (
        f"the measured {row['curve']} lies {format_percent(size).lstrip('+-')} {side} the "
        f"{model_name} fit at {_fmt_v(row['v_low_in_s'])}-{_fmt_v(row['v_high_in_s'])} in/s"
    )


def _negligible_misfit_words(model_name: str, row: Mapping) -> str:
    """Why the bin with the largest |t| is not a misfit: not significant after the
    Bonferroni correction, or smaller than the models' accuracy, or both."""
    tolerance = _misfit_percent(row["curve"], row["tolerance"])
    clear = row["p"] < row["p_limit"]
    small = abs(row["mean"]) <= row["tolerance"]
    statistic = f"|t| = {abs(row['t']):.1f}, p = {row['p']:.2g} against {row['p_limit']:.2g} after correction"
    accuracy = f"the {abs(tolerance):.2g} % in {row['curve']} the models are accurate to"
    if clear and small:
        judgement = (
            f"statistically clear ({statistic}) but physically negligible: smaller than {accuracy} "
            f"({abs(row['mean']) / row['tolerance']:.2g} of it)"
        )
    elif small:
        judgement = f"neither statistically significant ({statistic}) nor larger than {accuracy}"
    else:
        judgement = f"larger than {accuracy} but not statistically significant ({statistic})"
    return f"the largest binned misfit, where {_misfit_words(model_name, row)}, is {judgement}"


def discrepancy_sentence(model_name: str, bins: list[dict], trend: dict | None, n_runs: int) -> str:
    """Plain sentence: where and by how much the model is wrong (or that it is not).

    Sizes are percentages of the model (two significant digits, so that a misfit that
    is not zero never reads as ``0.00 %``), with their direction in words. A misfit is
    called significant only when it is both statistically clear (``p`` below the
    corrected limit) and larger than the models' accuracy (``tolerance``); when no bin
    is, the sentence says which of the two the largest one (by ``|t|``) fails.
    """
    sig = [b for b in bins if b["significant"]]
    parts = []
    for curve in ("damping", "frequency"):
        rows = [b for b in sig if b["curve"] == curve]
        if not rows:
            continue
        lo = min(b["v_low_in_s"] for b in rows)
        hi = max(b["v_high_in_s"] for b in rows)
        worst = max(rows, key=lambda b: abs(b["mean"]))
        parts.append(
            f"the measured {curve} differs from the {model_name} fit between "
            f"{_fmt_v(lo)} and {_fmt_v(hi)} in/s, by up to "
            f"{format_percent(_misfit_percent(curve, worst['mean']))} "
            f"(|t| = {abs(worst['t']):.1f} over {worst['n_runs']} runs) at "
            f"{_fmt_v(worst['v_low_in_s'])}-{_fmt_v(worst['v_high_in_s'])} in/s"
        )
    if trend is not None and trend["significant"]:
        parts.append(
            f"the runs' damping curve shifts with run order ({trend['order']}) by "
            f"{format_percent(_misfit_percent('damping', trend['change_over_sequence']))} from the "
            f"first to the last run where the shift is largest (t = {trend['t']:.1f})"
        )
    if not parts:
        worst = max(bins, key=lambda b: abs(b["t"]), default=None)
        tail = "" if worst is None else "; " + _negligible_misfit_words(model_name, worst)
        return (
            f"The {model_name} baseline fits damping and frequency at every amplitude to "
            f"within the run-to-run scatter or the models' accuracy ({n_runs} runs){tail}."
        )
    text = "; ".join(parts)
    return text[0].upper() + text[1:] + "."


# ------------------------------------------------------------------ decision
def heldout_units(data: ConfigurationData) -> np.ndarray:
    """Independent unit of held-out evidence of each segment: its run, or with one run its
    half decade of amplitude (counted from the anchor, as the discrepancy bins)."""
    if data.n_runs >= 2:
        return data.run_index
    code = amplitude_bin(data.velocity_in_s, data.anchor_velocity_in_s, 2)
    return code - code.min()


def heldout_standard_error(unit_squares: np.ndarray, unit_weights: np.ndarray) -> float:
    """Standard error of a model's squared held-out error over the units of evidence.

    ``E^2 = sum_u S_u / sum_u W_u`` over the units ``u`` (runs), ``S_u`` the unit's
    weighted squared held-out residuals and ``W_u`` its weight. The units are taken as
    independent draws, so ``E^2`` is a ratio estimator whose variance, to first order,
    is ``n / (n - 1) sum_u (S_u - E^2 W_u)^2 / W^2``; 0 with fewer than two units.
    """
    present = unit_weights > 0
    squares, weights = unit_squares[present], unit_weights[present]
    total = float(np.sum(weights))
    if squares.size < 2 or total <= 0:
        return 0.0
    mean = float(np.sum(squares) / total)
    variance = squares.size / (squares.size - 1) * float(np.sum((squares - mean * weights) ** 2)) / total**2
    return float(np.sqrt(variance))


def decide(
    baseline_error: float,
    baseline_bic: float,
    baseline_fails: bool,
    candidates: Mapping[str, dict],
    envelope_structure: bool = False,
    unit_squares: Mapping[str, np.ndarray] | None = None,
    unit_weights: np.ndarray | None = None,
) -> tuple[str, str]:
    """The decision rule.

    Parameters
    ----------
    baseline_error, baseline_bic : float
        Held-out error and BIC of the best baseline.
    baseline_fails : bool
        Whether the baseline shows a significant misfit (binned or run-order).
    candidates : mapping
        cause -> dict with ``heldout_error``, ``bic``, ``residual_significant`` and
        optionally ``shows_signature`` (default true).

    envelope_structure : bool
        Whether the ring-downs are not single-mode decays (:func:`envelope_structure`).
    unit_squares, unit_weights : optional
        Per candidate, its held-out weighted squared residuals summed over each
        independent unit of evidence (a run; with one run, a half decade of amplitude,
        :func:`heldout_units`), and the units' weights: they give the standard error of
        the best candidate's held-out error. Without them only equal errors tie.

    Returns
    -------
    cause, reason : str
        ``none``, a cause id, or ``unknown``; and the rule that fired.

    Rule
    ----
    * ``unknown`` when the envelopes are not single-mode free decays: no model of a
      single mode (baseline or candidate) can remove that misfit.
    * A candidate is *eligible* when its held-out error is below the baseline's, its
      BIC is below the baseline's, and its fit shows its cause's signature
      (:func:`stiffness_signature`).
    * ``none`` when the baseline has no significant misfit and no eligible candidate
      cuts the held-out error below ``CLEAR_GAIN`` x the baseline's.
    * Otherwise the best eligible candidate by held-out error; candidates whose squared
      held-out error is within one standard error of the best's (the one-standard-error
      rule of cross-validation, :func:`heldout_standard_error`) predict as well as far
      as the data can tell, and the one with the lowest BIC (fewest parameters for the
      same fit) is taken. ``unknown`` when no
      candidate is eligible, or when the best
      leaves a significant misfit and does not cut the held-out error below
      ``RESIDUAL_GAIN`` x the baseline's.
    """
    if envelope_structure:
        return "unknown", (
            "even at the runs' highest amplitudes the segment envelopes depart from "
            "exponential decays by more than ENVELOPE_DEPARTURE_LIMIT of their decay: "
            "a disturbance outside every single-mode model (e.g. a second mode "
            "beating in the band)"
        )
    eligible = {
        c: v
        for c, v in candidates.items()
        if v["heldout_error"] < baseline_error and v["bic"] < baseline_bic and v.get("shows_signature", True)
    }
    clear = {c: v for c, v in eligible.items() if v["heldout_error"] < CLEAR_GAIN * baseline_error}
    if not baseline_fails and not clear:
        return "none", (
            "no significant misfit of the baseline and no candidate reduces the "
            f"held-out error below {CLEAR_GAIN} of the baseline's"
        )
    if not eligible:
        return "unknown", (
            "the baseline misfit is significant but no candidate lowers both the held-out error and the BIC "
            "with its cause's signature"
        )
    leader = min(eligible, key=lambda c: eligible[c]["heldout_error"])
    reach = eligible[leader]["heldout_error"] ** 2
    if unit_squares is not None and unit_weights is not None:
        reach += heldout_standard_error(unit_squares[leader], unit_weights)
    near = {c: v for c, v in eligible.items() if v["heldout_error"] ** 2 <= reach}
    best = min(near, key=lambda c: near[c]["bic"])
    v = eligible[best]
    if v["residual_significant"] and v["heldout_error"] >= RESIDUAL_GAIN * baseline_error:
        return "unknown", (
            f"the best eligible candidate ({best}) leaves a significant misfit and cuts the "
            f"held-out error only to {v['heldout_error'] / baseline_error:.2f} of "
            "the baseline's"
        )
    why = "baseline misfit significant" if baseline_fails else "clear held-out gain"
    return best, (f"{why}; {best} has the lowest held-out error among candidates that also lower the BIC")


# -------------------------------------------------------------- configuration
def _finite(x):
    """JSON-safe float (None for non-finite)."""
    if x is None:
        return None
    x = float(x)
    return x if np.isfinite(x) else None


def _clean(obj):
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return _finite(obj)
    return obj


@dataclass
class ConfigurationDiagnosis:
    """Everything computed for one configuration (the document plus the fits)."""

    document: dict
    fits: dict[str, FitResult]
    data: ConfigurationData
    scatter: Scatter
    residuals: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    resamples: list[dict] = field(default_factory=list)
    """Cause and gain ratio on each bootstrap resample (:func:`resample_decisions`)."""
    evidence: dict[str, ModelEvidence] = field(default_factory=dict)
    """What the decision was taken on (:func:`evaluate_decision`), per model; not kept in
    the interim files."""


EXPLAINS_LIMIT = 2.0
"""``explains_data`` (output contract): the model's mean residual in every half decade
of amplitude, in units of the measured scatter, stays within this limit on both curves."""


def explains_data(data: ConfigurationData, residuals: Mapping[str, np.ndarray]) -> dict:
    """Whether a model explains the data: binned residuals within ±2 measured scatter.

    Per half decade of amplitude (counted down from the anchor) and per curve, the mean
    of the residuals over the measured scatter (``z_noise``, ``f_noise``: each run with
    its own offsets). The model explains the data when every such mean is within
    :data:`EXPLAINS_LIMIT`.

    Returns
    -------
    dict
        ``explains_data`` (bool), ``limit``, ``worst`` (the largest bin: curve, range,
        mean) and ``failing_bins`` (every bin outside the limit, in amplitude order).
    """
    code = amplitude_bin(data.velocity_in_s, data.anchor_velocity_in_s, 2)
    bins = []
    for curve, key in (("damping", "z_noise"), ("frequency", "f_noise")):
        r = residuals[key]
        for b in np.unique(code):
            in_bin = code == b
            bins.append(
                {
                    "curve": curve,
                    "v_low_in_s": float(data.anchor_velocity_in_s * 10 ** (b / 2.0)),
                    "v_high_in_s": float(data.anchor_velocity_in_s * 10 ** ((b + 1) / 2.0)),
                    "mean_over_scatter": float(np.mean(r[in_bin])),
                    "n_segments": int(in_bin.sum()),
                }
            )
    failing = [b for b in bins if abs(b["mean_over_scatter"]) > EXPLAINS_LIMIT]
    failing.sort(key=lambda b: (b["curve"], b["v_low_in_s"]))
    return {
        "explains_data": not failing,
        "limit": EXPLAINS_LIMIT,
        "worst": max(bins, key=lambda b: abs(b["mean_over_scatter"]), default=None),
        "failing_bins": failing,
    }


def at_bounds(model: AveragedModel, coords: np.ndarray, data: ConfigurationData) -> np.ndarray:
    """Per parameter, -1 / 1 where the fit sits on the lower / upper edge of its fit range
    (within a thousandth of it: not identified by the data), else 0."""
    lo, hi = parameter_box(model, data)
    unit = (np.asarray(coords, dtype=float) - lo) / (hi - lo)
    return np.where(unit <= 1e-3, -1, np.where(unit >= 1 - 1e-3, 1, 0))


def bound_flags(model: AveragedModel | str, coords: np.ndarray, data: ConfigurationData) -> list[str]:
    """Parameters of a fit that sit on an edge of their fit range (not identified there)."""
    model = MODELS[model] if isinstance(model, str) else model
    flags = []
    for spec, edge, c in zip(model.params, at_bounds(model, coords, data), coords):
        if edge:
            value = float(np.exp(c)) if spec.scale == "log" else float(c)
            if spec.name == "joint_stiffness_fraction" and edge > 0:
                flags.append(
                    f"{spec.name} = {value:.3g} at its physical limit: the data ask for a joint "
                    "carrying more of the modal stiffness than a lap joint's contact does "
                    "(docs/discovery.md, fit ranges)"
                )
                continue
            side = "lower" if edge < 0 else "upper"
            flags.append(
                f"{spec.name} = {value:.3g} at the {side} edge of its fit range: not identified by the data"
            )
    return flags


def stiffness_signature(fit: FitResult, data: ConfigurationData) -> dict:
    """Whether a ``dahl_stiffness`` fit shows the stiffness-nonlinearity signature.

    The output contract's signature: the frequency shifts with amplitude more than the
    friction that fits the damping explains. Over the measured amplitudes the relative
    change of the fitted model's damped frequency is compared with that of its friction
    alone (the same fit with the stiffness term switched off); the signature is there
    when the whole change is larger in magnitude.

    Why: Dahl's pre-sliding damping grows in proportion to amplitude, its softening
    with its square, so a stiff Dahl joint deep in pre-sliding, with a stiffness term
    that cancels its softening, reproduces a velocity-squared loss (damping in
    proportion to amplitude, frequency put) as closely as ``dahl_quadratic`` does. Such
    a fit's stiffness term works against the friction's frequency change; that of an
    amplitude-dependent stiffness the data show adds to it or outgrows it.

    Returns
    -------
    dict
        ``relative_frequency_change`` (model, lowest to highest amplitude),
        ``friction_relative_frequency_change`` (stiffness term off) and
        ``shows_signature`` (bool).
    """
    velocity = np.array([float(np.min(data.velocity_in_s)), float(np.max(data.velocity_in_s))])
    changes = []
    for params in (fit.params, {**fit.params, "stiffness_shift": 0.0}):
        _, frequency_hz = model_curves(fit.model, params, velocity, response_order=data.response_order)
        changes.append(float(frequency_hz[1] / frequency_hz[0] - 1.0))
    whole, friction = changes
    return {
        "relative_frequency_change": whole,
        "friction_relative_frequency_change": friction,
        "shows_signature": bool(abs(whole) > abs(friction)),
    }


@dataclass
class ModelEvidence:
    """What the decision needs of one fitted model, per segment.

    ``residuals`` are the all-data fit's (:func:`model_residuals`); ``heldout`` the
    cross-validation's (:func:`cross_validate`); ``n_params`` the fitted parameters;
    ``shows_signature`` whether a candidate's fit shows its cause's signature
    (:func:`stiffness_signature`; true where there is no such check).
    """

    residuals: dict[str, np.ndarray]
    heldout: dict
    n_params: int
    shows_signature: bool = True


def _subset(
    data: ConfigurationData, segments: np.ndarray, run_index: np.ndarray, n_runs: int
) -> ConfigurationData:
    """The segments ``segments`` of a configuration, relabelled into ``n_runs`` runs."""
    pick = lambda a: None if a is None else a[segments]  # noqa: E731
    return ConfigurationData(
        name=data.name,
        velocity_in_s=data.velocity_in_s[segments],
        zeta=data.zeta[segments],
        frequency_hz=data.frequency_hz[segments],
        run_index=run_index,
        run_names=[f"r{k}" for k in range(n_runs)],
        bearing_area_in2=data.bearing_area_in2,
        response_order=data.response_order,
        fit_rms=pick(data.fit_rms),
        response_amplitude=pick(data.response_amplitude),
        anchor_velocity_in_s=data.anchor_velocity_in_s,
        run_order=data.run_order,
    )


def evaluate_decision(
    data: ConfigurationData,
    evidence: Mapping[str, ModelEvidence],
    *,
    envelope_significant: bool,
    segments: np.ndarray | None = None,
    run_index: np.ndarray | None = None,
    run_position: np.ndarray | None = None,
    n_runs: int | None = None,
    extended_models: Mapping[str, str] | None = None,
) -> dict:
    """Held-out errors, BIC, discrepancy tests and the decision, on (a resample of) the data.

    Called once on all segments for the verdict, and on resamples of runs (or of
    amplitude blocks with one run) for its confidence: the fits are those of all the
    data, the evidence is recomputed from the resampled segments' residuals.

    Parameters
    ----------
    data : ConfigurationData
    evidence : mapping
        Model id -> :class:`ModelEvidence`.
    envelope_significant : bool
        :func:`envelope_structure`'s verdict (not resampled).
    segments, run_index, run_position, n_runs : optional
        A resample: the segments drawn (with repeats), their new run labels, the drawn
        runs' positions in run order, and the number of drawn runs.
    extended_models : mapping, optional
        Cause -> the model that represents it once named, where that is not the
        candidate of :data:`CAUSE_MODELS` (the recovered threshold distribution,
        :func:`refine_microslip`).

    Returns
    -------
    dict
        ``cause``, ``reason``, ``baseline`` (model id), ``errors`` and ``bic`` per model,
        ``bins`` and ``trend`` of the baseline, ``baseline_fails``, ``candidates``,
        ``extended_models``.
    """
    if segments is None:
        segments = np.arange(data.n)
        view = data
    else:
        view = _subset(data, segments, run_index, n_runs)
    n_runs_view = view.n_runs
    weights = amplitude_weights(view.velocity_in_s, view.anchor_velocity_in_s)
    n_eff = effective_observations(view)
    units = heldout_units(view)
    n_units = int(units.max()) + 1 if units.size else 0
    # the scored segments are the data's (calibration segments are not), the same for every model
    scored = next(iter(evidence.values())).heldout["scored"][segments]
    unit_weights = np.bincount(units[scored], weights=weights[scored], minlength=n_units)
    errors, bic, residuals, unit_squares = {}, {}, {}, {}
    for m, ev in evidence.items():
        square = 0.5 * (ev.heldout["squared_zeta"] + ev.heldout["squared_frequency"])[segments]
        unit_squares[m] = np.bincount(units[scored], weights=(weights * square)[scored], minlength=n_units)
        errors[m] = {
            "error": _weighted_rms(square[scored], weights[scored]),
            "error_zeta": _weighted_rms(ev.heldout["squared_zeta"][segments][scored], weights[scored]),
            "error_frequency": _weighted_rms(
                ev.heldout["squared_frequency"][segments][scored], weights[scored]
            ),
        }
        res = {
            k: ev.residuals[k][segments]
            for k in (
                "ln_zeta",
                "rel_f",
                "ln_zeta_shared",
                "ln_zeta_calibrated",
                "ln_zeta_slope",
                "calibration",
                "z_noise",
                "f_noise",
            )
        }
        residuals[m] = res
        in_sample = _weighted_rms(0.5 * (res["z_noise"] ** 2 + res["f_noise"] ** 2), weights) ** 2
        offsets = 2 * (n_runs_view - 1) if n_runs_view >= 2 else 0  # frequency and zeta0 per run
        bic[m] = information_criterion(in_sample, ev.n_params + offsets, n_eff)
    base = min((m for m in BASELINE_MODELS if m in evidence), key=lambda m: errors[m]["error"])
    bins = binned_discrepancy(view, residuals[base])
    trend = run_order_trend(view, residuals[base], n_tests=RUN_ORDER_TESTS, run_position=run_position)
    baseline_fails = (
        any(b["significant"] for b in bins) or bool(trend and trend["significant"]) or envelope_significant
    )
    candidates = {}
    for cause, m in CAUSE_MODELS.items():
        if m not in evidence:
            continue
        cb = binned_discrepancy(view, residuals[m])
        ct = run_order_trend(view, residuals[m], n_tests=RUN_ORDER_TESTS, run_position=run_position)
        candidates[cause] = {
            "model": m,
            "heldout_error": errors[m]["error"],
            "heldout_error_zeta": errors[m]["error_zeta"],
            "heldout_error_frequency": errors[m]["error_frequency"],
            "ratio_to_baseline": errors[m]["error"] / errors[base]["error"],
            "bic": bic[m],
            "delta_bic": bic[m] - bic[base],
            "residual_significant": bool(
                any(b["significant"] for b in cb) or (ct is not None and ct["significant"])
            ),
            "significant_bins": int(sum(b["significant"] for b in cb)),
            "shows_signature": evidence[m].shows_signature,
        }
    cause, reason = decide(
        errors[base]["error"],
        bic[base],
        baseline_fails,
        candidates,
        envelope_structure=envelope_significant,
        unit_squares={c: unit_squares[v["model"]] for c, v in candidates.items()},
        unit_weights=unit_weights,
    )
    return {
        "cause": cause,
        "reason": reason,
        "baseline": base,
        "errors": errors,
        "bic": bic,
        "n_eff": n_eff,
        "bins": bins,
        "trend": trend,
        "baseline_fails": baseline_fails,
        "candidates": candidates,
        "extended_models": {**CAUSE_MODELS, **(extended_models or {})},
    }


def resample_decisions(
    data: ConfigurationData,
    evidence: Mapping[str, ModelEvidence],
    *,
    envelope_significant: bool,
    n_resamples: int,
    seed: int,
    n_folds: int,
    extended_models: Mapping[str, str] | None = None,
) -> list[dict]:
    """The decision on ``n_resamples`` bootstrap resamples of the runs.

    With two runs or more, runs are drawn with replacement (a run drawn twice counts as
    two runs, keeping its place in run order); with one run, the amplitude blocks of the
    cross-validation are drawn instead. Returns one :func:`evaluate_decision` result
    (``cause``, gain ``ratio``) per resample.
    """
    rng = np.random.default_rng(seed)
    if data.n_runs >= 2:
        units = [np.flatnonzero(data.run_index == r) for r in range(data.n_runs)]
    else:
        units = [np.flatnonzero(m) for m in folds_of(data, n_folds)]
    out = []
    for _ in range(n_resamples):
        draw = rng.integers(0, len(units), len(units))
        segments = np.concatenate([units[k] for k in draw])
        if data.n_runs >= 2:
            labels = np.concatenate([np.full(units[k].size, j) for j, k in enumerate(draw)])
            result = evaluate_decision(
                data,
                evidence,
                envelope_significant=envelope_significant,
                segments=segments,
                run_index=labels,
                run_position=draw.astype(float),
                n_runs=len(units),
                extended_models=extended_models,
            )
        else:
            result = evaluate_decision(
                data,
                evidence,
                envelope_significant=envelope_significant,
                segments=segments,
                run_index=np.zeros(segments.size, dtype=int),
                n_runs=1,
                extended_models=extended_models,
            )
        out.append({"cause": result["cause"], "ratio": _gain_ratio(result)})
    return out


def _extended_model(result: Mapping) -> str:
    """Model id that represents the decision's cause (the baseline for ``none``; for
    ``unknown`` the candidate with the lowest held-out error)."""
    cause, candidates = result["cause"], result["candidates"]
    if cause == "none" or (cause == "unknown" and not candidates):
        return result["baseline"]
    if cause == "unknown":
        return candidates[min(candidates, key=lambda c: candidates[c]["heldout_error"])]["model"]
    return result["extended_models"][cause]


def _gain_ratio(result: Mapping) -> float:
    if result["cause"] == "none":
        return 1.0
    errors = result["errors"]
    return errors[_extended_model(result)]["error"] / errors[result["baseline"]]["error"]


def cause_fractions(causes: Sequence[str]) -> dict[str, float]:
    """Fraction of ``causes`` naming each cause, largest first (sums to 1)."""
    if not causes:
        return {}
    names, counts = np.unique(np.asarray(causes, dtype=object), return_counts=True)
    order = np.argsort(-counts, kind="stable")
    return {str(names[i]): float(counts[i] / len(causes)) for i in order}


# ------------------------------------------------------------ micro-slip refinement
def threshold_cells(data: ConfigurationData) -> int:
    """Half-decade slip-threshold cells of a configuration's recovered distribution.

    From half a decade below its lowest measured amplitude (elements that slipped at
    every amplitude measured still lower the frequency and add a damping falling as
    ``1 / V``) to the top of its range (higher thresholds never slip: linear stiffness).
    """
    span = float(np.log10(data.anchor_velocity_in_s / np.min(data.velocity_in_s)))
    return int(np.clip(np.ceil(2.0 * span - 1e-9) + 1, 1, MAX_THRESHOLD_CELLS))


def iwan_as_cells(iwan_params: Mapping[str, float], model: AveragedModel) -> dict[str, float]:
    """The Segalman Iwan fit written as a cell distribution (the refinement's nested start).

    The power-law density and the macro-slip element are integrated over each cell;
    what lies below the lowest cell goes into it, what lies above the top of the
    measured amplitudes (never slips) into the linear stiffness.
    """
    chi, macro = float(iwan_params["chi"]), float(iwan_params["macro_ratio"])
    anchor = float(iwan_params["anchor_velocity_in_s"])
    edges = threshold_cell_edges(len(model.cell_names)) * anchor / float(iwan_params["slip_velocity_in_s"])

    def cumulative(t: np.ndarray) -> np.ndarray:
        return np.minimum(t, 1.0) ** (chi + 1.0) / (1.0 + macro) + macro / (1.0 + macro) * (t >= 1.0)

    share = np.diff(cumulative(edges))
    share[0] += cumulative(edges[:1])[0]
    fractions = np.maximum(float(iwan_params["joint_stiffness_fraction"]) * share, 1e-6)
    start = {"f_lin_hz": iwan_params["f_lin_hz"], "zeta0": iwan_params["zeta0"]}
    start.update({name: float(b) for name, b in zip(model.cell_names, fractions)})
    return start


def fit_standard_errors(
    fit: FitResult, data: ConfigurationData, scatter: Scatter, context: FitContext
) -> np.ndarray:
    """Standard errors of a fit's coordinates (ln value for log parameters).

    Gauss-Newton covariance ``cost (J^T J)^-1`` of the normalised residuals, scaled by
    residuals / :func:`effective_observations`: segments of one ring-down are not
    independent, so the information is that of the occupied (run, half-decade) cells.
    """
    model = MODELS[fit.model]
    problem = _Problem(model, data, scatter, np.ones(data.n, dtype=bool), context)
    span = problem.hi - problem.lo
    unit = np.clip((fit.coords - problem.lo) / span, 0.0, 1.0)
    jac = problem.jacobian(unit) / span
    covariance = np.linalg.pinv(jac.T @ jac) * fit.cost * jac.shape[0] / effective_observations(data)
    return np.sqrt(np.maximum(np.diag(covariance), 0.0))


def refine_microslip(
    data: ConfigurationData,
    scatter: Scatter,
    context: FitContext,
    iwan_fit: FitResult,
    *,
    settings: FitSettings = FitSettings(),
) -> tuple[FitResult, dict]:
    """Fit and cross-validate the Iwan joint whose slip-threshold density the data set.

    Started from the Segalman fit written as cells (:func:`iwan_as_cells`), so that it
    never fits worse than the power law it generalises.

    Returns
    -------
    fit, heldout : FitResult, dict
        The all-data fit and :func:`cross_validate`'s result.
    """
    model = MODELS[f"iwan_cells_{threshold_cells(data)}"]
    start = iwan_as_cells({**iwan_fit.params, **fixed_params(model, data, context)}, model)
    fit = fit_model(model, data, scatter, context, settings=settings, nested_start=start)
    return fit, cross_validate(model, data, scatter, context, fit, settings=settings)


def threshold_distribution(
    fit: FitResult, data: ConfigurationData, scatter: Scatter, context: FitContext
) -> list[dict]:
    """The recovered slip-threshold cells: velocity range, stiffness share, its standard error."""
    model = MODELS[fit.model]
    errors = fit_standard_errors(fit, data, scatter, context)
    on_edge = at_bounds(model, fit.coords, data) != 0
    edges = threshold_cell_edges(len(model.cell_names)) * data.anchor_velocity_in_s
    names = model.param_names
    cells = []
    for k, name in enumerate(model.cell_names):
        i = names.index(name)
        value = fit.params[name]
        cells.append(
            {
                "threshold_low_in_s": float(edges[k]),
                "threshold_high_in_s": float(edges[k + 1]),
                "stiffness_fraction": float(value),
                # at an edge of its fit range the share is not identified: no error bar
                "standard_error": None if on_edge[i] else float(value * errors[i]),
            }
        )
    return cells


def diagnose_configuration(
    data: ConfigurationData,
    context: FitContext,
    *,
    settings: FitSettings = FitSettings(),
    segment_cycles: float = AnalysisSettings.segment_cycles,
) -> ConfigurationDiagnosis:
    """Baselines, discrepancy, candidates, verdict and its confidence for one configuration."""
    scatter = scatter_of(data)
    fits: dict[str, FitResult] = {}
    cv: dict[str, dict] = {}
    for name in BASELINE_MODELS + tuple(CAUSE_MODELS.values()):
        if name == "dahl_drift" and data.n_runs < 3:
            continue
        nested = None
        if name != "dahl" and name in NESTED_DAHL and "dahl" in fits:
            nested = {**fits["dahl"].params, **NESTED_DAHL[name](data)}
        started = time.perf_counter()
        fits[name] = fit_model(name, data, scatter, context, settings=settings, nested_start=nested)
        cv[name] = cross_validate(name, data, scatter, context, fits[name], settings=settings)
        log.info(
            "%s %s: fitted and cross-validated in %.1f s (held-out error %.3g)",
            data.name,
            name,
            time.perf_counter() - started,
            cv[name]["error"],
        )
    residuals = {m: model_residuals(f, data, scatter, context) for m, f in fits.items()}
    evidence = {m: ModelEvidence(residuals[m], cv[m], len(MODELS[m].params)) for m in fits}
    stiffness_model = CAUSE_MODELS["stiffness_nonlinearity"]
    signature = stiffness_signature(fits[stiffness_model], data)
    evidence[stiffness_model].shows_signature = signature["shows_signature"]
    envelope = envelope_structure(data, segment_cycles=segment_cycles)
    envelope_significant = bool(envelope and envelope["significant"])
    result = evaluate_decision(data, evidence, envelope_significant=envelope_significant)
    extended_models, refinement = {}, None
    if (
        result["cause"] == "microslip_power_law"
        and not explains_data(data, residuals["iwan"])["explains_data"]
    ):
        started = time.perf_counter()
        name = f"iwan_cells_{threshold_cells(data)}"
        fits[name], cv[name] = refine_microslip(data, scatter, context, fits["iwan"], settings=settings)
        residuals[name] = model_residuals(fits[name], data, scatter, context)
        evidence[name] = ModelEvidence(residuals[name], cv[name], len(MODELS[name].params))
        # the same decision (the candidates are unchanged), now with the refinement's error and BIC
        result = evaluate_decision(data, evidence, envelope_significant=envelope_significant)
        errors, bic = result["errors"], result["bic"]
        adopted = errors[name]["error"] < errors["iwan"]["error"] and bic[name] < bic["iwan"]
        if adopted:
            extended_models = {"microslip_power_law": name}
            result["extended_models"].update(extended_models)
        refinement = {
            "model": name,
            "adopted": bool(adopted),
            "rule": "adopted as the extended model when it lowers both the held-out error and the BIC of iwan",
            "heldout_error": errors[name]["error"],
            "bic": bic[name],
            "iwan_heldout_error": errors["iwan"]["error"],
            "iwan_bic": bic["iwan"],
            "cells": threshold_distribution(fits[name], data, scatter, context),
            "standard_error": "Gauss-Newton, scaled by the fit cost and residuals over effective observations",
        }
        log.info(
            "%s %s (slip thresholds from the data): fitted and cross-validated in %.1f s "
            "(held-out error %.3g, iwan %.3g; %s)",
            data.name,
            name,
            time.perf_counter() - started,
            errors[name]["error"],
            errors["iwan"]["error"],
            "adopted" if adopted else "not adopted",
        )
    resamples = resample_decisions(
        data,
        evidence,
        envelope_significant=envelope_significant,
        n_resamples=settings.resamples,
        seed=settings.seed,
        n_folds=settings.folds,
        extended_models=extended_models,
    )
    cause, reason, base = result["cause"], result["reason"], result["baseline"]
    errors, bins, trend, candidates = result["errors"], result["bins"], result["trend"], result["candidates"]
    candidates["stiffness_nonlinearity"]["signature"] = signature
    for entry in candidates.values():
        m = entry["model"]
        entry["in_sample_rms"] = float(np.sqrt(fits[m].cost))
        entry["params"] = fits[m].params
        entry["flags"] = bound_flags(m, fits[m].coords, data)
    ranking = [{"cause": "none", "score": errors[base]["error"]}]
    ranking += [{"cause": c, "score": v["heldout_error"]} for c, v in candidates.items()]
    ranking.sort(key=lambda r: r["score"])
    ext_model = _extended_model(result)
    ext_err = errors[ext_model]["error"]
    explained = explains_data(data, residuals[ext_model])
    sentence = discrepancy_sentence(base, bins, trend, data.n_runs)
    if envelope_significant:
        sentence = (
            f"The ring-downs are not single-mode decays: even at each run's highest "
            f"amplitudes the envelope departs from an exponential within a segment by "
            f"{100 * envelope['departure_ratio']:.0f} % of its decay across the segment "
            f"(median over runs; limit {100 * envelope['limit']:.0f} %), which no {base} "
            f"fit or candidate can follow; {data.n_dropped} segments had zeta <= 0. " + sentence
        )
    run_spread = {}
    if data.n_runs >= 2:
        run_spread = {
            "relative_frequency_std": float(np.std(residuals[base]["delta_f"], ddof=1)),
            "zeta0_std": float(np.std(residuals[base]["delta_zeta0"], ddof=1)),
        }
    document = {
        "baseline": {
            "model": base,
            "params": fits[base].params,
            "error": {"metric": HELD_OUT_METRIC, "value": errors[base]["error"]},
            "flags": bound_flags(base, fits[base].coords, data),
        },
        "discrepancy": sentence,
        "cause": cause,
        "evidence": {
            "decision_rule": reason,
            "n_runs": data.n_runs,
            "n_segments": data.n,
            "n_segments_dropped": data.n_dropped,
            "effective_observations": result["n_eff"],
            "scatter": {
                "ln_zeta_median": float(np.median(scatter.noise_ln_zeta)),
                "relative_frequency_median": float(np.median(scatter.noise_rel_f)),
                "model_tolerance_ln_zeta": TOL_LN_ZETA,
                "model_tolerance_relative_frequency": TOL_REL_F,
            },
            "run_offsets": run_spread,
            "baselines": {
                m: {
                    "heldout_error": errors[m]["error"],
                    "heldout_error_zeta": errors[m]["error_zeta"],
                    "heldout_error_frequency": errors[m]["error_frequency"],
                    "in_sample_rms": float(np.sqrt(fits[m].cost)),
                    "bic": result["bic"][m],
                }
                for m in BASELINE_MODELS
            },
            "baseline_misfit_significant": result["baseline_fails"],
            "binned_residuals": bins,
            "run_order_trend": trend,
            "envelope_structure": envelope,
            "candidates": candidates,
            "clear_gain_threshold": CLEAR_GAIN,
            "residual_gain_threshold": RESIDUAL_GAIN,
            "explains_data": explained,
            "threshold_distribution": refinement,
            "resamples": len(resamples),
        },
        "ranking": ranking,
        "extended_model": {
            "model": ext_model,
            "params": fits[ext_model].params,
            "removes_misfit": cause != "unknown" and explained["explains_data"],
            "flags": bound_flags(ext_model, fits[ext_model].coords, data),
        },
        "gain": {
            "metric": HELD_OUT_METRIC,
            "baseline": errors[base]["error"],
            "extended": ext_err,
            "ratio": 1.0 if cause == "none" else ext_err / errors[base]["error"],
        },
        "explains_data": explained["explains_data"],
        "confidence": cause_fractions([r["cause"] for r in resamples]),
    }
    return ConfigurationDiagnosis(_clean(document), fits, data, scatter, residuals, resamples, evidence)


# ------------------------------------------------------- across configurations
def across_configurations(
    diagnoses: Mapping[str, ConfigurationDiagnosis], context: FitContext, extended_model: str | None
) -> dict:
    """Parameters as functions of bearing area; each configuration predicted from the rest.

    Every fit coordinate (ln value for scale parameters) of a model is taken as
    linear in ``ln(bearing area)`` (a constant with two configurations left); the
    left-out configuration's curves are predicted from those lines and scored
    with its own scatter (RMS normalised residual, both curves).

    Returns
    -------
    dict
        ``applicable`` False (with ``reason``) when fewer than 3 configurations have
        areas; else per configuration the baseline's and the extended model's
        prediction errors and their ratio, and their means.
    """
    with_area = {
        n: d
        for n, d in diagnoses.items()
        if d.data.bearing_area_in2 is not None and d.data.bearing_area_in2 > 0
    }
    if len(with_area) < 3:
        return {
            "applicable": False,
            "reason": f"{len(with_area)} configuration(s) with a bearing area; 3 are needed",
        }
    baselines = {d.document["baseline"]["model"] for d in with_area.values()}
    base_model = "dahl" if "dahl" in baselines or len(baselines) != 1 else baselines.pop()
    models = {"baseline": base_model}
    if extended_model and extended_model != base_model:
        models["extended"] = extended_model
    out = {
        "applicable": True,
        "parametrisation": "fit coordinates linear in ln(bearing area)",
        "metric": HELD_OUT_METRIC,
        "models": models,
        "configurations": {},
    }
    names = list(with_area)
    log_area = np.log([with_area[n].data.bearing_area_in2 for n in names])
    for role, m in models.items():
        model = MODELS[m]
        if any(m not in with_area[n].fits for n in names):
            out["models"].pop(role)
            continue
        coords = np.array([with_area[n].fits[m].coords for n in names])
        for i, n in enumerate(names):
            keep = np.arange(len(names)) != i
            design = np.vstack([np.ones(keep.sum()), log_area[keep]]).T
            beta, *_ = np.linalg.lstsq(design, coords[keep], rcond=None)
            pred = np.array([1.0, log_area[i]]) @ beta
            d = with_area[n]
            params = {p.name: float(v[0, 0]) for p, v in zip(model.params, to_physical(model, pred).values())}
            params.update(fixed_params(model, d.data, context))
            fit = FitResult(m, pred, params, np.nan)
            res = model_residuals(fit, d.data, d.scatter, context)
            err = _weighted_rms(
                0.5 * (res[f"z_{HELD_OUT_SCALE}"] ** 2 + res[f"f_{HELD_OUT_SCALE}"] ** 2),
                amplitude_weights(d.data.velocity_in_s, d.data.anchor_velocity_in_s),
            )
            entry = out["configurations"].setdefault(n, {"bearing_area_in2": d.data.bearing_area_in2})
            entry[f"{role}_error"] = err
            entry[f"{role}_params"] = params
    for entry in out["configurations"].values():
        if "extended_error" in entry and "baseline_error" in entry:
            entry["ratio"] = entry["extended_error"] / entry["baseline_error"]
    errs = out["configurations"].values()
    out["baseline_mean_error"] = float(np.mean([e["baseline_error"] for e in errs]))
    if "extended" in out["models"]:
        out["extended_mean_error"] = float(np.mean([e["extended_error"] for e in errs]))
        out["ratio"] = out["extended_mean_error"] / out["baseline_mean_error"]
    return _clean(out)


# ------------------------------------------------------------------- campaign
def configuration_outcomes(outcomes: Sequence) -> tuple[dict[str, ConfigurationDiagnosis], dict[str, str]]:
    """The diagnoses and the skipped configurations (name -> why) of the configurations'
    outcomes (:class:`workflow.io.interim.DiagnosedConfiguration`), in the order of the
    segments table; a configuration with no segment in it (``order`` -1: every run
    excluded, or every segment rejected) comes last among the skipped, never dropped."""
    ordered = sorted(outcomes, key=lambda o: (o.order < 0, o.order))
    diagnoses = {o.configuration: o.diagnosis for o in ordered if o.diagnosis is not None}
    skipped = {o.configuration: o.skipped for o in ordered if o.diagnosis is None}
    return diagnoses, skipped


def campaign_verdict(causes: Sequence[str], ratios: Sequence[float]) -> str:
    """Campaign cause: the most frequent configuration cause other than ``none``.

    Ties go to the cause with the lowest mean gain ratio; ``none`` only when every
    configuration is ``none`` (or there is none).
    """
    named = [(c, r) for c, r in zip(causes, ratios) if c != "none"]
    if not named:
        return "none"
    counts: dict[str, list[float]] = {}
    for c, r in named:
        counts.setdefault(c, []).append(r)
    return min(counts, key=lambda c: (-len(counts[c]), float(np.mean(counts[c]))))


def campaign_confidence(diagnoses: Mapping[str, ConfigurationDiagnosis]) -> dict[str, float]:
    """Fraction of joint resamples whose campaign verdict names each cause.

    Resample ``b`` of every configuration (each drawn from its own runs) gives one set of
    configuration causes and gain ratios, and :func:`campaign_verdict` turns it into one
    campaign cause."""
    counts = {len(d.resamples) for d in diagnoses.values()}
    if not diagnoses or len(counts) != 1 or 0 in counts:
        return {}
    n = counts.pop()
    verdicts = [
        campaign_verdict(
            [d.resamples[b]["cause"] for d in diagnoses.values()],
            [d.resamples[b]["ratio"] for d in diagnoses.values()],
        )
        for b in range(n)
    ]
    return cause_fractions(verdicts)


def diagnose_campaign(
    segments: pd.DataFrame,
    campaign_name: str,
    *,
    response_quantity: str | Mapping[str, str] = "acceleration",
    settings: FitSettings | None = None,
    segment_cycles: float = AnalysisSettings.segment_cycles,
    runs: pd.DataFrame | None = None,
    return_details: bool = False,
):
    """The ``results/diagnosis.json`` document of a campaign.

    Parameters
    ----------
    segments : DataFrame
        The kept segments (results/tables/segments.parquet): ``configuration``,
        ``run``, ``velocity_amplitude_in_s``, ``zeta``, ``frequency_hz``,
        ``bearing_area_in2``.
    campaign_name : str
    response_quantity : str or mapping
        Recorded quantity (campaign.yaml ``response.quantity``), for all
        configurations or per configuration: the envelope of an acceleration record
        decays differently from a displacement's when the frequency changes.
    settings : FitSettings, optional
    segment_cycles : float
        Log-decrement segment length in cycles (config ``analysis.segment_cycles``),
        for the envelope-structure check.
    runs : DataFrame, optional
        The runs table (results/tables/runs.parquet): its ``record_start`` orders each
        configuration's runs for the run-order tests; without it, file-name order.
    return_details : bool
        Also return the per-configuration :class:`ConfigurationDiagnosis` objects.

    Returns
    -------
    dict
        ``campaign``, ``cause``, ``configurations`` (per the output contract) and
        ``across_configurations``; all numbers finite (None where not applicable).
    """
    settings = settings or FitSettings()
    context = campaign_fit_context(segments)
    diagnoses: dict[str, ConfigurationDiagnosis] = {}
    skipped = {}
    for name in dict.fromkeys(segments["configuration"].astype(str)):
        quantity = (
            response_quantity
            if isinstance(response_quantity, str)
            else response_quantity.get(name, "acceleration")
        )
        outcome = diagnose_configuration_segments(
            segments,
            name,
            context,
            response_quantity=quantity,
            settings=settings,
            segment_cycles=segment_cycles,
            record_start=record_starts(runs, name),
        )
        if isinstance(outcome, str):
            skipped[name] = outcome
        else:
            diagnoses[name] = outcome
    document = campaign_document(campaign_name, context, diagnoses, skipped)
    return (document, diagnoses) if return_details else document


# ---------------------------------------------------------------- residuals
RESIDUAL_COLUMNS = [
    "configuration",
    "run",
    "segment",
    "role",
    "model",
    "velocity_amplitude_in_s",
    "curve",
    "measured",
    "predicted",
    "scatter",
    "residual",
]


def residual_table(diagnoses: Mapping[str, ConfigurationDiagnosis]) -> pd.DataFrame:
    """Residuals of the baseline and the extended model at every measured segment.

    Parameters
    ----------
    diagnoses : mapping
        Configuration -> :class:`ConfigurationDiagnosis` (the second value returned by
        ``diagnose_campaign(..., return_details=True)``).

    Returns
    -------
    DataFrame
        One row per configuration x segment x model role x curve: ``configuration``,
        ``run``, ``segment`` (index of the segment among the configuration's usable
        ones), ``role`` ("baseline" or "extended"), ``model`` (model id; for cause
        ``none`` the extended model is the baseline), ``velocity_amplitude_in_s``,
        ``curve`` ("zeta" or "frequency_hz"), ``measured``, ``predicted`` (the fitted
        model's curve at the segment's amplitude, all-data fit), ``scatter`` (the
        measured run-to-run scatter: in ``ln zeta``, or in relative frequency) and
        ``residual`` (``ln(measured / predicted)`` or ``measured / predicted - 1``,
        divided by ``scatter``; the same normalisation as the held-out error).
    """
    frames = []
    for name, d in diagnoses.items():
        roles = {
            "baseline": d.document["baseline"]["model"],
            "extended": d.document["extended_model"]["model"],
        }
        data = d.data
        runs = np.array(data.run_names, dtype=object)[data.run_index] if data.n else []
        for role, m in roles.items():
            res = d.residuals[m]
            for curve, measured, predicted, scatter, residual in (
                ("zeta", data.zeta, res["zeta_model"], d.scatter.noise_ln_zeta, res["z_noise"]),
                ("frequency_hz", data.frequency_hz, res["f_model"], d.scatter.noise_rel_f, res["f_noise"]),
            ):
                frames.append(
                    pd.DataFrame(
                        {
                            "configuration": name,
                            "run": runs,
                            "segment": np.arange(data.n),
                            "role": role,
                            "model": m,
                            "velocity_amplitude_in_s": data.velocity_in_s,
                            "curve": curve,
                            "measured": measured,
                            "predicted": predicted,
                            "scatter": scatter,
                            "residual": residual,
                        }
                    )
                )
    if not frames:
        return pd.DataFrame(
            {
                c: pd.Series(
                    dtype=float
                    if c in ("velocity_amplitude_in_s", "measured", "predicted", "scatter", "residual")
                    else object
                )
                for c in RESIDUAL_COLUMNS
            }
        )
    return pd.concat(frames, ignore_index=True)[RESIDUAL_COLUMNS]


# ------------------------------------------------- one configuration at a time
CAMPAIGN_RULE = (
    "most frequent configuration cause other than none (ties: lowest mean "
    "gain ratio); none only when every configuration is none"
)


def campaign_fit_context(segments: pd.DataFrame) -> FitContext:
    """The campaign's :class:`FitContext`: reference velocity = 0.9 quantile of every
    configuration's segment velocity amplitudes (in/s; 1 when there are none).

    It is computed from all segments even when one configuration is diagnosed, so that a
    configuration's fits do not depend on which job fitted them.
    """
    v_all = segments["velocity_amplitude_in_s"].to_numpy(float)
    v_all = v_all[np.isfinite(v_all) & (v_all > 0)]
    return FitContext(float(np.quantile(v_all, 0.9)) if v_all.size else 1.0)


def record_starts(runs: pd.DataFrame | None, name: str) -> dict[str, str]:
    """Run name -> ISO 8601 recording start of configuration ``name``'s runs, from the runs
    table (results/tables/runs.parquet; empty where a file states none, or no table)."""
    if runs is None or "record_start" not in runs:
        return {}
    rows = runs[runs["configuration"].astype(str) == name]
    return dict(zip(rows["run"].astype(str), rows["record_start"].fillna("").astype(str)))


def diagnose_configuration_segments(
    segments: pd.DataFrame,
    name: str,
    context: FitContext,
    *,
    response_quantity: str = "acceleration",
    settings: FitSettings | None = None,
    segment_cycles: float = AnalysisSettings.segment_cycles,
    record_start: Mapping[str, str] | None = None,
) -> ConfigurationDiagnosis | str:
    """:func:`diagnose_configuration` of configuration ``name`` of the segments table, or
    why it is skipped (too few usable segments or amplitudes to fit and validate models).

    Parameters
    ----------
    segments : DataFrame
        The campaign's kept segments (results/tables/segments.parquet).
    name : str
    context : FitContext
        The campaign's (:func:`campaign_fit_context`).
    response_quantity : str
        The configuration's recorded quantity (campaign.yaml ``response.quantity``).
    settings : FitSettings, optional
    segment_cycles : float
        Log-decrement segment length, cycles.
    record_start : mapping, optional
        Run name -> recording start (:func:`record_starts`): the run order.
    """
    data = prepare_configuration(segments, name, RESPONSE_ORDER[response_quantity], record_start)
    if data.n < 12 or np.unique(np.round(np.log10(data.velocity_in_s), 2)).size < 4:
        return f"only {data.n} usable segments: too few to fit and validate models"
    return diagnose_configuration(
        data, context, settings=settings or FitSettings(), segment_cycles=segment_cycles
    )


def campaign_document(
    campaign_name: str,
    context: FitContext,
    diagnoses: Mapping[str, ConfigurationDiagnosis],
    skipped: Mapping[str, str],
) -> dict:
    """The ``results/diagnosis.json`` document from the configurations' diagnoses.

    Parameters
    ----------
    campaign_name : str
    context : FitContext
        The campaign's (:func:`campaign_fit_context`).
    diagnoses : mapping
        Configuration -> :class:`ConfigurationDiagnosis`, in campaign order.
    skipped : mapping
        Configuration -> why it was not diagnosed.

    Returns
    -------
    dict
        ``campaign``, ``cause``, ``confidence``, ``configurations`` (per the output
        contract), ``across_configurations``, ``skipped_configurations`` and the
        reference velocity; all numbers finite (None where not applicable).
    """
    configurations = {n: d.document for n, d in diagnoses.items()}
    cause = campaign_verdict(
        [d["cause"] for d in configurations.values()], [d["gain"]["ratio"] for d in configurations.values()]
    )
    document = {
        "campaign": campaign_name,
        "cause": cause,
        "confidence": campaign_confidence(diagnoses),
        "campaign_rule": CAMPAIGN_RULE,
        "configurations": configurations,
        "across_configurations": across_configurations(diagnoses, context, CAUSE_MODELS.get(cause)),
        "skipped_configurations": dict(skipped),
        "reference_velocity_in_s": context.reference_velocity_in_s,
    }
    return _clean(document)

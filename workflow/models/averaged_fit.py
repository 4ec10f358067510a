"""Weighted least-squares fits of the averaged models to a configuration's two curves.

Every model of :mod:`workflow.models.averaged` is fitted to ``ln zeta`` and relative
frequency at once, each residual divided by the segment's standard uncertainty
(:class:`workflow.models.configuration_data.Scatter`): a quasi-random (Sobol) global stage
over the parameter box (:func:`parameter_box`; log coordinates for scale parameters),
then ``scipy.optimize.least_squares`` from the best distinct global points. With two runs
or more, every run has its own small-amplitude frequency and linear damping on top of the
joint physics the runs share (:func:`run_offsets`, closed form).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from workflow.models.averaged import MODELS, AveragedModel, CurveGrid
from workflow.models.configuration_data import ConfigurationData, Scatter
from workflow.models.joint_averages import threshold_cell_edges
from workflow.models.sampling import scrambled_sobol_points
from workflow.models.settings import DiscoverySettings

__all__ = [
    "LOCAL_NFEV",
    "TWO_STAGE_MODELS",
    "SCREEN_NFEV",
    "FOLD_NFEV",
    "FitContext",
    "JOINT_SHARE_MAX",
    "SLIP_SCALE_ABOVE_RANGE",
    "CELL_FRACTION_BOX",
    "parameter_box",
    "at_bounds",
    "to_physical",
    "to_coords",
    "FitResult",
    "RunGroups",
    "run_groups",
    "run_offsets",
    "run_offset_variances",
    "apply_run_offsets",
    "centred_run_offsets",
    "calibration_segments",
    "fixed_params",
    "unseen_cell_ties",
    "fit_model",
    "fit_jacobian",
    "model_residuals",
    "damping_curve_slope",
]


LOCAL_NFEV = 60
"""Most residual evaluations of one local refinement from a global start."""

TWO_STAGE_MODELS = ("lugre",)
"""Models refined in two stages (expensive ones): every start briefly, the best fully."""

SCREEN_NFEV = 8
"""Evaluations of the short refinement from each start of a two-stage model (the best is
continued)."""

FOLD_NFEV = 12
"""Most evaluations when refitting a cross-validation fold from the all-data fit."""


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


def at_bounds(model: AveragedModel, coords: np.ndarray, data: ConfigurationData) -> np.ndarray:
    """Per parameter, -1 / 1 where the fit sits on the lower / upper edge of its fit range
    (within a thousandth of it: not identified by the data), else 0."""
    lo, hi = parameter_box(model, data)
    unit = (np.asarray(coords, dtype=float) - lo) / (hi - lo)
    return np.where(unit <= 1e-3, -1, np.where(unit >= 1 - 1e-3, 1, 0))


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
    segments in ``use`` (default all) count.

    Examples
    --------
    >>> groups = run_groups(np.array([0, 0, 1, 1, 1]), 3)
    >>> groups.member.sum(axis=0).tolist(), groups.present.tolist()
    ([2.0, 3.0, 0.0], [True, True, False])
    """
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


def run_offset_variances(
    zeta_model: np.ndarray,
    s_rel_f: np.ndarray,
    s_ln_zeta: np.ndarray,
    noise_rel_f: np.ndarray,
    noise_ln_zeta: np.ndarray,
    groups: RunGroups,
) -> tuple[np.ndarray, np.ndarray]:
    """Variances of :func:`run_offsets`' estimates from the scatter of the segments used.

    Each offset is a weighted mean of its segments' residuals (weights from the total
    uncertainties ``s_rel_f``, ``s_ln_zeta``); where those scatter independently by the
    measured scatter alone (``noise_rel_f``, ``noise_ln_zeta``), its variance is
    ``sum (a_i noise_i)^2 / (sum a_i)^2`` with ``a_i`` its weights. A run calibrated on
    a few noisy segments carries a large one.

    Returns
    -------
    var_delta_f, var_delta_zeta0 : ndarray, shape (n_runs,)
        Variances of the relative frequency offset and of the linear-damping offset; 0
        for a run with no segment used.

    Examples
    --------
    Four segments of one run, each scattering by 0.1 in ``ln zeta`` around a damping
    ratio of 1e-3: the linear damping of the run is known to ``1e-3 x 0.1 / 2``.

    >>> groups = run_groups(np.zeros(4, dtype=int), 1)
    >>> one = np.ones(4)
    >>> var_f, var_z = run_offset_variances(np.full(4, 1e-3), one, one, one, np.full(4, 0.1), groups)
    >>> float(np.sqrt(var_z[0]))
    5e-05
    """
    member = groups.member
    w_f = 1.0 / s_rel_f**2
    var_f = ((w_f * noise_rel_f) ** 2 @ member) / np.maximum((w_f @ member) ** 2, 1e-300)
    g = 1.0 / np.maximum(zeta_model, 1e-12)
    a_z = g * g / s_ln_zeta**2  # the weight of each segment's linear-damping estimate ln_res / g
    var_z = ((a_z * noise_ln_zeta / g) ** 2 @ member) / np.maximum((a_z @ member) ** 2, 1e-300)
    return var_f, var_z


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
    at least :data:`MIN_CALIBRATION_SEGMENTS`, never the whole run).

    Examples
    --------
    A quarter of eight segments, raised to the minimum of three:

    >>> calibration_segments(np.arange(1.0, 9.0), np.zeros(8, dtype=int), np.array([0])).tolist()
    [True, True, True, False, False, False, False, False]
    """
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


def unseen_cell_ties(
    model: AveragedModel, velocity_in_s: np.ndarray, fixed: Mapping[str, float]
) -> list[tuple[int, int]]:
    """Slip-threshold cells no fitted segment reaches, each tied to the highest cell one does.

    A cell whose lowest threshold lies at or above the largest fitted amplitude holds
    elements that never slip there: they add stiffness the linear frequency absorbs, and
    the data say nothing of its share. Held out, the top amplitudes of one hit leave the
    top cell so (its quarter decade lies in the top block): the fit then puts any share there
    (one of the lab's micro-slip + loss hits, bench seed 1934: 8.8e-6 where every other
    fold put 5.1e-3) and its prediction of the top block is whatever that share makes
    (3800 scatters off there, where the folds below predict within one to four). Tied, the density of thresholds per ``ln t`` continues at
    the highest seen cell's level (the cells are equally wide in ``ln t``): beyond the
    data the prediction continues the density they show.

    Returns
    -------
    list of (int, int)
        (coordinate of an unseen cell, coordinate of the highest seen cell); empty for a
        model without cells or where every cell is reached.
    """
    names = model.cell_names
    if not names or velocity_in_s.size == 0:
        return []
    lower_edges = threshold_cell_edges(len(names))[:-1] * float(fixed["anchor_velocity_in_s"])
    seen = np.flatnonzero(lower_edges < float(np.max(velocity_in_s)))
    if seen.size == 0 or seen[-1] == len(names) - 1:
        return []
    index = {p.name: i for i, p in enumerate(model.params)}
    source = index[names[int(seen[-1])]]
    return [(index[name], source) for name in names[int(seen[-1]) + 1 :]]


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
            response_order=data.response_order_of(mask),
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
        self.unseen_cells = unseen_cell_ties(model, data.velocity_in_s[mask], self.fixed)

    def coordinates(self, unit: np.ndarray) -> np.ndarray:
        """Fit coordinates of unit-box points (P, k), unseen cells tied (:func:`unseen_cell_ties`)."""
        coords = self.lo + np.atleast_2d(unit) * (self.hi - self.lo)
        for cell, source in self.unseen_cells:
            coords[:, cell] = coords[:, source]
        return coords

    def physical(self, unit: np.ndarray) -> dict[str, np.ndarray]:
        p = to_physical(self.model, self.coordinates(unit))
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
    settings: DiscoverySettings = DiscoverySettings(),
    max_nfev: int = LOCAL_NFEV,
    mask: np.ndarray | None = None,
    warm_start: np.ndarray | None = None,
    nested_start: Mapping[str, float] | Sequence[Mapping[str, float]] | None = None,
) -> FitResult:
    """Weighted least-squares fit of a model to both curves of (part of) a configuration.

    Parameters
    ----------
    model : AveragedModel or str
    data : ConfigurationData
    scatter : Scatter
        Per-segment uncertainties (weights).
    context : FitContext
    settings : DiscoverySettings
        Global samples, local starts, seed (config.yaml's ``discovery``).
    max_nfev : int
        Most residual evaluations of one local refinement from a global start.
    mask : ndarray of bool, optional
        Segments used (default all).
    warm_start : ndarray, optional
        Fit coordinates to refine from (skips the global stage: used for the
        cross-validation folds, started from the all-data fit).
    nested_start : mapping or sequence of mappings, optional
        Physical parameters of a model this one contains (e.g. the Dahl fit with the
        extension switched off): refined as one more start, so that an extended
        model never fits worse than the model it extends. A combination of two
        mechanisms passes one start per single-mechanism fit.

    Returns
    -------
    FitResult

    Examples
    --------
    Dahl curves fitted back to the parameters that made them:

    >>> from workflow.models.averaged import model_curves
    >>> from workflow.models.configuration_data import ConfigurationData, scatter_of
    >>> truth = {"f_lin_hz": 100.0, "zeta0": 0.002, "joint_stiffness_fraction": 0.01, "slip_velocity_in_s": 1.0}
    >>> v = np.geomspace(0.05, 5.0, 40)
    >>> zeta, frequency_hz = model_curves("dahl", truth, v)
    >>> data = ConfigurationData("c", v, zeta, frequency_hz, np.zeros(v.size, int), ["run01"], None)
    >>> settings = DiscoverySettings(global_samples=64, local_starts=2)
    >>> fit = fit_model("dahl", data, scatter_of(data), FitContext(1.0), settings=settings)
    >>> {name: float(f"{value:.3g}") for name, value in fit.params.items()}
    {'f_lin_hz': 100.0, 'zeta0': 0.002, 'joint_stiffness_fraction': 0.01, 'slip_velocity_in_s': 1.0}
    """
    model = MODELS[model] if isinstance(model, str) else model
    mask = np.ones(data.n, dtype=bool) if mask is None else mask
    problem = _Problem(model, data, scatter, mask, context)
    span = problem.hi - problem.lo
    if warm_start is not None:
        starts = [np.clip((warm_start - problem.lo) / span, 0.0, 1.0)]
    else:
        starts = []
        nested = [nested_start] if isinstance(nested_start, Mapping) else list(nested_start or [])
        for start in nested:
            starts.append(np.clip((to_coords(model, start) - problem.lo) / span, 0.0, 1.0))
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
        best_u, best_cost = _local_fit(problem, starts[0], FOLD_NFEV)
    elif model.name not in TWO_STAGE_MODELS:
        for start in starts:
            u, c = _local_fit(problem, start, max_nfev)
            if c < best_cost:
                best_u, best_cost = u, c
    else:
        # two stages: a short refinement from every start, then the best one continued
        screened = [_local_fit(problem, start, SCREEN_NFEV) for start in starts]
        u0 = min(screened, key=lambda r: r[1])[0]
        best_u, best_cost = _local_fit(problem, u0, max_nfev)
    coords = problem.coordinates(best_u)[0]
    params = {p.name: float(v[0, 0]) for p, v in zip(model.params, to_physical(model, coords).values())}
    params.update(problem.fixed)
    return FitResult(model.name, coords, params, best_cost)


def fit_jacobian(
    fit: FitResult, data: ConfigurationData, scatter: Scatter, context: FitContext
) -> np.ndarray:
    """Jacobian of a fit's normalised residuals (all segments) in its fit coordinates.

    Forward differences in the unit box, divided by the box's span: shape
    ``(2 n, k)`` for ``n`` segments and ``k`` fitted parameters.
    """
    model = MODELS[fit.model]
    problem = _Problem(model, data, scatter, np.ones(data.n, dtype=bool), context)
    span = problem.hi - problem.lo
    unit = np.clip((fit.coords - problem.lo) / span, 0.0, 1.0)
    return problem.jacobian(unit) / span


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
    held-out run's are, ``ln_zeta_slope``, the shared model's log-log damping slope
    (:func:`damping_curve_slope`), ``scatter_ln_zeta`` and ``scatter_rel_f``, the
    measured scatter of ``ln zeta`` and of the relative frequency at each segment, and
    ``offset_variance_ln_zeta``,
    ``offset_variance_rel_f``, the variance each segment's residual carries from its
    run's offsets, estimated (before centring) from the noise of the segments they were
    set by (:func:`run_offset_variances`; 0 with one run).
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
    offset_variance_rel_f, offset_variance_ln_zeta = np.zeros(data.n), np.zeros(data.n)
    if data.n_runs >= 2:
        calibration = calibration_segments(data.velocity_in_s, data.run_index, np.arange(n_runs))
        calibration_groups = run_groups(data.run_index, n_runs, calibration)
        own = run_offsets(f_res, ln_res, zeta, scatter.rel_f, scatter.ln_zeta, calibration_groups)
        ln_calibrated = apply_run_offsets(f_res, ln_res, zeta, *own, data.run_index)[1]
        offsets = run_offsets if offsets_from is not None else centred_run_offsets
        fitted_groups = run_groups(data.run_index, n_runs, offsets_from)
        delta_f, delta_z = offsets(f_res, ln_res, zeta, scatter.rel_f, scatter.ln_zeta, fitted_groups)
        var_f, var_z = run_offset_variances(
            zeta, scatter.rel_f, scatter.ln_zeta, scatter.noise_rel_f, scatter.noise_ln_zeta, fitted_groups
        )
        offset_variance_rel_f = var_f[data.run_index]
        offset_variance_ln_zeta = var_z[data.run_index] / np.maximum(zeta, 1e-12) ** 2
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
        "scatter_ln_zeta": scatter.noise_ln_zeta,
        "scatter_rel_f": scatter.noise_rel_f,
        "offset_variance_ln_zeta": offset_variance_ln_zeta,
        "offset_variance_rel_f": offset_variance_rel_f,
    }


def damping_curve_slope(
    velocity_in_s: np.ndarray, ln_zeta_model: np.ndarray, run_index: np.ndarray
) -> np.ndarray:
    """Log-log slope ``d ln zeta / d ln V`` of each run's model damping curve at its segments.

    A change of the joint's friction limit moves its damping curve along ``ln V`` (the
    slip velocity scales with it, the linear damping stays), so ``-slope`` is the change of
    ``ln zeta`` per unit change of ``ln Fc``: the shape a run-to-run change of the joint
    leaves in the residuals (:func:`~workflow.discovery.misfit.run_order_trend`). Central differences along each
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

"""Micro-slip refinement: the Iwan joint whose slip-threshold distribution the data set.

When the power-law Iwan joint does not explain the data and micro-slip is the verdict or,
with a significant baseline misfit, an eligible candidate
(:func:`workflow.discovery.configuration.needs_threshold_cells`), the thresholds are recovered as quarter-decade cells of stiffness share, started from the power-law fit
written as cells, with Gauss-Newton standard errors.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from workflow.discovery.heldout import cross_validate, effective_observations
from workflow.models.averaged import MAX_THRESHOLD_CELLS, MODELS, AveragedModel
from workflow.models.averaged_fit import (
    FitContext,
    FitResult,
    at_bounds,
    fit_jacobian,
    fit_model,
    fixed_params,
)
from workflow.models.configuration_data import ConfigurationData, Scatter
from workflow.models.joint_averages import threshold_cell_edges
from workflow.models.settings import DiscoverySettings

__all__ = [
    "threshold_cells",
    "iwan_as_cells",
    "fit_standard_errors",
    "refine_microslip",
    "threshold_distribution",
]


def threshold_cells(data: ConfigurationData) -> int:
    """Quarter-decade slip-threshold cells of a configuration's recovered distribution.

    From at least half a decade below its lowest measured amplitude (elements that slipped at
    every amplitude measured still lower the frequency and add a damping falling as
    ``1 / V``) to the top of its range (higher thresholds never slip: linear stiffness).
    """
    span = float(np.log10(data.anchor_velocity_in_s / np.min(data.velocity_in_s)))
    return int(np.clip(np.ceil(4.0 * span - 1e-9) + 2, 1, MAX_THRESHOLD_CELLS))


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
    jac = fit_jacobian(fit, data, scatter, context)
    covariance = np.linalg.pinv(jac.T @ jac) * fit.cost * jac.shape[0] / effective_observations(data)
    return np.sqrt(np.maximum(np.diag(covariance), 0.0))


def refine_microslip(
    data: ConfigurationData,
    scatter: Scatter,
    context: FitContext,
    iwan_fit: FitResult,
    *,
    settings: DiscoverySettings = DiscoverySettings(),
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

"""The paper's models in the workflow: which modal coordinate, fits per configuration,
and the tables and curves the figures and the report read.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from workflow.measured.settings import AnalysisSettings
from workflow.models.settings import DiscoverySettings, ModelSettings

if TYPE_CHECKING:  # pandas is imported where tables are built: figures 7-8 draw without it
    import pandas as pd

__all__ = [
    "PAPER_DAHL",
    "PAPER_LUGRE",
    "SPECIMEN_FREQUENCY_TOLERANCE",
    "MIN_SEGMENTS_TO_FIT",
    "ModalCoordinate",
    "choose_modal_coordinate",
    "run_start_velocities",
    "averaged_fit_params",
    "averaged_start",
    "fit_configuration",
    "configuration_models_document",
    "fit_table",
    "model_curve_frames",
]


#: Paper figure 7 (Dahl) and figure 8 (LuGre) parameter values, in the paper's units.
PAPER_DAHL = {"sigma": (2 * np.pi) ** 2, "fc": 38.0}
PAPER_LUGRE = {
    "sigma0": (2 * np.pi) ** 2,
    "sigma1": 0.008 * np.pi,
    "alpha0": 38.0,
    "alpha1": 0.5 * 38.0,
    "alpha2": 0.008 * np.pi,
    "v0": 1.0,
    "vd": 1.0,
}

#: The specimen model stands for a campaign only if every measured mode lies this
#: close (relative) to the model's first-mode frequency.
SPECIMEN_FREQUENCY_TOLERANCE = 0.15

#: Fewer kept segments than this: the configuration's models are not fitted.
MIN_SEGMENTS_TO_FIT = 12

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ModalCoordinate:
    """How the modal coordinate xi of eq. 9 maps to the sensor.

    ``response_per_modal`` is sensor displacement per unit xi (in). With the
    specimen model, xi is the mass-normalised first mode and friction parameters
    are modal (force per unit xi); otherwise xi is the sensor displacement itself.
    """

    source: str  # "specimen model" or "sensor"
    response_per_modal: float
    model_frequency_hz: float | None


def choose_modal_coordinate(
    mode_hz_by_configuration: dict[str, float],
    areas_in2: dict[str, float | None],
) -> ModalCoordinate:
    """The specimen's FE mode when the campaign is plausibly the paper's specimen.

    That is: every configuration has a bearing area and its measured mode lies
    within :data:`SPECIMEN_FREQUENCY_TOLERANCE` of the model's first mode.
    Otherwise the modal coordinate is the sensor's displacement.
    """
    if mode_hz_by_configuration and all(areas_in2.get(name) is not None for name in mode_hz_by_configuration):
        from workflow.models import specimen

        first = specimen.first_mode()
        if all(
            abs(mode_hz / first.frequency_hz - 1) <= SPECIMEN_FREQUENCY_TOLERANCE
            for mode_hz in mode_hz_by_configuration.values()
        ):
            return ModalCoordinate(
                "specimen model", abs(float(first.accelerometer_participation)), float(first.frequency_hz)
            )
    return ModalCoordinate("sensor", 1.0, None)


def run_start_velocities(segments: pd.DataFrame) -> np.ndarray:
    """Starting velocity amplitude of each run, in/s: its largest kept segment."""
    return segments.groupby("run", sort=False)["velocity_amplitude_in_s"].max().to_numpy(float)


def averaged_fit_params(
    model: str, segments: pd.DataFrame, response_quantity: str, seed: int
) -> dict[str, float]:
    """The averaged model's fit to one configuration's segments, for a configuration the
    diagnosis did not fit (too few distinct amplitudes to validate models)."""
    from workflow.models.averaged import RESPONSE_ORDER
    from workflow.models.averaged_fit import FitContext, fit_model
    from workflow.models.configuration_data import mean_unbiased_damping, prepare_configuration, scatter_of

    data = prepare_configuration(
        segments, str(segments["configuration"].iloc[0]), RESPONSE_ORDER[response_quantity]
    )
    velocity = segments["velocity_amplitude_in_s"].to_numpy(float)
    context = FitContext(float(np.quantile(velocity, 0.9)))
    scatter = scatter_of(data)
    fit = fit_model(
        model, mean_unbiased_damping(data, scatter), scatter, context, settings=DiscoverySettings(seed=seed)
    )
    return fit.params


def averaged_start(model: str, params: dict[str, float]) -> np.ndarray:
    """Search point of the time-domain fit from the averaged model's fitted parameters.

    The averaged (describing-function) model of :mod:`workflow.models.averaged` has the
    same parameters as the time-domain search (stuck-joint frequency, the joint's
    share of the stiffness, the velocity at which the joint slips, zeta0; LuGre's
    stiction ratio and Stribeck velocity) and fits in seconds, so its optimum is a
    good start for the expensive time-domain refinement. The diagnosis fits it for
    every configuration (``results/interim/diagnosis``); the paper-model fits start
    from that fit rather than fitting it again.
    """
    p = params
    point = [
        p["f_lin_hz"],
        np.log10(p["joint_stiffness_fraction"]),
        np.log10(p["slip_velocity_in_s"]),
        np.log10(p["zeta0"]),
    ]
    if model == "lugre":
        stribeck = np.log10(p["stribeck_velocity_in_s"])
        point += [
            np.log10(max(p["stiction_ratio"], 1e-3)),
            stribeck,
            stribeck,
            p["micro_damping_ratio"] * p["zeta0"],
            0.0,
        ]
    return np.array(point)


def fit_configuration(
    segments: pd.DataFrame,
    *,
    models: tuple[str, ...],
    sample_rate_hz: float,
    record_duration_s: float,
    band_hz: tuple[float, float],
    response_quantity: str,
    coordinate: ModalCoordinate,
    analysis: AnalysisSettings,
    settings: ModelSettings,
    averaged_params: dict[str, dict[str, float]],
) -> dict:
    """Fit each friction model to one configuration's damping and frequency curves.

    ``analysis`` is the decay analysis the segments went through (the simulated
    ring-downs go through the same); ``settings`` the search and simulation settings;
    ``averaged_params`` each model's averaged-model fit (physical parameters), the
    start of its time-domain fit.

    Returns a JSON-ready document: per model its parameters, one-sigma
    uncertainties, fit-quality numbers and the simulated curves.
    """
    from workflow.models.fitting import RingdownFitContext, fit_friction_model, simulation_rate_hz

    context = RingdownFitContext(
        fs_hz=simulation_rate_hz(sample_rate_hz, band_hz),
        band_hz=tuple(band_hz),
        record_duration_s=record_duration_s,
        slip_per_modal=1.0,
        response_per_modal=coordinate.response_per_modal,
        response=response_quantity,
        analysis=analysis,
        steps_per_period=settings.steps_per_period,
    )
    document = {
        "modal_coordinate": coordinate.source,
        "response_per_modal_in": coordinate.response_per_modal,
        "models": {},
    }
    name = str(segments["configuration"].iloc[0])
    for offset, model in enumerate(models):
        started = time.perf_counter()
        log.info("%s %s: time-domain fit from the averaged model's optimum", name, model)
        result = fit_friction_model(
            model,
            segments["velocity_amplitude_in_s"].to_numpy(float),
            segments["zeta"].to_numpy(float),
            segments["frequency_hz"].to_numpy(float),
            segments["run"].to_numpy(str),
            run_start_velocities(segments),
            context,
            global_samples=settings.global_samples,
            local_starts=settings.local_starts,
            max_iterations=settings.local_iterations,
            seed=settings.seed + offset,
            initial_points=averaged_start(model, averaged_params[model]),
        )
        log.info(
            "%s %s: %d ring-downs simulated in %.1f s",
            name,
            model,
            result.n_simulations,
            time.perf_counter() - started,
        )
        document["models"][model] = {
            "params": {key: float(value) for key, value in result.params.items()},
            "uncertainties": {key: float(value) for key, value in result.uncertainties.items()},
            "cost": float(result.cost),
            "rms_log_zeta": float(result.rms_log_zeta),
            "rms_rel_frequency": float(result.rms_rel_frequency),
            "n_simulations": int(result.n_simulations),
            "curves": {key: np.asarray(value, float).tolist() for key, value in result.curves.items()},
        }
    return document


def configuration_models_document(
    segments: pd.DataFrame,
    configuration: str,
    modes: pd.DataFrame,
    bearing_areas_in2: dict[str, float | None],
    *,
    response_quantity: str,
    analysis: AnalysisSettings,
    settings: ModelSettings,
    averaged_params: dict[str, dict[str, float]] | None,
) -> dict:
    """One configuration's Dahl and LuGre time-domain fits as ``results/models`` holds them.

    Parameters
    ----------
    segments : DataFrame
        Kept segments of every configuration (the segments table).
    configuration : str
    modes : DataFrame
        The modes table indexed by configuration (mode, band, sample rate, record length).
    bearing_areas_in2 : dict
        Configuration -> bearing area, in² (None when not given): with the modes, they
        decide the modal coordinate (:func:`choose_modal_coordinate`).
    response_quantity : str
        The campaign's measured quantity.
    analysis, settings
        As :func:`fit_configuration`.
    averaged_params : dict or None
        Model -> the diagnosis's averaged fit (the start of each time-domain fit); None
        when the diagnosis skipped the configuration: the averaged models are fitted here.

    Returns
    -------
    dict
        :func:`fit_configuration`'s document, or ``models`` empty and ``skipped`` saying
        why when fewer than :data:`MIN_SEGMENTS_TO_FIT` segments are usable.
    """
    mine = segments[segments["configuration"] == configuration]
    if len(mine) < MIN_SEGMENTS_TO_FIT:
        return {
            "models": {},
            "skipped": f"only {len(mine)} usable segments "
            f"(at least {MIN_SEGMENTS_TO_FIT} needed to fit); see runs.parquet",
        }
    coordinate = choose_modal_coordinate(modes["mode_hz"].dropna().to_dict(), bearing_areas_in2)
    mode = modes.loc[configuration]
    models = ("dahl", "lugre")
    if averaged_params is None:
        averaged_params = {
            model: averaged_fit_params(model, mine, response_quantity, settings.seed) for model in models
        }
    return fit_configuration(
        mine,
        models=models,
        sample_rate_hz=float(mode["sample_rate_hz"]),
        record_duration_s=float(mode["record_duration_s"]),
        band_hz=(float(mode["band_low_hz"]), float(mode["band_high_hz"])),
        response_quantity=response_quantity,
        coordinate=coordinate,
        analysis=analysis,
        settings=settings,
        averaged_params=averaged_params,
    )


def fit_table(documents: dict[str, dict]) -> pd.DataFrame:
    """One row per configuration, model and parameter: value, uncertainty, fit quality."""
    import pandas as pd

    rows: list[dict] = []
    for configuration, document in documents.items():
        for model, fit in document["models"].items():
            for name, value in fit["params"].items():
                rows.append(
                    {
                        "configuration": configuration,
                        "model": model,
                        "parameter": name,
                        "value": value,
                        "std": fit["uncertainties"].get(name, np.nan),
                        "rms_log_zeta": fit["rms_log_zeta"],
                        "rms_rel_frequency": fit["rms_rel_frequency"],
                        "modal_coordinate": document["modal_coordinate"],
                    }
                )
    return pd.DataFrame(
        rows,
        columns=[
            "configuration",
            "model",
            "parameter",
            "value",
            "std",
            "rms_log_zeta",
            "rms_rel_frequency",
            "modal_coordinate",
        ],
    )


def model_curve_frames(document: dict) -> dict[str, pd.DataFrame]:
    """Model name -> simulated curves (velocity amplitude, zeta, frequency) for plotting."""
    import pandas as pd

    frames = {}
    for model, fit in document["models"].items():
        curves = fit["curves"]
        frame = pd.DataFrame(
            {
                "velocity_amplitude_in_s": curves["velocity_amplitude_in_s"],
                "zeta": curves["zeta"],
                "frequency_hz": curves["frequency_hz"],
            }
        ).sort_values("velocity_amplitude_in_s")
        frames[model] = frame
    return frames

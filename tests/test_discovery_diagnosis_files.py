"""The diagnosis one configuration at a time (rule diagnose_configuration, its interim
file) gives the document and residuals of the campaign diagnosed in one piece."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd

from tests.support.discovery import diagnose_with_details
from tests.test_discovery_synthetic import DAHL, FAST, synthetic_segments
from workflow.discovery.campaign import (
    campaign_document,
    campaign_fit_context,
    configuration_outcomes,
    residual_table,
)
from workflow.discovery.configuration import diagnose_configuration_segments
from workflow.discovery.diagnosis_files import (
    DiagnosedConfiguration,
    read_configuration_diagnosis,
    write_configuration_diagnosis,
)
from workflow.models.averaged import MODELS
from workflow.models.averaged_fit import FitContext, FitResult, model_residuals, to_coords
from workflow.models.settings import DiscoverySettings


def _campaign() -> pd.DataFrame:
    """Three configurations with areas, and one with too few segments to diagnose."""
    frames = [
        synthetic_segments(
            "dahl",
            {**DAHL, "slip_velocity_in_s": 1.5 * area**-0.8},
            seed=30 + i,
            n_runs=4,
            configuration=f"a{i}",
            area=area,
        )
        for i, area in enumerate([0.3, 0.7, 1.2])
    ]
    few = synthetic_segments("dahl", DAHL, seed=40, n_runs=1, configuration="few").head(5)
    return pd.concat([frames[0], few, *frames[1:]], ignore_index=True)


def test_configurations_diagnosed_apart_and_read_back_give_the_campaigns_document(tmp_path):
    segments = _campaign()
    whole, details = diagnose_with_details(segments, "fanout", settings=FAST)
    context = campaign_fit_context(segments)
    outcomes = []
    # written in reverse order: the document follows the segments table, not the jobs
    for name in ["absent", "a2", "a1", "few", "a0"]:
        rows = np.flatnonzero(segments["configuration"] == name)
        result = (
            diagnose_configuration_segments(segments, name, context, settings=FAST)
            if rows.size
            else "no kept segment"
        )
        outcome = DiagnosedConfiguration(
            name,
            int(rows[0]) if rows.size else -1,
            context.reference_velocity_in_s,
            None if isinstance(result, str) else result,
            result if isinstance(result, str) else "",
        )
        write_configuration_diagnosis(tmp_path / f"{name}.npz", outcome)
        outcomes.append(read_configuration_diagnosis(tmp_path / f"{name}.npz"))
    diagnoses, skipped = configuration_outcomes(outcomes)
    # a configuration with no segment (all its runs excluded) is listed, last, not dropped
    assert list(skipped) == ["few", "absent"]
    document = campaign_document(
        "fanout", FitContext(outcomes[0].reference_velocity_in_s), diagnoses, skipped
    )
    assert document["skipped_configurations"].pop("absent") == "no kept segment"
    assert json.dumps(document, sort_keys=False) == json.dumps(whole, sort_keys=False)
    assert document["across_configurations"]["applicable"]
    pd.testing.assert_frame_equal(residual_table(diagnoses), residual_table(details))


def test_the_interim_file_keeps_every_array_exactly(tmp_path):
    segments = synthetic_segments("dahl", DAHL, seed=3, n_runs=3)
    context = campaign_fit_context(segments)
    diagnosis = diagnose_configuration_segments(segments, "c", context, settings=FAST)
    write_configuration_diagnosis(tmp_path / "c.npz", DiagnosedConfiguration("c", 0, 1.0, diagnosis))
    back = read_configuration_diagnosis(tmp_path / "c.npz").diagnosis
    for model, fit in diagnosis.fits.items():
        assert np.array_equal(back.fits[model].coords, fit.coords)
        assert back.fits[model].params == fit.params and back.fits[model].cost == fit.cost
        for key, value in diagnosis.residuals[model].items():
            assert np.array_equal(back.residuals[model][key], value, equal_nan=True)
    for name in ("velocity_in_s", "zeta", "frequency_hz", "run_index", "fit_rms"):
        assert np.array_equal(getattr(back.data, name), getattr(diagnosis.data, name))
    assert back.data.run_names == diagnosis.data.run_names
    assert np.array_equal(back.scatter.noise_ln_zeta, diagnosis.scatter.noise_ln_zeta)
    assert back.resamples == diagnosis.resamples


def test_paper_fits_start_from_the_diagnosis_fits_no_worse_than_their_own():
    """The time-domain fits start from the diagnosis's averaged Dahl and LuGre fits
    instead of fitting them again: Dahl's is the very fit the paper-model rule made
    itself (same settings, context-free), LuGre's is started from Dahl as well and so
    fits at least as well."""
    from workflow.models.paper import averaged_fit_params

    segments = synthetic_segments("dahl", DAHL, seed=5, n_runs=4)
    settings = DiscoverySettings()
    diagnosis = diagnose_configuration_segments(
        segments, "c", campaign_fit_context(segments), settings=settings
    )
    assert (
        averaged_fit_params("dahl", segments, "acceleration", settings.seed) == diagnosis.fits["dahl"].params
    )
    own = averaged_fit_params("lugre", segments, "acceleration", settings.seed)
    data = diagnosis.data
    context = campaign_fit_context(segments)
    own_cost = model_residuals(
        FitResult("lugre", to_coords(MODELS["lugre"], own), own, np.nan),
        data,
        diagnosis.scatter,
        context,
    )
    assert diagnosis.fits["lugre"].cost <= np.mean(
        np.concatenate([own_cost["z_norm"], own_cost["f_norm"]]) ** 2
    ) * (1 + 1e-9)

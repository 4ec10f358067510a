"""Rule diagnose_configuration: one configuration's diagnosis (baselines, candidates,
verdict and its resamples), for the campaign's diagnose rule, then the paper's models
(Dahl, LuGre) fitted to its curves in the time domain from the diagnosis's averaged fits."""

import time

from workflow.discovery.campaign import campaign_fit_context
from workflow.discovery.configuration import diagnose_configuration_segments, record_starts
from workflow.discovery.diagnosis_files import DiagnosedConfiguration, write_configuration_diagnosis
from workflow.io.interim import read_campaign
from workflow.io.settings import DecaySettings, ModelSettings
from workflow.io.tables import read_table, write_json
from workflow.measured.runs import first_mode_and_channel, first_mode_rows
from workflow.models.averaged_fit import FitSettings
from workflow.models.paper import configuration_models_document
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "diagnose_configuration")
configuration = snakemake.wildcards.configuration
campaign = read_campaign(snakemake.input.campaign_settings)
# the first mode, seen by the first channel (docs/outputs.md)
segments = first_mode_and_channel(read_table(snakemake.input.segments), campaign.response.channel_names()[0])
decay = DecaySettings(**snakemake.params.decay)
# the reference velocity comes from every configuration's segments, not this one's
context = campaign_fit_context(segments)
rows = (segments["configuration"].astype(str) == configuration).to_numpy().nonzero()[0]
diagnosis, skipped = None, ""
if rows.size:
    started = time.perf_counter()
    log.info("%s: fitting the baselines and the candidate models to %d segments", configuration, rows.size)
    result = diagnose_configuration_segments(
        segments,
        configuration,
        context,
        response_quantity=campaign.response.quantity,
        settings=FitSettings(**snakemake.params.discovery),
        segment_cycles=decay.segment_cycles,
        record_start=record_starts(read_table(snakemake.input.runs), configuration),
    )
    if isinstance(result, str):
        skipped = result
        log.warning("%s: not diagnosed: %s", configuration, skipped)
    else:
        diagnosis = result
        for model, fit in diagnosis.fits.items():
            log.info("%s %s: in-sample rms %.3f scatter", configuration, model, fit.cost**0.5)
        log.info(
            "%s: %s (gain ratio %s) after %.1f s",
            configuration,
            diagnosis.document["cause"],
            diagnosis.document["gain"]["ratio"],
            time.perf_counter() - started,
        )
else:
    skipped = "no kept segment: every run excluded (runs.parquet) or every segment rejected (segments_rejected.parquet)"
    log.warning("%s: not diagnosed: %s", configuration, skipped)
write_configuration_diagnosis(
    snakemake.output.diagnosis,
    DiagnosedConfiguration(
        configuration,
        int(rows[0]) if rows.size else -1,
        context.reference_velocity_in_s,
        diagnosis,
        skipped,
    ),
)

document = configuration_models_document(
    segments,
    configuration,
    first_mode_rows(read_table(snakemake.input.modes)).set_index("configuration"),
    {name: spec.bearing_area_in2 for name, spec in campaign.configurations.items()},
    response_quantity=campaign.response.quantity,
    analysis=decay,
    settings=ModelSettings(**snakemake.params.models),
    averaged_params=None
    if diagnosis is None
    else {model: diagnosis.fits[model].params for model in ("dahl", "lugre")},
)
if "skipped" in document:
    # a configuration whose runs were all excluded: the others still get their fits
    log.warning("%s: models not fitted: %s", configuration, document["skipped"])
for model, fit in document["models"].items():
    log.info(
        "%s %s: rms ln zeta %.3f, rms rel f %.2e, %d ring-downs, %s",
        configuration,
        model,
        fit["rms_log_zeta"],
        fit["rms_rel_frequency"],
        fit["n_simulations"],
        fit["params"],
    )
write_json(snakemake.output.models, {"configuration": configuration, **document})

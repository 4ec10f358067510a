"""Rule diagnose_configuration: one configuration's diagnosis (baselines, candidates,
verdict and its resamples), for the campaign's diagnose rule, then the paper's models
(Dahl, LuGre) fitted to its curves in the time domain from the diagnosis's averaged fits."""

import time

from workflow.discovery.diagnosis_files import write_configuration_diagnosis
from workflow.discovery.modes import diagnosed_outcome
from workflow.io.interim import read_campaign
from workflow.io.tables import read_table, write_json
from workflow.measured.campaign_tables import (
    first_mode_and_channel,
    first_mode_rows,
    paper_channel,
    recorded_quantity,
)
from workflow.measured.settings import AnalysisSettings
from workflow.models.paper import configuration_models_document
from workflow.models.settings import DiscoverySettings, ModelSettings
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "diagnose_configuration")
configuration = snakemake.wildcards.configuration
campaign = read_campaign(snakemake.input.campaign_settings)
# the first mode, seen by the first channel listed that the runs kept (docs/outputs.md)
segments = read_table(snakemake.input.segments)
channel = paper_channel(segments, campaign.response.channel_names())
segments = first_mode_and_channel(segments, channel)
if channel != campaign.response.channel_names()[0]:
    log.info("the paper's models read channel %r: the channels listed before it were left out", channel)
decay = AnalysisSettings(**snakemake.params.analysis)
started = time.perf_counter()
outcome = diagnosed_outcome(
    segments,
    read_table(snakemake.input.runs),
    configuration,
    settings=DiscoverySettings(**snakemake.params.discovery),
    segment_cycles=decay.segment_cycles,
    segment_overlap=decay.segment_overlap,
)
diagnosis = outcome.diagnosis
if diagnosis is None:
    log.warning("%s: not diagnosed: %s", configuration, outcome.skipped)
else:
    for model, fit in diagnosis.fits.items():
        log.info("%s %s: in-sample rms %.3f scatter", configuration, model, fit.cost**0.5)
    log.info(
        "%s: %s (gain ratio %s) after %.1f s",
        configuration,
        diagnosis.document["cause"],
        diagnosis.document["gain"]["ratio"],
        time.perf_counter() - started,
    )
write_configuration_diagnosis(snakemake.output.diagnosis, outcome)

document = configuration_models_document(
    segments,
    configuration,
    first_mode_rows(read_table(snakemake.input.modes)).set_index("configuration"),
    campaign.bearing_areas_in2(),
    response_quantity=recorded_quantity(segments, campaign.response.quantity or "acceleration"),
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

"""Rule diagnose_configuration: one configuration's diagnosis (baselines, candidates,
verdict and its resamples), for the campaign's diagnose rule and the paper-model fits."""

import time

from workflow.discovery.diagnosis import (
    FitSettings,
    campaign_fit_context,
    diagnose_configuration_segments,
    record_starts,
)
from workflow.io.interim import DiagnosedConfiguration, read_campaign, write_configuration_diagnosis
from workflow.io.settings import DecaySettings
from workflow.io.tables import read_table
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "diagnose_configuration")
configuration = snakemake.wildcards.configuration
campaign = read_campaign(snakemake.input.campaign_settings)
segments = read_table(snakemake.input.segments)
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
        segment_cycles=DecaySettings(**snakemake.params.decay).segment_cycles,
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
    log.info("%s: no segments: left out of the diagnosis", configuration)
write_configuration_diagnosis(
    snakemake.output[0],
    DiagnosedConfiguration(
        configuration,
        int(rows[0]) if rows.size else -1,
        context.reference_velocity_in_s,
        diagnosis,
        skipped,
    ),
)

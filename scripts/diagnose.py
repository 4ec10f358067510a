"""Rule diagnose: results/diagnosis.json and the residuals behind it, from every
configuration's diagnosis; then, from those two files, the baseline and extended model
residuals of every configuration, the candidate comparison and the held-out area
prediction."""

import json
from pathlib import Path

from workflow.discovery.campaign import campaign_document, configuration_outcomes, residual_table
from workflow.discovery.diagnosis_files import read_configuration_diagnosis
from workflow.io.interim import read_campaign
from workflow.io.tables import read_table, write_json, write_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.models.averaged_fit import FitContext
from workflow.outputs import discovery_figures, figures
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "diagnose")
campaign = read_campaign(snakemake.input.campaign_settings)
outcomes = [read_configuration_diagnosis(path) for path in snakemake.input.configurations]
diagnoses, skipped = configuration_outcomes(outcomes)
context = FitContext(outcomes[0].reference_velocity_in_s)
document = campaign_document(campaign.name, context, diagnoses, skipped)
units = UNIT_SYSTEMS[snakemake.params.units]
write_table(residual_table(diagnoses), snakemake.output.residuals, unit_system=units)
write_json(snakemake.output.diagnosis, document)
log.info("campaign verdict: %s", document["cause"])
for name, entry in document["configurations"].items():
    log.info(
        "%s: %s (gain ratio %s) - %s", name, entry["cause"], entry["gain"]["ratio"], entry["discrepancy"]
    )

# the figures from the files as written (as any later reader sees them)
document = json.loads(Path(snakemake.output.diagnosis).read_text())
residuals = read_table(snakemake.output.residuals)
for configuration, path in zip(
    snakemake.params.configurations, snakemake.output.residual_figures, strict=True
):
    figures.save(discovery_figures.residuals_figure(residuals, configuration, document, units=units), path)
figures.save(discovery_figures.candidates_figure(document), snakemake.output.candidates)
figures.save(discovery_figures.heldout_figure(document, units=units), snakemake.output.heldout)

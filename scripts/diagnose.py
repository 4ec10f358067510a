"""Rule diagnose: results/diagnosis.json and the residuals behind it, from every
configuration's diagnosis."""

from workflow.discovery.campaign import campaign_document, configuration_outcomes, residual_table
from workflow.discovery.diagnosis_files import read_configuration_diagnosis
from workflow.io.interim import read_campaign
from workflow.io.tables import write_json, write_table
from workflow.models.averaged_fit import FitContext
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "diagnose")
campaign = read_campaign(snakemake.input.campaign_settings)
outcomes = [read_configuration_diagnosis(path) for path in snakemake.input.configurations]
diagnoses, skipped = configuration_outcomes(outcomes)
context = FitContext(outcomes[0].reference_velocity_in_s)
document = campaign_document(campaign.name, context, diagnoses, skipped)
write_table(residual_table(diagnoses), snakemake.output.residuals)
write_json(snakemake.output.diagnosis, document)
log.info("campaign verdict: %s", document["cause"])
for name, entry in document["configurations"].items():
    log.info(
        "%s: %s (gain ratio %s) - %s", name, entry["cause"], entry["gain"]["ratio"], entry["discrepancy"]
    )

"""Rule diagnose: results/diagnosis.json and the residuals behind it."""

from workflow.discovery.diagnosis import FitSettings, diagnose_campaign, residual_table
from workflow.io.interim import read_campaign
from workflow.io.settings import DecaySettings
from workflow.io.tables import read_table, write_json, write_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "diagnose")
campaign = read_campaign(snakemake.input.campaign_settings)
segments = read_table(snakemake.input.segments)
document, details = diagnose_campaign(
    segments,
    campaign.name,
    response_quantity=campaign.response.quantity,
    settings=FitSettings(**snakemake.params.discovery),
    segment_cycles=DecaySettings(**snakemake.params.decay).segment_cycles,
    runs=read_table(snakemake.input.runs),
    return_details=True,
)
write_table(
    residual_table(details), snakemake.output.residuals, unit_system=UNIT_SYSTEMS[snakemake.params.units]
)
write_json(snakemake.output.diagnosis, document)
log.info("campaign verdict: %s", document["cause"])
for name, entry in document["configurations"].items():
    log.info(
        "%s: %s (gain ratio %s) - %s", name, entry["cause"], entry["gain"]["ratio"], entry["discrepancy"]
    )

"""Rule diagnose: results/diagnosis.json and the residuals behind it."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow.campaign import read_validated_campaign
from workflow.discovery import FitSettings, diagnose_campaign, residual_table
from workflow.logs import setup_script_logging
from workflow.tables import read_table, write_json, write_table

log = setup_script_logging(snakemake.log[0], "diagnose")
campaign = read_validated_campaign(snakemake.input.campaign_settings)
segments = read_table(snakemake.input.segments)
document, details = diagnose_campaign(
    segments,
    campaign.name,
    response_quantity=campaign.response.quantity,
    settings=FitSettings(**snakemake.params.discovery),
    segment_cycles=snakemake.params.segment_cycles,
    return_details=True,
)
write_table(residual_table(details), snakemake.output.residuals)
write_json(snakemake.output.diagnosis, document)
log.info("campaign verdict: %s", document["cause"])
for name, entry in document["configurations"].items():
    log.info("%s: %s (gain ratio %s) - %s", name, entry["cause"], entry["gain"]["ratio"], entry["discrepancy"])

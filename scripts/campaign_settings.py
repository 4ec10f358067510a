"""Rule campaign_settings: campaign.yaml validated once, as JSON for every later job
(which then needs neither PyYAML nor pydantic)."""

from pathlib import Path

from workflow.io.campaign import load_campaign
from workflow.io.interim import write_campaign
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "campaign_settings")
campaign = load_campaign(Path(snakemake.input.campaign_yaml).parent)
write_campaign(snakemake.output[0], campaign)
log.info("campaign %s: %d configurations", campaign.name, len(campaign.configurations))

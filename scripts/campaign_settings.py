"""Rule campaign_settings: campaign.yaml validated once, as JSON for every later job
(which then needs neither PyYAML nor pydantic)."""

from pathlib import Path

from workflow.io.campaign import campaign_to_dict, load_campaign
from workflow.io.tables import write_json
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "campaign_settings")
campaign = load_campaign(Path(snakemake.input.campaign_yaml).parent)
write_json(snakemake.output[0], campaign_to_dict(campaign))
log.info("campaign %s: %d configurations", campaign.name, len(campaign.configurations))

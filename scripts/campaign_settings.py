"""Rule campaign_settings: campaign.yaml validated once, as JSON for every later job
(which then needs neither PyYAML nor pydantic)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow.campaign import campaign_to_dict, load_campaign
from workflow.logs import setup_script_logging
from workflow.tables import write_json

log = setup_script_logging(snakemake.log[0], "campaign_settings")
campaign = load_campaign(Path(snakemake.input.campaign_yaml).parent)
write_json(snakemake.output[0], campaign_to_dict(campaign))
log.info("campaign %s: %d configurations", campaign.name, len(campaign.configurations))

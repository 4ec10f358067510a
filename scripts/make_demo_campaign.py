"""Rule demo_campaign: the built-in campaign, measured in the virtual lab."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow.logs import setup_script_logging
from workflow.virtual_lab import generate_campaign

log = setup_script_logging(snakemake.log[0], "demo_campaign")
out_dir = Path(snakemake.output.campaign_yaml).parent
truth = generate_campaign(
    out_dir,
    seed=snakemake.params.seed,
    runs_per_configuration=snakemake.params.runs_per_configuration,
)
log.info("demo campaign %s: %d configurations, truth beside it", out_dir, len(truth["configurations"]))

"""Rule demo_campaign: the built-in campaign, measured in the virtual lab."""

from pathlib import Path

from workflow.lab.campaigns import generate_campaign
from workflow.lab.settings import LabSettings
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "demo_campaign")
out_dir = Path(snakemake.output.campaign_yaml).parent
truth = generate_campaign(
    out_dir,
    seed=snakemake.params.seed,
    runs_per_configuration=snakemake.params.runs_per_configuration,
    settings=LabSettings(
        frequency_spread=snakemake.params.frequency_spread,
        damping_spread=snakemake.params.damping_spread,
        slip_force_spread=snakemake.params.slip_force_spread,
    ),
)
log.info("demo campaign %s: %d configurations, truth beside it", out_dir, len(truth["configurations"]))

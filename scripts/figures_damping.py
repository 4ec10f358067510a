"""Rule figures_damping: paper figures 10-12 (damping vs velocity amplitude, one per
configuration) and paper figure 13 (damping fits against bearing area)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow import figures
from workflow.campaign import read_validated_campaign
from workflow.logs import setup_script_logging
from workflow.tables import read_table

log = setup_script_logging(snakemake.log[0], "figures_damping")
segments = read_table(snakemake.input.segments)
curves = read_table(snakemake.input.curves)
for configuration, path in zip(snakemake.params.configurations, snakemake.output.damping, strict=True):
    mine = segments[segments["configuration"] == configuration]
    figure = figures.damping_vs_amplitude(
        mine,
        title=f"{configuration}: local equivalent damping vs velocity amplitude ({mine['run'].nunique()} runs)",
        curve=curves[curves["configuration"] == configuration],
    )
    figures.save(figure, path)
    log.info("%s: %d segments plotted", configuration, len(mine))
campaign = read_validated_campaign(snakemake.input.campaign_settings)
figure = figures.area_fits(
    curves,
    read_table(snakemake.input.area),
    title=f"{campaign.name}: damping vs velocity amplitude and bearing area",
)
figures.save(figure, snakemake.output.area)

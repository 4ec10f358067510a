"""Rule figures_damping: paper figures 10-12 (damping vs velocity amplitude, one per
configuration) and paper figure 13 (damping fits against bearing area)."""

from workflow.io.interim import read_campaign
from workflow.io.tables import read_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.outputs import figures
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "figures_damping")
units = UNIT_SYSTEMS[snakemake.params.units]
segments = read_table(snakemake.input.segments)
curves = read_table(snakemake.input.curves)
for configuration, path in zip(snakemake.params.configurations, snakemake.output.damping, strict=True):
    mine = segments[segments["configuration"] == configuration]
    figure = figures.damping_vs_amplitude(
        mine,
        title=f"{configuration}: local equivalent damping vs velocity amplitude ({mine['run'].nunique()} runs)",
        curve=curves[curves["configuration"] == configuration],
        units=units,
    )
    figures.save(figure, path)
    log.info("%s: %d segments plotted", configuration, len(mine))
campaign = read_campaign(snakemake.input.campaign_settings)
figure = figures.area_fits(
    curves,
    read_table(snakemake.input.area),
    title=f"{campaign.name}: damping vs velocity amplitude and bearing area",
    units=units,
)
figures.save(figure, snakemake.output.area)

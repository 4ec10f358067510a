"""Rule figures_backbone: damped frequency vs velocity amplitude of every configuration."""

from workflow.io.tables import read_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.outputs import figures
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "figures_backbone")
segments = read_table(snakemake.input.segments)
for configuration, path in zip(snakemake.params.configurations, snakemake.output.backbones, strict=True):
    mine = segments[segments["configuration"] == configuration]
    figure = figures.frequency_vs_amplitude(
        mine,
        title=f"{configuration}: backbone (frequency vs velocity amplitude)",
        units=UNIT_SYSTEMS[snakemake.params.units],
    )
    figures.save(figure, path)
    log.info("%s: %d segments plotted", configuration, len(mine))

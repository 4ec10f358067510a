"""Rule figure_damping: paper figures 10-12, damping vs velocity amplitude of one configuration."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow import figures
from workflow.logs import setup_script_logging
from workflow.tables import read_table

log = setup_script_logging(snakemake.log[0], "figure_damping")
configuration = snakemake.wildcards.configuration
segments = read_table(snakemake.input.segments)
curves = read_table(snakemake.input.curves)
mine = segments[segments["configuration"] == configuration]
curve = curves[curves["configuration"] == configuration]
figure = figures.damping_vs_amplitude(
    mine,
    title=f"{configuration}: local equivalent damping vs velocity amplitude ({mine['run'].nunique()} runs)",
    curve=curve,
)
figures.save(figure, snakemake.output.damping)
log.info("%d segments plotted", len(mine))

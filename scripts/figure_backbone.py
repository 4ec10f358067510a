"""Rule figure_backbone: damped frequency vs velocity amplitude of one configuration."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow import figures
from workflow.logs import setup_script_logging
from workflow.tables import read_table

log = setup_script_logging(snakemake.log[0], "figure_backbone")
configuration = snakemake.wildcards.configuration
segments = read_table(snakemake.input.segments)
mine = segments[segments["configuration"] == configuration]
figure = figures.frequency_vs_amplitude(
    mine, title=f"{configuration}: backbone (frequency vs velocity amplitude)"
)
figures.save(figure, snakemake.output[0])
log.info("%d segments plotted", len(mine))

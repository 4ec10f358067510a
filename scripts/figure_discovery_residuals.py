"""Rule figure_discovery_residuals: baseline and extended model residuals of one configuration."""

import json
from pathlib import Path

from workflow.io.tables import read_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.outputs import discovery_figures, figures
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "figure_discovery_residuals")
document = json.loads(Path(snakemake.input.diagnosis).read_text())
residuals = read_table(snakemake.input.residuals)
figure = discovery_figures.residuals_figure(
    residuals, snakemake.wildcards.configuration, document, units=UNIT_SYSTEMS[snakemake.params.units]
)
figures.save(figure, snakemake.output[0])

"""Rule figures_discovery: baseline and extended model residuals of every configuration,
the candidate comparison and the held-out area prediction."""

import json
from pathlib import Path

from workflow.io.tables import read_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.outputs import discovery_figures, figures
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "figures_discovery")
document = json.loads(Path(snakemake.input.diagnosis).read_text())
residuals = read_table(snakemake.input.residuals)
units = UNIT_SYSTEMS[snakemake.params.units]
for configuration, path in zip(snakemake.params.configurations, snakemake.output.residuals, strict=True):
    figures.save(discovery_figures.residuals_figure(residuals, configuration, document, units=units), path)
figures.save(discovery_figures.candidates_figure(document), snakemake.output.candidates)
figures.save(discovery_figures.heldout_figure(document, units=units), snakemake.output.heldout)

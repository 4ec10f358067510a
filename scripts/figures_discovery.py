"""Rule figures_discovery: from results/diagnosis.json and its residual table, the
baseline and extended model residuals of every configuration, the candidate comparison
and the held-out area prediction, in config units."""

import json
from pathlib import Path

from workflow.io.tables import read_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.outputs import discovery_figures, figures
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "figures_discovery")
units = UNIT_SYSTEMS[snakemake.params.units]
document = json.loads(Path(snakemake.input.diagnosis).read_text())
residuals = read_table(snakemake.input.residuals)
for configuration, path in zip(
    snakemake.params.configurations, snakemake.output.residual_figures, strict=True
):
    figures.save(discovery_figures.residuals_figure(residuals, configuration, document, units=units), path)
figures.save(discovery_figures.candidates_figure(document), snakemake.output.candidates)
figures.save(discovery_figures.heldout_figure(document, units=units), snakemake.output.heldout)
log.info(
    "%d residual figures, the candidates and the held-out prediction", len(snakemake.output.residual_figures)
)

"""Rule figure_discovery_summary: candidate comparison and held-out area prediction."""

import json
from pathlib import Path

from workflow.io.units import UNIT_SYSTEMS
from workflow.outputs import discovery_figures, figures
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "figure_discovery_summary")
document = json.loads(Path(snakemake.input.diagnosis).read_text())
figures.save(discovery_figures.candidates_figure(document), snakemake.output.candidates)
figures.save(
    discovery_figures.heldout_figure(document, units=UNIT_SYSTEMS[snakemake.params.units]),
    snakemake.output.heldout,
)

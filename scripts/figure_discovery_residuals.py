"""Rule figure_discovery_residuals: baseline and extended model residuals of one configuration."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow import discovery_figures, figures
from workflow.logs import setup_script_logging
from workflow.tables import read_table

log = setup_script_logging(snakemake.log[0], "figure_discovery_residuals")
document = json.loads(Path(snakemake.input.diagnosis).read_text())
residuals = read_table(snakemake.input.residuals)
figure = discovery_figures.residuals_figure(residuals, snakemake.wildcards.configuration, document)
figures.save(figure, snakemake.output[0])

"""Rule model_table: fitted friction-model parameters of every configuration, one table."""

import json
from pathlib import Path

from workflow.io.tables import write_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.models.paper import fit_table
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "model_table")
documents = {}
for path in snakemake.input:
    document = json.loads(Path(path).read_text())
    documents[document["configuration"]] = document
write_table(fit_table(documents), snakemake.output[0], unit_system=UNIT_SYSTEMS[snakemake.params.units])

"""Rule model_table: fitted friction-model parameters of every configuration, one table."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow.logs import setup_script_logging
from workflow.modelling import fit_table
from workflow.tables import write_table

log = setup_script_logging(snakemake.log[0], "model_table")
documents = {}
for path in snakemake.input:
    document = json.loads(Path(path).read_text())
    documents[document["configuration"]] = document
write_table(fit_table(documents), snakemake.output[0])

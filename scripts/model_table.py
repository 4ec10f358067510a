"""Rule model_table: fitted friction-model parameters of every configuration, one table,
and the same as the report's readable HTML page."""

import json
from pathlib import Path

from workflow.io.tables import atomic_write_bytes, write_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.models.paper import fit_table
from workflow.outputs.report import model_fits_html
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "model_table")
documents = {}
for path in snakemake.input:
    document = json.loads(Path(path).read_text())
    documents[document["configuration"]] = document
fits = fit_table(documents)
write_table(fits, snakemake.output.table, unit_system=UNIT_SYSTEMS[snakemake.params.units])
atomic_write_bytes(snakemake.output.page, model_fits_html(fits).encode())
log.info("%d parameters of %d configurations", len(fits), fits["configuration"].nunique())

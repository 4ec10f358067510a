"""Rule run_summary: the verdict, the runs used and excluded, and where the report is
(results/summary.txt, printed at the end of the run by the Snakefile's onsuccess)."""

import json
from pathlib import Path

from workflow.io.tables import atomic_write_bytes, read_table
from workflow.outputs.summary import run_summary
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "run_summary")
document = json.loads(Path(snakemake.input.diagnosis).read_text())
text = run_summary(document, read_table(snakemake.input.runs))
atomic_write_bytes(snakemake.output[0], text.encode())
log.info("summary written: %d lines", text.count("\n"))

"""Rule report_model_fits: the Dahl and LuGre parameters as a readable HTML table."""

from workflow.io.tables import atomic_write_bytes, read_table
from workflow.outputs.report import model_fits_html
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "report_model_fits")
fits = read_table(snakemake.input[0])
atomic_write_bytes(snakemake.output[0], model_fits_html(fits).encode())
log.info("%d parameters of %d configurations", len(fits), fits["configuration"].nunique())

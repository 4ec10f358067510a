"""Rule collect_tables: the campaign's segments, runs and modes as Parquet tables."""

from workflow.io.escape import spreadsheet_text
from workflow.io.interim import read_campaign
from workflow.io.tables import atomic_write_bytes, write_table
from workflow.measured.campaign_tables import collect_tables
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "collect_tables")
campaign = read_campaign(snakemake.input.campaign_settings)
tables = collect_tables(
    segment_paths=snakemake.input.segments,
    quality_paths=snakemake.input.quality,
    status_paths=snakemake.input.status,
    mode_paths=snakemake.input.modes,
    campaign=campaign,
    excluded_paths=snakemake.params.excluded_paths,
)
response_unit = {"response_amplitude": tables["response_unit"]}
for name in ("segments", "rejected", "runs", "quality", "modes"):
    write_table(tables[name], snakemake.output[name], units=response_unit)
runs = tables["runs"]
# beside the Parquet: the table of runs opens in any spreadsheet or text editor; its
# text cells (run names, paths, reasons) through spreadsheet_text, so none is a formula
text_columns = runs.select_dtypes(include=["object", "string"]).columns
shown = runs.assign(**{column: runs[column].map(spreadsheet_text) for column in text_columns})
atomic_write_bytes(snakemake.output.runs_csv, shown.to_csv(index=False).encode())
log.info(
    "%d runs used, %d excluded; %d segments kept",
    int((runs["status"] == "used").sum()),
    int((runs["status"] == "excluded").sum()),
    len(tables["segments"]),
)
for row in runs[runs["status"] == "excluded"].itertuples():
    log.warning("excluded %s/%s: %s", row.configuration, row.run, row.reason)

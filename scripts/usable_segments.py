"""Rule usable_segments: the campaign's kept segments, or a stop that says why there are
none (which runs, why, what to change), before any fit, figure or diagnosis is tried."""

from pathlib import Path

from workflow.io.tables import atomic_write_bytes
from workflow.measured.campaign_tables import nothing_analysed_in_tables
from workflow.runtime.logs import ScriptStop, setup_script_logging

log = setup_script_logging(snakemake.log[0], "usable_segments")
message = nothing_analysed_in_tables(snakemake.input.runs, snakemake.input.segments, snakemake.input.rejected)
if message is not None:
    raise ScriptStop(message)
atomic_write_bytes(snakemake.output[0], Path(snakemake.input.segments).read_bytes())

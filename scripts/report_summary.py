"""Rule report_summary: the report's first page (the verdict) and its tables as HTML, then
the run's summary: the verdict, the runs used and excluded, and where the report is
(results/summary.txt, printed at the end of the run by the Snakefile's onsuccess)."""

import json
from pathlib import Path

from workflow.io.tables import atomic_write_bytes, read_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.measured.campaign_tables import first_mode_and_channel, paper_channel
from workflow.outputs import landing_page, report_tables, verdict_page
from workflow.outputs.summary import run_summary
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "report_summary")
document = json.loads(Path(snakemake.input.diagnosis).read_text())
runs = read_table(snakemake.input.runs)
# the paper's tables are the first mode's, on the paper's channel (docs/outputs.md)
segments = read_table(snakemake.input.segments)
channel = paper_channel(segments, snakemake.params.channels)
hypotheses = first_mode_and_channel(read_table(snakemake.input.hypotheses), channel)
segments = first_mode_and_channel(segments, channel)
damping_fits = first_mode_and_channel(read_table(snakemake.input.damping_fits), channel)
areas = dict(zip(damping_fits["configuration"], damping_fits["bearing_area_in2"]))
units = UNIT_SYSTEMS[snakemake.params.units]

pages = {
    "verdict": verdict_page.verdict_html(
        document,
        runs=runs,
        hypotheses=hypotheses,
        areas=areas,
        segments=segments,
        units=units,
    ),
    "hypotheses": report_tables.hypotheses_html(hypotheses, units),
    "runs": report_tables.runs_html(runs),
    "rejected": report_tables.rejected_segments_html(read_table(snakemake.input.rejected)),
    "quality": report_tables.quality_html(read_table(snakemake.input.quality)),
    "damping_fits": report_tables.damping_fits_html(damping_fits),
    "candidates": report_tables.candidates_html(document),
}
for name, text in pages.items():
    atomic_write_bytes(snakemake.output[name], text.encode())
# the report's first page: the verdict, then report/workflow.rst (see rules/report.smk)
landing = landing_page.landing_rst(
    landing_page.verdict_rst(document, runs=runs, hypotheses=hypotheses, segments=segments, units=units),
    Path(snakemake.input.description).read_text(),
)
atomic_write_bytes(snakemake.output.landing, landing.encode())
log.info("verdict %s; %d pages written", document.get("cause"), len(pages))
text = run_summary(document, runs)
atomic_write_bytes(snakemake.output.summary, text.encode())
log.info("summary written: %d lines", text.count("\n"))

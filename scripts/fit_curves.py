"""Rule fit_curves: damping polynomial fits, bootstrap bands, hypotheses, area fits."""

from workflow.io.interim import read_campaign
from workflow.io.tables import read_table, write_table
from workflow.measured.campaign_tables import fit_damping_curves
from workflow.measured.settings import DampingFitSettings
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "fit_curves")
campaign = read_campaign(snakemake.input.campaign_settings)
areas = campaign.bearing_areas_in2()
segments = read_table(snakemake.input.segments)
tables = fit_damping_curves(segments, areas, DampingFitSettings(**snakemake.params.fits))
for name in ("fits", "curves", "hypotheses", "area"):
    write_table(tables[name], snakemake.output[name])
for row in tables["hypotheses"].itertuples():
    log.info(
        "%s [%s]: %s (%.4g, CI %.4g..%.4g)",
        row.hypothesis,
        row.configuration,
        row.verdict,
        row.estimate,
        row.ci_low,
        row.ci_high,
    )

"""Rule analyse_runs: band-pass, envelope and segmented log decrement of a group of
runs of one configuration (``runs_per_job`` of them), with their quality checks.

Each run is read, checked and analysed on its own: a run that cannot be used is
excluded with its reason and the others go on."""

from pathlib import Path

from workflow.io.interim import read_campaign, read_mode, write_run_statuses
from workflow.io.tables import concatenate_columns, write_columns
from workflow.measured.runs import analyse_run_file
from workflow.measured.settings import AnalysisSettings, QualitySettings
from workflow.runtime.logs import ScriptStop, setup_script_logging

log = setup_script_logging(snakemake.log[0], "analyse_runs")
campaign_dir = Path(snakemake.params.campaign)
campaign = read_campaign(snakemake.input.campaign_settings)
mode = read_mode(snakemake.input.mode)
decay_settings = AnalysisSettings(**snakemake.params.analysis)
quality_settings = QualitySettings(**snakemake.params.quality)

results = []
for run_file in snakemake.input.runs:
    run_path = Path(run_file).relative_to(campaign_dir).as_posix()
    result = analyse_run_file(
        campaign_dir,
        run_path,
        configuration=snakemake.wildcards.configuration,
        campaign=campaign,
        mode=mode,
        quality_settings=quality_settings,
        decay_settings=decay_settings,
    )
    if result.status["status"] == "excluded":
        log.warning("excluded %s", result.status["reason"])
        if snakemake.params.strict:
            raise ScriptStop(f"strict mode: run excluded: {result.status['reason']}")
    else:
        kept = result.segments["kept"]
        log.info("%s: %d segments kept of %d", run_path, int(kept.sum()), len(kept))
    results.append(result)

write_columns(snakemake.output.segments, concatenate_columns([result.segments for result in results]))
write_columns(snakemake.output.quality, concatenate_columns([result.quality for result in results]))
write_run_statuses(snakemake.output.status, [result.status for result in results])

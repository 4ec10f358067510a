"""Rule analyse_runs: band-pass, envelope and segmented log decrement of a group of
runs of one configuration (``runs_per_job`` of them), with their quality checks; the
first group is rule identify_mode's.

Each run is read, checked and analysed on its own: a run that cannot be used is
excluded with its reason and the others go on."""

from pathlib import Path

from workflow.io.interim import read_campaign, read_mode
from workflow.measured.runs import analyse_run_group, first_exclusion, write_run_group
from workflow.measured.settings import AnalysisSettings, QualitySettings
from workflow.runtime.logs import ScriptStop, setup_script_logging

log = setup_script_logging(snakemake.log[0], "analyse_runs")
campaign_dir = Path(snakemake.params.campaign)
results = analyse_run_group(
    campaign_dir,
    [Path(path).relative_to(campaign_dir).as_posix() for path in snakemake.input.runs],
    configuration=snakemake.wildcards.configuration,
    campaign=read_campaign(snakemake.input.campaign_settings),
    mode=read_mode(snakemake.input.mode),
    quality_settings=QualitySettings(**snakemake.params.quality),
    decay_settings=AnalysisSettings(**snakemake.params.analysis),
)
if snakemake.params.strict and (reason := first_exclusion(results)):
    raise ScriptStop(f"strict mode: run excluded: {reason}")
write_run_group(snakemake.output.segments, snakemake.output.quality, snakemake.output.status, results)

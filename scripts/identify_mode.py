"""Rule identify_mode: the modes and analysis bands of one configuration, then the
analysis of its first group of runs (rule analyse_runs's work) with the runs already
read for the mode search, so that no file of that group is read twice."""

from pathlib import Path

from workflow.io.interim import read_campaign, write_mode
from workflow.measured.mode_identification import identify_configuration_mode
from workflow.measured.runs import analyse_run_group, first_exclusion, read_runs, write_run_group
from workflow.measured.settings import AnalysisSettings, QualitySettings
from workflow.runtime.logs import ScriptStop, setup_script_logging

log = setup_script_logging(snakemake.log[0], "identify_mode")
configuration = snakemake.wildcards.configuration
campaign_dir = Path(snakemake.params.campaign)
campaign = read_campaign(snakemake.input.campaign_settings)
analysis = AnalysisSettings(**snakemake.params.analysis)
quality_settings = QualitySettings(**snakemake.params.quality)
run_paths = [Path(path).relative_to(campaign_dir).as_posix() for path in snakemake.input.runs]
reads = read_runs(campaign_dir, run_paths, campaign, quality_settings)
found = identify_configuration_mode(
    campaign_dir,
    run_paths,
    configuration=configuration,
    campaign=campaign,
    mode_search=analysis,
    quality_settings=quality_settings,
    reads=reads,
)
for run, problems in found.skipped_runs.items():
    log.warning("mode search skips %s: %s", run, "; ".join(problems))
if found.mode is None:
    # Every run of this configuration then gets excluded with this reason; the other
    # configurations go on.
    log.error(found.error)
else:
    log.info(
        "configuration %s: mode %.3f Hz (%s), band %s",
        configuration,
        found.mode.mode_hz,
        found.mode.method,
        found.mode.band_hz,
    )
write_mode(snakemake.output.mode, found)

first_group = [Path(path).relative_to(campaign_dir).as_posix() for path in snakemake.params.first_group]
results = analyse_run_group(
    campaign_dir,
    first_group,
    reads={path: reads[path] for path in first_group},
    configuration=configuration,
    campaign=campaign,
    mode=found,
    quality_settings=quality_settings,
    decay_settings=analysis,
)
if snakemake.params.strict and (reason := first_exclusion(results)):
    raise ScriptStop(f"strict mode: run excluded: {reason}")
write_run_group(snakemake.output.segments, snakemake.output.quality, snakemake.output.status, results)

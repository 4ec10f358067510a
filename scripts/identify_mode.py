"""Rule identify_mode: first-mode frequency and analysis band of one configuration."""

from pathlib import Path

from workflow.io.interim import read_campaign, write_mode
from workflow.measured.mode_identification import identify_configuration_mode
from workflow.measured.settings import AnalysisSettings, QualitySettings
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "identify_mode")
configuration = snakemake.wildcards.configuration
campaign_dir = Path(snakemake.params.campaign)
found = identify_configuration_mode(
    campaign_dir,
    [Path(path).relative_to(campaign_dir).as_posix() for path in snakemake.input.runs],
    configuration=configuration,
    campaign=read_campaign(snakemake.input.campaign_settings),
    mode_search=AnalysisSettings(**snakemake.params.analysis),
    quality_settings=QualitySettings(**snakemake.params.quality),
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
write_mode(snakemake.output[0], found)

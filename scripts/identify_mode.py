"""Rule identify_mode: first-mode frequency and analysis band of one configuration."""

from pathlib import Path

from workflow.io.campaign import list_runs, read_validated_campaign
from workflow.io.settings import QualitySettings
from workflow.io.tables import write_json
from workflow.measured.runs import analysis_window, identify_mode, read_and_check
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "identify_mode")
configuration = snakemake.wildcards.configuration
campaign_dir = Path(snakemake.params.campaign)
campaign = read_validated_campaign(snakemake.input.campaign_settings)
spec = campaign.configurations[configuration]
quality_settings = QualitySettings(**snakemake.params.quality)

records, windows, skipped = [], [], {}
for run_file in list_runs(campaign_dir, campaign):
    if run_file.configuration != configuration:
        continue
    record, problems = read_and_check(campaign_dir, run_file.path, campaign, quality_settings)
    if problems:
        skipped[run_file.run] = problems
        log.warning("mode search skips %s: %s", run_file.path, "; ".join(problems))
        continue
    records.append(record)
    windows.append(analysis_window(record, spec.window_s))

try:
    mode = identify_mode(
        records,
        windows=windows,
        campaign_mode_hz=campaign.mode_hz,
        campaign_band_hz=campaign.band_hz,
        band_half_width=snakemake.params.band_half_width,
        mode_search_hz=snakemake.params.mode_search_hz,
        mode_search_fraction=snakemake.params.mode_search_fraction,
        min_mode_prominence=quality_settings.min_mode_prominence,
    )
    document = {**mode.to_dict(), "skipped_runs": skipped}
    log.info(
        "configuration %s: mode %.3f Hz (%s), band %s", configuration, mode.mode_hz, mode.method, mode.band_hz
    )
except ValueError as error:
    # Every run of this configuration then gets excluded with this reason;
    # the other configurations go on.
    document = {
        "error": f"configuration {configuration}: first mode not found: {error}",
        "skipped_runs": skipped,
    }
    log.error(document["error"])
write_json(snakemake.output[0], document)

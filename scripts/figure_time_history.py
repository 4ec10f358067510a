"""Rule figure_time_history: paper figure 9 for the first used run of the first configuration."""

from dataclasses import asdict
from pathlib import Path

import numpy as np

from workflow.io.campaign import read_run
from workflow.io.interim import read_campaign
from workflow.io.settings import DecaySettings
from workflow.io.tables import read_table
from workflow.measured import decay
from workflow.measured.runs import analysis_window
from workflow.outputs import figures
from workflow.runtime.logs import ScriptStop, setup_script_logging

log = setup_script_logging(snakemake.log[0], "figure_time_history")
campaign_dir = Path(snakemake.params.campaign)
campaign = read_campaign(snakemake.input.campaign_settings)
configuration = snakemake.params.configuration
runs = read_table(snakemake.input.runs_table)
used = runs[(runs["configuration"] == configuration) & (runs["status"] == "used")]
if used.empty:
    # A configuration whose runs were all excluded must not take the figure down:
    # show the first used run of the next configuration (campaign.yaml order).
    all_used = runs[runs["status"] == "used"]
    if all_used.empty:
        raise ScriptStop("no usable run in the campaign to show (see runs.parquet)")
    log.warning(
        "configuration %s has no usable run (see runs.parquet); figure 9 shows %s",
        configuration,
        all_used.iloc[0]["configuration"],
    )
    configuration = all_used.iloc[0]["configuration"]
    used = all_used[all_used["configuration"] == configuration]
modes = read_table(snakemake.input.modes).set_index("configuration")
figure_path = snakemake.output[0]
row = used.iloc[0]
record = read_run(campaign_dir, row["path"], campaign)
band_hz = (float(modes.loc[configuration, "band_low_hz"]), float(modes.loc[configuration, "band_high_hz"]))
start, stop = analysis_window(record, campaign.configurations[configuration].window_s)
result = decay.analyse_decay(
    record.response,
    record.sample_rate_hz,
    band_hz,
    mode_hz=float(modes.loc[configuration, "mode_hz"]),
    start_index=start if (start, stop) != (0, record.n_samples) else None,
    stop_index=stop,
    **asdict(DecaySettings(**snakemake.params.decay)),
)
time_s = np.arange(record.n_samples) / record.sample_rate_hz
figure = figures.time_history(
    time_s,
    record.response,
    result.filtered,
    result.envelope,
    response_label=f"{record.response_quantity} ({record.response_unit})",
    title=f"{configuration} / {row['run']}: unfiltered and filtered response",
    band_hz=band_hz,
    decay_start_s=result.start_index / record.sample_rate_hz,
)
figures.save(figure, figure_path)
log.info("figure 9 from %s", row["path"])

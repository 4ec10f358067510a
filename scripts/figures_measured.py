"""Rule figures_measured, on the paper's channel (the first listed that the runs kept):
paper figure 9 (the first used run of the first configuration), figures 10-12 (damping vs
velocity amplitude, one per configuration), figure 13 (damping fits against bearing area)
and the backbones (frequency vs velocity amplitude); then every mode on every channel."""

from pathlib import Path

import numpy as np

from workflow.discovery.wording import runs_words
from workflow.io.escape import plot_text
from workflow.io.interim import read_campaign
from workflow.io.run_files import read_run
from workflow.io.tables import read_table
from workflow.io.units import UNIT_SYSTEMS, response_in_units
from workflow.measured import decay
from workflow.measured.campaign_tables import first_mode_and_channel, first_mode_rows, paper_channel
from workflow.measured.runs import analysis_window
from workflow.measured.settings import AnalysisSettings
from workflow.outputs import figures
from workflow.runtime.logs import ScriptStop, setup_script_logging

log = setup_script_logging(snakemake.log[0], "figures_measured")
units = UNIT_SYSTEMS[snakemake.params.units]
campaign_dir = Path(snakemake.input.campaign_yaml).parent
campaign = read_campaign(snakemake.input.campaign_settings)
# the paper's figures: the first mode, from the paper's channel (docs/outputs.md)
all_segments = read_table(snakemake.input.segments)
channel = paper_channel(all_segments, campaign.response.channel_names())

# figure 9
configuration = snakemake.params.configurations[0]
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
modes = first_mode_rows(read_table(snakemake.input.modes)).set_index("configuration")
row = used.iloc[0]
record = read_run(campaign_dir, row["path"], campaign)
if channel in record.channel_names():  # a channel this file's unit refused: the first kept
    record = record.for_channel(channel)
band_hz = (float(modes.loc[configuration, "band_low_hz"]), float(modes.loc[configuration, "band_high_hz"]))
start, stop = analysis_window(record, campaign.configurations[configuration].window_s)
result = decay.analyse_decay(
    record.response,
    record.sample_rate_hz,
    band_hz,
    mode_hz=float(modes.loc[configuration, "mode_hz"]),
    start_index=start if (start, stop) != (0, record.n_samples) else None,
    stop_index=stop,
    **AnalysisSettings(**snakemake.params.analysis).decay_options(),
)
time_s = np.arange(record.n_samples) / record.sample_rate_hz
# in SI the record's unit (g, in/s, ...) is converted: one factor for all three curves
scale, shown_unit = response_in_units(1.0, record.response_quantity, record.response_unit, units)
figure = figures.time_history(
    time_s,
    scale * record.response,
    scale * result.filtered,
    scale * result.envelope,
    response_label=f"{plot_text(record.response_quantity)} ({plot_text(shown_unit)})",
    title=f"{plot_text(configuration)} / {plot_text(row['run'])}: unfiltered and filtered response",
    band_hz=band_hz,
    decay_start_s=result.start_index / record.sample_rate_hz,
)
figures.save(figure, snakemake.output.time_history)
log.info("figure 9 from %s", row["path"])

# figures 10-13
segments = first_mode_and_channel(all_segments, channel)
curves = first_mode_and_channel(read_table(snakemake.input.curves), channel)
for configuration, path in zip(snakemake.params.configurations, snakemake.output.damping, strict=True):
    mine = segments[segments["configuration"] == configuration]
    figure = figures.damping_vs_amplitude(
        mine,
        title=f"{plot_text(configuration)}: local equivalent damping vs velocity amplitude "
        f"({runs_words(mine['run'].nunique())})",
        curve=curves[curves["configuration"] == configuration],
        units=units,
    )
    figures.save(figure, path)
    log.info("%s: %d segments plotted", configuration, len(mine))
figure = figures.area_fits(
    curves,
    first_mode_and_channel(read_table(snakemake.input.area), channel),
    title=f"{plot_text(campaign.name)}: damping vs velocity amplitude and bearing area",
    units=units,
)
figures.save(figure, snakemake.output.area)

# the backbones
for configuration, path in zip(snakemake.params.configurations, snakemake.output.backbones, strict=True):
    mine = segments[segments["configuration"] == configuration]
    figure = figures.frequency_vs_amplitude(
        mine,
        title=f"{plot_text(configuration)}: backbone (frequency vs velocity amplitude)",
        units=units,
    )
    figures.save(figure, path)
    log.info("%s: backbone of %d segments plotted", configuration, len(mine))

# every mode on every channel (campaigns with several)
for path in snakemake.output.modes_channels:
    figure = figures.modes_and_channels(
        all_segments,
        title=f"{plot_text(campaign.name)}: damping and frequency of every mode, per channel",
        channels=snakemake.params.channels,
        units=units,
    )
    figures.save(figure, path)
    log.info("every mode and channel: %d segments plotted", len(all_segments))

"""Rules diagnose_modes and diagnose_joint: one configuration's diagnosis for every mode,
seen by one response channel (the first mode of the paper's channel is rule
diagnose_configuration's) or, with no channel given, by every channel at once (one joint
analysis), one file per mode, for the campaign's diagnose rule (workflow/discovery/modes.py)."""

from pathlib import Path

from workflow.discovery.diagnosis_files import write_configuration_diagnosis
from workflow.discovery.modes import diagnosed_outcome, joint_outcome
from workflow.io.interim import read_campaign
from workflow.io.tables import read_table
from workflow.measured.campaign_tables import paper_channel
from workflow.measured.settings import AnalysisSettings
from workflow.models.settings import DiscoverySettings
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], snakemake.rule)
configuration = snakemake.wildcards.configuration
channel = snakemake.params.channel
campaign = read_campaign(snakemake.input.campaign_settings)
segments = read_table(snakemake.input.segments)
diagnosed_by_configuration = channel is not None and channel == paper_channel(
    segments, campaign.response.channel_names()
)
segments = segments[
    segments["channel"].isin(campaign.response.channel_names() if channel is None else [channel])
]
runs = read_table(snakemake.input.runs)
decay = AnalysisSettings(**snakemake.params.analysis)
folder = Path(snakemake.output[0])
folder.mkdir(parents=True, exist_ok=True)
# numbered as the campaign's modes (rule diagnose's), not as those this channel kept: a
# sensor at a node of the first mode has the second as its first
modes_hz = sorted(read_table(snakemake.input.modes)["nominal_mode_hz"].dropna().unique())
for index, mode_hz in enumerate(modes_hz):
    if index == 0 and diagnosed_by_configuration:
        continue  # rule diagnose_configuration's
    seen = segments[segments["mode_hz"] == mode_hz]
    if seen.empty:
        continue  # left out of this mode
    outcome = (diagnosed_outcome if channel is not None else joint_outcome)(
        seen,
        runs,
        configuration,
        settings=DiscoverySettings(**snakemake.params.discovery),
        segment_cycles=decay.segment_cycles,
        segment_overlap=decay.segment_overlap,
    )
    verdict = outcome.skipped if outcome.diagnosis is None else outcome.diagnosis.document["cause"]
    seen_by = "every channel" if channel is None else f"channel {channel!r}"
    log.info("%s, mode %.6g Hz, %s: %s", configuration, mode_hz, seen_by, verdict)
    write_configuration_diagnosis(folder / f"{index:02d}.npz", outcome)

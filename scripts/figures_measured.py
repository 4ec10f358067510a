"""Rule figures_measured: paper figures 10-12 (damping vs velocity amplitude) and the
backbone of every configuration, and paper figure 13 (damping fits against bearing area)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow import figures
from workflow.campaign import read_validated_campaign
from workflow.logs import setup_script_logging
from workflow.tables import read_table

log = setup_script_logging(snakemake.log[0], "figures_measured")
segments = read_table(snakemake.input.segments)
curves = read_table(snakemake.input.curves)
outputs = zip(snakemake.params.configurations, snakemake.output.damping, snakemake.output.backbones, strict=True)
for configuration, damping_path, backbone_path in outputs:
    mine = segments[segments["configuration"] == configuration]
    curve = curves[curves["configuration"] == configuration]
    figure = figures.damping_vs_amplitude(
        mine,
        title=f"{configuration}: local equivalent damping vs velocity amplitude ({mine['run'].nunique()} runs)",
        curve=curve,
    )
    figures.save(figure, damping_path)
    figure = figures.frequency_vs_amplitude(
        mine, title=f"{configuration}: backbone (frequency vs velocity amplitude)"
    )
    figures.save(figure, backbone_path)
    log.info("%s: %d segments plotted", configuration, len(mine))
campaign = read_validated_campaign(snakemake.input.campaign_settings)
figure = figures.area_fits(
    curves,
    read_table(snakemake.input.area),
    title=f"{campaign.name}: damping vs velocity amplitude and bearing area",
)
figures.save(figure, snakemake.output.area)

"""Rule figure_area_fits: paper figure 13, damping fits against bearing area."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(snakemake.scriptdir).parent))

from workflow import figures
from workflow.campaign import load_campaign
from workflow.logs import setup_script_logging
from workflow.tables import read_table

log = setup_script_logging(snakemake.log[0], "figure_area_fits")
campaign = load_campaign(Path(snakemake.params.campaign))
figure = figures.area_fits(
    read_table(snakemake.input.curves),
    read_table(snakemake.input.area),
    title=f"{campaign.name}: damping vs velocity amplitude and bearing area",
)
figures.save(figure, snakemake.output[0])

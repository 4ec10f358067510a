"""Rule figures_models: the fitted friction-model parameters of every configuration, one
table and the same as the report's readable HTML page, then paper figures 14 (Dahl) and
15 (LuGre) of every configuration."""

import json
from pathlib import Path

from workflow.io.escape import plot_text
from workflow.io.tables import atomic_write_bytes, read_table, write_table
from workflow.io.units import UNIT_SYSTEMS
from workflow.measured.campaign_tables import first_mode_and_channel, paper_channel, with_mode_and_channel
from workflow.models.paper import fit_table, model_curve_frames
from workflow.outputs import figures
from workflow.outputs.report_tables import model_fits_html
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "figures_models")
units = UNIT_SYSTEMS[snakemake.params.units]
documents = {}
for path in snakemake.input.fits:
    document = json.loads(Path(path).read_text())
    documents[document["configuration"]] = document
fits = fit_table(documents)
segments = read_table(snakemake.input.segments)
channel = paper_channel(segments, snakemake.params.channels)
segments = first_mode_and_channel(segments, channel)
first_mode_hz = segments["mode_hz"].min() if len(segments) else None
write_table(with_mode_and_channel(fits, first_mode_hz, channel), snakemake.output.table)
atomic_write_bytes(snakemake.output.page, model_fits_html(fits, units).encode())
log.info("%d parameters of %d configurations", len(fits), fits["configuration"].nunique())

for configuration, dahl_path, lugre_path in zip(
    snakemake.params.configurations, snakemake.output.dahl, snakemake.output.lugre, strict=True
):
    mine = segments[segments["configuration"] == configuration]
    document = documents[configuration]
    # the simulated curves only where they are compared with data (their ends carry the
    # simulation's own start-up and noise-floor effects)
    low, high = mine["velocity_amplitude_in_s"].min(), mine["velocity_amplitude_in_s"].max()
    curves = {
        model: frame[frame["velocity_amplitude_in_s"].between(low, high)]
        for model, frame in model_curve_frames(document).items()
    }
    for model, path, label in (("dahl", dahl_path, "Dahl"), ("lugre", lugre_path, "LuGre")):
        fit = document["models"].get(model)
        if fit is None:
            title = f"{plot_text(configuration)}: {label} not fitted ({plot_text(document.get('skipped', 'no fit'))})"
            figures.save(figures.model_comparison(mine, {}, title=title, units=units), path)
            continue
        title = (
            f"{plot_text(configuration)}: measured vs fitted {label} simulation\n"
            f"(rms error: ln ζ {fit['rms_log_zeta']:.3f}, frequency {100 * fit['rms_rel_frequency']:.3f} %)"
        )
        models = {f"{label} + ζ0 (fitted)": curves[model]}
        figures.save(figures.model_comparison(mine, models, title=title, units=units), path)
    log.info("%s: figures 14 and 15 drawn", configuration)

"""Rule figure_friction_loops: paper figures 7 (Dahl) and 8 (LuGre) with the paper's values."""

import textwrap

import numpy as np

from workflow.io.units import UNIT_SYSTEMS
from workflow.models.friction import hysteresis_loop
from workflow.models.paper import PAPER_DAHL, PAPER_LUGRE
from workflow.outputs import figures
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "figure_friction_loops")
units = UNIT_SYSTEMS[snakemake.params.units]
amplitudes_in = (0.25, 0.5, 1.0, 2.0, 4.0)
for model, params, path, name in (
    ("dahl", PAPER_DAHL, snakemake.output.dahl, "Dahl"),
    ("lugre", PAPER_LUGRE, snakemake.output.lugre, "LuGre"),
):
    # the paper's loops are displacement-driven at 1 Hz (LuGre is rate dependent)
    x, force = hysteresis_loop(model, params, np.array(amplitudes_in), frequency_hz=1.0, cycles=2)
    loops = [(amplitude, x[k], force[k]) for k, amplitude in enumerate(amplitudes_in)]
    values = textwrap.fill(f"({figures.parameter_text(params, units)})", 80)
    title = f"Friction force vs displacement: {name}\n{values}"
    figures.save(figures.friction_loops(loops, title=title, units=units), path)
    log.info("%s loops at %s in", model, amplitudes_in)

"""Rule figure_friction_loops: paper figures 7 (Dahl) and 8 (LuGre) with the paper's values."""

from workflow.models.friction import hysteresis_loop
from workflow.models.paper import PAPER_DAHL, PAPER_LUGRE
from workflow.outputs import figures
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "figure_friction_loops")
amplitudes_in = (0.25, 0.5, 1.0, 2.0, 4.0)
for model, params, path, name in (
    ("dahl", PAPER_DAHL, snakemake.output.dahl, "Dahl (σ = (2π)², Fc = 38)"),
    (
        "lugre",
        PAPER_LUGRE,
        snakemake.output.lugre,
        "LuGre (σ0 = (2π)², σ1 = 0.008π, α0 = 38, α1 = α0/2, α2 = σ1, v0 = vd = 1)",
    ),
):
    # the paper's loops are displacement-driven at 1 Hz (LuGre is rate dependent)
    loops = [
        (amplitude, *hysteresis_loop(model, params, amplitude, frequency_hz=1.0, cycles=2))
        for amplitude in amplitudes_in
    ]
    figures.save(figures.friction_loops(loops, title=f"Friction force vs displacement: {name}"), path)
    log.info("%s loops at %s in", model, amplitudes_in)

"""Rule diagnose: results/diagnosis.json and the residuals behind it, from every
configuration's diagnosis."""

from pathlib import Path

from workflow.discovery.campaign import campaign_document, configuration_outcomes, residual_table
from workflow.discovery.diagnosis_files import read_configuration_diagnosis
from workflow.discovery.modes import mode_document, with_modes
from workflow.io.interim import read_campaign
from workflow.io.tables import read_table, write_json, write_table
from workflow.measured.campaign_tables import paper_channel, with_mode_and_channel
from workflow.models.averaged_fit import FitContext
from workflow.runtime.logs import setup_script_logging

log = setup_script_logging(snakemake.log[0], "diagnose")
campaign = read_campaign(snakemake.input.campaign_settings)


def document_of(outcomes):
    """The campaign's document from its configurations' outcomes (one mode and channel)."""
    diagnoses, skipped = configuration_outcomes(outcomes)
    context = FitContext(outcomes[0].reference_velocity_in_s)
    return diagnoses, campaign_document(campaign.name, context, diagnoses, skipped)


# the first mode on the paper's channel (rule diagnose_configuration's): the residuals,
# the figures, the paper's models
diagnoses, first = document_of(
    [read_configuration_diagnosis(path) for path in snakemake.input.configurations]
)
# no mode found anywhere: one entry, of no frequency, with the configurations skipped
modes_hz = [
    float(hz) for hz in sorted(read_table(snakemake.input.modes)["nominal_mode_hz"].dropna().unique())
]
channels = snakemake.params.channels
paper = channels.index(paper_channel(read_table(snakemake.input.segments), channels))
residuals = with_mode_and_channel(
    residual_table(diagnoses), modes_hz[0] if modes_hz else None, channels[paper]
)
write_table(residuals, snakemake.output.residuals)
# every other (mode, channel): rule diagnose_modes's files, <configuration>/c<channel>/<mode>.npz
outcomes: dict[tuple[int, int], list] = {(0, paper): None}
for folder in map(Path, snakemake.input.modes_channels):
    for path in sorted(folder.glob("*.npz")):
        outcomes.setdefault((int(path.stem), int(folder.name[1:])), []).append(
            read_configuration_diagnosis(path)
        )
documents = {key: first if key == (0, paper) else document_of(found)[1] for key, found in outcomes.items()}
# several channels: every mode's joint analysis, rule diagnose_joint's <configuration>/<mode>.npz
joint_outcomes: dict[int, list] = {}
for folder in map(Path, snakemake.input.joint):
    for path in sorted(folder.glob("*.npz")):
        joint_outcomes.setdefault(int(path.stem), []).append(read_configuration_diagnosis(path))
joint = {mode: document_of(found)[1] for mode, found in joint_outcomes.items()}
document = with_modes(
    [
        mode_document(
            mode_hz,
            {channels[c]: documents[(m, c)] for c in range(len(channels)) if (m, c) in documents},
            joint.get(m),
        )
        for m, mode_hz in enumerate(modes_hz or [None])
    ]
)
write_json(snakemake.output.diagnosis, document)
log.info("campaign verdict: %s", document["cause"])
for entry in document["modes"][1:]:
    log.info("mode %s Hz: %s", entry["mode_hz"], entry["cause"])
for name, entry in document["configurations"].items():
    log.info(
        "%s: %s (gain ratio %s) - %s", name, entry["cause"], entry["gain"]["ratio"], entry["discrepancy"]
    )

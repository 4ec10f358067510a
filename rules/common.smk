# Helpers shared by the rules: validated config, the campaign's runs, target lists.

import os
import re
import sys
import time
from dataclasses import asdict
from pathlib import Path


from workflow.config import ConfigError, validate_config
from workflow.runtime.resources import analyse_runs_mem_mb, identify_mode_mem_mb
from workflow.runtime.scheduler import largest_area_first
from workflow.io.escape import terminal_lines, terminal_text, visible_controls

# Rules pass each settings section (or the keys of it their step reads) as a plain dict,
# asdict(...): Snakemake re-runs a job when such a param changes, and cannot see into a
# dataclass. Each script rebuilds the dataclass from it.
try:
    SETTINGS = validate_config(
        config,
        source=" or ".join(
            [f"config.yaml ({Path(workflow.basedir) / 'config.yaml'})"]
            + [f"--configfile {path}" for path in workflow.config_settings.configfiles]
        ),
        command_line=dict(workflow.config_settings.config),
    )
except ConfigError as error:
    raise WorkflowError(f"invalid configuration:\n{terminal_lines(error)}") from None

CAMPAIGN = Path(SETTINGS.campaign)

LAPJOINT_ENV = "../envs/lapjoint.yaml"
"""Every rule's software, for ``--software-deployment-method conda``: the project's
dependencies, and the project itself installed from this source tree by
envs/lapjoint.post-deploy.sh, which finds it through ``LAPJOINT_SOURCE``."""
os.environ["LAPJOINT_SOURCE"] = workflow.basedir


envvars:
    "LAPJOINT_SOURCE",


USES_DEMO = SETTINGS.uses_demo_campaign()

CAMPAIGN_FOLDER_FILE = Path("results/interim/campaign_folder.txt")
"""The campaign folder whose results results/ holds (:func:`record_campaign_folder`)."""


def record_campaign_folder():
    """Record that results/ holds this campaign's results (the Snakefile's onstart: once
    jobs are about to run, never on a dry run)."""
    CAMPAIGN_FOLDER_FILE.parent.mkdir(parents=True, exist_ok=True)
    CAMPAIGN_FOLDER_FILE.write_text(f"{CAMPAIGN.resolve()}\n", encoding="utf-8")


def other_campaign_in_results():
    """The campaign folder whose results results/ holds, when it is another one than
    this run's (None when it is this one, or results/ records none)."""
    if not CAMPAIGN_FOLDER_FILE.exists():
        return None
    recorded = CAMPAIGN_FOLDER_FILE.read_text(encoding="utf-8").strip()
    return None if Path(recorded) == CAMPAIGN.resolve() else recorded


if workflow.is_main_process and (_other := other_campaign_in_results()) is not None:
    # results/ is per working directory (output contract): a second campaign's results
    # would mix with the first's, figures and report included
    raise WorkflowError(
        f"results/ in {Path.cwd()} holds the results of the campaign in {terminal_text(_other)}, "
        f"and this run is for {terminal_text(CAMPAIGN.resolve())}: their figures, tables and report "
        "would mix. Run this campaign in a working directory of its own (add -d FOLDER, and "
        f"-s {workflow.main_snakefile} if you are not in the project folder), or remove results/ "
        "to replace the other campaign's results."
    )

if workflow.is_main_process:
    # After a hard kill, Snakemake's lock files stay behind; clear them when no other
    # lapjoint run is alive here, so that `snakemake -c2 all` resumes (workflow/runtime/locks.py).
    from workflow.runtime.locks import clear_stale_snakemake_locks

    for _stale in clear_stale_snakemake_locks():
        logger.info(f"removed stale lock .snakemake/locks/{_stale} (no lapjoint run is alive here)")


STARTED_S = time.time()
"""When this Snakemake run started (the tables of an earlier run say nothing about it)."""


def nothing_analysed_this_run():
    """Why nothing could be analysed, when rule usable_segments stopped for it in this run,
    else None."""
    from workflow.measured.campaign_tables import NOTHING_ANALYSED, nothing_analysed_in_tables

    log = Path("results/logs/usable_segments.log")
    # a second of slack: some file systems keep whole seconds
    if not (log.exists() and log.stat().st_mtime >= STARTED_S - 1.0 and NOTHING_ANALYSED in log.read_text()):
        return None
    return nothing_analysed_in_tables(
        "results/tables/runs.parquet",
        "results/interim/segments.parquet",
        "results/tables/segments_rejected.parquet",
    )


def campaign_inventory():
    """Run files of the campaign, in campaign.yaml order, the paths its globs lead to that
    are not read (docs/input-safety.md), as runs-table rows, and the validated
    campaign.yaml (None for the demo).

    The demo campaign is planned from its settings (it may not exist yet: a rule
    generates it); any other campaign is listed from its campaign.yaml, and its band
    and mode are checked against the sample rate its files declare before any job runs.
    """
    from workflow.io.campaign import CAMPAIGN_FILE, load_campaign
    from workflow.io.readers.ascii import declared_sample_rate_hz
    from workflow.io.campaign import frequency_problem
    from workflow.io.records import CampaignFormatError
    from workflow.io.run_files import ExcludedPath, scan_campaign

    if USES_DEMO:
        from workflow.lab.layout import planned_run_files

        return planned_run_files(SETTINGS.demo.runs_per_configuration), [], None
    if not CAMPAIGN.is_dir():
        raise WorkflowError(
            f"campaign folder {terminal_text(CAMPAIGN)} does not exist (working directory {Path.cwd()}); "
            "set campaign in config.yaml or with --config campaign=PATH"
        )
    if visible_controls(CAMPAIGN) != str(CAMPAIGN):
        raise WorkflowError(
            f"the campaign folder's path {terminal_text(CAMPAIGN)} holds control characters, which "
            "Snakemake prints raw with every job; rename the folder"
        )
    try:
        campaign = load_campaign(CAMPAIGN)
        runs, excluded = scan_campaign(CAMPAIGN, campaign)
    except (CampaignFormatError, FileNotFoundError) as error:
        raise WorkflowError(
            f"cannot read campaign {terminal_text(CAMPAIGN)}: {terminal_lines(error)}"
        ) from None
    # Snakemake prints each job's input paths raw: a run file whose name would act on the
    # terminal is listed as excluded instead of read
    excluded += [
        ExcludedPath(
            run.configuration,
            run.run,
            run.path,
            f"{CAMPAIGN.as_posix()}/{run.path}: not read: its name holds control characters "
            "(shown as escapes), which a terminal would act on; rename the file",
        )
        for run in runs
        if visible_controls(run.path) != run.path
    ]
    runs = [run for run in runs if visible_controls(run.path) == run.path]
    if SETTINGS.strict and excluded:
        raise WorkflowError(
            "strict mode: campaign paths not read:\n"
            + "\n".join(terminal_text(entry.reason) for entry in excluded)
        )
    rates_hz = {run.path: declared_sample_rate_hz(CAMPAIGN, run, campaign) for run in runs}
    known_hz = {path: rate for path, rate in rates_hz.items() if rate is not None}
    if known_hz:
        # The fastest record decides: slower ones that cannot hold the band are
        # excluded with the reason when read, the others analysed.
        fastest = max(known_hz, key=known_hz.get)
        problem = frequency_problem(campaign, known_hz[fastest], f"declared by {fastest}")
        if problem is not None:
            raise WorkflowError(f"invalid campaign {CAMPAIGN}: {CAMPAIGN / CAMPAIGN_FILE}: {problem}")
    return runs, excluded, campaign


def channels_and_modes(campaign):
    """The response channels' names in the tables (campaign.yaml's ``response``), and
    whether the campaign may have several modes (``modes_hz`` listing several, or auto);
    ``campaign`` is the loaded campaign.yaml, None for the demo."""
    from workflow.io.campaign import SINGLE_CHANNEL_NAME

    if campaign is None:
        return (SINGLE_CHANNEL_NAME,), False
    return campaign.response.channel_names(), campaign.auto_modes or len(campaign.mode_requests()) > 1


def configuration_areas_in2(campaign):
    """Configuration -> bearing area (in^2) as campaign.yaml states it, None where it
    states none; the demo's from its plan (``campaign`` None)."""
    if campaign is None:
        from workflow.lab.layout import PAPER_CONFIGURATIONS

        return dict(PAPER_CONFIGURATIONS)
    return campaign.bearing_areas_in2()


RUN_FILES, EXCLUDED_PATHS, CAMPAIGN_SPEC = campaign_inventory()
RESPONSE_CHANNELS, SEVERAL_MODES = channels_and_modes(CAMPAIGN_SPEC)
DIAGNOSIS_PRIORITY = largest_area_first(configuration_areas_in2(CAMPAIGN_SPEC))


def diagnosis_priority(wildcards):
    """A configuration's diagnosis before the figures of the measured data, the largest
    bearing area first (workflow.runtime.scheduler.largest_area_first)."""
    return DIAGNOSIS_PRIORITY.get(wildcards.configuration, 1)


def channel_index(channel_key):
    """The 0-based index of the response channel a ``c00``, ``c01``, ... key names."""
    return int(channel_key[1:])


def mode_channel_diagnoses():
    """The outputs of diagnose_modes (a rule): every configuration's channels, the first only when
    the campaign may have more than one mode (its first mode is diagnose_configuration's)."""
    first = 0 if SEVERAL_MODES else 1
    return [
        f"results/interim/diagnosis_modes/{name}/c{index:02d}"
        for name in CONFIGURATIONS
        for index in range(first, len(RESPONSE_CHANNELS))
    ]


def joint_diagnoses():
    """The outputs of diagnose_joint (a rule): every configuration's, when the campaign has several
    response channels (one channel's diagnosis is the configuration's)."""
    if len(RESPONSE_CHANNELS) < 2:
        return []
    return [f"results/interim/diagnosis_joint/{name}" for name in CONFIGURATIONS]


CONFIGURATIONS = list(dict.fromkeys(run.configuration for run in RUN_FILES))
RUNS = {name: [run for run in RUN_FILES if run.configuration == name] for name in CONFIGURATIONS}
if not RUN_FILES:
    raise WorkflowError(
        f"campaign {terminal_text(CAMPAIGN)} has no run files"
        + "".join(f"\n{terminal_text(entry.reason)}" for entry in EXCLUDED_PATHS)
    )
if EXCLUDED_PATHS and workflow.is_main_process:
    for _entry in EXCLUDED_PATHS:
        logger.warning(f"excluded {terminal_text(_entry.reason)}")


wildcard_constraints:
    configuration="|".join(re.escape(name) for name in CONFIGURATIONS),
    number=r"\d\d",
    group=r"runs\d+",
    channel_key=r"c\d\d",


def campaign_yaml(wildcards):
    """The campaign's campaign.yaml, named by an input function: Snakemake's report
    writes a rule's literal input paths and the params of a rule whose outputs it shows
    raw into a <script> element, which a campaign path holding `</script>` would end."""
    return CAMPAIGN / "campaign.yaml"


def configuration_run_files(wildcards):
    return [CAMPAIGN / run.path for run in RUNS[wildcards.configuration]]


FIRST_RUN_GROUP = "runs01"
"""The first group of every configuration's runs: analysed by its identify_mode job."""


def run_groups(configuration):
    """The configuration's runs in groups of ``runs_per_job`` (campaign order), one job
    each (identify_mode for the first, analyse_runs for the others): name -> runs."""
    runs = RUNS[configuration]
    size = SETTINGS.runs_per_job
    return {f"runs{index // size + 1:02d}": runs[index : index + size] for index in range(0, len(runs), size)}


def first_run_group_files(wildcards):
    return [CAMPAIGN / run.path for run in run_groups(wildcards.configuration)[FIRST_RUN_GROUP]]


def run_group_files(wildcards):
    group = run_groups(wildcards.configuration).get(wildcards.group)
    if group is None:
        raise WorkflowError(f"no run group {wildcards.group} in configuration {wildcards.configuration}")
    return [CAMPAIGN / run.path for run in group]


def run_group_outputs(kind, extension):
    """Every run group's interim ``kind`` file (segments, quality or status)."""
    return [
        f"results/interim/{kind}/{name}/{group}.{extension}"
        for name in CONFIGURATIONS
        for group in run_groups(name)
    ]


def damping_figure_number(configuration):
    """The paper's figures 10, 11, 12 are damping vs amplitude per configuration;
    configurations past the third keep number 12."""
    return min(10 + CONFIGURATIONS.index(configuration), 12)


def damping_figures():
    return [
        f"results/figures/fig{damping_figure_number(name):02d}_damping_{name}.png" for name in CONFIGURATIONS
    ]


def backbone_figures():
    return [f"results/figures/backbone_{name}.png" for name in CONFIGURATIONS]


def modes_channels_figures():
    """The figure of every mode and channel, for a campaign that may have several."""
    several = SEVERAL_MODES or len(RESPONSE_CHANNELS) > 1
    return ["results/figures/modes_channels.png"] if several else []


def measured_outputs():
    """The measured-data chain: tables, figures 9-13 and the backbones."""
    return [
        "results/tables/segments.parquet",
        "results/tables/runs.parquet",
        "results/tables/runs.csv",
        "results/tables/quality.parquet",
        "results/tables/damping_fits.parquet",
        "results/tables/hypotheses.parquet",
        "results/figures/fig09_time_history.png",
        *damping_figures(),
        "results/figures/fig13_area_fits.png",
        *backbone_figures(),
        *modes_channels_figures(),
    ]


def model_outputs():
    """The paper's models: figures 7, 8, 14, 15 and the fitted parameters."""
    return [
        "results/figures/fig07_dahl_loops.png",
        "results/figures/fig08_lugre_loops.png",
        "results/tables/model_fits.parquet",
        *[f"results/figures/fig14_dahl_{name}.png" for name in CONFIGURATIONS],
        *[f"results/figures/fig15_lugre_{name}.png" for name in CONFIGURATIONS],
    ]


def discovery_outputs():
    """The diagnosis of what the paper's model gets wrong (output contract)."""
    return [
        "results/diagnosis.json",
        "results/tables/diagnosis_residuals.parquet",
        *[f"results/figures/discovery_residuals_{name}.png" for name in CONFIGURATIONS],
        "results/figures/discovery_candidates.png",
        "results/figures/discovery_heldout.png",
    ]


LANDING_PAGE = Path("results/report/landing.rst")
"""The report's first page once report_summary has written it (rules/report.smk)."""


def report_outputs():
    """The report's own pages (the figures and tables they describe come from the others)."""
    return [
        str(LANDING_PAGE),
        "results/report/verdict.html",
        "results/report/hypotheses.html",
        "results/report/runs.html",
        "results/report/quality.html",
        "results/report/rejected_segments.html",
        "results/report/damping_fits.html",
        "results/report/model_fits.html",
        "results/report/diagnosis_candidates.html",
    ]

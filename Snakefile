# lapjoint: impact-hammer ring-downs of bolted lap joints -> damping and frequency
# curves, the paper's friction models, and a diagnosis of what they get wrong.
#
#   snakemake -c2 all                                  # built-in demo campaign
#   snakemake -c2 all --config campaign=PATH           # your own campaign
#   snakemake -c2 all -s /path/to/lapjoint/Snakefile -d WORKDIR

from snakemake.utils import min_version

from workflow.io.escape import terminal_lines, terminal_text
from workflow.outputs.report_command import REPORT_COMMAND_FILE, report_command
from workflow.runtime.params_pandas import defer_pandas_import
from workflow.runtime.scheduler import cancel_scheduler_timers

min_version("9.0")
# Snakemake would import pandas (0.3-0.7 s) to look for pandas params; ours are plain values
defer_pandas_import()


configfile: workflow.source_path("config.yaml")


include: "rules/common.smk"
include: "rules/demo.smk"
include: "rules/measured.smk"
include: "rules/figures.smk"
include: "rules/models.smk"
include: "rules/discovery.smk"
include: "rules/report.smk"


rule all:
    default_target: True
    input:
        measured_outputs(),
        model_outputs(),
        discovery_outputs(),
        report_outputs(),
        "results/summary.txt",


onstart:
    # results/ now holds this campaign's results: planning refuses another campaign here
    # (rules/common.smk), so that two campaigns' figures and report never mix
    record_campaign_folder()


onsuccess:
    # The summary closes the console output of `all`, after Snakemake's own lines,
    # so that a reader sees the verdict and the excluded runs without scrolling.
    # The report command is made here, where the Snakefile, working directory and
    # command line are known, so that it works as printed from any folder.
    summary = Path("results/summary.txt")
    if summary.exists() and (not workflow.dag_settings.targets or "all" in workflow.dag_settings.targets):
        command = report_command(
            workflow.main_snakefile,
            Path.cwd(),
            Path(workflow.basedir) / "report" / "report.css",
            workflow.config_settings.configfiles,
            workflow.config_settings.config,
        )
        Path(REPORT_COMMAND_FILE).write_text(command + "\n")
        print(f"\n{summary.read_text()}", end="", file=sys.stderr)
        print(f"  {terminal_text(command, limit=None)}", file=sys.stderr)
    cancel_scheduler_timers()


onerror:
    cancel_scheduler_timers()
    # Nothing analysed: the reasons, not Snakemake's lines, are the last thing printed.
    nothing = nothing_analysed_this_run()
    if nothing is not None:
        print(f"\nlapjoint: {terminal_lines(nothing)}", file=sys.stderr)
        sys.exit(1)


rule measured:
    input:
        measured_outputs(),


rule models:
    input:
        model_outputs(),


rule discovery:
    input:
        discovery_outputs(),

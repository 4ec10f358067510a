"""Every rule that does work declares what a cluster needs (threads, memory, run time),
logs to its own file and keeps a benchmark file, and its script logs its cost
(bench/bench_workflow.py reads both)."""

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def rule_blocks() -> dict[str, str]:
    """Rule name -> its text, for every rule in rules/*.smk (at any indentation)."""
    blocks = {}
    for path in sorted((REPO / "rules").glob("*.smk")):
        text = path.read_text()
        starts = list(re.finditer(r"^( *)rule (\w+):\n", text, flags=re.M))
        for start, following in zip(starts, starts[1:] + [None]):
            blocks[start.group(2)] = text[start.end() : following.start() if following else len(text)]
    return blocks


RULES = rule_blocks()


def test_rules_were_found():
    assert {"analyse_runs", "identify_mode", "diagnose_configuration", "diagnose"} <= set(RULES)


@pytest.mark.parametrize("name", sorted(RULES))
def test_rule_declares_threads_resources_log_and_benchmark(name):
    block = RULES[name]
    assert re.search(r"^\s+threads: \d+$", block, flags=re.M), name
    resources = re.search(r"^\s+resources:\n((?:\s+\w+=.+\n)+)", block, flags=re.M)
    assert resources and "mem_mb=" in resources.group(1) and "runtime=" in resources.group(1), name
    assert re.search(r'^\s+log:\n\s+"results/logs/', block, flags=re.M), name
    assert re.search(r'^\s+benchmark:\n\s+"results/benchmarks/', block, flags=re.M), name


def rule_script(name: str) -> Path | None:
    """The script a rule runs (its ``script:`` directive), or None."""
    script = re.search(r'^\s+script:\n\s+"\.\./(scripts/\w+\.py)"', RULES[name], flags=re.M)
    return REPO / script.group(1) if script else None


@pytest.mark.parametrize("name", sorted(RULES))
def test_rule_script_logs_to_the_rule_log(name):
    script = rule_script(name)
    assert script, f"{name} runs no script"
    assert "setup_script_logging(snakemake.log[0]" in script.read_text(), name


@pytest.mark.parametrize("name", sorted(RULES))
def test_rule_script_logs_its_cost_under_the_rule_name(name):
    """bench_workflow.py adds each job's cost line to the rule its logger names: a script
    that serves several rules names the one it runs for (``snakemake.rule``)."""
    text = rule_script(name).read_text()
    assert (
        f'setup_script_logging(snakemake.log[0], "{name}")' in text
        or "setup_script_logging(snakemake.log[0], snakemake.rule)" in text
    ), name


SMK_FILES = sorted([REPO / "Snakefile", *(REPO / "rules").glob("*.smk")])
# Statements that would rebind Snakemake's `workflow` object inside a Snakefile.
BINDS_WORKFLOW = re.compile(
    r"^\s*(?:import workflow\b|from \S+ import .*\bworkflow\b|workflow\s*=|def workflow\b"
    r"|for .*\bworkflow\b.* in |with .* as workflow\b)",
    flags=re.M,
)


@pytest.mark.parametrize("path", SMK_FILES, ids=lambda path: path.name)
def test_no_smk_file_rebinds_snakemakes_workflow_object(path):
    """Inside a Snakefile, `workflow` is Snakemake's object; the library is reached only as
    `from workflow.<stage>.<module> import ...`, which leaves that name alone."""
    assert not BINDS_WORKFLOW.findall(path.read_text())


@pytest.mark.parametrize(
    "line, binds",
    [
        ("import workflow.config", True),
        ("from lapjoint import workflow", True),
        ("workflow = None", True),
        ("from workflow.config import validate_config", False),
        ("configfile: workflow.source_path('config.yaml')", False),
    ],
)
def test_the_binding_check_tells_a_binding_from_a_use(line, binds):
    assert bool(BINDS_WORKFLOW.search(line)) == binds


@pytest.mark.parametrize("path", sorted((REPO / "scripts").glob("*.py")), ids=lambda path: path.name)
def test_scripts_reach_the_installed_library_without_path_edits(path):
    assert "sys.path" not in path.read_text()


@pytest.mark.parametrize("name", sorted(RULES))
def test_rule_names_its_software(name):
    """snakemake --lint asks every rule for its software: the project's one environment."""
    assert re.search(r"^\s+conda:\n\s+LAPJOINT_ENV$", RULES[name], flags=re.M), name


@pytest.mark.parametrize(
    "name", ["collect_tables", "fit_curves", "diagnose_configuration", "diagnose", "analyse_runs"]
)
def test_analysis_rules_do_not_depend_on_the_units_results_are_shown_in(name):
    # config units is a presentation choice: switching it must re-run no analysis
    assert "SETTINGS.units" not in RULES[name] and "units=" not in RULES[name], name

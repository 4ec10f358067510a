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
            blocks[start.group(2)] = text[start.end(): following.start() if following else len(text)]
    return blocks


RULES = rule_blocks()


def test_rules_were_found():
    assert {"analyse_runs", "identify_mode", "fit_friction_models", "diagnose"} <= set(RULES)


@pytest.mark.parametrize("name", sorted(RULES))
def test_rule_declares_threads_resources_log_and_benchmark(name):
    block = RULES[name]
    assert re.search(r"^\s+threads: \d+$", block, flags=re.M), name
    resources = re.search(r"^\s+resources:\n((?:\s+\w+=.+\n)+)", block, flags=re.M)
    assert resources and "mem_mb=" in resources.group(1) and "runtime=" in resources.group(1), name
    assert re.search(r'^\s+log:\n\s+"results/logs/', block, flags=re.M), name
    assert re.search(r'^\s+benchmark:\n\s+"results/benchmarks/', block, flags=re.M), name


@pytest.mark.parametrize("name", sorted(RULES))
def test_rule_script_logs_to_the_rule_log(name):
    script = re.search(r'^\s+script:\n\s+"\.\./(scripts/\w+\.py)"', RULES[name], flags=re.M)
    assert script, f"{name} runs no script"
    assert "setup_script_logging(snakemake.log[0]" in (REPO / script.group(1)).read_text(), name

"""Mutation score of the modules that decide numbers, with mutmut.

Run: ``pip install -e '.[mutation]'`` once, then
``PYTHONPATH=$PWD .venv/bin/python bench/mutation_score.py [--children N] [TARGET ...]``
(targets below; default ``units``). For each target, the project's tracked files are
copied to a temporary folder, mutmut mutates that one module and runs only the tests that
exercise it (every mutant: one small change of an operator, a constant, a string or a
call), and the bench prints the mutants killed, survived and otherwise (timeouts,
suspicious), the score (killed over all) and each survivor's diff. A survivor is a change
no test notices: kill it with a test, or argue in the test file why it is equivalent.

Each mutant costs one run of the target's tests. On one core: ``units``, ``decide`` and
``confidence`` about 1.5 minutes each, ``heldout`` 1, ``misfit`` 2, ``combined`` 3,
``decay`` far longer.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

TARGETS = {
    "units": (
        "workflow/io/units.py",
        ["tests/test_io_units.py", "tests/test_io_units_spellings.py", "tests/test_io_column_grammar.py"],
        "",
    ),
    "record_rules": (
        "workflow/io/record_rules.py",
        [
            "tests/test_io_column_grammar.py",
            "tests/test_io_campaign.py",
            "tests/test_io_readers_system_formats.py",
        ],
        "",
    ),
    "decay": (
        "workflow/measured/decay.py",
        ["tests/test_measured_decay.py", "tests/test_measured_decay_truth.py"],
        "",
    ),
    # Segment layout only (the decay's other functions take hours of mutants on one core).
    "segment_bounds": (
        "workflow/measured/segment_fits.py:segment_bounds",
        ["tests/test_measured_decay.py", "tests/test_measured_decay_truth.py"],
        "segment or overlap",
    ),
    # The confidence: the runs' reweightings, the accuracy margin, the soft decisions.
    "confidence": ("workflow/discovery/confidence.py", ["tests/test_discovery_confidence.py"], ""),
    # The combination rule (paired tests, what each mechanism removes, a term read off a
    # residual); the end-to-end lab cases of its test file take seconds each, left out.
    "combined": (
        "workflow/discovery/combined.py",
        [
            "tests/test_discovery_combined.py",
            "tests/test_discovery_combined_statistics.py",
            "tests/test_discovery_confidence.py",
        ],
        "not two_hidden and not edge_of_its_range and not clear_velocity and not single_state_joint_with "
        "and not gate_a_single",
    ),
    # The baseline's misfit tests and explains_data (the signatures and the envelope test
    # are the lab cases' and the diagnosis tests', minutes per mutant).
    "misfit": (
        "workflow/discovery/misfit.py:misfit_significant,bin_span_in_s,_lag1_effective,bin_observations,"
        "bin_is_judged,binned_discrepancy,run_order_trend,explains_data",
        ["tests/test_discovery_misfit.py"],
        "",
    ),
    # The held-out statistics but the cross-validation itself (fits, the lab cases').
    "heldout": (
        "workflow/discovery/heldout.py:heldout_scales,folds_of,amplitude_bin,amplitude_weights,weighted_rms,"
        "effective_observations,information_criterion,heldout_units,heldout_standard_error",
        ["tests/test_discovery_heldout.py"],
        "",
    ),
    # The decision rule itself; the rest of decision.py (the evidence it is fed) is covered
    # by the diagnosis tests, minutes per mutant.
    "decide": (
        "workflow/discovery/decision.py:decide",
        ["tests/test_discovery_decision.py"],
        "not named_none",
    ),
}
"""Target -> (the module mutated, ``:function[,function...]`` to mutate those functions only; the tests
run against each mutant; a pytest ``-k`` expression selecting among them, or "")."""


def mutmut_config(module: str, tests: list[str], selection: str) -> str:
    """setup.cfg of the copy: mutate ``module`` only, run ``tests`` only."""
    lines = [
        "[mutmut]",
        "source_paths = workflow",
        f"only_mutate = {module}",
        "pytest_add_cli_args_test_selection =",
    ]
    lines += [f"    {test}" for test in tests]
    # mutmut runs its own children: each runs the tests in one process (no xdist workers)
    lines += ["pytest_add_cli_args =", "    -p", "    no:cacheprovider", "    -n", "    0"]
    lines += ["    -k", f"    {selection}"] if selection else []
    return "\n".join(lines + [""])


def copy_project(destination: Path) -> None:
    """The tracked files of the checkout (no results, no virtual environment)."""
    tracked = (
        subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=True)
        .stdout.decode()
        .split("\0")
    )
    for relative in filter(None, tracked):
        source = REPO / relative
        if source.is_file() and not relative.startswith(("results/", "docs/")):
            target = destination / relative
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target)


def mutmut(folder: Path, *args: str) -> str:
    return subprocess.run(
        [sys.executable, "-m", "mutmut", *args], cwd=folder, capture_output=True, text=True, check=True
    ).stdout


def score(target: str, children: int) -> None:
    where, tests, selection = TARGETS[target]
    module, _, listed = where.partition(":")
    functions = listed.split(",") if listed else []
    with tempfile.TemporaryDirectory(prefix="mutation-") as tmp:
        folder = Path(tmp)
        copy_project(folder)
        (folder / "setup.cfg").write_text(mutmut_config(module, tests, selection))
        # mutmut names a mutant module.x_function__mutmut_N
        names = [f"{module[:-3].replace('/', '.')}.x_{function}__mutmut_*" for function in functions]
        mutmut(folder, "run", "--max-children", str(children), *names)
        outcomes: dict[str, list[str]] = {}
        for line in mutmut(folder, "results", "--all", "true").splitlines():
            name, _, outcome = line.strip().rpartition(": ")
            if name and (not functions or any(f".x_{function}__mutmut_" in name for function in functions)):
                outcomes.setdefault(outcome, []).append(name)
        killed = len(outcomes.get("killed", []))
        total = sum(len(names) for names in outcomes.values())
        others = ", ".join(
            f"{len(names)} {outcome}" for outcome, names in outcomes.items() if outcome != "killed"
        )
        print(f"{target} ({where}; tests: {' '.join(tests)}{' -k ' + repr(selection) if selection else ''})")
        print(f"  mutants {total}: killed {killed}{', ' + others if others else ''}")
        print(f"  mutation score {killed / max(total, 1):.1%}")
        for name in outcomes.get("survived", []):
            print(mutmut(folder, "show", name))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("targets", nargs="*", default=["units"], choices=sorted(TARGETS))
    parser.add_argument(
        "--children", type=int, default=1, help="mutants tested at once (the machine is shared)"
    )
    arguments = parser.parse_args()
    try:
        import mutmut  # noqa: F401
    except ImportError:
        sys.exit("mutmut is not installed: pip install -e '.[mutation]'")
    for target in arguments.targets:
        score(target, arguments.children)


if __name__ == "__main__":
    main()

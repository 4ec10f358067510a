"""Shared by the tests that run the real workflow: the snakemake call, file checksums and a
run file with one bad cell."""

import hashlib
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def run_snakemake(workdir: Path, *args: str, timeout: float) -> subprocess.CompletedProcess:
    """``snakemake -s Snakefile -d workdir ARGS`` in a subprocess, output captured."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.run(
        [sys.executable, "-m", "snakemake", "-s", str(REPO / "Snakefile"), "-d", str(workdir), *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
    )


CHEAP = [
    "models={global_samples: 4, local_starts: 1, local_iterations: 1, steps_per_period: 8}",
    "discovery={global_samples: 32, local_starts: 1, folds: 3}",
    "fits={bootstrap_samples: 50}",
]
"""--config values that make the friction and candidate fits quick (tests of outputs, not of fits)."""

CHEAP_BUT_DISCOVERY = [value for value in CHEAP if not value.startswith("discovery=")]
""":data:`CHEAP` with the discovery's candidates fitted as the workflow fits them (tests of
verdicts and their confidence: with one local start a baseline can stop short of its
optimum, and what an extension then "removes" is the baseline's fit, not the data's
physics)."""


def checksums(folder: Path) -> dict[str, str]:
    """SHA-256 of every file below ``folder``, by relative path."""
    return {
        str(path.relative_to(folder)): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


BAD_CELL = "1.2.3"
"""What :func:`write_run_with_bad_cell` puts in the file: a cell that is not a number."""


def write_run_with_bad_cell(source: Path, target: Path, line: int = 40) -> None:
    """Copy the run file ``source`` to ``target`` with the first data cell of ``line``
    (1-based, tab-separated) replaced by :data:`BAD_CELL`."""
    lines = Path(source).read_text().splitlines()
    cells = lines[line - 1].split("\t")
    lines[line - 1] = lines[line - 1].replace(cells[1], BAD_CELL, 1)
    Path(target).write_text("\n".join(lines) + "\n")


def failed_check_reasons(record, settings, mode_hz=None) -> list[str]:
    """Reasons of the failed record-level quality checks of one run (empty: it passes),
    from the rows the workflow writes into quality.parquet."""
    from workflow.measured.quality import quality_rows

    rows = quality_rows(record, settings, mode_hz=mode_hz)
    return [row["reason"] for row in rows if row["applied"] and not row["passed"]]


REALDATA = next(
    (
        folder
        for folder in (REPO.parent / "shared" / "realdata", REPO.parents[1] / "shared" / "realdata")
        if folder.is_dir()
    ),
    REPO.parent / "shared" / "realdata",
)
"""Real campaigns and exports, never committed: ``../shared/realdata`` beside the repository
(or beside the folder of worktrees that holds it)."""


def needs_realdata(*parts: str):
    """Mark a test that reads ``REALDATA/parts``: skipped where it is absent, a failure
    then with ``LAPJOINT_REQUIRE_REALDATA=1`` (tests/conftest.py)."""
    import pytest

    folder = REALDATA.joinpath(*parts)

    def mark(test):
        test = pytest.mark.skipif(not folder.is_dir(), reason=f"real data not present at {folder}")(test)
        return pytest.mark.group("realdata")(test)

    return mark

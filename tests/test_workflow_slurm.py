"""Smoke test: the workflow runs unchanged on SLURM and gives the local run's results.

Runs a small generated campaign (one configuration, two runs) up to its tables and
a figure through
``snakemake --executor slurm --profile profiles/slurm`` and through ``snakemake -c2``,
then checks that both produced the same outputs and equal Parquet tables (compared
with pandas, not byte for byte: Parquet files embed writer metadata).

Needs a SLURM cluster that answers ``sinfo`` and the executor plugin
(``pip install -e '.[slurm]'``); otherwise it is skipped with the reason. On this
machine, as root: ``.ci/slurm_up.sh --install``, then
``pytest tests/test_workflow_slurm.py``, then ``.ci/slurm_down.sh``. With
``LAPJOINT_REQUIRE_SLURM=1`` (as in CI) a missing cluster fails the test instead.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]
PROFILE = ROOT / "profiles" / "slurm"
SNAKEFILE = ROOT / "Snakefile"
TIMEOUT_S = 600
# The measured-data chain through SLURM in six job levels (identify_mode with the first group
# of runs, analyse_runs per further group, collect_tables, usable_segments, fit_curves, then
# the figures): every kind of step but the friction-model fits, which take minutes and add
# nothing SLURM-specific.
TARGETS = [
    "results/tables/segments.parquet",
    "results/tables/runs.parquet",
    "results/tables/damping_fits.parquet",
    "results/tables/hypotheses.parquet",
    "results/figures/backbone_no_washer.png",
]


def slurm_unavailable() -> str | None:
    """Why the smoke test cannot run here, or None if it can."""
    if importlib.util.find_spec("snakemake_executor_plugin_slurm") is None:
        return "snakemake-executor-plugin-slurm is not installed (pip install -e '.[slurm]')"
    if shutil.which("sinfo") is None:
        return "no SLURM client (sinfo) on PATH; as root, .ci/slurm_up.sh --install starts one"
    try:
        answer = subprocess.run(
            ["sinfo", "--noheader", "--format=%T"],
            capture_output=True,
            text=True,
            timeout=20,
        )
    except subprocess.TimeoutExpired:
        return "sinfo did not answer within 20 s"
    if answer.returncode != 0:
        first = (answer.stderr.strip().splitlines() or ["no message"])[-1]
        return f"no SLURM controller answers sinfo ({first}); as root, .ci/slurm_up.sh starts one"
    states = {line.strip().rstrip("*~#!%$@^-") for line in answer.stdout.splitlines()}
    if not states & {"idle", "mixed", "allocated", "completing"}:
        return f"no SLURM node is up (node states: {sorted(states) or 'none'})"
    return None


REASON = slurm_unavailable()
REQUIRED = os.environ.get("LAPJOINT_REQUIRE_SLURM") == "1"
pytestmark = [
    pytest.mark.group("slurm"),
    pytest.mark.skipif(REASON is not None and not REQUIRED, reason=f"SLURM smoke test: {REASON}"),
]


def snakemake(workdir: Path, campaign: Path, *options: str) -> tuple[float, str]:
    """Run the workflow to TARGETS on `campaign` in `workdir`; return seconds and log."""
    command = [
        sys.executable,
        "-m",
        "snakemake",
        *TARGETS,
        "-s",
        str(SNAKEFILE),
        "-d",
        str(workdir),
        *options,
        "--config",
        f"campaign={campaign}",
    ]
    start = time.perf_counter()
    # Own session, so that a time-out ends snakemake and every job script it started.
    process = subprocess.Popen(
        command,
        cwd=workdir,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        log, _ = process.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGTERM)
        try:
            log, _ = process.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            log, _ = process.communicate()
        pytest.fail(f"{' '.join(command)} did not finish in {TIMEOUT_S} s\n{log[-6000:]}")
    seconds = time.perf_counter() - start
    if process.returncode != 0:
        slurm_logs = sorted((workdir / ".snakemake" / "slurm_logs").rglob("*.log"))
        rule_logs = sorted((workdir / "results" / "logs").rglob("*.log"))
        details = "\n".join(
            f"---- {log}\n{log.read_text(errors='replace')[-3000:]}" for log in [*slurm_logs, *rule_logs]
        )
        pytest.fail(
            f"{' '.join(command)} exited {process.returncode} after {seconds:.0f} s\n"
            f"{log[-6000:]}\n{details}",
            pytrace=False,
        )
    return seconds, log


def outputs(workdir: Path) -> set[str]:
    """Result files (tables, figures, interim data), without logs and timings."""
    results = workdir / "results"
    return {
        str(path.relative_to(results))
        for path in results.rglob("*")
        if path.is_file() and path.relative_to(results).parts[0] not in {"logs", "benchmarks"}
    }


def test_slurm_run_equals_local_run():
    if REASON is not None:
        pytest.fail(f"LAPJOINT_REQUIRE_SLURM=1 but {REASON}", pytrace=False)
    from workflow.lab.campaigns import generate_campaign

    base = Path(tempfile.mkdtemp(prefix="lapjoint-slurm-test-"))
    try:
        campaign = base / "campaign"
        generate_campaign(
            campaign,
            seed=11,
            runs_per_configuration=2,
            configurations={"no_washer": 1.36},
        )
        on_slurm = base / "slurm"
        local = base / "local"
        on_slurm.mkdir()
        local.mkdir()

        slurm_s, slurm_log = snakemake(on_slurm, campaign, "--executor", "slurm", "--profile", str(PROFILE))
        local_s, _ = snakemake(local, campaign, "-c2")
        print(f"SLURM run {slurm_s:.1f} s, local -c2 run {local_s:.1f} s")

        assert "SLURM jobid" in slurm_log, "the SLURM run submitted no job to SLURM"
        produced = outputs(on_slurm)
        assert produced == outputs(local)
        tables = sorted(name for name in produced if name.startswith("tables/"))
        assert {"tables/segments.parquet", "tables/runs.parquet", "tables/runs.csv"} <= set(tables)
        assert any(name.startswith("figures/") for name in produced)
        for name in tables:
            if name.endswith(".csv"):
                from_slurm, from_local = ((d / "results" / name).read_bytes() for d in (on_slurm, local))
                assert from_slurm == from_local, name
                continue
            from_slurm = pd.read_parquet(on_slurm / "results" / name)
            from_local = pd.read_parquet(local / "results" / name)
            pd.testing.assert_frame_equal(from_slurm, from_local, check_exact=True, obj=name)
        segments = pd.read_parquet(on_slurm / "results" / "tables" / "segments.parquet")
        assert len(segments) > 0, "the SLURM run kept no segment"
    finally:
        shutil.rmtree(base, ignore_errors=True)

"""A workflow killed mid-way resumes cleanly (issue 7).

``snakemake`` is started on a small campaign, SIGKILLed with all its jobs after
some per-run results exist but before the campaign tables do (the kill of a power
loss or the OOM killer: no clean-up runs), and started again with the same plain
command. The resumed run must complete and give the same tables and documents as
an uninterrupted run in another working directory, leave no temporary file in
results/, and leave the raw files untouched.
"""

from __future__ import annotations

import functools
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq
import pytest
from helpers import checksums, run_snakemake

from workflow.lab.campaigns import generate_campaign
from workflow.runtime import locks

REPO = Path(__file__).resolve().parents[1]
CONFIGURATIONS = {"no_washer": 1.36, "small_washer": 0.17}
# The measured-data chain's part of ``all`` (the friction-model fits take minutes).
TARGETS = [
    "results/tables/segments.parquet",
    "results/tables/runs.parquet",
    "results/tables/damping_fits.parquet",
    "results/tables/hypotheses.parquet",
    "results/figures/fig09_time_history.png",
    "results/figures/fig13_area_fits.png",
    "results/figures/fig10_damping_no_washer.png",
    "results/figures/fig11_damping_small_washer.png",
    "results/figures/backbone_no_washer.png",
    "results/figures/backbone_small_washer.png",
]


snakemake = functools.partial(run_snakemake, timeout=600)
# One run per job (a configuration's first in its identify_mode job): the kill then lands
# between per-run results.
ONE_RUN_PER_JOB = "runs_per_job=1"


def start_snakemake(workdir: Path, campaign: Path, output: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "snakemake",
            "-s",
            str(REPO / "Snakefile"),
            "-d",
            str(workdir),
            "-c2",
            *TARGETS,
            "--config",
            f"campaign={campaign}",
            ONE_RUN_PER_JOB,
        ],
        stdout=output.open("w"),
        stderr=subprocess.STDOUT,
        env=env,
        start_new_session=True,  # its own process group: the kill takes every job with it
    )


def kill_mid_way(process: subprocess.Popen, workdir: Path, timeout_s: float = 300) -> int:
    """SIGKILL the run's process group once some runs are analysed but the campaign
    tables are not yet written; return how many per-run tables existed."""
    interim = workdir / "results/interim/segments"
    final = workdir / "results/tables/segments.parquet"
    deadline = time.monotonic() + timeout_s
    try:
        while time.monotonic() < deadline and process.poll() is None:
            done = list(interim.rglob("*.npz")) if interim.is_dir() else []
            if len(done) >= 2 and not final.exists():
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
                return len(done)
            time.sleep(0.02)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    pytest.fail("the workflow was not caught between the per-run tables and the campaign tables")


def result_files(workdir: Path) -> set[str]:
    """Everything under results/ except logs and benchmarks (timestamps, timings)."""
    results = workdir / "results"
    return {
        path.relative_to(results).as_posix()
        for path in results.rglob("*")
        if path.is_file() and path.relative_to(results).parts[0] not in ("logs", "benchmarks")
    }


@pytest.fixture(scope="module")
def interrupted_and_reference(tmp_path_factory):
    root = tmp_path_factory.mktemp("interrupt")
    campaign = root / "campaign"
    generate_campaign(campaign, seed=21, runs_per_configuration=2, configurations=CONFIGURATIONS)
    raw_before = checksums(campaign)

    killed = root / "killed"
    killed.mkdir()
    first = start_snakemake(killed, campaign, root / "killed.log")
    n_done = kill_mid_way(first, killed)
    left = {
        "locks": sorted(p.name for p in (killed / ".snakemake/locks").glob("*.lock")),
        "incomplete": len(list((killed / ".snakemake/incomplete").glob("*"))),
        "n_done": n_done,
    }
    # What a kill during a table or figure write leaves: its temporary file (the
    # target itself is only ever renamed into place, complete).
    stale = [
        killed / "results/tables/.segments.parquet.k1ll3d",
        killed / "results/figures/.fig09_time_history.tmp.png",
    ]
    for path in stale:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"PAR1 truncated")

    resumed = snakemake(killed, "-c2", *TARGETS, "--config", f"campaign={campaign}", ONE_RUN_PER_JOB)

    reference = root / "reference"
    reference.mkdir()
    uninterrupted = snakemake(reference, "-c2", *TARGETS, "--config", f"campaign={campaign}", ONE_RUN_PER_JOB)
    return {
        "campaign": campaign,
        "raw_before": raw_before,
        "killed": killed,
        "reference": reference,
        "left": left,
        "resumed": resumed,
        "uninterrupted": uninterrupted,
    }


def test_the_kill_left_an_interrupted_run_behind(interrupted_and_reference):
    # The scenario is real: Snakemake's lock files and incomplete markers stayed.
    left = interrupted_and_reference["left"]
    assert left["n_done"] >= 2
    assert left["locks"], "no stale lock: the process was not killed mid-way"


def test_plain_rerun_completes(interrupted_and_reference):
    resumed = interrupted_and_reference["resumed"]
    assert resumed.returncode == 0, resumed.stderr[-4000:]
    assert "removed stale lock .snakemake/locks/" in resumed.stderr
    assert "LockException" not in resumed.stderr
    uninterrupted = interrupted_and_reference["uninterrupted"]
    assert uninterrupted.returncode == 0, uninterrupted.stderr[-4000:]
    assert "removed stale lock" not in uninterrupted.stderr


def test_resumed_results_equal_an_uninterrupted_run(interrupted_and_reference):
    killed = interrupted_and_reference["killed"]
    reference = interrupted_and_reference["reference"]
    files = result_files(reference)
    assert result_files(killed) == files
    parquet = sorted(name for name in files if name.endswith(".parquet"))
    documents = sorted(name for name in files if name.endswith(".json"))
    assert "tables/segments.parquet" in parquet and "tables/runs.parquet" in parquet
    assert len(documents) >= 7  # the campaign, modes and run statuses
    for name in parquet:
        ours, theirs = killed / "results" / name, reference / "results" / name
        pd.testing.assert_frame_equal(pd.read_parquet(ours), pd.read_parquet(theirs), check_exact=True)
        assert pq.read_schema(ours).equals(pq.read_schema(theirs), check_metadata=True), name
    for name in documents:
        ours = json.loads((killed / "results" / name).read_text())
        assert ours == json.loads((reference / "results" / name).read_text()), name
    runs = pd.read_parquet(killed / "results/tables/runs.parquet")
    assert (runs["status"] == "used").all() and len(runs) == 4


def test_no_temporary_or_truncated_file_remains(interrupted_and_reference):
    results = interrupted_and_reference["killed"] / "results"
    hidden = sorted(p.relative_to(results).as_posix() for p in results.rglob(".*"))
    assert hidden == []
    for path in results.rglob("*.parquet"):
        pq.read_metadata(path)  # a truncated Parquet file has no footer and fails here


def test_nothing_left_to_do_after_the_resumed_run(interrupted_and_reference):
    killed = interrupted_and_reference["killed"]
    campaign = interrupted_and_reference["campaign"]
    result = snakemake(killed, "-n", "-c2", *TARGETS, "--config", f"campaign={campaign}", ONE_RUN_PER_JOB)
    assert result.returncode == 0, result.stderr[-2000:]
    assert "Nothing to be done" in result.stdout + result.stderr


def test_raw_files_unchanged(interrupted_and_reference):
    campaign = interrupted_and_reference["campaign"]
    assert checksums(campaign) == interrupted_and_reference["raw_before"]


# ------------------------------------------------------------------ stale-lock detection


HOLDER = """
import sys, time
from workflow.runtime.locks import clear_stale_snakemake_locks
clear_stale_snakemake_locks(sys.argv[1])
print("holding", flush=True)
time.sleep(60)
"""


def _fake_locks(workdir: Path) -> Path:
    folder = workdir / ".snakemake" / "locks"
    folder.mkdir(parents=True)
    for name in ("0.input.lock", "0.output.lock"):
        (folder / name).write_text("results/tables/segments.parquet\n")
    return folder


def test_locks_of_a_live_run_are_kept(tmp_path, monkeypatch):
    monkeypatch.setattr(locks, "_held", None)
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(tmp_path)],
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(REPO)},
    )
    try:
        assert holder.stdout.readline().strip() == "holding"
        folder = _fake_locks(tmp_path)  # the live run's locks
        assert locks.clear_stale_snakemake_locks(tmp_path) == []
        assert sorted(p.name for p in folder.iterdir()) == ["0.input.lock", "0.output.lock"]
    finally:
        holder.kill()
        holder.wait()
    # Its holder dead, the same locks are stale and go.
    assert locks.clear_stale_snakemake_locks(tmp_path) == ["0.input.lock", "0.output.lock"]
    assert list(folder.iterdir()) == []


def test_stale_locks_go_once_per_process(tmp_path, monkeypatch):
    monkeypatch.setattr(locks, "_held", None)
    folder = _fake_locks(tmp_path)
    assert locks.clear_stale_snakemake_locks(tmp_path) == ["0.input.lock", "0.output.lock"]
    _fake_locks_again = folder / "0.input.lock"
    _fake_locks_again.write_text("x\n")  # this process's own Snakemake lock from now on
    assert locks.clear_stale_snakemake_locks(tmp_path) == []
    assert _fake_locks_again.exists()

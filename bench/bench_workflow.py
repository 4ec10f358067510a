"""Workflow timings on the demo campaign (issues 6 and 16), as a table of medians.

    python bench/bench_workflow.py [--repeats 3] [--target all] [--scale]
    python bench/bench_workflow.py --only high_rate runs300 [--repeats 3]

For each repeat, in a fresh working directory: the demo campaign is generated
first (its own rule, timed apart), then a cold ``snakemake -c2 TARGET``, a run with
nothing to do, and a run after changing ``analysis.segment_cycles``. ``--scale``
adds, each repeated as often and cold: one impact hit recorded by three sensors at
12.8 kHz for 5 s (64000 samples a channel, analysed as three one-run
configurations), a 300-run campaign (10 configurations x 30 runs) for the growth with
runs, and the demo's 30 runs with records 4 times as long (32768 samples) for the
growth with record length; ``--only`` runs just the named ones of these (cold, no demo).
Per rule: wall time from Snakemake's
``benchmark:`` files, and each job's CPU split into start-up (interpreter, Snakemake's
script preamble, imports) and work, with its peak memory, from the cost line that every
script logs (workflow/runtime/logs.py), summed over the rule's jobs (``cpu_s``) and over
every job (the total the tables print under them).
"""

import argparse
import glob
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

REPO = Path(__file__).resolve().parents[1]


def snakemake(workdir: Path, *args: str) -> float:
    """Wall time of one ``snakemake -c2`` call in ``workdir``, seconds."""
    start = time.perf_counter()
    subprocess.run(
        [
            sys.executable,
            "-m",
            "snakemake",
            "-s",
            str(REPO / "Snakefile"),
            "-d",
            str(workdir),
            "-c2",
            *args,
            "--quiet",
            "all",
        ],
        check=True,
        capture_output=True,
    )
    return time.perf_counter() - start


COST = re.compile(
    r" (\S+) INFO cost: start-up ([0-9.]+) s CPU, work ([0-9.]+) s CPU, peak memory ([0-9]+) MB"
)


def rule_table(workdir: Path) -> pd.DataFrame:
    """Per rule: jobs, wall seconds (Snakemake's benchmark files), and the split of each
    job's CPU time into start-up and work with its peak memory (the cost line every
    script logs, workflow/runtime/logs.py)."""
    walls, costs = [], []
    for path in glob.glob(str(workdir / "results/benchmarks/**/*.tsv"), recursive=True):
        rule = Path(path).relative_to(workdir / "results/benchmarks").parts[0].removesuffix(".tsv")
        walls.append({"rule": rule, "wall_s": pd.read_csv(path, sep="\t")["s"].iloc[0]})
    for path in glob.glob(str(workdir / "results/logs/**/*.log"), recursive=True):
        found = COST.search(Path(path).read_text())
        if found:
            rule, start_up, work, peak = found.groups()
            costs.append(
                {
                    "rule": rule,
                    "start_up_s": float(start_up),
                    "work_s": float(work),
                    "cpu_s": float(start_up) + float(work),
                    "peak_mb": float(peak),
                }
            )
    wall = (
        pd.DataFrame(walls)
        .groupby("rule")
        .agg(jobs=("wall_s", "size"), median_wall_s=("wall_s", "median"), total_wall_s=("wall_s", "sum"))
    )
    cost = (
        pd.DataFrame(costs)
        .groupby("rule")
        .agg(
            median_start_up_s=("start_up_s", "median"),
            median_work_s=("work_s", "median"),
            cpu_s=("cpu_s", "sum"),
            peak_mb=("peak_mb", "max"),
        )
    )
    return wall.join(cost, how="outer").round(2).sort_values("cpu_s", ascending=False)


def print_rule_table(workdir: Path) -> None:
    """The per-rule table of a run and the CPU seconds of all its jobs."""
    table = rule_table(workdir)
    print(table.to_string())
    print(f"CPU of all jobs (start-up + work): {table['cpu_s'].sum():.1f} s")


def cold_runs(campaign: Path, target: str, repeats: int) -> tuple[list[float], Path]:
    """Wall times of ``repeats`` cold runs of ``target`` on ``campaign``, and the last workdir."""
    seconds = []
    for _ in range(repeats):
        workdir = Path(tempfile.mkdtemp(prefix="lapjoint-bench-scale-"))
        seconds.append(snakemake(workdir, target, "--config", f"campaign={campaign}"))
    return seconds, workdir


HIGH_RATE_HZ = 12800.0
HIGH_RATE_SAMPLES = 64000
SENSOR_GAINS = {"accelerometer": 1.0, "mid": 0.6, "end": 0.3}
"""Mode 1 at each of the three sensors, relative to the accelerometer."""


def high_rate_hit(root: Path) -> Path:
    """One hit recorded by three sensors at 12.8 kHz for 5 s, as a campaign whose
    configurations are the sensors (one run each): the virtual lab writes each sensor's
    record, and they are gathered into one campaign folder."""
    from workflow.lab.virtual_lab import LabSettings, generate_sensor_campaigns

    settings = LabSettings(sample_rate_hz=HIGH_RATE_HZ, samples_per_run=HIGH_RATE_SAMPLES)
    generate_sensor_campaigns(
        root / "sensors",
        SENSOR_GAINS,
        seed=7,
        runs_per_configuration=1,
        configurations={"hit": None},
        settings=settings,
    )
    campaign = root / "high_rate"
    lines = (root / "sensors" / "accelerometer" / "campaign.yaml").read_text().splitlines()
    lines = lines[: lines.index("configurations:") + 1]
    for sensor in SENSOR_GAINS:
        (campaign / sensor).mkdir(parents=True)
        (root / "sensors" / sensor / "hit" / "run01.txt").rename(campaign / sensor / "run01.txt")
        lines.append(f'  {sensor}: {{files: "{sensor}/*.txt"}}')
    (campaign / "campaign.yaml").write_text("\n".join(lines) + "\n")
    return campaign


SCALE_CAMPAIGNS = {
    "high_rate": "one hit, three sensors at 12.8 kHz for 5 s (three one-run configurations)",
    "runs300": "300 runs (10 x 30)",
    "long": "30 runs of 32768 samples (4 x longer records)",
}


def scale_campaigns(root: Path, names: list[str]) -> dict[str, Path]:
    """The named campaigns of :data:`SCALE_CAMPAIGNS`, generated under ``root``."""
    from workflow.lab.virtual_lab import generate_campaign

    campaigns = {}
    for name in names:
        if name == "high_rate":
            campaigns[name] = high_rate_hit(root)
        elif name == "runs300":
            campaigns[name] = root / "runs300"
            generate_campaign(
                campaigns[name],
                seed=3,
                runs_per_configuration=30,
                configurations={f"c{index:02d}": 0.17 + 0.12 * index for index in range(10)},
            )
        else:
            campaigns[name] = root / "long"
            generate_campaign(campaigns[name], seed=3, samples_per_run=4 * 8192)
    return campaigns


def run_scale(names: list[str], target: str, repeats: int, reference: float | None) -> None:
    """Cold runs of the named scale campaigns, each with its per-rule table."""
    root = Path(tempfile.mkdtemp(prefix="lapjoint-scale-"))
    for name, campaign in scale_campaigns(root, names).items():
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        seconds, workdir = cold_runs(campaign, target, repeats)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu_s = (after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime) / repeats
        median = statistics.median(seconds)
        versus = f" = {median / reference:.2f} x the 30-run demo time" if reference else ""
        print(
            f"\n{SCALE_CAMPAIGNS[name]}, cold {target}: {median:.1f} s (median of {repeats}){versus}, "
            f"{cpu_s:.1f} s CPU a run (Snakemake and its jobs, mean)"
        )
        print_rule_table(workdir)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--target", default="all")
    parser.add_argument("--scale", action="store_true")
    parser.add_argument("--only", nargs="+", choices=list(SCALE_CAMPAIGNS))
    args = parser.parse_args()
    if args.only:
        run_scale(args.only, args.target, args.repeats, None)
        return
    cold = f"cold {args.target}"
    timings: dict[str, list[float]] = {
        "demo generation": [],
        cold: [],
        "nothing to do": [],
        "segment_cycles changed": [],
    }
    last = None
    for _ in range(args.repeats):
        workdir = Path(tempfile.mkdtemp(prefix="lapjoint-bench-"))
        timings["demo generation"].append(snakemake(workdir, "demo_campaign"))
        timings[cold].append(snakemake(workdir, args.target))
        timings["nothing to do"].append(snakemake(workdir, args.target))
        timings["segment_cycles changed"].append(
            snakemake(workdir, args.target, "--config", "analysis={segment_cycles: 8}")
        )
        last = workdir
    print(f"| step (median of {args.repeats}, 2 cores) | seconds |")
    print("|---|---|")
    for name, values in timings.items():
        print(f"| {name} | {statistics.median(values):.1f} |")
    print()
    print("Per rule, cold run (last repeat):")
    print_rule_table(last)
    if args.scale:
        run_scale(list(SCALE_CAMPAIGNS), args.target, args.repeats, statistics.median(timings[cold]))


if __name__ == "__main__":
    main()

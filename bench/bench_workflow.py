"""Workflow timings on the demo campaign (issue 6 targets), as a table of medians.

    python bench/bench_workflow.py [--repeats 3] [--target measured] [--scale]

For each repeat, in a fresh working directory: the demo campaign is generated
first (its own rule, timed apart), then a cold ``snakemake -c2 TARGET``, a run with
nothing to do, and a run after changing ``analysis.segment_cycles``. ``--scale``
adds a 300-run campaign (10 configurations x 30 runs) for the growth with runs, and
the demo's 30 runs with records 4 times as long (32768 samples) for the growth with
record length. Peak memory per rule comes from Snakemake's ``benchmark:`` files.
"""

import argparse
import glob
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
    subprocess.run([sys.executable, "-m", "snakemake", "-s", str(REPO / "Snakefile"), "-d", str(workdir),
                    "-c2", *args, "--quiet", "all"], check=True, capture_output=True)
    return time.perf_counter() - start


def rule_table(workdir: Path) -> pd.DataFrame:
    rows = []
    for path in glob.glob(str(workdir / "results/benchmarks/**/*.tsv"), recursive=True):
        frame = pd.read_csv(path, sep="\t")
        rule = Path(path).relative_to(workdir / "results/benchmarks").parts[0].removesuffix(".tsv")
        rows.append({"rule": rule, "s": frame["s"].iloc[0], "max_rss_mb": frame["max_rss"].iloc[0]})
    table = pd.DataFrame(rows)
    return table.groupby("rule").agg(jobs=("s", "size"), median_s=("s", "median"), total_s=("s", "sum"),
                                     peak_rss_mb=("max_rss_mb", "max"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--target", default="measured")
    parser.add_argument("--scale", action="store_true")
    args = parser.parse_args()
    timings: dict[str, list[float]] = {"demo generation": [], f"cold {args.target}": [],
                                       "nothing to do": [], "segment_cycles changed": []}
    last = None
    for _ in range(args.repeats):
        workdir = Path(tempfile.mkdtemp(prefix="lapjoint-bench-"))
        timings["demo generation"].append(snakemake(workdir, "demo_campaign"))
        timings[f"cold {args.target}"].append(snakemake(workdir, args.target))
        timings["nothing to do"].append(snakemake(workdir, args.target))
        timings["segment_cycles changed"].append(
            snakemake(workdir, args.target, "--config", "analysis={segment_cycles: 8}"))
        last = workdir
    print(f"| step (median of {args.repeats}, 2 cores) | seconds |")
    print("|---|---|")
    for name, values in timings.items():
        print(f"| {name} | {statistics.median(values):.1f} |")
    print()
    print("Per rule, cold run (Snakemake benchmark files, last repeat):")
    print(rule_table(last).to_string())
    if args.scale:
        from workflow.virtual_lab import generate_campaign

        campaign = Path(tempfile.mkdtemp(prefix="lapjoint-300-")) / "campaign"
        generate_campaign(campaign, seed=3, runs_per_configuration=30,
                          configurations={f"c{index:02d}": 0.17 + 0.12 * index for index in range(10)})
        workdir = Path(tempfile.mkdtemp(prefix="lapjoint-bench-300-"))
        seconds = snakemake(workdir, args.target, "--config", f"campaign={campaign}")
        ratio = seconds / statistics.median(timings[f"cold {args.target}"])
        print(f"\n300 runs (10 x 30), cold {args.target}: {seconds:.1f} s = {ratio:.1f} x the 30-run time")
        print(rule_table(workdir).to_string())

        campaign = Path(tempfile.mkdtemp(prefix="lapjoint-long-")) / "campaign"
        generate_campaign(campaign, seed=3, samples_per_run=4 * 8192)
        workdir = Path(tempfile.mkdtemp(prefix="lapjoint-bench-long-"))
        seconds = snakemake(workdir, args.target, "--config", f"campaign={campaign}")
        ratio = seconds / statistics.median(timings[f"cold {args.target}"])
        print(f"\n30 runs of 32768 samples (4 x longer), cold {args.target}: {seconds:.1f} s "
              f"= {ratio:.1f} x the 8192-sample time")
        print(rule_table(workdir).to_string())


if __name__ == "__main__":
    main()

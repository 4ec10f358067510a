"""Peak memory of reading and analysing long ASCII run files, against the ``mem_mb``
the rules declare for the jobs that do it (workflow/runtime/resources.py).

Run: ``PYTHONPATH=$PWD .venv/bin/python bench/bench_long_record_memory.py [size_mb]``
(default 200). Writes a ring-down of about ``size_mb`` MB (time, force, response at
25.6 kHz) to a temporary campaign, then runs each stage in a fresh process and prints
its peak resident memory (``VmHWM``): the interpreter and imports alone, the reader
(``read_run``), the whole ``identify_mode`` job on a configuration of two such runs (as
scripts/identify_mode.py does it: every run read and held for the mode search, then its
first group, here both runs, analysed from the runs held) and the whole ``analyse_runs``
work for one run (a later group's); beside each, the bytes per sample above the imports.
"""

import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from workflow.runtime.resources import analyse_runs_mem_mb, identify_mode_mem_mb

REPO = Path(__file__).resolve().parents[1]
SAMPLE_RATE_HZ = 25600.0
BYTES_PER_ROW = 36  # "0.0000391\t0.001234567\t-0.000123456\n" with 9 significant digits

STAGES = {
    "imports": "",
    "read_run": "record = read_run(root, 'long/run01.txt', campaign)",
    "identify_mode": (
        "reads = read_runs(root, RUNS, campaign, quality_settings)\n"
        "found = identify_configuration_mode(root, RUNS, configuration='long', campaign=campaign,\n"
        "    mode_search=AnalysisSettings(), quality_settings=quality_settings, reads=reads)\n"
        "write_mode(sys.argv[2], found)\n"
        "results = analyse_run_group(root, RUNS, reads=reads, configuration='long', campaign=campaign,\n"
        "    mode=found, quality_settings=quality_settings, decay_settings=AnalysisSettings())\n"
        "print([result.status['status'] for result in results], found.mode)"
    ),
    "analyse_runs": (
        "result = analyse_run_file(root, 'long/run01.txt', configuration='long', campaign=campaign,\n"
        "    mode=read_mode(sys.argv[2]), quality_settings=quality_settings,\n"
        "    decay_settings=AnalysisSettings())\n"
        "print(result.status['status'], result.status['reason'])"
    ),
}

PRELUDE = """
import sys
from pathlib import Path
from workflow.io.campaign import load_campaign
from workflow.io.run_files import read_run
from workflow.io.interim import read_mode, write_mode
from workflow.measured.settings import AnalysisSettings, QualitySettings
from workflow.measured.mode_identification import identify_configuration_mode
from workflow.measured.runs import analyse_run_file, analyse_run_group, read_runs
root = Path(sys.argv[1])
RUNS = ['long/run01.txt', 'long/run02.txt']
campaign = load_campaign(root)
quality_settings = QualitySettings()
"""


# VmHWM of the process's own memory map: ru_maxrss would also count the parent's
# memory, which Linux carries across the exec of a spawned child.
PEAK = "\nprint(next(line.split()[1] for line in open('/proc/self/status') if line.startswith('VmHWM:')))\n"


def write_campaign(root: Path, size_mb: float) -> Path:
    n = int(size_mb * 1e6 / BYTES_PER_ROW)
    t = np.arange(n) / SAMPLE_RATE_HZ
    force = 50.0 * np.exp(-(((t - 0.01) / 0.0002) ** 2))
    response = 3.0 * np.exp(-0.5 * t) * np.sin(2 * np.pi * 125.0 * t)
    response += 1e-4 * np.random.default_rng(1).standard_normal(n)
    (root / "long").mkdir(parents=True)
    (root / "campaign.yaml").write_text(
        "name: long\nmode_hz: 125\nresponse: {quantity: acceleration, unit: g}\nforce: {unit: lbf}\n"
        "configurations:\n  long: {}\n"
    )
    path = root / "long" / "run01.txt"
    with open(path, "w") as handle:
        handle.write(f"Sample rate: {SAMPLE_RATE_HZ:g} Hz\nTime (s)\tForce (lbf)\tAcceleration (g)\n")
        np.savetxt(
            handle, np.column_stack([t, force, response]), fmt=("%.7f", "%.9f", "%.9f"), delimiter="\t"
        )
    shutil.copyfile(path, root / "long" / "run02.txt")
    return path


def peak_mb(stage: str, root: Path, *extra: str) -> tuple[float, float, str]:
    """Peak RSS (MB, 1e6 bytes, as ``mem_mb``), wall time (s) and last stdout line of one
    stage in a fresh process."""
    start = time.perf_counter()
    result = subprocess.run(
        [sys.executable, "-c", PRELUDE + STAGES[stage] + PEAK, str(root), *extra],
        capture_output=True,
        text=True,
        check=True,
        cwd=REPO,
    )
    elapsed_s = time.perf_counter() - start
    *output, peak_kb = result.stdout.strip().splitlines()
    return int(peak_kb) * 1024 / 1e6, elapsed_s, output[-1] if output else ""


def main(size_mb: float = 200.0) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        path = write_campaign(root, size_mb)
        file_mb = path.stat().st_size / 1e6
        n_samples = sum(1 for _ in open(path)) - 2
        print(f"run file: {file_mb:.0f} MB, {n_samples} samples")
        runs = [path, root / "long" / "run02.txt"]
        declared = {
            "identify_mode": identify_mode_mem_mb(runs, runs),
            "analyse_runs": analyse_runs_mem_mb([path]),
        }
        print(f"{'stage':<16}{'peak MB':>9}{'B/sample':>9}{'wall s':>8}  declared mem_mb")
        mode_path = str(root / "mode.json")
        imports_mb = 0.0
        for stage, extra, what in (
            ("imports", (), ""),
            ("read_run", (), ""),
            ("identify_mode", (mode_path,), "2 runs held, both analysed"),
            ("analyse_runs", (mode_path,), "1 run"),
        ):
            peak, elapsed_s, last = peak_mb(stage, root, *extra)
            imports_mb = imports_mb or peak
            per_sample = (peak - imports_mb) * 1e6 / n_samples
            line = f"{stage:<16}{peak:>9.0f}{per_sample:>9.0f}{elapsed_s:>8.1f}"
            if stage in declared:
                within = "within" if peak <= declared[stage] else "ABOVE"
                line += f"  {declared[stage]} ({within}; {what}; {last.strip()[:60]})"
            print(line)


if __name__ == "__main__":
    main(*(float(arg) for arg in sys.argv[1:2]))

"""Peak memory of reading and analysing one long ASCII run file, against the ``mem_mb``
the rules declare for the jobs that do it.

Run: ``PYTHONPATH=$PWD .venv/bin/python bench/bench_long_record_memory.py [size_mb]``
(default 200). Writes a ring-down of about ``size_mb`` MB (time, force, response at
25.6 kHz) to a temporary campaign, then runs each stage in a fresh process and prints
its peak resident memory (``VmHWM``): the interpreter and imports alone, the reader
(``read_run``), the mode search of ``identify_mode`` and the whole ``analyse_runs`` work
for that run.
"""

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
SAMPLE_RATE_HZ = 25600.0
BYTES_PER_ROW = 36  # "0.0000391\t0.001234567\t-0.000123456\n" with 9 significant digits

STAGES = {
    "imports": "",
    "read_run": "record = read_run(root, 'long/run01.txt', campaign)",
    "identify_mode": (
        "record, problems = read_and_check(root, 'long/run01.txt', campaign, quality_settings)\n"
        "mode = identify_mode([record], windows=[(0, record.n_samples)], campaign_mode_hz=campaign.mode_hz,\n"
        "    campaign_band_hz=None, band_half_width=0.2, mode_search_hz=None, mode_search_fraction=0.3)\n"
        "print(json.dumps(mode.to_dict()))"
    ),
    "analyse_runs": (
        "result = analyse_run_file(root, 'long/run01.txt', configuration='long', campaign=campaign,\n"
        "    mode_document=MODE, quality_settings=quality_settings, analysis=AnalysisSettings().run_parameters())\n"
        "print(result.status['status'], result.status['reason'])"
    ),
}

PRELUDE = """
import json, sys
from pathlib import Path
from workflow.io.campaign import load_campaign, read_run
from workflow.io.settings import AnalysisSettings, QualitySettings
from workflow.measured.runs import analyse_run_file, identify_mode, read_and_check
root = Path(sys.argv[1])
MODE = json.loads(sys.argv[2]) if len(sys.argv) > 2 else None
campaign = load_campaign(root)
quality_settings = QualitySettings()
"""


# VmHWM of the process's own memory map: ru_maxrss would also count the parent's
# memory, which Linux carries across the exec of a spawned child.
PEAK = "\nprint(next(line.split()[1] for line in open('/proc/self/status') if line.startswith('VmHWM:')))\n"


def declared_mem_mb() -> dict[str, int]:
    """``mem_mb`` of the rules that read whole run files."""
    text = (REPO / "rules" / "measured.smk").read_text()
    found = {}
    for rule in ("identify_mode", "analyse_runs"):
        block = text[text.index(f"rule {rule}:") :]
        found[rule] = int(re.search(r"mem_mb=(\d+)", block).group(1))
    return found


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
    return path


def peak_mb(stage: str, root: Path, *extra: str) -> tuple[float, float, str]:
    """Peak RSS (MB), wall time (s) and last stdout line of one stage in a fresh process."""
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
    return int(peak_kb) / 1024.0, elapsed_s, output[-1] if output else ""


def main(size_mb: float = 200.0) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        path = write_campaign(root, size_mb)
        file_mb = path.stat().st_size / 1e6
        print(f"run file: {file_mb:.0f} MB, {sum(1 for _ in open(path)) - 2} samples")
        declared = declared_mem_mb()
        print(f"{'stage':<16}{'peak MB':>9}{'wall s':>8}  declared mem_mb")
        for stage in ("imports", "read_run"):
            peak, elapsed_s, _ = peak_mb(stage, root)
            print(f"{stage:<16}{peak:>9.0f}{elapsed_s:>8.1f}")
        peak, elapsed_s, mode_json = peak_mb("identify_mode", root)
        within = "within" if peak <= declared["identify_mode"] else "ABOVE"
        print(f"{'identify_mode':<16}{peak:>9.0f}{elapsed_s:>8.1f}  {declared['identify_mode']} ({within})")
        peak, elapsed_s, status = peak_mb("analyse_runs", root, mode_json)
        within = "within" if peak <= declared["analyse_runs"] else "ABOVE"
        print(
            f"{'analyse_runs':<16}{peak:>9.0f}{elapsed_s:>8.1f}  {declared['analyse_runs']} ({within}; run {status})"
        )


if __name__ == "__main__":
    main(*(float(arg) for arg in sys.argv[1:2]))

"""Time reading one run in each file format, and the import cost of each format library.

Run: ``PYTHONPATH=. .venv/bin/python bench/bench_readers.py [samples] [repeats]``.
Writes one run (force and response, ``samples`` samples, default 131072 like the real
LMS record) as ASCII, Test.Lab MAT 5, MAT 7.3, UFF58, UFF58b and TDMS with the test
suite's writers, then prints the median ``read_run`` time (warm: library imported) and,
in fresh interpreters, the median import time of scipy.io, h5py, pyuff and nptdms, the
start-up a per-run job pays once when its campaign has such a file.
"""

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from system_format_files import (  # noqa: E402
    lms_export_group,
    to_uff_ascii_precision,
    uff58_record,
    write_mat73,
    write_tdms,
    write_testlab_mat,
    write_uff58,
)

from workflow.io.campaign import load_campaign  # noqa: E402
from workflow.io.run_files import read_run  # noqa: E402

RATE_HZ = 51200.0


def write_runs(folder: Path, n: int) -> list[str]:
    rng = np.random.default_rng(1)
    force = to_uff_ascii_precision(rng.normal(size=n))
    response = to_uff_ascii_precision(rng.normal(size=n))
    dt = 1.0 / RATE_HZ
    runs = folder / "c"
    runs.mkdir(parents=True)
    rows = "\n".join(f"{f:.11e}\t{r:.11e}" for f, r in zip(force, response))
    (runs / "ascii.txt").write_text(f"Force (lbf)\tAcceleration (g)\n{rows}\n")
    groups = {
        "Force": lms_export_group(["Time Hammer:+Z"], force, "lbf", dt),
        "Signal": lms_export_group(["Time Acc1:+Z"], response, "g", dt),
    }
    write_testlab_mat(runs / "testlab.mat", groups)
    write_mat73(runs / "testlab73.mat", groups)
    for name, binary in (("uff58.uff", False), ("uff58b.uff", True)):
        write_uff58(
            runs / name,
            [
                uff58_record("Hammer", force, "lbf", 13, dt, binary=binary),
                uff58_record("Acc1", response, "g", 12, dt, binary=binary),
            ],
        )
    properties = {"wf_increment": dt}
    write_tdms(
        runs / "tdms.tdms",
        "Impact",
        {
            "Force": (force, {**properties, "unit_string": "lbf"}),
            "Acceleration": (response, {**properties, "unit_string": "g"}),
        },
    )
    (folder / "campaign.yaml").write_text(
        "name: bench\nsample_rate_hz: 51200\nresponse: {quantity: acceleration, unit: g}\n"
        'force: {unit: lbf}\nconfigurations:\n  c: {files: "c/*"}\n'
    )
    return sorted(p.name for p in runs.iterdir())


def import_seconds(module: str, repeats: int) -> float:
    code = f"import time; t = time.perf_counter(); import {module}; print(time.perf_counter() - t)"
    times = [
        float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)
        for _ in range(repeats)
    ]
    return float(np.median(times))


def main(n: int = 131072, repeats: int = 5) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        names = write_runs(folder, n)
        campaign = load_campaign(folder)
        print(f"read_run of one run, {n} samples x 2 channels (median of {repeats}, warm)")
        for name in names:
            read_run(folder, f"c/{name}", campaign)
            times = []
            for _ in range(repeats):
                start = time.perf_counter()
                read_run(folder, f"c/{name}", campaign)
                times.append(time.perf_counter() - start)
            size_mb = (folder / "c" / name).stat().st_size / 1e6
            print(f"  {name:<16}{np.median(times) * 1e3:8.1f} ms  ({size_mb:.1f} MB)")
    print(f"import in a fresh interpreter (median of {repeats})")
    for module in ("scipy.io", "h5py", "pyuff", "nptdms"):
        print(f"  {module:<16}{import_seconds(module, repeats) * 1e3:8.1f} ms")


if __name__ == "__main__":
    main(*(int(arg) for arg in sys.argv[1:]))

"""Time the generation of the 30-run demo campaign (3 configurations x 10 runs).

Run: ``.venv/bin/python bench/bench_demo_generation.py [repeats]``.
Prints the median and range over the repeats, split into the per-configuration
set-up (modal analysis, describing functions, Dahl fit) and the runs.
"""

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from workflow.lab.campaigns import generate_campaign
from workflow.lab.configurations import _configuration_physics, setup_configuration
from workflow.lab.layout import PAPER_CONFIGURATIONS
from workflow.lab.settings import LabSettings


def main(repeats: int = 5) -> None:
    totals, setups = [], []
    settings = LabSettings()
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeats):
            # cold: the per-configuration physics cache is emptied first
            _configuration_physics.cache_clear()
            start = time.perf_counter()
            for name, area in PAPER_CONFIGURATIONS.items():
                setup_configuration(name, area, settings)
            setups.append(time.perf_counter() - start)
            _configuration_physics.cache_clear()
            start = time.perf_counter()
            generate_campaign(Path(tmp) / f"demo{i}", seed=2004, runs_per_configuration=10)
            totals.append(time.perf_counter() - start)
    totals, setups = np.array(totals), np.array(setups)
    print(f"{'stage':<28}{'median s':>10}{'min s':>8}{'max s':>8}")
    for label, values in (
        ("configuration set-up (x3)", setups),
        ("30 runs (by difference)", totals - setups),
        ("generate_campaign (cold)", totals),
    ):
        print(f"{label:<28}{np.median(values):>10.2f}{values.min():>8.2f}{values.max():>8.2f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)

"""Agreement with a published peer method on a real record.

The PFF sample (../shared/realdata/pff-lms-sample, 51.2 kHz impact decay, mode near
151 Hz) ships with that method's own damping and frequency output. This runs the
measured-data chain on the record through the same library calls as the workflow's
rules and compares the two over the part of the record where both are valid (the
peer's first and last ~0.2 s carry its end effects).

    python bench/peer_comparison.py [--realdata ../shared/realdata]
"""

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from peer_speed import project_record

from workflow.io.campaign import load_campaign


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--realdata", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "realdata"
    )
    args = parser.parse_args()
    folder = args.realdata / "pff-lms-sample"
    reference = pd.read_csv(args.realdata / "pff-lms-sample.reference.csv")
    found, result = project_record(folder, load_campaign(folder))
    mode = found.mode
    segments = pd.DataFrame(result.segments)
    kept = segments[segments["kept"]]
    valid = reference[(reference["time_s"] > 0.2) & (reference["time_s"] < reference["time_s"].max() - 0.2)]
    overlap = kept[(kept["t_s"] >= valid["time_s"].min()) & (kept["t_s"] <= valid["time_s"].max())]
    peer_zeta = np.interp(overlap["t_s"], valid["time_s"], valid["damping_ratio"])
    peer_hz = np.interp(overlap["t_s"], valid["time_s"], valid["frequency_hz"])
    relative = overlap["zeta"].to_numpy() / peer_zeta - 1
    print(
        f"mode {mode.mode_hz:.2f} Hz, band {mode.band_hz[0]:.1f}-{mode.band_hz[1]:.1f} Hz; "
        f"{len(kept)} of {len(segments)} segments kept, {len(overlap)} inside the peer's valid range"
    )
    print("| quantity | median difference | median absolute difference |")
    print("|---|---|---|")
    print(
        f"| damping ratio (relative) | {100 * np.median(relative):+.1f} % | {100 * np.median(np.abs(relative)):.1f} % |"
    )
    print(
        f"| frequency | {np.median(overlap['frequency_hz'] - peer_hz):+.3f} Hz | "
        f"{np.median(np.abs(overlap['frequency_hz'] - peer_hz)):.3f} Hz |"
    )


if __name__ == "__main__":
    main()

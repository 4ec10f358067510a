"""Files of a virtual-lab campaign: run files (ASCII export, MAT 5), campaign.yaml and
where the truth lives.

The campaign folder follows ``campaign-format.md``; the truth is written
beside it as ``<campaign_dir>.truth.json`` (mode 2's as ``<campaign_dir>.mode2.truth.json``),
never inside.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from workflow.lab.settings import PRETRIGGER_SAMPLES, SAMPLE_RATE_HZ

__all__ = [
    "campaign_yaml",
    "format_run",
    "truth_path",
    "write_run_mat",
]


def format_run(
    time_s, force_lbf, acceleration_g, sample_rate_hz=SAMPLE_RATE_HZ, names=("Acceleration",)
) -> str:
    """The run file text (Dactron-like ASCII export); one acceleration column per name
    (``acceleration_g`` of shape (n,) or (n_sensors, n))."""
    columns = np.atleast_2d(acceleration_g)
    if len(names) != columns.shape[0]:
        raise ValueError(f"{len(names)} column names for {columns.shape[0]} acceleration columns")
    lines = [
        "Virtual lab ASCII export (lapjoint)",
        f"Sample rate: {sample_rate_hz:g} Hz",
        f"Pre-trigger: {PRETRIGGER_SAMPLES} samples",
        "\t".join(["Time (s)", "Force (lbf)", *(f"{name} (g)" for name in names)]),
    ]
    body = np.char.add(np.char.add(np.char.mod("%.6f", time_s), "\t"), np.char.mod("%.10g", force_lbf))
    for column in columns:
        body = np.char.add(np.char.add(body, "\t"), np.char.mod("%.10g", column))
    return "\n".join(lines + body.tolist()) + "\n"


def write_run_mat(path, time_s, force_lbf, acceleration_g, names) -> None:
    """One run as a MATLAB 5 MAT file of plain variables: ``t`` (s), ``force`` (lbf) and
    one acceleration vector (g) per sensor, named as the sensor."""
    import scipy.io

    variables = {"t": np.asarray(time_s), "force": np.asarray(force_lbf)}
    for name, column in zip(names, np.atleast_2d(acceleration_g), strict=True):
        variables[name] = column
    scipy.io.savemat(path, variables, format="5", oned_as="column")
    # the header's text holds the writing time: a fixed one keeps a seed's files identical
    with open(path, "r+b") as f:
        f.write(MAT_HEADER_TEXT.ljust(116))


MAT_HEADER_TEXT = b"MATLAB 5.0 MAT-file, written by the lapjoint virtual lab"


FILE_FORMATS = {"txt": "ASCII export", "mat": "MATLAB 5 MAT, plain variables"}


def campaign_yaml(name, configurations, modes_hz, sample_rate_hz, channels=None, file_format="txt") -> str:
    lines = [
        f"name: {name}",
        f"sample_rate_hz: {sample_rate_hz:g}",
        f"pretrigger_samples: {PRETRIGGER_SAMPLES}",
    ]
    if modes_hz == "auto":
        lines.append("modes_hz: auto")
    elif len(modes_hz) == 1:
        lines.append(f"mode_hz: {modes_hz[0]:g}")
    else:
        lines.append("modes_hz: [" + ", ".join(f"{f:g}" for f in modes_hz) + "]")
    if channels is None:
        lines.append("response: {quantity: acceleration, unit: g}")
    else:
        lines.append("response: {quantity: acceleration, unit: g, channels: [" + ", ".join(channels) + "]}")
    lines += ["force: {unit: lbf}", "configurations:"]
    for cname, area in configurations.items():
        area_part = f"bearing_area_in2: {area:g}, " if area is not None else ""
        lines.append(f'  {cname}: {{{area_part}files: "{cname}/*.{file_format}"}}')
    return "\n".join(lines) + "\n"


def truth_path(out_dir, mode: int = 1) -> Path:
    """Where the truth JSON of a campaign folder's mode lives (beside it, not inside):
    ``<campaign>.truth.json`` for mode 1, ``<campaign>.mode<k>.truth.json`` for mode k."""
    out = Path(out_dir)
    suffix = ".truth.json" if mode == 1 else f".mode{mode}.truth.json"
    return out.parent / (out.name + suffix)

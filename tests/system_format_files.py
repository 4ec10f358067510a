"""Run files in acquisition-system formats, written by each format's own library (scipy.io,
h5py, pyuff, npTDMS), for the reader tests and the mixed-format workflow test."""

from datetime import datetime, timedelta
from pathlib import Path

import numpy as np

UFF_ASCII_DIGITS = 12
"""Significant digits pyuff writes for a double in an ASCII dataset 58 (E20.12)."""


def to_uff_ascii_precision(values: np.ndarray) -> np.ndarray:
    """The values as an ASCII dataset 58 stores them (12 significant digits)."""
    return np.array([float(f"{v:.{UFF_ASCII_DIGITS - 1}e}") for v in np.asarray(values, float)])


def write_plain_mat(path: Path, **variables) -> None:
    """A MAT 5 file of plain variables (scipy.io.savemat)."""
    import scipy.io

    scipy.io.savemat(path, variables)


def lms_export_group(
    names, values, unit, interval_s, start_s=0.0, factor=1.0, offset=0.0, n_declared=None, creation_time=None
):
    """One Test.Lab export struct (x_values / y_values / function_record) as a dict;
    ``creation_time``: a datetime, written as Test.Lab writes it (``YYYY/MM/DD HH:MM:SS``)."""
    values = np.asarray(values, float)
    n = values.shape[0]
    record = {"name": names[0] if len(names) == 1 else np.array(names, dtype=object), "type": "Signal"}
    if creation_time is not None:
        record["creation_time"] = creation_time.strftime("%Y/%m/%d %H:%M:%S")
    return {
        "x_values": {
            "start_value": float(start_s),
            "increment": float(interval_s),
            "number_of_values": n if n_declared is None else n_declared,
            "quantity": {"label": "s"},
        },
        "y_values": {
            "values": values,
            "quantity": {
                "label": unit,
                "unit_transformation": {"factor": factor, "offset": offset, "log_reference": 1},
            },
        },
        "function_record": record,
    }


def write_testlab_mat(path: Path, groups: dict) -> None:
    """A Test.Lab-style MAT 5 export: one struct per channel group (scipy.io.savemat)."""
    import scipy.io

    scipy.io.savemat(path, groups)


def _write_hdf5_value(parent, name, value) -> None:
    if isinstance(value, dict):
        group = parent.create_group(name)
        group.attrs["MATLAB_class"] = np.bytes_("struct")
        for key, item in value.items():
            _write_hdf5_value(group, key, item)
    elif isinstance(value, str):
        dataset = parent.create_dataset(
            name, data=np.array([ord(c) for c in value], dtype=np.uint16)[:, None]
        )
        dataset.attrs["MATLAB_class"] = np.bytes_("char")
    else:
        array = np.atleast_2d(np.asarray(value, dtype=float))
        if array.shape[0] == 1 and array.ndim == 2 and array.size > 1:
            array = array.T  # a MATLAB column vector
        dataset = parent.create_dataset(name, data=array.T)  # HDF5 holds the transpose
        dataset.attrs["MATLAB_class"] = np.bytes_("double")


def write_mat73(path: Path, variables: dict) -> None:
    """A MATLAB 7.3 file (HDF5 with MATLAB's 512-byte header and class attributes), via h5py."""
    import h5py

    with h5py.File(path, "w", userblock_size=512) as handle:
        for name, value in variables.items():
            _write_hdf5_value(handle, name, value)
    header = (
        b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 ."
    )
    with open(path, "r+b") as handle:
        handle.write(header.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02IM")


def uff58_record(name, values, unit, data_type, interval_s, start_s=0.0, binary=False, recorded=None) -> dict:
    """A dataset 58 time record for pyuff (data type 12 acceleration, 13 excitation force, ...);
    ``recorded``: a datetime, written in ID line 3 as the format has it (``DD-MMM-YY HH:MM:SS``)."""
    import pyuff

    values = np.asarray(values, float)
    return pyuff.prepare_58(
        binary=int(binary),
        id1=name,
        id2="",
        id3="" if recorded is None else recorded.strftime("%d-%b-%y %H:%M:%S"),
        id4="",
        id5="",
        func_type=1,
        rsp_node=1,
        rsp_dir=1,
        ref_node=0,
        ref_dir=0,
        num_pts=values.size,
        abscissa_spacing=1,
        abscissa_min=start_s,
        abscissa_inc=interval_s,
        abscissa_spec_data_type=17,
        abscissa_axis_units_lab="s",
        ordinate_spec_data_type=data_type,
        ordinate_axis_units_lab=unit,
        orddenom_spec_data_type=0,
        orddenom_axis_units_lab="",
        z_axis_spec_data_type=0,
        z_axis_axis_units_lab="",
        data=values,
        x=start_s + interval_s * np.arange(values.size),
    )


def write_uff58(path: Path, records: list[dict]) -> None:
    """A UFF file of dataset 58 records (pyuff)."""
    import pyuff

    Path(path).unlink(missing_ok=True)
    pyuff.UFF(str(path)).write_sets(records, mode="add")


def write_tdms(path: Path, group: str, channels: dict[str, tuple[np.ndarray, dict]]) -> None:
    """A TDMS file with one group; channels: name -> (values, properties) (npTDMS)."""
    from nptdms import ChannelObject, TdmsWriter

    with TdmsWriter(str(path)) as writer:
        writer.write_segment(
            [
                ChannelObject(group, name, np.asarray(values), properties=properties)
                for name, (values, properties) in channels.items()
            ]
        )


def convert_run(record, target: Path, interval_s: float, binary_uff: bool = False, recorded=None) -> None:
    """Write an ASCII run's samples (a RunRecord with force in lbf, acceleration in g) in the
    format of ``target``'s extension (``.uff``: binary 58b when ``binary_uff``), with the
    recording start ``recorded`` (a datetime; TDMS: UTC) where the format keeps one."""
    start_s = -record.pretrigger_samples * interval_s
    force, response = record.force_lbf, record.response
    suffix = target.suffix
    if suffix == ".mat":
        write_testlab_mat(
            target,
            {
                "Force": lms_export_group(
                    ["Time Hammer:+Z"], force, "lbf", interval_s, start_s, creation_time=recorded
                ),
                "Signal": lms_export_group(
                    ["Time Acc1:+Z"], response, "g", interval_s, start_s, creation_time=recorded
                ),
            },
        )
    elif suffix == ".uff":
        binary = binary_uff
        write_uff58(
            target,
            [
                uff58_record("Hammer", force, "lbf", 13, interval_s, start_s, binary, recorded),
                uff58_record("Acc1 +Z", response, "g", 12, interval_s, start_s, binary, recorded),
            ],
        )
    elif suffix == ".tdms":
        properties = {"wf_increment": interval_s, "wf_start_offset": start_s}
        if recorded is not None:
            properties["wf_start_time"] = np.datetime64(recorded.replace(tzinfo=None), "us")
        write_tdms(
            target,
            "Impact",
            {
                "Force": (force, {**properties, "unit_string": "lbf"}),
                "Acceleration": (response, {**properties, "unit_string": "g"}),
            },
        )
    else:
        raise ValueError(f"no writer for {target.name}")


MIXED_FORMATS = ("ascii", "mat", "uff", "uff58b", "tdms")
"""Formats given to a campaign's runs, in turn, by :func:`write_mixed_format_copy`."""

FIRST_RECORDING = datetime(2026, 3, 5, 14, 0, 0)
"""Recording start of the last run file by name in :func:`write_mixed_format_copy`."""


def write_mixed_format_copy(source, target) -> dict[str, str]:
    """Copy an ASCII campaign folder with its runs turned, in turn, into ASCII, Test.Lab MAT,
    UFF58, UFF58b and TDMS files (same samples, same run names); returns run path -> format.

    The system-format files record a start time, one minute apart, in the reverse of the
    run names' order (the k-th of n runs: ``FIRST_RECORDING + (n - 1 - k)`` minutes).

    Every configuration's ``files`` glob becomes ``<configuration>/*``.
    """
    import shutil

    from workflow.io.campaign import load_campaign
    from workflow.io.run_files import list_runs, read_run

    source, target = Path(source), Path(target)
    campaign = load_campaign(source)
    target.mkdir(parents=True)
    yaml_text = (source / "campaign.yaml").read_text()
    for name, spec in campaign.configurations.items():
        yaml_text = yaml_text.replace(f'"{spec.files}"', f'"{name}/*"')
    (target / "campaign.yaml").write_text(yaml_text)
    formats = {}
    runs = list_runs(source, campaign)
    for index, run in enumerate(runs):
        fmt = MIXED_FORMATS[index % len(MIXED_FORMATS)]
        folder = target / run.configuration
        folder.mkdir(exist_ok=True)
        if fmt == "ascii":
            path = folder / Path(run.path).name
            shutil.copyfile(source / run.path, path)
        else:
            record = read_run(source, run, campaign)
            suffix = {"mat": ".mat", "uff": ".uff", "uff58b": ".uff", "tdms": ".tdms"}[fmt]
            path = folder / f"{run.run}{suffix}"
            recorded = FIRST_RECORDING + timedelta(minutes=len(runs) - 1 - index)
            convert_run(
                record, path, 1.0 / record.sample_rate_hz, binary_uff=fmt == "uff58b", recorded=recorded
            )
        formats[path.relative_to(target).as_posix()] = fmt
    return formats

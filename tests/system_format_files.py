"""Run files in acquisition-system formats, written by each format's own library (scipy.io,
h5py, pyuff, npTDMS), for the reader tests and the mixed-format workflow test."""

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


def lms_export_group(names, values, unit, interval_s, start_s=0.0, factor=1.0, offset=0.0, n_declared=None):
    """One Test.Lab export struct (x_values / y_values / function_record) as a dict."""
    values = np.asarray(values, float)
    n = values.shape[0]
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
        "function_record": {
            "name": names[0] if len(names) == 1 else np.array(names, dtype=object),
            "type": "Signal",
        },
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


def uff58_record(name, values, unit, data_type, interval_s, start_s=0.0, binary=False) -> dict:
    """A dataset 58 time record for pyuff (data type 12 acceleration, 13 excitation force, ...)."""
    import pyuff

    values = np.asarray(values, float)
    return pyuff.prepare_58(
        binary=int(binary),
        id1=name,
        id2="",
        id3="",
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


def convert_run(record, target: Path, interval_s: float, binary_uff: bool = False) -> None:
    """Write an ASCII run's samples (a RunRecord with force in lbf, acceleration in g) in the
    format of ``target``'s extension (``.uff``: binary 58b when ``binary_uff``)."""
    start_s = -record.pretrigger_samples * interval_s
    force, response = record.force_lbf, record.response
    suffix = target.suffix
    if suffix == ".mat":
        write_testlab_mat(
            target,
            {
                "Force": lms_export_group(["Time Hammer:+Z"], force, "lbf", interval_s, start_s),
                "Signal": lms_export_group(["Time Acc1:+Z"], response, "g", interval_s, start_s),
            },
        )
    elif suffix == ".uff":
        binary = binary_uff
        write_uff58(
            target,
            [
                uff58_record("Hammer", force, "lbf", 13, interval_s, start_s, binary),
                uff58_record("Acc1 +Z", response, "g", 12, interval_s, start_s, binary),
            ],
        )
    elif suffix == ".tdms":
        properties = {"wf_increment": interval_s, "wf_start_offset": start_s}
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


def write_mixed_format_copy(source, target) -> dict[str, str]:
    """Copy an ASCII campaign folder with its runs turned, in turn, into ASCII, Test.Lab MAT,
    UFF58, UFF58b and TDMS files (same samples, same run names); returns run path -> format.

    Every configuration's ``files`` glob becomes ``<configuration>/*``.
    """
    import shutil

    from workflow.io.campaign import list_runs, load_campaign, read_run

    source, target = Path(source), Path(target)
    campaign = load_campaign(source)
    target.mkdir(parents=True)
    yaml_text = (source / "campaign.yaml").read_text()
    for name, spec in campaign.configurations.items():
        yaml_text = yaml_text.replace(f'"{spec.files}"', f'"{name}/*"')
    (target / "campaign.yaml").write_text(yaml_text)
    formats = {}
    for index, run in enumerate(list_runs(source, campaign)):
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
            convert_run(record, path, 1.0 / record.sample_rate_hz, binary_uff=fmt == "uff58b")
        formats[path.relative_to(target).as_posix()] = fmt
    return formats

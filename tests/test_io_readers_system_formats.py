"""Run files in acquisition-system formats (campaign-format.md, "System formats"): MAT 5 and
7.3 (plain and Test.Lab), UFF58 ASCII and binary, TDMS; the decimal-comma ASCII path."""

import dataclasses
import shutil
import sys
from datetime import datetime
from pathlib import Path

import numpy as np
import pytest
from helpers import REALDATA, REPO, needs_realdata
from system_format_files import (
    lms_export_group,
    to_uff_ascii_precision,
    uff58_record,
    write_mat73,
    write_plain_mat,
    write_tdms,
    write_testlab_mat,
    write_uff58,
)

from workflow.io.campaign import load_campaign
from workflow.io.records import CampaignFormatError
from workflow.io.run_files import read_run

RAW = REALDATA / "raw"

N = 2048
RATE_HZ = 2560.0
DT_S = 1.0 / RATE_HZ
PRETRIGGER = 25


def samples():
    """A decaying 125 Hz response in g and a hammer pulse in lbf, N samples at 2560 Hz."""
    t = np.arange(N) * DT_S
    response_g = np.exp(-3.0 * t) * np.sin(2 * np.pi * 125.0 * t) + 1e-3 * np.cos(7.0 * t)
    force_lbf = 20.0 * np.exp(-(((t - PRETRIGGER * DT_S) / 4e-4) ** 2)) + 1e-3 * np.sin(3.0 * t)
    return force_lbf, response_g


def campaign_in(tmp_path, yaml_text, name, writer):
    """A campaign folder with one run file written by ``writer(path)``; returns (folder, campaign)."""
    folder = tmp_path / "campaign"
    (folder / "c").mkdir(parents=True, exist_ok=True)
    (folder / "campaign.yaml").write_text(yaml_text)
    writer(folder / "c" / name)
    return folder, load_campaign(folder)


def yaml_of(response="{quantity: acceleration, unit: g}", force="{unit: lbf}", extra="", files="c/*"):
    force_line = f"force: {force}\n" if force else ""
    return f'name: t\nresponse: {response}\n{force_line}{extra}configurations:\n  c: {{files: "{files}"}}\n'


def read(tmp_path, name, writer, yaml_text=None):
    folder, campaign = campaign_in(tmp_path, yaml_text or yaml_of(), name, writer)
    return read_run(folder, f"c/{name}", campaign)


def error(tmp_path, name, writer, yaml_text=None) -> str:
    with pytest.raises(CampaignFormatError) as caught:
        read(tmp_path, name, writer, yaml_text)
    return str(caught.value)


def ascii_record(tmp_path, force_lbf, response_g):
    """The same samples read from an ASCII run (the reference every format must equal)."""
    rows = "\n".join(f"{float(f)!r}\t{float(r)!r}" for f, r in zip(force_lbf, response_g))
    text = f"Sample rate: {RATE_HZ:g} Hz\nPre-trigger: {PRETRIGGER} samples\nForce (lbf)\tAcceleration (g)\n{rows}\n"
    return read(tmp_path / "ascii", "run.txt", lambda p: p.write_text(text))


def assert_same_record(record, reference):
    assert record.n_samples == reference.n_samples
    assert record.sample_rate_hz == pytest.approx(reference.sample_rate_hz, rel=1e-12)
    assert record.pretrigger_samples == reference.pretrigger_samples
    np.testing.assert_array_equal(record.response, reference.response)
    np.testing.assert_array_equal(record.force_lbf, reference.force_lbf)


# --------------------------------------------------------------------------------------
# Round trips through each library's own writer, against the same samples in ASCII


def test_plain_mat_round_trip_equals_ascii(tmp_path):
    force, response = samples()
    t = (np.arange(N) - PRETRIGGER) * DT_S
    record = read(
        tmp_path,
        "run.mat",
        lambda p: write_plain_mat(p, t=t, hammer_force=force, acc=response, fs=RATE_HZ),
    )
    assert_same_record(record, ascii_record(tmp_path, force, response))
    assert record.pretrigger_source == "file"
    np.testing.assert_allclose(record.time_s, t, rtol=0, atol=1e-15)


def test_testlab_mat_round_trip_equals_ascii_with_units_from_the_file(tmp_path):
    force, response = samples()
    groups = {
        "Force": lms_export_group(["Time Hammer:+Z"], force, "lbf", DT_S, -PRETRIGGER * DT_S),
        "Signal": lms_export_group(
            ["Time Acc1:+Z", "Time Acc2:+Z"], np.c_[response, -response], "g", DT_S, -PRETRIGGER * DT_S
        ),
    }
    yaml_text = yaml_of(response='{quantity: acceleration, unit: g, channel: "Time Acc1:+Z"}')
    record = read(tmp_path, "run.mat", lambda p: write_testlab_mat(p, groups), yaml_text)
    assert_same_record(record, ascii_record(tmp_path, force, response))
    assert record.sample_rate_source == "file"
    assert record.header["format"] == "MAT (Test.Lab export)"


def test_testlab_time_signal_names_are_not_time_vectors(tmp_path):
    """'Time Acc1:+Z' with a unit label the reader does not know is the response by its
    name after the function-type prefix, not a time vector."""
    force, response = samples()
    groups = {"Signal": lms_export_group(["Time Acc1:+Z"], response, "EU", DT_S)}
    record = read(tmp_path, "run.mat", lambda p: write_testlab_mat(p, groups), yaml_of(force=None))
    np.testing.assert_array_equal(record.response, response)


def test_testlab_unit_transformation_gives_the_label_unit(tmp_path):
    """Test.Lab stores SI values with a label 'g' and factor 1/g: the reader gives g."""
    force, response = samples()
    si = response * 9.80665
    groups = {"Signal": lms_export_group(["Time Acc1:+Z"], si, "g", DT_S, factor=1 / 9.80665)}
    record = read(tmp_path, "run.mat", lambda p: write_testlab_mat(p, groups), yaml_of(force=None))
    # one multiply and one divide by 9.80665: a few ulp
    np.testing.assert_allclose(record.response, response, rtol=4 * np.finfo(float).eps, atol=1e-15)


def test_mat73_testlab_round_trip_equals_ascii(tmp_path):
    force, response = samples()
    variables = {
        "Force": lms_export_group(["Time Hammer:+Z"], force, "lbf", DT_S, -PRETRIGGER * DT_S),
        "Signal": lms_export_group(["Time Acc1:+Z"], response, "g", DT_S, -PRETRIGGER * DT_S),
    }
    record = read(tmp_path, "run.mat", lambda p: write_mat73(p, variables))
    assert record.header["format"] == "MAT 7.3 (Test.Lab export)"
    assert_same_record(record, ascii_record(tmp_path, force, response))


def test_mat73_plain_variables_round_trip_equals_ascii(tmp_path):
    force, response = samples()
    t = (np.arange(N) - PRETRIGGER) * DT_S
    variables = {"time": t, "hammer": force, "accel": response, "dt": DT_S}
    record = read(tmp_path, "run.mat", lambda p: write_mat73(p, variables))
    assert record.header["format"] == "MAT 7.3"
    assert_same_record(record, ascii_record(tmp_path, force, response))


@pytest.mark.parametrize("binary", [False, True])
def test_uff58_round_trip_equals_ascii_to_the_digits_it_keeps(tmp_path, binary):
    force, response = samples()
    if not binary:  # ASCII dataset 58 keeps 12 significant digits; so does the reference
        force, response = to_uff_ascii_precision(force), to_uff_ascii_precision(response)
    records = [
        uff58_record("Hammer", force, "lbf", 13, DT_S, -PRETRIGGER * DT_S, binary),
        uff58_record("Acc1 +Z", response, "g", 12, DT_S, -PRETRIGGER * DT_S, binary),
    ]
    record = read(tmp_path, "run.uff", lambda p: write_uff58(p, records))
    assert record.header["format"] == ("UFF58b" if binary else "UFF58")
    assert_same_record(record, ascii_record(tmp_path, force, response))


def test_tdms_round_trip_equals_ascii(tmp_path):
    force, response = samples()
    properties = {"wf_increment": DT_S, "wf_start_offset": -PRETRIGGER * DT_S}
    channels = {
        "Force": (force, {**properties, "unit_string": "lbf"}),
        "Acceleration": (response, {**properties, "unit_string": "g"}),
    }
    record = read(tmp_path, "run.tdms", lambda p: write_tdms(p, "Impact", channels))
    assert_same_record(record, ascii_record(tmp_path, force, response))
    assert record.header["response channel"] == "Impact/Acceleration"


RECORDED = datetime(2026, 3, 5, 14, 7, 9)
"""A recording start written into the files below."""


def _start_time_writers(recorded):
    """File name -> writer of a run that records ``recorded`` as its start, per format."""
    force, response = samples()
    groups = {
        "Force": lms_export_group(["Time Hammer:+Z"], force, "lbf", DT_S, creation_time=recorded),
        "Signal": lms_export_group(["Time Acc1:+Z"], response, "g", DT_S, creation_time=recorded),
    }
    records = [
        uff58_record("Hammer", force, "lbf", 13, DT_S, recorded=recorded),
        uff58_record("Acc1 +Z", response, "g", 12, DT_S, recorded=recorded),
    ]
    binary = [
        uff58_record("Hammer", force, "lbf", 13, DT_S, binary=True, recorded=recorded),
        uff58_record("Acc1 +Z", response, "g", 12, DT_S, binary=True, recorded=recorded),
    ]
    properties = {"wf_increment": DT_S, "wf_start_time": np.datetime64(recorded, "us")}
    channels = {
        "Force": (force, {**properties, "unit_string": "lbf"}),
        "Acceleration": (response, {**properties, "unit_string": "g"}),
    }
    return {
        "run.mat": lambda p: write_testlab_mat(p, groups),
        "run73.mat": lambda p: write_mat73(p, groups),
        "run.uff": lambda p: write_uff58(p, records),
        "run58b.uff": lambda p: write_uff58(p, binary),
        "run.tdms": lambda p: write_tdms(p, "Impact", channels),
    }


@pytest.mark.parametrize("name", list(_start_time_writers(RECORDED)))
def test_recording_start_is_read_from_each_format(tmp_path, name):
    record = read(tmp_path, name, _start_time_writers(RECORDED)[name])
    # TDMS time stamps are UTC; Test.Lab and UFF58 write local clock time with no zone
    expected = "2026-03-05T14:07:09+00:00" if name.endswith(".tdms") else "2026-03-05T14:07:09"
    assert record.record_start == expected


def test_tdms_recording_start_from_the_file_properties(tmp_path):
    from nptdms import ChannelObject, RootObject, TdmsWriter

    force, response = samples()

    def writer(path):
        with TdmsWriter(str(path)) as tdms:
            tdms.write_segment(
                [
                    RootObject(properties={"DateTime": np.datetime64(RECORDED, "us")}),
                    ChannelObject(
                        "Impact", "Force", force, properties={"wf_increment": DT_S, "unit_string": "lbf"}
                    ),
                    ChannelObject(
                        "Impact", "Acc", response, properties={"wf_increment": DT_S, "unit_string": "g"}
                    ),
                ]
            )

    assert read(tmp_path, "run.tdms", writer).record_start == "2026-03-05T14:07:09+00:00"


def test_files_without_a_recording_start_have_none(tmp_path):
    force, response = samples()
    records = [
        uff58_record("Hammer", force, "lbf", 13, DT_S),
        uff58_record("Acc1 +Z", response, "g", 12, DT_S),
    ]
    records[1]["id3"] = "Record 1 / free text"  # ID line 3 holds no date: not an error
    assert read(tmp_path / "uff", "run.uff", lambda p: write_uff58(p, records)).record_start == ""
    records[1]["id2"] = "05-Mar-26 14:07:09"  # where some exporters put it
    assert (
        read(tmp_path / "uff2", "run.uff", lambda p: write_uff58(p, records)).record_start
        == "2026-03-05T14:07:09"
    )
    assert ascii_record(tmp_path, force, response).record_start == ""


def test_force_in_newtons_is_converted_to_lbf(tmp_path):
    force, response = samples()
    channels = {
        "Force": (force * (0.45359237 * 9.80665), {"wf_increment": DT_S, "unit_string": "N"}),  # lbf -> N
        "Acceleration": (response, {"wf_increment": DT_S, "unit_string": "g"}),
    }
    record = read(tmp_path, "run.tdms", lambda p: write_tdms(p, "g", channels), yaml_of(force=None))
    np.testing.assert_allclose(record.force_lbf, force, rtol=4 * np.finfo(float).eps)


# --------------------------------------------------------------------------------------
# Channel selection


def test_channel_by_name_and_by_index(tmp_path):
    force, response = samples()
    groups = {
        "Signal": lms_export_group(["Time A:+X", "Time B:+X"], np.c_[response, 2 * response], "g", DT_S)
    }
    write = lambda p: write_testlab_mat(p, groups)
    by_name = read(
        tmp_path / "a",
        "run.mat",
        write,
        yaml_of(response='{quantity: acceleration, unit: g, channel: "Time B:+X"}'),
    )
    by_index = read(
        tmp_path / "b", "run.mat", write, yaml_of(response="{quantity: acceleration, unit: g, channel: 1}")
    )
    np.testing.assert_array_equal(by_name.response, 2 * response)
    np.testing.assert_array_equal(by_index.response, 2 * response)


def test_ambiguous_channel_lists_the_channels(tmp_path):
    force, response = samples()
    groups = {"Signal": lms_export_group(["Time A:+X", "Time B:+X"], np.c_[response, response], "g", DT_S)}
    message = error(tmp_path, "run.mat", lambda p: write_testlab_mat(p, groups))
    assert "c/run.mat" in message and "2 response channels" in message
    assert "[0] 'Time A:+X' (g), [1] 'Time B:+X' (g)" in message
    assert "channel" in message


@pytest.mark.parametrize("reference", ['"nope"', "5"])
def test_unknown_channel_lists_the_channels(tmp_path, reference):
    force, response = samples()
    channels = {"acc": (response, {"wf_increment": DT_S, "unit_string": "g"})}
    yaml_text = yaml_of(response=f"{{quantity: acceleration, unit: g, channel: {reference}}}")
    message = error(tmp_path, "run.tdms", lambda p: write_tdms(p, "g", channels), yaml_text)
    assert "response.channel" in message and "[0] 'g/acc' (g)" in message


def test_plain_mat_without_channel_names_its_variables(tmp_path):
    force, response = samples()
    message = error(
        tmp_path,
        "run.mat",
        lambda p: write_plain_mat(p, x=response, f=force, fs=RATE_HZ),
        yaml_of(force=None),
    )
    assert "'f'" in message and "'x'" in message and "response channels" in message


# --------------------------------------------------------------------------------------
# Units, sample interval, time origin


def test_unit_disagreement_names_both(tmp_path):
    force, response = samples()
    channels = {"acc": (response, {"wf_increment": DT_S, "unit_string": "m/s^2"})}
    message = error(tmp_path, "run.tdms", lambda p: write_tdms(p, "g", channels))
    assert "channel 'g/acc'" in message and "'m/s^2'" in message and "'g'" in message


def test_sample_interval_missing_everywhere(tmp_path):
    force, response = samples()
    message = error(tmp_path, "run.mat", lambda p: write_plain_mat(p, acc=response), yaml_of(force=None))
    assert "sample interval missing" in message and "variable 'acc'" in message


def test_sample_interval_from_campaign_yaml_fills_the_gap(tmp_path):
    force, response = samples()
    record = read(
        tmp_path,
        "run.mat",
        lambda p: write_plain_mat(p, acc=response),
        yaml_of(force=None, extra="sample_rate_hz: 2560\n"),
    )
    assert record.sample_rate_hz == RATE_HZ and record.sample_rate_source == "campaign.yaml"


def test_sample_rate_disagreement_names_both(tmp_path):
    force, response = samples()
    channels = {"acc": (response, {"wf_increment": 1 / 5120, "unit_string": "g"})}
    message = error(
        tmp_path, "run.tdms", lambda p: write_tdms(p, "g", channels), yaml_of(extra="sample_rate_hz: 2560\n")
    )
    assert "wf_increment" in message and "5120" in message and "campaign.yaml" in message


def test_pretrigger_disagreement_names_both(tmp_path):
    force, response = samples()
    channels = {"acc": (response, {"wf_increment": DT_S, "wf_start_offset": -10 * DT_S, "unit_string": "g"})}
    message = error(
        tmp_path,
        "run.tdms",
        lambda p: write_tdms(p, "g", channels),
        yaml_of(extra="pretrigger_samples: 25\n"),
    )
    assert "10 samples" in message and "pretrigger_samples 25" in message


# --------------------------------------------------------------------------------------
# Bad files: excluded with the file, the record and the problem


def _truncate(path: Path, fraction: float) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * fraction)])


def _garble(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[: len(data) // 2] = bytes(range(256)) * (len(data) // 512) + bytes(len(data) // 2 % 256)
    path.write_bytes(bytes(data))


def _writers():
    force, response = samples()
    properties = {"wf_increment": DT_S, "unit_string": "g"}
    return {
        "run.mat": lambda p: write_testlab_mat(
            p, {"Signal": lms_export_group(["Time Acc1:+Z"], response, "g", DT_S)}
        ),
        "run.uff": lambda p: write_uff58(p, [uff58_record("Acc1", response, "g", 12, DT_S)]),
        "runb.uff": lambda p: write_uff58(p, [uff58_record("Acc1", response, "g", 12, DT_S, binary=True)]),
        "run.tdms": lambda p: write_tdms(p, "g", {"acc": (response, properties)}),
    }


@pytest.mark.parametrize("name", list(_writers()))
@pytest.mark.parametrize("damage", ["truncated", "garbled", "empty"])
def test_damaged_files_name_the_file_and_the_problem(tmp_path, name, damage):
    write = _writers()[name]

    def damaged(path):
        write(path)
        if damage == "truncated":
            _truncate(path, 0.6)
        elif damage == "garbled":
            _garble(path)
        else:
            path.write_bytes(b"")

    message = error(tmp_path, name, damaged, yaml_of(force=None))
    assert f"c/{name}" in message
    expected = {
        "truncated": ("truncated", "cannot read"),
        "garbled": ("corrupt", "cannot read", "no dataset 58"),
        "empty": ("the file is empty",),
    }[damage]
    assert any(words in message for words in expected), message


def test_uff_cut_in_its_second_record_is_truncated_not_a_missing_channel(tmp_path):
    force, response = samples()
    records = [uff58_record("Hammer", force, "lbf", 13, DT_S), uff58_record("Acc1", response, "g", 12, DT_S)]

    def cut(path):
        write_uff58(path, records)
        _truncate(path, 0.8)

    message = error(tmp_path, "run.uff", cut)
    # the second dataset starts after the first one's 2 + 11 + N/4 lines and its closing line
    assert f"c/run.uff:{2 + 11 + N // 4 + 2}: truncated" in message


def test_testlab_sample_count_mismatch_names_the_variable(tmp_path):
    force, response = samples()
    groups = {"Signal": lms_export_group(["Time Acc1:+Z"], response, "g", DT_S, n_declared=N + 100)}
    message = error(tmp_path, "run.mat", lambda p: write_testlab_mat(p, groups), yaml_of(force=None))
    assert "variable 'Signal'" in message and "number_of_values" in message and str(N + 100) in message


def test_nan_in_a_channel_names_the_record_and_sample(tmp_path):
    force, response = samples()
    response = response.copy()
    response[300] = np.nan
    channels = {"acc": (response, {"wf_increment": DT_S, "unit_string": "g"})}
    message = error(tmp_path, "run.tdms", lambda p: write_tdms(p, "g", channels), yaml_of(force=None))
    assert "channel 'g/acc'" in message and "sample 300" in message


def test_nan_in_a_uff_record_names_the_dataset_and_sample(tmp_path):
    force, response = samples()

    def with_nan(path):
        write_uff58(path, [uff58_record("Acc1", response, "g", 12, DT_S)])
        lines = path.read_text().split("\n")
        # 2 delimiter/type lines and 11 header lines, then 4 values per line: line 101 holds
        # samples 348-351 (0-based)
        lines[100] = "NaN".rjust(20) + lines[100][20:]
        path.write_text("\n".join(lines))

    message = error(tmp_path, "run.uff", with_nan, yaml_of(force=None))
    assert "dataset 1 (58, ID 'Acc1')" in message and "sample 348" in message


def test_readers_are_imported_only_for_their_files(tmp_path):
    """Reading an ASCII run loads none of the format libraries (per-run jobs stay light)."""
    import subprocess

    force, response = samples()
    ascii_record(tmp_path, force, response)
    folder = str(tmp_path / "ascii" / "campaign")
    code = (
        "import sys; from workflow.io.campaign import load_campaign; from workflow.io.run_files import read_run; "
        f"read_run({folder!r}, 'c/run.txt', load_campaign({folder!r})); "
        "print(sorted(m for m in ('scipy.io', 'h5py', 'pyuff', 'nptdms') if m in sys.modules))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, check=True
    )
    assert result.stdout.strip() == "[]"


# --------------------------------------------------------------------------------------
# Decimal commas (ASCII)


def test_decimal_commas_read_like_points(tmp_path):
    force, response = samples()
    reference = ascii_record(tmp_path, force, response)
    rows = "\n".join(f"{float(f)!r};{float(r)!r}".replace(".", ",") for f, r in zip(force, response))
    text = (
        f"Sample rate: 2560,0 Hz\nPre-trigger: {PRETRIGGER} samples\nForce (lbf);Acceleration (g)\n{rows}\n"
    )
    record = read(
        tmp_path / "comma", "run.txt", lambda p: p.write_text(text), yaml_of(extra='decimal: ","\n')
    )
    assert_same_record(record, reference)


def test_decimal_commas_leave_a_header_date_alone(tmp_path):
    force, response = samples()
    reference = ascii_record(tmp_path, force, response)
    rows = "\n".join(f"{float(f)!r};{float(r)!r}".replace(".", ",") for f, r in zip(force, response))
    text = (
        "Messung vom 12.05.2004, 14:03\nSample rate: 2560,0 Hz\n"
        f"Pre-trigger: {PRETRIGGER} samples\nForce (lbf);Acceleration (g)\n{rows}\n"
    )
    record = read(
        tmp_path / "comma", "run.txt", lambda p: p.write_text(text), yaml_of(extra='decimal: ","\n')
    )
    assert_same_record(record, reference)


def test_decimal_commas_with_comma_separated_columns_are_an_error(tmp_path):
    text = "Force (lbf),Acceleration (g)\n" + "\n".join("0.5,1.25" for _ in range(300)) + "\n"
    message = error(
        tmp_path,
        "run.txt",
        lambda p: p.write_text(text),
        yaml_of(extra='decimal: ","\nsample_rate_hz: 2560\n'),
    )
    assert "c/run.txt:2:" in message and "decimal" in message


def test_decimal_key_is_validated(tmp_path):
    (tmp_path / "campaign.yaml").write_text(yaml_of(extra='decimal: ":"\n'))
    with pytest.raises(CampaignFormatError, match="decimal"):
        load_campaign(tmp_path)


# --------------------------------------------------------------------------------------
# The real exports in ../shared/realdata/raw


def _copy_campaign(tmp_path, yaml_text, source: Path, target: str) -> Path:
    folder = tmp_path / "campaign"
    (folder / Path(target).parent).mkdir(parents=True)
    (folder / "campaign.yaml").write_text(yaml_text)
    shutil.copyfile(source, folder / target)
    return folder


@needs_realdata("raw")
def test_real_plain_mat_equals_the_converted_campaign(tmp_path):
    yaml_text = (
        "name: pff-lms-sample\nsample_rate_hz: 51200\nmode_hz: 151\n"
        "response: {quantity: acceleration, unit: m/s^2, channel: x}\n"
        'configurations:\n  decay: {files: "decay/*.mat"}\n'
    )
    folder = _copy_campaign(tmp_path, yaml_text, RAW / "pff_Sample_LMS_Data.mat", "decay/run01.mat")
    record = read_run(folder, "decay/run01.mat", load_campaign(folder))
    converted_dir = REALDATA / "pff-lms-sample"
    converted = read_run(converted_dir, "decay/run01.txt", load_campaign(converted_dir))
    assert record.n_samples == converted.n_samples == 131072
    assert record.sample_rate_hz == converted.sample_rate_hz == 51200
    # the converted file prints 7 significant digits
    np.testing.assert_allclose(record.response, converted.response, rtol=5e-7, atol=1e-12)
    assert record.pretrigger_samples == 512  # t starts at -0.01 s
    assert record.force_lbf is None  # 'f' is not named a force: campaign.yaml does not ask for it


@needs_realdata("raw")
def test_real_testlab_export_reads_the_laser_channel_in_its_unit(tmp_path):
    yaml_text = (
        "name: unesp\nmode_hz: 18.7\n"
        'response: {quantity: velocity, unit: m/s, channel: "Time Laser:+X"}\n'
        'configurations:\n  t5nm: {files: "t5nm/*.mat", window_s: [51.19921875, 64]}\n'
    )
    folder = _copy_campaign(tmp_path, yaml_text, RAW / "unesp_T5Nm_Sine_09Hz_Time.mat", "t5nm/sine_09hz.mat")
    record = read_run(folder, "t5nm/sine_09hz.mat", load_campaign(folder))
    assert record.sample_rate_hz == 1024 and record.sample_rate_source == "file"
    assert record.n_samples == 65536
    assert record.record_start == "2019-06-04T23:52:35"  # function_record.creation_time
    converted = read_run(
        REALDATA / "unesp-bolted-beam",
        "t5nm/sine_09hz.txt",
        load_campaign(REALDATA / "unesp-bolted-beam"),
    )
    # the converted file is samples 52428... of the laser channel, printed to 7 digits
    start = 52428
    np.testing.assert_allclose(
        record.response[start : start + converted.n_samples], converted.response, rtol=5e-7, atol=1e-12
    )
    wrong_unit = yaml_text.replace("unit: m/s,", "unit: in/s,")
    (folder / "campaign.yaml").write_text(wrong_unit)
    with pytest.raises(CampaignFormatError, match=r"Time Laser:\+X.*'m/s'.*'in/s'"):
        read_run(folder, "t5nm/sine_09hz.mat", load_campaign(folder))


@needs_realdata("raw")
@pytest.mark.parametrize("name", ["pff_Sample_LMS_Data.mat", "unesp_T5Nm_Sine_09Hz_Time.mat"])
def test_real_exports_corrupted_give_their_messages(tmp_path, name):
    folder = _copy_campaign(
        tmp_path,
        'name: x\nsample_rate_hz: 1024\nresponse: {quantity: velocity, unit: m/s, channel: 0}\nconfigurations:\n  c: {files: "c/*.mat"}\n',
        RAW / name,
        "c/run.mat",
    )
    _truncate(folder / "c" / "run.mat", 0.5)
    with pytest.raises(CampaignFormatError) as caught:
        read_run(folder, "c/run.mat", load_campaign(folder))
    assert "c/run.mat" in str(caught.value) and "cannot read as a MAT file" in str(caught.value)


def test_campaign_json_copy_keeps_channels_and_decimal(tmp_path):
    from workflow.io.campaign import campaign_from_dict, campaign_to_dict

    (tmp_path / "campaign.yaml").write_text(
        yaml_of(
            response='{quantity: velocity, unit: m/s, channel: "Time Laser:+X"}',
            force="{unit: N, channel: 2}",
            extra='decimal: ","\n',
        )
    )
    campaign = load_campaign(tmp_path)
    assert campaign.response.channel == "Time Laser:+X" and campaign.force.channel == 2
    assert campaign_from_dict(campaign_to_dict(campaign)) == dataclasses.replace(campaign)


@pytest.mark.parametrize("compressed", [True, False])
def test_mat5_headers_name_every_variable_and_defer_exactly_the_plain_vectors(tmp_path, compressed):
    import zlib

    import scipy.io

    from workflow.io.readers.mat import _DeferredVector, _read_mat5, _real_samples, mat5_variable_headers

    path = tmp_path / "run.mat"
    samples = np.linspace(-1.0, 1.0, 50)
    variables = {
        "column": samples[:, None],
        "row": samples[None, :],
        "whole": (samples * 100).astype(np.int16),
        "wave": samples + 1j * samples,
        "fs": 1000.0,
        "matrix": np.ones((3, 4)),
        "flags": samples > 0,
        "label": "text",
        "group": {"y_values": {"values": samples}, "x_values": {"increment": 0.001}},
        "one": np.array([[2.0]]),
        "a_rather_long_variable_name_of_sixty_characters_abcdefghijklm": samples,
        "single": samples.astype(np.float32),
        "bytes": np.arange(50, dtype=np.uint8),
        "long": np.arange(-25, 25, dtype=np.int64),
        "two": np.array([3, -4], dtype=np.int8),  # a small data element: in the tag's 4 bytes
    }
    scipy.io.savemat(path, variables, do_compression=compressed)
    headers = mat5_variable_headers(path.read_bytes())
    expected = scipy.io.loadmat(path, squeeze_me=True, simplify_cells=True)
    assert [h.name for h in headers] == [name for name, _, _ in scipy.io.whosmat(path)]
    read = _read_mat5(path, "run.mat")
    assert list(read) == [name for name in expected if not name.startswith("__")]
    for header in headers:
        value = expected[header.name]
        vector = isinstance(value, np.ndarray) and value.ndim == 1 and value.size > 1
        assert header.plain_vector == (vector and np.issubdtype(value.dtype, np.number)), header.name
        mine = read[header.name]
        if header.plain_vector and header.name != "fs":
            assert isinstance(mine, _DeferredVector)
            mine = mine.load()
            assert mine.dtype == value.dtype
            # real and not logical: a view of the inflated bytes; complex and logical: scipy's
            element = path.read_bytes()[header.first : header.stop]
            element = zlib.decompress(element[8:]) if header.compressed else element
            assert (_real_samples(element, "<") is None) == (header.name in ("wave", "flags")), header.name
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(mine, value)


def test_mat5_unused_vectors_are_not_decompressed(tmp_path, monkeypatch):
    import scipy.io

    from workflow.io.readers import mat
    from workflow.io.records import CampaignFormatError

    force, response = samples()
    path = tmp_path / "run.mat"
    scipy.io.savemat(
        path, {"t": np.arange(response.size) * DT_S, "x": response, "f": force}, do_compression=True
    )
    loaded = []
    read_vector = mat._plain_vector
    monkeypatch.setattr(
        mat,
        "_plain_vector",
        lambda data, header, shown: loaded.append(header.name) or read_vector(data, header, shown),
    )
    channels = mat.read_mat_channels(path, "run.mat").channels
    assert [c.name for c in channels] == ["t", "x", "f"] and not loaded
    np.testing.assert_array_equal(channels[1].samples(), response)
    assert loaded == ["x"]
    # damage inside the unused vector f goes unnoticed; inside x it is an error
    headers = {h.name: h for h in mat.mat5_variable_headers(path.read_bytes())}
    for name, fails in (("f", False), ("x", True)):
        data = bytearray(path.read_bytes())
        middle = (headers[name].first + headers[name].stop) // 2
        data[middle : middle + 64] = bytes(64)
        path.write_bytes(bytes(data))
        channels = mat.read_mat_channels(path, "run.mat").channels
        if fails:
            with pytest.raises(CampaignFormatError, match="cannot read as a MAT file"):
                channels[1].samples()
        else:
            np.testing.assert_array_equal(channels[1].samples(), response)

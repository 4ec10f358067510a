"""Several sensors and several modes of one hit (campaign-format.md): campaign.yaml's
``response.channels``, ``modes_hz`` / ``bands_hz`` / ``modes_hz: auto``, a response unit
read from the file, and every reader's multi-channel path, each checked against a file
written by its format's own library."""

import dataclasses
import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers import REALDATA, needs_realdata
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

from workflow.io.campaign import (
    SINGLE_CHANNEL_NAME,
    ResponseSpec,
    campaign_from_dict,
    campaign_to_dict,
    load_campaign,
)
from workflow.io.records import CampaignFormatError
from workflow.io.run_files import read_run

N = 4096
RATE_HZ = 2560.0
DT_S = 1.0 / RATE_HZ


def three_sensors():
    """Three accelerometers (g) seeing one hit: two modes, each sensor its own mix."""
    t = np.arange(N) * DT_S
    first = np.exp(-4.0 * t) * np.sin(2 * np.pi * 80.5 * t)
    second = np.exp(-9.0 * t) * np.sin(2 * np.pi * 297.7 * t)
    return {
        "acc1": 1.0 * first + 0.2 * second,
        "acc2": 0.5 * first - 0.7 * second,
        "acc3": -0.8 * first + 0.4 * second,
    }


def write_campaign(tmp_path, yaml_text, name, writer):
    folder = tmp_path / "campaign"
    (folder / "c").mkdir(parents=True, exist_ok=True)
    (folder / "campaign.yaml").write_text(yaml_text)
    writer(folder / "c" / name)
    return folder


def read_one(tmp_path, yaml_text, name, writer):
    folder = write_campaign(tmp_path, yaml_text, name, writer)
    return read_run(folder, f"c/{name}", load_campaign(folder))


def yaml_with(response, extra=""):
    return f'name: t\nsample_rate_hz: {RATE_HZ:g}\nresponse: {response}\n{extra}configurations:\n  c: {{files: "c/*"}}\n'


def assert_channels(record, expected, names, unit="g"):
    """The record's response channels are ``expected``'s ``names``, in that order, in ``unit``."""
    assert record.channel_names() == tuple(names)
    for channel, name in zip(record.responses, names):
        np.testing.assert_array_equal(channel.values, expected[name])
        assert channel.unit == unit
    np.testing.assert_array_equal(record.response, expected[names[0]])
    second = record.for_channel(names[-1])
    np.testing.assert_array_equal(second.response, expected[names[-1]])
    assert second.response_unit == unit and second.n_samples == record.n_samples


# --------------------------------------------------------------------------------------
# campaign.yaml


def load(tmp_path, yaml_text):
    (tmp_path / "campaign.yaml").write_text(yaml_text)
    return load_campaign(tmp_path)


def load_error(tmp_path, yaml_text) -> str:
    with pytest.raises(CampaignFormatError) as caught:
        load(tmp_path, yaml_text)
    return str(caught.value)


def test_channels_and_modes_are_read_and_survive_the_json_copy(tmp_path):
    campaign = load(
        tmp_path,
        yaml_with(
            "{quantity: acceleration, channels: [acc1, 2, 'Time Acc3:+X']}",
            "modes_hz: [80.5, 297.7]\nbands_hz: [[70, 90], [280, 310]]\n",
        ),
    )
    assert campaign.response.channels == ("acc1", 2, "Time Acc3:+X")
    assert campaign.response.channel_names() == ("acc1", "2", "Time Acc3:+X")
    assert campaign.response.unit is None
    assert campaign.mode_requests() == ((80.5, (70.0, 90.0)), (297.7, (280.0, 310.0)))
    assert campaign_from_dict(campaign_to_dict(campaign)) == dataclasses.replace(campaign)


def test_auto_modes_and_the_one_mode_forms(tmp_path):
    auto = load(tmp_path, yaml_with("{quantity: acceleration, unit: g}", "modes_hz: auto\n"))
    assert auto.auto_modes and auto.mode_requests() == ()
    assert campaign_from_dict(campaign_to_dict(auto)) == dataclasses.replace(auto)
    one = load(
        tmp_path, yaml_with("{quantity: acceleration, unit: g}", "mode_hz: 125\nband_hz: [100, 150]\n")
    )
    assert not one.auto_modes and one.mode_requests() == ((125.0, (100.0, 150.0)),)
    assert one.response.channel_names() == (SINGLE_CHANNEL_NAME,)
    named = load(tmp_path, yaml_with("{quantity: acceleration, unit: g, channel: 1}"))
    assert named.mode_requests() == ((None, None),) and named.response.channel_names() == ("1",)


@pytest.mark.parametrize(
    ("response", "extra", "line", "words"),
    [
        ("{quantity: acceleration, unit: g, channel: a, channels: [b]}", "", 3, ["response", "not both"]),
        ("{quantity: acceleration, unit: g, channels: []}", "", 3, ["response.channels", "at least one"]),
        (
            "{quantity: acceleration, unit: g, channels: [a, a]}",
            "",
            3,
            ["response.channels", "'a' more than once"],
        ),
        ("{quantity: acceleration, unit: g}", "modes_hz: [300, 80]\n", 4, ["modes_hz", "increase"]),
        ("{quantity: acceleration, unit: g}", "modes_hz: []\n", 4, ["modes_hz", "at least one"]),
        ("{quantity: acceleration, unit: g}", "modes_hz: [80]\nmode_hz: 80\n", 5, ["mode_hz", "not both"]),
        ("{quantity: acceleration, unit: g}", "bands_hz: [[70, 90]]\n", 4, ["bands_hz", "needs modes_hz"]),
        (
            "{quantity: acceleration, unit: g}",
            "modes_hz: [80, 300]\nbands_hz: [[70, 90]]\n",
            5,
            ["1 band(s) for 2"],
        ),
        (
            "{quantity: acceleration, unit: g}",
            "modes_hz: [80, 300]\nbands_hz: [[70, 90], [200, 250]]\n",
            5,
            ["bands_hz", "does not hold its mode 300"],
        ),
        ("{quantity: acceleration, unit: g}", "modes_hz: [80, 1300]\n", 4, ["modes_hz[1]", "Nyquist"]),
        (
            "{quantity: acceleration, unit: g}",
            "modes_hz: automatic\n",
            4,
            ["modes_hz: expected a list", "or auto"],
        ),
    ],
)
def test_bad_channel_and_mode_keys_name_the_key_and_line(tmp_path, response, extra, line, words):
    message = load_error(tmp_path, yaml_with(response, extra))
    assert f"campaign.yaml:{line}:" in message
    for word in words:
        assert word in message


def test_the_contracts_example_reads_three_sensors_of_a_mat_file(tmp_path):
    # campaign-format.md, "Several sensors and several modes of one hit", as written there
    yaml_text = (
        "name: contract-example\n"
        "modes_hz: [80.5, 297.7]            # several modes; or `modes_hz: auto` (every mode found)\n"
        "response: {quantity: acceleration, unit: m/s^2, channels: [acc1, acc2, acc3]}\n"
        "configurations:\n"
        '  torque_20nm: {files: "t20/*.mat"}\n'
    )
    folder = tmp_path / "campaign"
    (folder / "t20").mkdir(parents=True)
    (folder / "campaign.yaml").write_text(yaml_text)
    sensors = three_sensors()
    write_plain_mat(folder / "t20" / "hit01.mat", t=np.arange(N) * DT_S, **sensors)
    campaign = load_campaign(folder)
    assert campaign.mode_requests() == ((80.5, None), (297.7, None))
    record = read_run(folder, "t20/hit01.mat", campaign)
    assert record.sample_rate_hz == pytest.approx(RATE_HZ, rel=1e-9)
    assert_channels(record, sensors, ["acc1", "acc2", "acc3"], unit="m/s^2")
    # and with the bands it names
    (folder / "campaign.yaml").write_text(
        yaml_text.replace("configurations:", "bands_hz: [[70, 90], [280, 310]]\nconfigurations:")
    )
    assert load_campaign(folder).mode_requests() == ((80.5, (70.0, 90.0)), (297.7, (280.0, 310.0)))


# --------------------------------------------------------------------------------------
# ASCII: columns by name or index


def ascii_writer(columns, names=None):
    def write(path):
        rows = "\n".join("\t".join(repr(float(v)) for v in row) for row in zip(*columns))
        head = "" if names is None else "\t".join(names) + "\n"
        path.write_text(head + rows + "\n")

    return write


def test_ascii_columns_by_name_with_units_from_the_file(tmp_path):
    sensors = three_sensors()
    t = np.arange(N) * DT_S
    writer = ascii_writer([t, *sensors.values()], ["Time (s)", "acc1 (g)", "acc2 (g)", "acc3 (g)"])
    record = read_one(
        tmp_path, yaml_with("{quantity: acceleration, channels: [acc3, ACC1]}"), "run.txt", writer
    )
    assert record.channel_names() == ("acc3", "ACC1")
    np.testing.assert_array_equal(record.responses[0].values, sensors["acc3"])
    np.testing.assert_array_equal(record.responses[1].values, sensors["acc1"])
    assert record.responses[1].source == "acc1 (g)"
    assert record.time_s is not None


def test_ascii_columns_by_index_without_names(tmp_path):
    sensors = three_sensors()
    t = np.arange(N) * DT_S
    writer = ascii_writer([t, *sensors.values()])
    record = read_one(
        tmp_path, yaml_with("{quantity: acceleration, unit: g, channels: [1, 2, 3]}"), "run.txt", writer
    )
    assert_channels(
        record, {"1": sensors["acc1"], "2": sensors["acc2"], "3": sensors["acc3"]}, ["1", "2", "3"]
    )
    assert record.time_s is not None and record.force_lbf is None


@pytest.mark.parametrize(
    ("response", "names", "words"),
    [
        (
            "{quantity: acceleration, channels: [acc2]}",
            ["Time (s)", "acc1 (g)", "acc2", "acc3 (g)"],
            ["'acc2'", "no unit"],
        ),
        (
            "{quantity: acceleration, unit: g, channels: [acc1, acc9]}",
            ["Time (s)", "acc1 (g)", "acc2 (g)", "acc3 (g)"],
            ["'acc9'", "no column", "[3] 'acc3 (g)'"],
        ),
        (
            "{quantity: acceleration, unit: g, channels: [acc1, 7]}",
            ["Time (s)", "acc1 (g)", "acc2 (g)", "acc3 (g)"],
            ["7", "4 column(s)"],
        ),
        (
            "{quantity: acceleration, unit: m/s^2, channels: [acc1, acc2]}",
            ["Time (s)", "acc1 (g)", "acc2 (g)", "acc3 (g)"],
            ["'acc1 (g)'", "disagrees", "'m/s^2'"],
        ),
        (
            "{quantity: acceleration, unit: g, channels: [acc1, acc2]}",
            None,
            ["'acc1'", "no line of column names"],
        ),
    ],
)
def test_ascii_channel_errors_name_the_file_and_the_column(tmp_path, response, names, words):
    sensors = three_sensors()
    writer = ascii_writer([np.arange(N) * DT_S, *sensors.values()], names)
    with pytest.raises(CampaignFormatError) as caught:
        read_one(tmp_path, yaml_with(response), "run.txt", writer)
    message = str(caught.value)
    assert "c/run.txt" in message
    for word in words:
        assert word in message


# --------------------------------------------------------------------------------------
# System formats, each file written by its own library


def test_plain_mat_variables(tmp_path):
    sensors = three_sensors()
    writer = lambda p: write_plain_mat(p, t=np.arange(N) * DT_S, **sensors)  # noqa: E731
    record = read_one(
        tmp_path,
        yaml_with("{quantity: acceleration, unit: g, channels: [acc1, acc2, acc3]}"),
        "run.mat",
        writer,
    )
    assert_channels(record, sensors, ["acc1", "acc2", "acc3"])


def test_mat73_variables(tmp_path):
    sensors = three_sensors()
    writer = lambda p: write_mat73(p, {"t": np.arange(N) * DT_S, **sensors})  # noqa: E731
    record = read_one(
        tmp_path, yaml_with("{quantity: acceleration, unit: g, channels: [acc2, acc3]}"), "run.mat", writer
    )
    assert_channels(record, sensors, ["acc2", "acc3"])


def test_testlab_function_records_with_units_from_the_file(tmp_path):
    sensors = three_sensors()
    names = ["Time Acc1:+X", "Time Acc2:+X", "Time Acc3:+X"]
    group = lms_export_group(names, np.column_stack(list(sensors.values())), "g", DT_S)
    writer = lambda p: write_testlab_mat(p, {"Signal": group})  # noqa: E731
    # neither sample rate nor unit in campaign.yaml: the export records both
    yaml_text = "name: t\nresponse: {quantity: acceleration, channels: ['Time Acc1:+X', 2]}\nconfigurations:\n  c: {files: 'c/*'}\n"
    record = read_one(tmp_path, yaml_text, "run.mat", writer)
    expected = {"Time Acc1:+X": sensors["acc1"], "2": sensors["acc3"]}
    assert_channels(record, expected, ["Time Acc1:+X", "2"])
    assert record.responses[1].source == "Time Acc3:+X"
    assert record.sample_rate_hz == pytest.approx(RATE_HZ)


def test_uff58_datasets(tmp_path):
    sensors = three_sensors()
    records = [uff58_record(name, values, "g", 12, DT_S) for name, values in sensors.items()]
    writer = lambda p: write_uff58(p, records)  # noqa: E731
    yaml_text = "name: t\nresponse: {quantity: acceleration, channels: [acc3, acc1]}\nconfigurations:\n  c: {files: 'c/*'}\n"
    record = read_one(tmp_path, yaml_text, "run.uff", writer)
    expected = {name: to_uff_ascii_precision(values) for name, values in sensors.items()}
    assert_channels(record, expected, ["acc3", "acc1"])


def test_tdms_channels(tmp_path):
    sensors = three_sensors()
    properties = {"unit_string": "g", "wf_increment": DT_S, "wf_start_offset": 0.0}
    writer = lambda p: write_tdms(p, "hit", {name: (v, properties) for name, v in sensors.items()})  # noqa: E731
    yaml_text = "name: t\nresponse: {quantity: acceleration, channels: [hit/acc2, acc1]}\nconfigurations:\n  c: {files: 'c/*'}\n"
    record = read_one(tmp_path, yaml_text, "run.tdms", writer)
    expected = {"hit/acc2": sensors["acc2"], "acc1": sensors["acc1"]}
    assert_channels(record, expected, ["hit/acc2", "acc1"])


def test_system_channel_errors(tmp_path):
    sensors = three_sensors()
    writer = lambda p: write_plain_mat(p, t=np.arange(N) * DT_S, **sensors)  # noqa: E731
    with pytest.raises(
        CampaignFormatError, match=r"c/run.mat: campaign.yaml response.channels: 'acc7' matches no channel"
    ):
        read_one(
            tmp_path,
            yaml_with("{quantity: acceleration, unit: g, channels: [acc1, acc7]}"),
            "run.mat",
            writer,
        )
    with pytest.raises(CampaignFormatError, match=r"c/run.mat: .*'acc1' more than once"):
        read_one(
            tmp_path, yaml_with("{quantity: acceleration, unit: g, channels: [acc1, 1]}"), "run.mat", writer
        )
    # a plain MAT file records no unit: campaign.yaml must give it
    with pytest.raises(CampaignFormatError, match=r"c/run.mat: variable 'acc2'.*records no unit.*add unit"):
        read_one(tmp_path, yaml_with("{quantity: acceleration, channels: [acc2]}"), "run.mat", writer)


def test_a_file_unit_of_another_quantity_is_refused_without_yaml_unit(tmp_path):
    sensors = three_sensors()
    group = lms_export_group(["Time Laser:+X"], sensors["acc1"][:, None], "m/s", DT_S)
    writer = lambda p: write_testlab_mat(p, {"Laser": group})  # noqa: E731
    yaml_text = "name: t\nresponse: {quantity: acceleration}\nconfigurations:\n  c: {files: 'c/*'}\n"
    with pytest.raises(
        CampaignFormatError,
        match=r"unit 'm/s' in the file is not a unit of acceleration .*; it is a unit of velocity: "
        r"leave quantity out of response in campaign.yaml .*or leave the channel out of channels",
    ):
        read_one(tmp_path, yaml_text, "run.mat", writer)


def test_a_channel_of_another_quantity_beside_others_is_refused_alone(tmp_path):
    # campaign.yaml says acceleration; the laser's m/s contradicts it: the laser is refused,
    # the accelerometers read
    sensors = three_sensors()
    groups = {
        "Laser": lms_export_group(["Time Laser:+X"], sensors["acc3"][:, None], "m/s", DT_S),
        "Signal": lms_export_group(["Time Acc1:+X"], sensors["acc1"][:, None], "g", DT_S),
    }
    writer = lambda p: write_testlab_mat(p, groups)  # noqa: E731
    names = ["Time Laser:+X", "Time Acc1:+X"]
    yaml_text = (
        f"name: t\nresponse: {{quantity: acceleration, channels: {names!r}}}\n"
        "configurations:\n  c: {files: 'c/*'}\n"
    )
    record = read_one(tmp_path, yaml_text, "run.mat", writer)
    assert record.channel_names() == ("Time Acc1:+X",) and record.response_unit == "g"
    np.testing.assert_array_equal(record.response, sensors["acc1"])
    [(name, why)] = record.refused_channels
    assert name == "Time Laser:+X"
    assert "unit 'm/s' in the file is not a unit of acceleration" in why and "leave quantity out" in why
    # an ASCII column with no unit where campaign.yaml gives none, beside one with its unit
    writer = ascii_writer(
        [np.arange(N) * DT_S, *sensors.values()], ["Time (s)", "acc1 (g)", "acc2", "acc3 (g)"]
    )
    record = read_one(
        tmp_path, yaml_with("{quantity: acceleration, channels: [acc2, acc3]}"), "run.txt", writer
    )
    assert record.channel_names() == ("acc3",)
    [(name, why)] = record.refused_channels
    assert name == "acc2" and "response column 'acc2': the file records no unit" in why


def test_without_a_quantity_each_channel_records_its_file_units_quantity(tmp_path):
    # a laser vibrometer (m/s) beside two accelerometers (g), as UNESP's beam was measured
    sensors = three_sensors()
    groups = {
        "Laser": lms_export_group(["Time Laser:+X"], sensors["acc3"][:, None], "m/s", DT_S),
        "Signal": lms_export_group(
            ["Time Acc1:+X", "Time Acc2:+X"], np.column_stack([sensors["acc1"], sensors["acc2"]]), "g", DT_S
        ),
    }
    writer = lambda p: write_testlab_mat(p, groups)  # noqa: E731
    names = ["Time Acc1:+X", "Time Laser:+X", "Time Acc2:+X"]
    yaml_text = f"name: t\nresponse: {{channels: {names!r}}}\nconfigurations:\n  c: {{files: 'c/*'}}\n"
    record = read_one(tmp_path, yaml_text, "run.mat", writer)
    assert [(c.unit, c.quantity) for c in record.responses] == [
        ("g", "acceleration"),
        ("m/s", "velocity"),
        ("g", "acceleration"),
    ]
    laser = record.for_channel("Time Laser:+X")
    assert (laser.response_quantity, laser.response_unit) == ("velocity", "m/s")
    np.testing.assert_array_equal(laser.response, sensors["acc3"])
    assert record.for_channel("Time Acc2:+X").response_quantity == "acceleration"


def test_ascii_columns_of_different_quantities_without_a_quantity_in_campaign_yaml(tmp_path):
    sensors = three_sensors()
    t = np.arange(N) * DT_S
    names = ["Time (s)", "acc1 (g)", "laser vel (in/s)", "disp3 (m)"]
    writer = ascii_writer([t, *sensors.values()], names)
    record = read_one(tmp_path, yaml_with("{channels: [acc1, laser vel, disp3]}"), "run.txt", writer)
    assert [c.quantity for c in record.responses] == ["acceleration", "velocity", "displacement"]
    assert record.for_channel("disp3").response_unit == "m"
    # with a quantity, a column named for another is the contradiction it was
    with pytest.raises(CampaignFormatError, match=r"'laser vel \(in/s\)' is velocity but campaign.yaml"):
        read_one(
            tmp_path, yaml_with("{quantity: acceleration, channels: [acc1, laser vel]}"), "run.txt", writer
        )


def test_a_response_unit_alone_names_the_quantity_and_nothing_at_all_is_refused_where_files_say_no_unit(
    tmp_path,
):
    assert ResponseSpec(unit="in/s").quantity == "velocity"
    assert ResponseSpec(unit="m/s2").quantity == "acceleration"
    with pytest.raises(ValueError, match=r"unit 'lbf' is no response unit; expected one of g, m/s\^2"):
        ResponseSpec(unit="lbf")
    sensors = three_sensors()
    writer = lambda p: write_plain_mat(p, acc1=sensors["acc1"])  # noqa: E731
    with pytest.raises(CampaignFormatError, match=r"c/run.mat: variable 'acc1'.*records no unit.*add unit"):
        read_one(tmp_path, yaml_with("{channels: [acc1]}"), "run.mat", writer)


# --------------------------------------------------------------------------------------
# Modes that decay, lines that do not


def decay_and_dwell(fs_hz=1024.0, duration_s=64.0, switch_off_s=51.2):
    """A 9 Hz dwell with its 18 Hz harmonic until ``switch_off_s``, then the free decay of
    an 18.79 Hz mode (zeta 0.4 %) it leaves ringing, as on the UNESP beam."""
    t = np.arange(int(duration_s * fs_hz)) / fs_hz
    on = t < switch_off_s
    dwell = on * (0.03 * np.sin(2 * np.pi * 9.0 * t) + 0.015 * np.sin(2 * np.pi * 18.0 * t))
    after = np.clip(t - switch_off_s, 0.0, None)
    omega = 2 * np.pi * 18.79
    mode = ~on * 0.05 * np.exp(-0.004 * omega * after) * np.sin(omega * after)
    noise = 1e-5 * np.random.default_rng(1).standard_normal(t.size)
    return t, dwell + mode + noise


def test_hold_fraction_of_a_free_decay_is_its_analytic_value():
    from scipy.optimize import brentq
    from scipy.special import log_ndtr

    from workflow.measured.mode import LINE_TRACK_RELATIVE_WIDTH, line_hold_fraction

    fs_hz, f_hz, zeta = 2560.0, 125.0, 0.01
    n = int(3.2 * fs_hz)
    t = np.arange(n) / fs_hz
    sigma = zeta * 2 * np.pi * f_hz
    x = np.exp(-sigma * t) * np.sin(2 * np.pi * f_hz * t)
    # The Gaussian band of time width s turns the decay starting at 0 into
    # exp(-sigma t) Phi((t - sigma s^2) / s); past the edges (three s each) the track holds
    # 3 dB from the interior's first sample until log(track) has fallen by ln(2) / 2.
    s = 1.0 / (2 * np.pi * LINE_TRACK_RELATIVE_WIDTH * f_hz)
    edge = int(np.ceil(3.0 * s * fs_hz))

    def log_track(time_s):
        return -sigma * time_s + log_ndtr((time_s - sigma * s**2) / s)

    start_s = edge / fs_hz
    cross_s = brentq(lambda time_s: log_track(start_s) - log_track(time_s) - np.log(2.0) / 2, start_s, 1.0)
    expected = (cross_s - start_s) / ((n - 2 * edge) / fs_hz)
    assert line_hold_fraction([x], fs_hz, f_hz) == pytest.approx(expected, abs=1.5 / (n - 2 * edge))


def test_a_long_record_tracks_its_line_at_fewer_instants_to_the_same_fraction():
    """On a 131,072-sample record at 51.2 kHz the track is read at 32 instants per band bin,
    not at every sample: exactly the band's analytic signal at those instants, and the hold
    fraction the same as over every sample to within one instant's spacing."""
    from workflow.measured.mode import (
        LINE_TRACK_RELATIVE_WIDTH,
        TRACK_POINTS_PER_BIN,
        _line_track,
        line_hold_fraction,
    )

    rng = np.random.default_rng(3)
    fs_hz, f_hz, n = 51200.0, 151.0, 131072
    t = np.arange(n) / fs_hz
    x = np.exp(-0.0018 * 2 * np.pi * f_hz * t) * np.sin(2 * np.pi * f_hz * t) + 1e-4 * rng.normal(size=n)
    sigma_hz = LINE_TRACK_RELATIVE_WIDTH * f_hz
    spectrum = np.fft.rfft(x - x.mean())
    coarse = _line_track(spectrum, n, fs_hz, f_hz, sigma_hz, points_per_bin=TRACK_POINTS_PER_BIN)
    frequency_hz = np.fft.rfftfreq(n, 1 / fs_hz)
    bins = np.flatnonzero(np.abs(frequency_hz - f_hz) < 40 * sigma_hz)
    assert coarse.size == TRACK_POINTS_PER_BIN * bins.size < n / 10
    # the definition at the instants j n / points: (2 / n) |sum_k X_k g_k exp(2 pi i k t / n)| / 2
    gain = np.exp(-0.5 * ((frequency_hz[bins] - f_hz) / sigma_hz) ** 2)
    instants = np.arange(coarse.size) * (n / coarse.size)
    definition = np.abs(np.exp(2j * np.pi * np.outer(instants, bins) / n) @ (spectrum[bins] * gain)) / n
    assert np.max(np.abs(coarse - definition)) < 1e-12 * definition.max()
    # the fraction over every sample, as the track was read before
    every = _line_track(spectrum, n, fs_hz, f_hz, sigma_hz)
    edge = int(np.ceil(3.0 / (2.0 * np.pi * sigma_hz) * fs_hz))
    inner = every[edge:-edge]
    full_fraction = np.mean(inner >= inner.max() / np.sqrt(2.0))
    inner_points = coarse.size * (1 - 2 * edge / n)
    assert line_hold_fraction([x], fs_hz, f_hz) == pytest.approx(full_fraction, abs=1.5 / inner_points)


def test_a_steady_line_beside_a_mode_does_not_decay_and_the_mode_does():
    from workflow.measured.mode import STATIONARY_HOLD_FRACTION, line_hold_fraction

    _, x = decay_and_dwell()
    assert line_hold_fraction([x], 1024.0, 18.0) > 0.75  # on for 51 of 64 s
    assert line_hold_fraction([x], 1024.0, 18.79) < STATIONARY_HOLD_FRACTION / 5


def test_auto_modes_leave_out_a_dwell_and_its_harmonic():
    from workflow.measured import mode as modal_id

    fs_hz = 2560.0
    t = np.arange(int(5 * fs_hz)) / fs_hz
    modes = [(80.5, 0.01, 1.0), (297.7, 0.005, 0.3), (610.0, 0.004, 0.1)]
    x = sum(a * np.exp(-z * 2 * np.pi * f * t) * np.sin(2 * np.pi * f * t) for f, z, a in modes)
    x = x + 0.05 * np.sin(2 * np.pi * 50.0 * t) + 0.03 * np.sin(2 * np.pi * 150.0 * t)
    x = x + 1e-4 * np.random.default_rng(2).standard_normal(t.size)
    frequency_hz, psd = modal_id.response_spectrum([x], fs_hz)
    found, left_out = modal_id.find_decaying_modes(
        [x], fs_hz, frequency_hz, np.sqrt(psd), (5.0, 0.4 * fs_hz), 0.2, 2.0
    )
    assert len(found) == 3
    # each within 5 % of its half-power bandwidth 2 zeta f (the peak's own width)
    for found_hz, (f, zeta, _) in zip(found, modes):
        assert abs(found_hz - f) < 0.05 * 2 * zeta * f
    assert any(
        "150.000 Hz" in reason and "3rd harmonic of the steady line at 50.000 Hz" in reason
        for reason in left_out
    )
    assert any("50.000 Hz does not decay" in reason for reason in left_out)


def test_the_first_mode_search_stops_on_a_line_that_does_not_decay(tmp_path):
    t, x = decay_and_dwell()
    writer = lambda p: write_plain_mat(p, t=t, v=x)  # noqa: E731
    yaml_text = "name: t\nmode_hz: 18.7\nresponse: {quantity: velocity, unit: m/s, channel: v}\nconfigurations:\n  c: {files: 'c/*'}\n"
    assert_dwell_line_named_then_mode_found(write_campaign(tmp_path, yaml_text, "run.mat", writer), yaml_text)


def assert_dwell_line_named_then_mode_found(folder, yaml_text):
    """Without window_s the search stops on the dwell's 18 Hz harmonic, naming it and asking
    for the window; with the window from the switch-off (51.2 s) it finds the 18.79 Hz mode."""
    found = identify(folder)
    assert found.mode is None
    assert "18.000 Hz does not decay in the analysis window" in found.error
    assert "2nd harmonic of the steady line at 9.000 Hz" in found.error and "window_s" in found.error
    (folder / "campaign.yaml").write_text(
        yaml_text.replace("{files: 'c/*'}", "{files: 'c/*', window_s: [51.2, 64]}")
    )
    found = identify(folder)
    # to half the resolution of a 12.8 s window (0.08 Hz)
    assert found.mode is not None and found.mode.mode_hz == pytest.approx(18.79, abs=0.04)


def identify(folder):
    from workflow.measured.mode_identification import identify_configuration_mode
    from workflow.measured.settings import AnalysisSettings, QualitySettings

    return identify_configuration_mode(
        folder,
        ["c/run.mat"],
        configuration="c",
        campaign=load_campaign(folder),
        mode_search=AnalysisSettings(),
        quality_settings=QualitySettings(),
    )


UNESP_EXPORT = REALDATA / "raw" / "unesp_T5Nm_Sine_09Hz_Time.mat"


@needs_realdata("raw")
def test_unesp_export_without_window_or_unit_names_the_dwell_line_and_asks_for_the_window(tmp_path):
    yaml_text = (
        "name: unesp\nmode_hz: 18.7\n"
        'response: {quantity: velocity, channel: "Time Laser:+X"}\n'
        "configurations:\n  c: {files: 'c/*'}\n"
    )
    folder = write_campaign(tmp_path, yaml_text, "run.mat", lambda p: shutil.copyfile(UNESP_EXPORT, p))
    record = read_run(folder, "c/run.mat", load_campaign(folder))
    assert record.response_unit == "m/s" and record.sample_rate_hz == 1024.0  # from the file
    assert_dwell_line_named_then_mode_found(folder, yaml_text)


# --------------------------------------------------------------------------------------
# diagnosis.json: modes and channels


def entry(cause, confidence, ratio, model="dahl"):
    """A configuration's entry of a one-channel document (the keys with_channels reads)."""
    return {
        "cause": cause,
        "confidence": confidence,
        "gain": {"ratio": ratio},
        "extended_model": {"model": model},
    }


def document(cause, confidence, ratio):
    """A one-configuration campaign document (the keys mode_document reads)."""
    return {
        "campaign": "c",
        "cause": cause,
        "confidence": confidence,
        "configurations": {"hit": entry(cause, confidence, ratio)},
        "skipped_configurations": {},
    }


def test_the_joint_verdict_is_kept_and_each_channel_listed_beside_it():
    """No vote: the configuration's entry is the joint analysis's even where most
    channels alone name something else; each channel's own verdict is under channels."""
    from workflow.discovery.modes import with_channels

    joint = entry("microslip_power_law", {"microslip_power_law": 0.7, "none": 0.3}, 0.5, "iwan")
    entries = {
        "acc1": entry("microslip_power_law", {"microslip_power_law": 0.9, "none": 0.1}, 0.4, "iwan"),
        "acc2": entry("none", {"none": 0.6, "microslip_power_law": 0.4}, 1.0),
        "acc3": entry("none", {"none": 0.8, "microslip_power_law": 0.2}, 1.0),
    }
    combined = with_channels(joint, entries)
    assert {k: v for k, v in combined.items() if k != "channels"} == joint
    assert list(combined["channels"]) == ["acc1", "acc2", "acc3"]
    assert combined["channels"]["acc3"] == {
        "cause": "none",
        "causes": ["none"],
        "confidence": entries["acc3"]["confidence"],
        "gain": {"ratio": 1.0},
    }


def test_modes_document_repeats_the_first_mode_at_the_top():
    from workflow.discovery.modes import mode_document, with_modes

    first = document("microslip_power_law", {"microslip_power_law": 1.0}, 0.2)
    one = mode_document(80.5, {"response": first})
    assert one == {"mode_hz": 80.5, **first}
    joint = document("quadratic_damping", {"quadratic_damping": 0.6, "none": 0.4}, 0.6)
    second = mode_document(
        297.7,
        {
            "a": document("none", {"none": 1.0}, 1.0),
            "b": document("quadratic_damping", {"quadratic_damping": 0.5, "none": 0.5}, 0.8),
        },
        joint,
    )
    # the joint analysis's verdict and confidence, each channel's beside it
    assert second["cause"] == "quadratic_damping" and second["confidence"] == joint["confidence"]
    assert second["configurations"]["hit"]["cause"] == "quadratic_damping"
    assert second["configurations"]["hit"]["channels"]["a"]["cause"] == "none"
    whole = with_modes([one, second])
    assert {key: value for key, value in whole.items() if key != "modes"} == first
    assert [mode["mode_hz"] for mode in whole["modes"]] == [80.5, 297.7]


# --------------------------------------------------------------------------------------
# The workflow on a hit seen by two sensors, every mode found


def two_sensor_campaign(root: Path) -> Path:
    """Three lab hits, each seen by two accelerometers (acc2 at half acc1's mode-1 shape),
    written as one ASCII file per hit with the two response columns by name (units in the
    names, none in campaign.yaml) and ``modes_hz: auto``."""
    from workflow.lab.campaigns import generate_sensor_campaigns

    generate_sensor_campaigns(
        root / "sensors",
        {"acc1": 1.0, "acc2": 0.5},
        seed=4,
        runs_per_configuration=3,
        configurations={"c": None},
    )
    campaign = root / "campaign"
    (campaign / "c").mkdir(parents=True)
    for run in ("run01", "run02", "run03"):
        one, two = (
            np.loadtxt(root / "sensors" / s / "c" / f"{run}.txt", skiprows=4) for s in ("acc1", "acc2")
        )
        columns = np.column_stack([one[:, :3], two[:, 2]])
        rows = "\n".join("\t".join(f"{value:.10g}" for value in row) for row in columns)
        (campaign / "c" / f"{run}.txt").write_text(
            f"Pre-trigger: 25 samples\nTime (s)\tForce (lbf)\tacc1 (g)\tacc2 (g)\n{rows}\n"
        )
    (campaign / "campaign.yaml").write_text(
        "name: two-sensors\nmodes_hz: auto\nresponse: {quantity: acceleration, channels: [acc1, acc2]}\n"
        'force: {unit: lbf}\nconfigurations:\n  c: {files: "c/*.txt"}\n'
    )
    return campaign


def test_workflow_analyses_every_mode_on_every_channel(tmp_path):
    import json

    import pandas as pd
    from helpers import CHEAP, run_snakemake

    campaign = two_sensor_campaign(tmp_path)
    work = tmp_path / "work"
    done = run_snakemake(work, "-c2", "all", "--config", f"campaign={campaign}", *CHEAP, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    modes = pd.read_parquet(work / "results/tables/modes.parquet")
    found_hz = sorted(modes["nominal_mode_hz"])
    assert len(found_hz) >= 2  # the lab's beam rings in its first modes
    assert found_hz[0] == pytest.approx(126.0, rel=0.03)  # the lab's first mode
    segments = pd.read_parquet(work / "results/tables/segments.parquet")
    pairs = set(zip(segments["mode_hz"], segments["channel"]))
    assert pairs == {(mode_hz, channel) for mode_hz in found_hz for channel in ("acc1", "acc2")}
    # acc2 sees mode 1 at half acc1's amplitude: the same decay at half the envelope
    first = segments[segments["mode_hz"] == found_hz[0]].groupby("channel")["response_amplitude"].max()
    assert first["acc2"] / first["acc1"] == pytest.approx(0.5, rel=0.05)
    for name in ("damping_fits", "hypotheses", "quality", "damping_curves"):
        table = pd.read_parquet(work / f"results/tables/{name}.parquet")
        assert {"mode_hz", "channel"} <= set(table.columns), name
    fits = pd.read_parquet(work / "results/tables/damping_fits.parquet")
    assert set(zip(fits["mode_hz"], fits["channel"])) == pairs
    document = json.loads((work / "results/diagnosis.json").read_text())
    assert [mode["mode_hz"] for mode in document["modes"]] == pytest.approx(found_hz)
    for mode in document["modes"]:
        configuration = mode["configurations"]["c"]
        assert set(configuration["channels"]) == {"acc1", "acc2"}
        assert set(configuration["joint"]["amplitude_factors"]) == {"acc1", "acc2"}
    # one joint analysis of mode 1 on acc1's scale: acc2's amplitudes doubled
    joint = document["configurations"]["c"]["joint"]
    assert joint["reference_channel"] == "acc1"
    assert joint["amplitude_factors"]["acc2"] == pytest.approx(2.0, rel=0.05)
    top = {key: value for key, value in document.items() if key != "modes"}
    assert top == {key: value for key, value in document["modes"][0].items() if key != "mode_hz"}


def test_verdict_page_has_a_section_per_mode_with_each_channel_escaped():
    from workflow.outputs.verdict_page import modes_section

    channel = "<b>acc1</b> & co"
    configuration = {
        "cause": "none",
        "confidence": {"none": 1.0},
        "gain": {"ratio": 1.0},
        "channels": {channel: {"cause": "none", "confidence": {"none": 1.0}, "gain": {"ratio": 1.0}}},
    }
    document = {
        "modes": [
            {
                "mode_hz": 80.5,
                "cause": "none",
                "confidence": {"none": 1.0},
                "configurations": {"hit": configuration},
            },
            {
                "mode_hz": 297.7,
                "cause": "none",
                "confidence": {"none": 1.0},
                "configurations": {"hit": configuration},
            },
        ]
    }
    html = "".join(modes_section(document))
    assert "mode 80.5 Hz" in html and "mode 297.7 Hz" in html
    assert "&lt;b&gt;acc1&lt;/b&gt; &amp; co" in html and channel not in html
    one = {"modes": [{"mode_hz": 80.5, "cause": "none", "configurations": {"hit": {"cause": "none"}}}]}
    assert modes_section(one) == []


def test_listed_modes_are_found_each_in_its_band_and_auto_finds_both(tmp_path):
    sensors = three_sensors()
    writer = lambda p: write_plain_mat(p, t=np.arange(N) * DT_S, **sensors)  # noqa: E731
    listed = yaml_with(
        "{quantity: acceleration, unit: g, channels: [acc1, acc2, acc3]}",
        "modes_hz: [80, 300]\nbands_hz: [[70, 90], [280, 310]]\n",
    )
    folder = write_campaign(tmp_path, listed, "run.mat", writer)
    found = identify(folder)
    assert [mode.band_hz for mode in found.modes] == [(70.0, 90.0), (280.0, 310.0)]
    # a 1.6 s record: 0.625 Hz bins; the peak is refined to a fraction of one
    assert [mode.mode_hz for mode in found.modes] == pytest.approx([80.5, 297.7], abs=0.3)
    (folder / "campaign.yaml").write_text(
        listed.replace("modes_hz: [80, 300]\nbands_hz: [[70, 90], [280, 310]]\n", "modes_hz: auto\n")
    )
    found = identify(folder)
    assert [mode.mode_hz for mode in found.modes] == pytest.approx([80.5, 297.7], abs=0.3)
    assert found.left_out == ()


def test_line_track_equals_the_full_complex_transform():
    """The track from real transforms equals the definition: the magnitude of the inverse
    complex FFT of the whole spectrum times the Gaussian gain, to rounding."""
    from workflow.measured.mode import _line_track

    rng = np.random.default_rng(8)
    fs_hz = 1024.0
    for n, line_hz in ((8192, 18.79), (8192, 400.0), (8191, 400.0)):
        x = rng.normal(size=n)
        sigma_hz = 0.01 * line_hz
        frequency_hz = np.fft.fftfreq(n, 1.0 / fs_hz)
        gain = np.exp(-0.5 * ((frequency_hz - line_hz) / sigma_hz) ** 2)
        definition = np.abs(np.fft.ifft(np.fft.fft(x) * gain))
        got = _line_track(np.fft.rfft(x), n, fs_hz, line_hz, sigma_hz)
        assert np.max(np.abs(got - definition)) < 1e-13 * np.max(definition)

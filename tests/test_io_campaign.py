"""Reading campaigns: campaign.yaml validation, run discovery, every run-file dialect
and every malformed case of campaign-format.md."""

import os

import numpy as np
import pytest
from helpers import REALDATA, needs_realdata

from workflow.io import interim
from workflow.io.campaign import load_campaign
from workflow.io.recording_time import run_order
from workflow.io.records import MIN_SAMPLES, CampaignFormatError, RunFile
from workflow.io.run_files import list_runs, read_run

FS_HZ = 2560.0
N = 300

YAML_FORCE = """\
name: test
sample_rate_hz: 2560
response: {quantity: acceleration, unit: g}
force: {unit: lbf}
configurations:
  cfg: {}
"""
YAML_NO_FORCE = """\
name: test
response: {quantity: acceleration, unit: g}
configurations:
  cfg: {}
"""


def signals(n=N):
    """Time (s), force (lbf) and response (g) columns of a synthetic ring-down."""
    t = np.arange(n) / FS_HZ
    force = 50.0 * np.exp(-(((t - 0.01) / 0.001) ** 2))
    response = 3.0 * np.exp(-2.0 * t) * np.sin(2 * np.pi * 125.0 * t)
    return t, force, response


def table(columns, delimiter="\t", fmt="{:.6f}", newline="\n"):
    """Numeric rows as text."""
    rows = [delimiter.join(fmt.format(v) for v in row) for row in zip(*columns)]
    return newline.join(rows) + newline


def write_campaign(tmp_path, yaml_text, files):
    """A campaign folder with campaign.yaml and the given {relative path: text}."""
    (tmp_path / "campaign.yaml").write_text(yaml_text)
    for relative, text in files.items():
        path = tmp_path / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(text.encode() if isinstance(text, str) else text)
    return load_campaign(tmp_path)


def read_one(tmp_path, text, yaml_text=YAML_FORCE):
    campaign = write_campaign(tmp_path, yaml_text, {"cfg/run01.txt": text})
    return read_run(tmp_path, "cfg/run01.txt", campaign)


def format_error(tmp_path, text, yaml_text=YAML_FORCE):
    with pytest.raises(CampaignFormatError) as info:
        read_one(tmp_path, text, yaml_text)
    error = info.value
    assert error.path.endswith("cfg/run01.txt"), error.path
    return error


# ------------------------------------------------------------------ campaign.yaml


def test_campaign_defaults(tmp_path):
    campaign = write_campaign(tmp_path, YAML_NO_FORCE, {})
    assert campaign.pretrigger_samples == 0 and not campaign.pretrigger_given
    assert campaign.sample_rate_hz is None and campaign.force is None
    assert campaign.mode_hz is None and campaign.band_hz is None
    assert campaign.configurations["cfg"].files == "cfg/*.txt"
    assert campaign.configurations["cfg"].bearing_area_in2 is None
    assert campaign.bearing_areas_in2() == {"cfg": None}
    assert campaign.configurations["cfg"].window_s is None


def test_campaign_full_example_of_the_contract(tmp_path):
    text = """\
name: washers-2004
sample_rate_hz: 2560
pretrigger_samples: 25
mode_hz: 125
band_hz: [100, 150]
response: {quantity: acceleration, unit: g}
force: {unit: lbf}
configurations:
  no_washer:    {bearing_area_in2: 1.36, files: "no_washer/*.txt"}
  large_washer: {bearing_area_in2: 0.66, files: "large_washer/*.txt"}
  small_washer: {bearing_area_in2: 0.17, window_s: [0.5, 3.0]}
"""
    campaign = write_campaign(tmp_path, text, {})
    assert list(campaign.configurations) == ["no_washer", "large_washer", "small_washer"]
    assert campaign.pretrigger_samples == 25 and campaign.pretrigger_given
    assert campaign.band_hz == (100.0, 150.0)
    assert campaign.configurations["small_washer"].files == "small_washer/*.txt"
    assert campaign.configurations["small_washer"].window_s == (0.5, 3.0)
    assert campaign.force.unit == "lbf"
    assert campaign.bearing_areas_in2() == {"no_washer": 1.36, "large_washer": 0.66, "small_washer": 0.17}


@pytest.mark.parametrize(
    "text",
    [
        YAML_FORCE,
        YAML_NO_FORCE,
        """\
name: 2004
pretrigger_samples: 25
band_hz: [100, 150]
response: {quantity: velocity, unit: "IN/S"}
force: {unit: newton}
configurations:
  a: {bearing_area_in2: 0.17, window_s: [0.5, 3.0]}
""",
    ],
)
def test_validated_campaign_survives_its_json_copy(tmp_path, text):
    # Later jobs read campaign.yaml's validated JSON copy: it must give back the very
    # same campaign, including what is not a key (pretrigger_given) and the tuples.
    campaign = write_campaign(tmp_path, text, {})
    path = tmp_path / "campaign.json"
    interim.write_campaign(path, campaign)
    copy = interim.read_campaign(path)
    assert copy == campaign
    assert copy.pretrigger_given == campaign.pretrigger_given


def test_name_defaults_to_folder_and_bare_configuration(tmp_path):
    folder = tmp_path / "my-campaign"
    folder.mkdir()
    campaign = write_campaign(
        folder, "response: {quantity: velocity, unit: m/s}\nconfigurations:\n  only:\n", {}
    )
    assert campaign.name == "my-campaign"
    assert campaign.configurations["only"].files == "only/*.txt"


@pytest.mark.parametrize(
    ("text", "line", "words"),
    [
        (
            YAML_NO_FORCE.replace("name: test", "name: test\nsampel_rate_hz: 2560"),
            2,
            ["sampel_rate_hz", "unknown key", "sample_rate_hz"],
        ),
        (
            YAML_NO_FORCE.replace("cfg: {}", "cfg: {bearing_area: 1.0}"),
            4,
            ["configurations.cfg.bearing_area", "unknown key", "bearing_area_in2"],
        ),
        (YAML_NO_FORCE.replace("unit: g}", "unit: g, units: g}"), 2, ["response.units", "unknown key"]),
        (YAML_NO_FORCE.replace("unit: g", "unit: m/s"), 2, ["response", "'m/s'", "acceleration"]),
        (YAML_NO_FORCE.replace("acceleration", "jerk"), 2, ["response.quantity"]),
        ("name: x\nconfigurations:\n  cfg: {}\n", None, ["response", "missing"]),
        (YAML_NO_FORCE + "band_hz: [150, 100]\n", 5, ["band_hz", "low < high"]),
        (YAML_NO_FORCE.replace("cfg: {}", "cfg: {window_s: [2, 1]}"), 4, ["window_s"]),
        (YAML_NO_FORCE + "sample_rate_hz: -5\n", 5, ["sample_rate_hz", "greater than 0"]),
        (YAML_NO_FORCE + "force: {unit: kg}\n", 5, ["force.unit", "'kg'"]),
        (YAML_NO_FORCE + "name: again\n", 5, ["name", "twice"]),
        (YAML_NO_FORCE.replace("cfg: {}", "cfg: {files: /abs/*.txt}"), 4, ["files", "relative"]),
        ("name: [unclosed\n", 2, ["not valid YAML"]),
        ("- a\n- b\n", 1, ["mapping"]),
    ],
)
def test_campaign_yaml_errors_name_file_key_and_line(tmp_path, text, line, words):
    (tmp_path / "campaign.yaml").write_text(text)
    with pytest.raises(CampaignFormatError) as info:
        load_campaign(tmp_path)
    error = info.value
    assert error.path.endswith("campaign.yaml")
    assert error.line == line
    for word in words:
        assert word in error.problem, (word, error.problem)
    assert str(error).startswith(error.path)


def test_missing_campaign_yaml(tmp_path):
    with pytest.raises(CampaignFormatError, match="campaign.yaml: missing"):
        load_campaign(tmp_path)


def test_error_string_with_and_without_line():
    assert str(CampaignFormatError("a/b.txt", 7, "bad")) == "a/b.txt:7: bad"
    assert str(CampaignFormatError("a/b.txt", None, "bad")) == "a/b.txt: bad"
    assert isinstance(CampaignFormatError("a", 1, "b"), ValueError)


def test_error_survives_pickling():
    import pickle

    error = pickle.loads(pickle.dumps(CampaignFormatError("x.txt", 3, "ragged")))
    assert (error.path, error.line, error.problem) == ("x.txt", 3, "ragged")


# ------------------------------------------------------------------ run discovery


def test_list_runs_orders_and_paths(tmp_path):
    yaml_text = YAML_NO_FORCE.replace("  cfg: {}", '  zeta: {files: "z/**/*.txt"}\n  alpha: {}')
    files = {
        "z/b.txt": "",
        "z/sub/a.txt": "",
        "alpha/run10.txt": "",
        "alpha/run02.txt": "",
        "alpha/._run01.txt": "",
        "alpha/notes.csv": "",
    }
    campaign = write_campaign(tmp_path, yaml_text, files)
    runs = list_runs(tmp_path, campaign)
    assert runs == [
        RunFile("zeta", "a", "z/sub/a.txt"),
        RunFile("zeta", "b", "z/b.txt"),
        RunFile("alpha", "run02", "alpha/run02.txt"),
        RunFile("alpha", "run10", "alpha/run10.txt"),
    ]


def test_runs_are_listed_in_the_run_order_the_diagnosis_uses(tmp_path):
    # "run1-b.txt" sorts before "run1.txt" as a file name, after "run1" as a run name;
    # the tables and the run-order test must agree on one order
    campaign = write_campaign(
        tmp_path, YAML_NO_FORCE, {"cfg/run1-b.txt": "", "cfg/run1.txt": "", "cfg/run0.txt": ""}
    )
    names = [run.run for run in list_runs(tmp_path, campaign)]
    assert names == ["run0", "run1", "run1-b"]
    assert run_order(names, {})[0] == names


def test_folders_starting_with_a_dot_are_skipped_unless_the_glob_names_one(tmp_path):
    files = {
        "cfg/a/run01.txt": "",
        "cfg/.ipynb_checkpoints/run01-checkpoint.txt": "",
        "cfg/.kept/run02.txt": "",
    }
    everywhere = YAML_NO_FORCE.replace("cfg: {}", 'cfg: {files: "cfg/*/*.txt"}')
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
    campaign = write_campaign(tmp_path / "a", everywhere, files)
    assert [run.path for run in list_runs(tmp_path / "a", campaign)] == ["cfg/a/run01.txt"]
    named = YAML_NO_FORCE.replace("cfg: {}", 'cfg: {files: "cfg/.kept/*.txt"}')
    campaign = write_campaign(tmp_path / "b", named, files)
    assert [run.path for run in list_runs(tmp_path / "b", campaign)] == ["cfg/.kept/run02.txt"]


def test_list_runs_rejects_two_runs_with_one_name(tmp_path):
    yaml_text = YAML_NO_FORCE.replace("cfg: {}", 'cfg: {files: "cfg/**/*.txt"}')
    campaign = write_campaign(tmp_path, yaml_text, {"cfg/a/r.txt": "", "cfg/b/r.txt": ""})
    with pytest.raises(CampaignFormatError, match="two runs named 'r'"):
        list_runs(tmp_path, campaign)


# ------------------------------------------------------------------ dialects

HEADER_NAMES = {
    "\t": "Time (s)\tForce (lbf)\tAcceleration (g)",
    ",": "Time (s),Force (lbf),Acceleration (g)",
    ";": "Time (s);Force (lbf);Acceleration (g)",
    " ": "Time (s)   Force (lbf)   Acceleration (g)",
}


@pytest.mark.parametrize("delimiter", ["\t", ",", ";", " ", "   "])
@pytest.mark.parametrize("newline", ["\n", "\r\n"])
@pytest.mark.parametrize("fmt", ["{:.6f}", "{:.6e}", "{:+.5E}"])
def test_every_delimiter_newline_and_notation(tmp_path, delimiter, newline, fmt):
    t, force, response = signals()
    names = HEADER_NAMES[delimiter[0]]
    text = newline.join(["Export", names]) + newline + table((t, force, response), delimiter, fmt, newline)
    record = read_one(tmp_path, text)
    resolution = 1e-6 if "f" in fmt else 1e-5 * np.abs(response).max()
    np.testing.assert_allclose(record.response, response, atol=resolution)
    np.testing.assert_allclose(record.force_lbf, force, atol=max(1e-6, 1e-5 * 50))
    np.testing.assert_allclose(record.time_s, t, atol=1e-6)
    assert record.n_samples == N
    assert record.sample_rate_hz == FS_HZ
    assert record.column_names == ("Time (s)", "Force (lbf)", "Acceleration (g)")
    assert (record.response_quantity, record.response_unit) == ("acceleration", "g")


def test_dactron_header_example(tmp_path):
    t, force, response = signals()
    text = (
        "Dactron RT Pro ASCII export\nSample rate: 2560 Hz\nPre-trigger: 25 samples\n"
        "Time (s)\tForce (lbf)\tAcceleration (g)\n" + table((t, force, response))
    )
    record = read_one(tmp_path, text, YAML_NO_FORCE)
    assert record.sample_rate_hz == 2560.0
    assert record.pretrigger_samples == 25 and record.pretrigger_source == "header"
    assert record.header == {"Sample rate": "2560 Hz", "Pre-trigger": "25 samples"}
    assert record.path == "cfg/run01.txt"


@pytest.mark.parametrize(
    "line", ["Sample rate (Hz): 2560", "Sample rate: 2.56 kHz", "Sampling frequency: 2560"]
)
def test_sample_rate_header_forms(tmp_path, line):
    _, force, response = signals()
    text = line + "\n" + table((response,))
    record = read_one(tmp_path, text, YAML_NO_FORCE)
    assert record.sample_rate_hz == pytest.approx(2560.0)
    assert record.sample_rate_source == "header"
    assert record.time_s is None


def test_pretrigger_in_milliseconds(tmp_path):
    _, _, response = signals()
    record = read_one(
        tmp_path, "Sample rate: 2560 Hz\nPre-trigger: 10 ms\n" + table((response,)), YAML_NO_FORCE
    )
    assert record.pretrigger_samples == round(0.010 * 2560)


def test_three_columns_without_names_are_time_force_response(tmp_path):
    t, force, response = signals()
    record = read_one(tmp_path, table((t, force, response)), YAML_NO_FORCE)
    np.testing.assert_allclose(record.force_lbf, force, atol=1e-6)
    np.testing.assert_allclose(record.response, response, atol=1e-6)
    assert record.sample_rate_source == "time column"
    assert record.sample_rate_hz == pytest.approx(FS_HZ, rel=1e-4)


def test_two_columns_without_names_and_force_in_yaml(tmp_path):
    _, force, response = signals()
    record = read_one(tmp_path, table((force, response)), YAML_FORCE)
    np.testing.assert_allclose(record.force_lbf, force, atol=1e-6)
    np.testing.assert_allclose(record.response, response, atol=1e-6)
    assert record.time_s is None and record.sample_rate_hz == FS_HZ


def test_two_columns_without_names_and_no_force_in_yaml(tmp_path):
    t, _, response = signals()
    record = read_one(tmp_path, table((t, response)), YAML_NO_FORCE)
    assert record.force_lbf is None
    np.testing.assert_allclose(record.time_s, t, atol=1e-6)
    np.testing.assert_allclose(record.response, response, atol=1e-6)


def test_one_column_is_the_response(tmp_path):
    _, _, response = signals()
    record = read_one(tmp_path, table((response,)), YAML_FORCE)
    assert record.force_lbf is None and record.time_s is None
    np.testing.assert_allclose(record.response, response, atol=1e-6)


def test_roles_follow_names_not_position(tmp_path):
    t, force, response = signals()
    text = "Accel (g),Other,Hammer,time\n" + table((response, force * 0, force, t), ",")
    record = read_one(tmp_path, text, YAML_NO_FORCE)
    np.testing.assert_allclose(record.response, response, atol=1e-6)
    np.testing.assert_allclose(record.force_lbf, force, atol=1e-6)
    np.testing.assert_allclose(record.time_s, t, atol=1e-6)


def test_force_in_newtons_is_converted_to_lbf(tmp_path):
    t, force, response = signals()
    force_n = force * 4.4482216152605
    text = "Time (s)\tForce (N)\tResponse (g)\n" + table((t, force_n, response), fmt="{:.8e}")
    record = read_one(tmp_path, text, YAML_NO_FORCE)
    np.testing.assert_allclose(record.force_lbf, force, rtol=1e-7, atol=1e-12)


def test_time_in_milliseconds_and_units_row(tmp_path):
    t, force, response = signals()
    text = "Time\tForce\tAcceleration\nms\tlbf\tg\n" + table((t * 1e3, force, response), fmt="{:.5f}")
    record = read_one(tmp_path, text, YAML_NO_FORCE)
    np.testing.assert_allclose(record.time_s, t, atol=1e-8)
    assert record.sample_rate_hz == pytest.approx(FS_HZ, rel=1e-4)


def test_names_with_single_spaces_and_space_delimiter(tmp_path):
    t, _, response = signals()
    text = "Time (s) Velocity (m/s)\n" + table((t, response), " ")
    yaml_text = YAML_NO_FORCE.replace("{quantity: acceleration, unit: g}", "{quantity: velocity, unit: m/s}")
    record = read_one(tmp_path, text, yaml_text)
    assert record.column_names == ("Time (s)", "Velocity (m/s)")


def test_trailing_delimiter_on_every_row(tmp_path):
    t, force, response = signals()
    rows = table((t, force, response), ",").replace("\n", ",\n")
    record = read_one(tmp_path, rows, YAML_NO_FORCE)
    np.testing.assert_allclose(record.response, response, atol=1e-6)


def test_blank_lines_after_the_numbers_are_fine(tmp_path):
    _, _, response = signals()
    record = read_one(tmp_path, table((response,)) + "\n\n  \n", YAML_FORCE)
    assert record.n_samples == N


def test_raw_file_is_not_modified_and_may_be_read_only(tmp_path):
    t, force, response = signals()
    text = table((t, force, response))
    campaign = write_campaign(tmp_path, YAML_NO_FORCE, {"cfg/run01.txt": text})
    path = tmp_path / "cfg/run01.txt"
    os.chmod(path, 0o444)
    before = (path.read_bytes(), path.stat().st_mtime_ns)
    read_run(tmp_path, RunFile("cfg", "run01", "cfg/run01.txt"), campaign)
    assert (path.read_bytes(), path.stat().st_mtime_ns) == before


# ------------------------------------------------------------------ malformed input


def _rows(n=N, ncols=3):
    t, force, response = signals(n)
    return table((t, force, response)[3 - ncols :]).splitlines()


def _replace_row(rows, index, new):
    rows = list(rows)
    rows[index] = new
    return "\n".join(rows) + "\n"


@pytest.mark.parametrize(
    ("make_text", "line", "words"),
    [
        (lambda: "", 1, ["empty"]),
        (lambda: "\n  \n", 1, ["empty"]),
        (lambda: "Export\nTime (s)\tForce\tAcc\n", 2, ["no numeric rows"]),
        (lambda: "Some text\nmore text", 2, ["no numeric rows"]),
        (lambda: "H\n" + _replace_row(_rows(), 40, "0.1\t0.2"), 42, ["ragged", "2 values", "expected 3"]),
        (lambda: "H\n" + _replace_row(_rows(), 40, "0.1\t0.2\t0.3\t0.4"), 42, ["ragged", "4 values"]),
        (lambda: "H\n" + _replace_row(_rows(), 7, "0.1\tabc\t0.3"), 9, ["non-numeric", "'abc'", "column 2"]),
        (lambda: _replace_row(_rows(), 99, "0.1\t0.2\tNaN"), 100, ["NaN/inf", "column 3"]),
        (lambda: _replace_row(_rows(), 99, "0.1\t-inf\t0.2"), 100, ["NaN/inf", "column 2"]),
        (lambda: _replace_row(_rows(), 5, "0.1\t1e999\t0.2"), 6, ["overflows"]),
        (lambda: _replace_row(_rows(), 5, "0.1\t\t0.2"), 6, ["empty cell", "column 2"]),
        (lambda: _replace_row(_rows(), 12, "0.1,0.2\t0.3"), 13, ["mixed delimiters", "comma", "tab"]),
        (lambda: _replace_row(_rows(), 12, "0.1\t0.2 0.3"), 13, ["mixed delimiters", "spaces"]),
        (lambda: _replace_row(_rows(), 12, "0.1;0.2;0.3"), 13, ["mixed delimiters", "semicolon"]),
        (lambda: _replace_row(_rows(), 12, ""), 13, ["blank line"]),
        (lambda: _replace_row(_rows(), 0, "0.0\tx\t0.1"), 1, ["non-numeric", "'x'"]),
        (lambda: _replace_row(_rows(), 0, "nan\t0.0\t0.1"), 1, ["NaN/inf"]),
        (lambda: _replace_row(_rows(), 0, "0.0,0.0\t0.1"), 1, ["mixed delimiters"]),
        (
            lambda: "Time\tForce\tAcc\n" + _replace_row(_rows(ncols=3), 0, "zz"),
            2,
            ["unexpected text", "line 1"],
        ),
        (lambda: "\n".join(_rows(MIN_SAMPLES - 1)) + "\n", MIN_SAMPLES - 1, ["only 255 samples", "256"]),
        (lambda: "\x00\x01binary", 1, ["binary"]),
    ],
)
def test_malformed_run_files_name_file_line_and_problem(tmp_path, make_text, line, words):
    error = format_error(tmp_path, make_text(), YAML_NO_FORCE)
    assert error.line == line, str(error)
    for word in words:
        assert word in error.problem, (word, str(error))
    assert str(error) == f"{error.path}:{line}: {error.problem}"


def test_time_not_increasing(tmp_path):
    t, force, response = signals()
    t[50] = t[49]
    error = format_error(
        tmp_path, "Time (s)\tForce (lbf)\tAcceleration (g)\n" + table((t, force, response)), YAML_NO_FORCE
    )
    assert error.line == 52 and "not increasing" in error.problem


def test_time_not_uniform(tmp_path):
    t, force, response = signals()
    t[100:] += 0.5 / FS_HZ  # half a sample of jitter from sample 100 on
    error = format_error(tmp_path, table((t, force, response)), YAML_NO_FORCE)
    assert error.line == 101 and "not uniform" in error.problem
    assert "%" in error.problem


def test_integer_first_time_stamp_keeps_the_uniformity_check(tmp_path):
    t, force, response = signals()
    rows = table((t, force, response)).splitlines()
    rows[0] = rows[0].replace("0.000000", "0", 1)
    record = read_one(tmp_path, "\n".join(rows) + "\n", YAML_NO_FORCE)
    assert record.time_s[0] == 0.0
    t[150:] += 0.1 / FS_HZ  # a tenth of a sample: far above the 1e-6 s print resolution
    rows = table((t, force, response)).splitlines()
    rows[0] = rows[0].replace("0.000000", "0", 1)
    error = format_error(tmp_path, "\n".join(rows) + "\n", YAML_NO_FORCE)
    assert error.line == 151 and "not uniform" in error.problem


def test_missing_sample_shows_as_non_uniform_time(tmp_path):
    t, force, response = signals()
    keep = np.arange(N) != 200
    error = format_error(tmp_path, table((t[keep], force[keep], response[keep])), YAML_NO_FORCE)
    assert error.line == 201 and "not uniform" in error.problem  # first sample after the gap


def test_sample_rate_missing_everywhere(tmp_path):
    _, _, response = signals()
    error = format_error(tmp_path, table((response,)), YAML_NO_FORCE)
    assert error.line is None and "sample rate missing" in error.problem


def test_header_sample_rate_contradicts_campaign_yaml(tmp_path):
    _, force, response = signals()
    error = format_error(tmp_path, "Note\nSample rate: 5120 Hz\n" + table((force, response)), YAML_FORCE)
    assert error.line == 2
    assert "5120" in error.problem and "2560" in error.problem and "campaign.yaml" in error.problem


def test_time_column_contradicts_campaign_yaml(tmp_path):
    t, force, response = signals()
    error = format_error(tmp_path, table((t * 2, force, response)), YAML_FORCE)
    assert error.line == 1
    assert "1279.99" in error.problem and "2560" in error.problem and "time column" in error.problem


def test_header_pretrigger_contradicts_campaign_yaml(tmp_path):
    _, force, response = signals()
    yaml_text = YAML_FORCE + "pretrigger_samples: 25\n"
    error = format_error(tmp_path, "Pre-trigger: 30 samples\n" + table((force, response)), yaml_text)
    assert error.line == 1 and "30" in error.problem and "25" in error.problem


def test_unreadable_header_values(tmp_path):
    _, _, response = signals()
    error = format_error(tmp_path, "X\nSample rate: fast\n" + table((response,)), YAML_NO_FORCE)
    assert error.line == 2 and "sample rate" in error.problem
    error = format_error(tmp_path, "Pre-trigger: 2.5 samples\n" + table((response,)), YAML_FORCE)
    assert error.line == 1 and "pre-trigger" in error.problem


def test_response_unit_disagrees_with_campaign_yaml(tmp_path):
    t, _, response = signals()
    error = format_error(
        tmp_path, "Head\nTime (s)\tAcceleration (m/s^2)\n" + table((t, response)), YAML_NO_FORCE
    )
    assert error.line == 2 and "'m/s^2'" in error.problem and "'g'" in error.problem


def test_response_quantity_disagrees_with_campaign_yaml(tmp_path):
    t, _, response = signals()
    error = format_error(tmp_path, "Time (s)\tVelocity\n" + table((t, response)), YAML_NO_FORCE)
    assert error.line == 1 and "velocity" in error.problem and "acceleration" in error.problem


def test_force_unit_disagrees_with_campaign_yaml(tmp_path):
    t, force, response = signals()
    error = format_error(tmp_path, "Time (s)\tForce (N)\tAcc (g)\n" + table((t, force, response)), YAML_FORCE)
    assert error.line == 1 and "'N'" in error.problem and "'lbf'" in error.problem


def test_two_response_columns_and_no_response_column(tmp_path):
    t, force, response = signals()
    error = format_error(tmp_path, "Time\tAcc1\tAcc2\n" + table((t, response, response)), YAML_NO_FORCE)
    assert error.line == 1 and "two response columns" in error.problem
    error = format_error(tmp_path, "Time\tForce\tStrain\n" + table((t, force, response)), YAML_NO_FORCE)
    assert error.line == 1 and "no response column" in error.problem


def test_four_columns_without_names(tmp_path):
    t, force, response = signals()
    error = format_error(tmp_path, "X\n" + table((t, force, response, response)), YAML_NO_FORCE)
    assert error.line == 2 and "4 columns" in error.problem


def test_names_that_do_not_match_the_column_count(tmp_path):
    t, _, response = signals()
    error = format_error(tmp_path, "Time Force Acceleration\n" + table((t, response)), YAML_NO_FORCE)
    assert error.line == 1 and "column names" in error.problem


def test_missing_file(tmp_path):
    campaign = write_campaign(tmp_path, YAML_NO_FORCE, {})
    with pytest.raises(CampaignFormatError, match="no such file"):
        read_run(tmp_path, "cfg/none.txt", campaign)


# ------------------------------------------------------------------ real campaigns


@needs_realdata("pff-lms-sample")
def test_real_pff_record_reads():
    """The real PFF record (its read time is a benchmark: bench/bench_readers.py)."""
    folder = REALDATA / "pff-lms-sample"
    campaign = load_campaign(folder)
    runs = list_runs(folder, campaign)
    assert [run.run for run in runs] == ["run01"]
    record = read_run(folder, runs[0], campaign)
    assert record.n_samples == 131072 and record.sample_rate_hz == 51200.0
    assert record.response_unit == "m/s^2" and record.force_lbf is None
    assert record.time_s[-1] == pytest.approx(2.5599805)
    assert record.response[0] == pytest.approx(0.4154297)


@needs_realdata("unesp-bolted-beam")
def test_real_unesp_campaign_reads_every_run():
    folder = REALDATA / "unesp-bolted-beam"
    campaign = load_campaign(folder)
    runs = list_runs(folder, campaign)
    assert len(runs) == 14 and runs[0].run == "sine_05hz" and runs[-1].run == "sine_20hz"
    for run in runs:
        record = read_run(folder, run, campaign)
        assert record.sample_rate_hz == 1024.0
        assert record.response_quantity == "velocity" and record.response_unit == "m/s"
        assert 13000 <= record.n_samples <= 13200
        assert np.isfinite(record.response).all()


def test_bad_line_deep_in_a_long_file_is_found_exactly(tmp_path):
    rows = _rows(n=5000)
    error = format_error(tmp_path, _replace_row(rows, 4500, "0.1\t0.2\tx"), YAML_NO_FORCE)
    assert error.line == 4501 and "'x'" in error.problem


def test_slow_path_gives_the_same_numbers(tmp_path):
    # A trailing comma on some rows only sends the block to the chunked careful pass.
    t, force, response = signals(5000)
    rows = table((t, force, response), ",").splitlines()
    rows[3000] += ","
    record = read_one(tmp_path, "\n".join(rows) + "\n", YAML_NO_FORCE)
    fast = read_one(tmp_path, table((t, force, response), ","), YAML_NO_FORCE)
    np.testing.assert_array_equal(record.response, fast.response)
    np.testing.assert_array_equal(record.time_s, fast.time_s)


# ------------------------------------------------------------------ spreadsheet and lab exports


def test_quoted_column_names_of_a_csv_writer_decide_roles_and_units(tmp_path):
    t, force, response = signals()
    text = '"Time (s)","Force (N)","Acceleration (g)"\n' + table((t, force, response), delimiter=",")
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
    record = read_one(tmp_path / "a", text, YAML_NO_FORCE)
    # 1 lbf = 0.45359237 kg x 9.80665 m/s^2 (exact)
    np.testing.assert_allclose(record.force_lbf, force / (0.45359237 * 9.80665), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(record.response, response, atol=1e-6)
    assert record.time_s is not None
    # a quoted unit that contradicts campaign.yaml is the disagreement the contract names
    error = format_error(tmp_path / "b", text, YAML_FORCE)
    assert "force column unit 'N' disagrees with campaign.yaml force unit 'lbf'" in str(error)


def test_header_lines_padded_with_empty_cells_are_read(tmp_path):
    t, force, response = signals()
    text = (
        "Dactron RT Pro ASCII export,,\nSample rate: 2560 Hz,,\nPre-trigger: 25 samples,,\n"
        "Time (s),Force (lbf),Acceleration (g)\n" + table((t, force, response), delimiter=",")
    )
    record = read_one(tmp_path, text, YAML_NO_FORCE)
    assert record.sample_rate_hz == 2560.0 and record.pretrigger_samples == 25


@pytest.mark.parametrize(
    ("unit", "factor"), [("seconds", 1.0), ("sec", 1.0), ("msec", 1e-3), ("milliseconds", 1e-3)]
)
def test_time_column_unit_words(tmp_path, unit, factor):
    t, force, response = signals()
    text = f"Time ({unit})\tForce (lbf)\tAcceleration (g)\n" + table((t / factor, force, response))
    record = read_one(tmp_path, text, YAML_NO_FORCE)
    assert record.sample_rate_hz == pytest.approx(FS_HZ, rel=1e-4)


def test_header_number_out_of_range_is_a_format_error_naming_the_line(tmp_path):
    _, _, response = signals()
    error = format_error(tmp_path, "Sample rate: 2560 Hz\nPre-trigger: 1e400 samples\n" + table((response,)))
    assert error.line == 2 and "cannot read the pre-trigger" in str(error)


@pytest.mark.parametrize("written", ["2004-05-12", "yes", "off"])
def test_campaign_name_is_free_text_whatever_yaml_makes_of_it(tmp_path, written):
    campaign = write_campaign(tmp_path, YAML_NO_FORCE.replace("name: test", f"name: {written}"), {})
    assert campaign.name == written


def test_names_with_channel_prefixes_and_colons_are_names_not_header_values(tmp_path):
    t, force, response = signals()
    text = "Time (s)\tCh1: Acceleration (g)\tCh2: Force (lbf)\n" + table((t, response, force))
    record = read_one(tmp_path, text, YAML_NO_FORCE)
    np.testing.assert_allclose(record.response, response, atol=1e-6)
    np.testing.assert_allclose(record.force_lbf, force, atol=1e-6)


@pytest.mark.parametrize(
    ("title", "yaml_text", "has_force"),
    [("Ring-down acceleration record", YAML_FORCE, True), ("Response history", YAML_NO_FORCE, False)],
)
def test_a_title_with_as_many_words_as_columns_is_not_a_line_of_names(tmp_path, title, yaml_text, has_force):
    t, force, response = signals()
    columns = (t, force, response) if has_force else (t, response)
    record = read_one(tmp_path, title + "\n" + table(columns), yaml_text)
    # the positional rules of the contract: time, force, response / time, response
    np.testing.assert_allclose(record.response, response, atol=1e-6)
    assert record.time_s is not None and (record.force_lbf is not None) == has_force


def test_a_time_column_that_starts_before_zero_gives_the_pre_trigger(tmp_path):
    t, force, response = signals()
    columns = (t - 25 / FS_HZ, force, response)
    text = "Time (s)\tForce (lbf)\tAcceleration (g)\n" + table(columns)
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
    record = read_one(tmp_path / "a", text, YAML_NO_FORCE)
    assert (record.pretrigger_samples, record.pretrigger_source) == (25, "time column")
    # campaign.yaml saying otherwise is the disagreement the contract names
    error = format_error(tmp_path / "b", text, YAML_NO_FORCE + "pretrigger_samples: 50\n")
    assert "pre-trigger of 25 samples" in str(error) and "pretrigger_samples says 50" in str(error)

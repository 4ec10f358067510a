"""Hostile campaigns, the input half of issue 36: files read from outside the campaign
folder, link loops, names of any length, samples the arithmetic cannot square, units that do
not parse, line numbers, windows beyond the record, non-numeric sample intervals.

Library cases call the reader and the mode search; one workflow case runs the real
snakemake on a campaign where bad runs sit beside good ones.
"""

import functools
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import run_snakemake
from system_format_files import lms_export_group, write_mat73, write_plain_mat, write_tdms, write_testlab_mat
from test_io_hostile_inputs import BASE_YAML, FS_HZ, make_campaign, run_text

from workflow.io import limits
from workflow.io.campaign import load_campaign
from workflow.io.interim import read_mode, write_mode
from workflow.io.records import CampaignFormatError
from workflow.io.run_files import read_run, scan_campaign
from workflow.measured.mode_identification import identify_configuration_mode
from workflow.measured.runs import analyse_run_file
from workflow.measured.settings import AnalysisSettings, QualitySettings

ONE_CONFIGURATION = BASE_YAML + "configurations:\n  cfg: {}\n"
SECRET = "root:$6$SECRETHASH$abc:19000:0:99999:7:::"
"""A line of a file outside the campaign that no message may print."""


def read_error(tmp_path, content, yaml_text=ONE_CONFIGURATION, name="run01.txt") -> CampaignFormatError:
    root = make_campaign(tmp_path, yaml_text, {f"cfg/{name}": content})
    with pytest.raises(CampaignFormatError) as info:
        read_run(root, f"cfg/{name}", load_campaign(root))
    assert info.value.path.endswith(f"cfg/{name}")
    return info.value


def ringing(n: int, scale: float = 1.0) -> np.ndarray:
    t = np.arange(n) / FS_HZ
    return scale * 3.0 * np.exp(-2.0 * t) * np.sin(2 * np.pi * 125.0 * t)


# ------------------------------------------------------------------ 1. campaign.yaml stays inside


def outside_campaign(tmp_path: Path) -> tuple[Path, Path]:
    """A campaign folder and, beside it, a file of secrets and a valid campaign.yaml."""
    root = make_campaign(tmp_path / "campaign", ONE_CONFIGURATION, {"cfg/run01.txt": run_text()})
    (tmp_path / "shadow").write_text("\n".join(f"{SECRET[:4]}{i}{SECRET[4:]}" for i in range(30)) + "\n")
    (tmp_path / "other.yaml").write_text(ONE_CONFIGURATION.replace("hostile", "elsewhere"))
    (root / "campaign.yaml").unlink()
    return root, tmp_path


@pytest.mark.parametrize("target", ["shadow", "other.yaml"])
def test_campaign_yaml_linked_out_of_the_folder_is_refused_unread(tmp_path, target):
    root, outside = outside_campaign(tmp_path)
    (root / "campaign.yaml").symlink_to(outside / target)
    with pytest.raises(CampaignFormatError) as info:
        load_campaign(root)
    message = str(info.value)
    assert message.startswith(
        f"{root.as_posix()}/campaign.yaml: not read: a symbolic link that leads outside"
    )
    assert "SECRETHASH" not in message and "root" not in message.replace(root.as_posix(), "")
    assert "elsewhere" not in message


def test_campaign_yaml_linked_inside_the_folder_is_read(tmp_path):
    root, _ = outside_campaign(tmp_path)
    (root / "meta").mkdir()
    (root / "meta" / "settings.yaml").write_text(ONE_CONFIGURATION)
    (root / "campaign.yaml").symlink_to(root / "meta" / "settings.yaml")
    assert load_campaign(root).name == "hostile"


def test_campaign_yaml_link_loop_is_a_message(tmp_path):
    root, _ = outside_campaign(tmp_path)
    (root / "campaign.yaml").symlink_to(root / "campaign.yaml")
    with pytest.raises(CampaignFormatError, match="campaign.yaml: not read: a symbolic link loop"):
        load_campaign(root)


def test_campaign_yaml_that_is_a_pipe_is_refused_without_waiting(tmp_path):
    root, _ = outside_campaign(tmp_path)
    os.mkfifo(root / "campaign.yaml")  # opening it would wait for a writer forever
    with pytest.raises(CampaignFormatError, match="campaign.yaml: not read: not a regular file"):
        load_campaign(root)


def test_campaign_yaml_of_many_unknown_keys_is_quoted_in_part(tmp_path):
    keys = "".join(f"{'k' * 500}{i}: 1\n" for i in range(200))
    make_campaign(tmp_path, ONE_CONFIGURATION + keys, {})
    with pytest.raises(CampaignFormatError) as info:
        load_campaign(tmp_path)
    message = str(info.value)
    assert message.count("unknown key") == limits.MAX_QUOTED_PROBLEMS
    assert "and 190 more problems" in message
    # each key quoted to its first characters: far shorter than the 100 kB of keys
    assert len(message) < 40 * limits.QUOTED_CHARACTERS * limits.MAX_QUOTED_PROBLEMS


def test_planning_refuses_a_linked_campaign_yaml_without_printing_its_target(tmp_path):
    root, outside = outside_campaign(tmp_path)
    (root / "campaign.yaml").symlink_to(outside / "shadow")
    result = run_snakemake(tmp_path, "-n", "all", "--config", f"campaign={root}", timeout=300)
    output = result.stdout + result.stderr
    assert result.returncode != 0
    assert "campaign.yaml: not read: a symbolic link that leads outside the campaign folder" in output
    assert "SECRETHASH" not in output


# ------------------------------------------------------------------ 2. link loops


def test_link_loops_are_excluded_as_broken_links_are(tmp_path):
    root = make_campaign(
        tmp_path,
        BASE_YAML + "configurations:\n  cfg: {files: 'cfg/**/*.txt'}\n",
        {"cfg/run01.txt": run_text()},
    )
    (root / "cfg" / "self.txt").symlink_to(root / "cfg" / "self.txt")
    (root / "cfg" / "a.txt").symlink_to(root / "cfg" / "b.txt")
    (root / "cfg" / "b.txt").symlink_to(root / "cfg" / "a.txt")
    (root / "cfg" / "up").symlink_to(root / "cfg")  # a folder loop: ** does not follow it
    runs, excluded = scan_campaign(root, load_campaign(root))
    assert [run.path for run in runs] == ["cfg/run01.txt"]
    reasons = {entry.path: entry.reason for entry in excluded}
    assert set(reasons) == {"cfg/self.txt", "cfg/a.txt", "cfg/b.txt"}
    for path, reason in reasons.items():
        assert (
            reason
            == f"{root.as_posix()}/{path}: not read: a symbolic link loop (the link leads back to itself)"
        )


def test_a_run_file_larger_than_the_bound_is_excluded_unread(tmp_path):
    root = make_campaign(tmp_path, ONE_CONFIGURATION, {"cfg/run01.txt": run_text()})
    with open(root / "cfg" / "huge.txt", "wb") as handle:  # sparse: no disk space used
        handle.truncate(limits.MAX_RUN_FILE_BYTES + 1)
    runs, excluded = scan_campaign(root, load_campaign(root))
    assert [run.run for run in runs] == ["run01"]
    assert [entry.path for entry in excluded] == ["cfg/huge.txt"]
    assert excluded[0].reason.endswith(
        "cfg/huge.txt: not read: 1000000001 bytes, larger than a run file may be (1000000000 bytes; "
        "docs/input-safety.md): "
        "cut the record to the ring-down or export fewer channels"
    )


# ------------------------------------------------------------------ 3. names bounded


def test_a_name_of_255_characters_passes_and_256_is_refused():
    assert limits.name_length_problem("name", "x" * limits.MAX_NAME_CHARACTERS) is None
    problem = limits.name_length_problem("name", "x" * (limits.MAX_NAME_CHARACTERS + 1))
    assert (
        problem.startswith("name 'xxx") and "(256 characters) is too long: at most 255 characters" in problem
    )


def test_a_campaign_name_of_100_kilobytes_is_refused_naming_its_line(tmp_path):
    error = read_error_yaml(
        tmp_path, f"name: {'N' * 100_000}\n" + ONE_CONFIGURATION.replace("name: hostile\n", "")
    )
    assert error.line == 1
    assert "name 'NNN" in error.problem and "(100000 characters) is too long: at most 1000" in error.problem
    assert len(str(error)) < 500


def test_a_campaign_name_of_1000_characters_is_a_title_and_is_read(tmp_path):
    make_campaign(tmp_path, f"name: {'N' * 1000}\n" + ONE_CONFIGURATION.replace("name: hostile\n", ""), {})
    assert load_campaign(tmp_path).name == "N" * 1000


def test_a_channel_name_in_campaign_yaml_beyond_255_characters_is_refused(tmp_path):
    yaml_text = ONE_CONFIGURATION.replace("unit: g}", f"unit: g, channel: {'c' * 300}}}")
    error = read_error_yaml(tmp_path, yaml_text)
    assert error.line == 2 and "response.channel" in error.problem and "too long" in error.problem


def read_error_yaml(tmp_path, yaml_text) -> CampaignFormatError:
    make_campaign(tmp_path, yaml_text, {})
    with pytest.raises(CampaignFormatError) as info:
        load_campaign(tmp_path)
    return info.value


def test_a_run_file_name_beyond_the_bound_is_excluded_and_the_others_read(tmp_path, monkeypatch):
    # File systems stop names at 255 bytes; the bound is lowered to reach it with a real file.
    monkeypatch.setattr(limits, "MAX_NAME_CHARACTERS", 20)
    long_name = "run_" + "x" * 100
    root = make_campaign(
        tmp_path, ONE_CONFIGURATION, {"cfg/run01.txt": run_text(), f"cfg/{long_name}.txt": run_text()}
    )
    runs, excluded = scan_campaign(root, load_campaign(root))
    assert [run.run for run in runs] == ["run01"]
    assert len(excluded) == 1
    assert "run file name 'run_xxx" in excluded[0].reason and "is too long: at most 20" in excluded[0].reason
    assert long_name not in excluded[0].reason + excluded[0].path + excluded[0].run


def test_an_ascii_column_name_beyond_255_characters_is_refused(tmp_path):
    text = run_text().replace("Acceleration (g)", "Acceleration " + "a" * 300 + " (g)")
    error = read_error(tmp_path, text)
    assert (
        error.line == 2 and "column name 'Acceleration aaa" in error.problem and "too long" in error.problem
    )


def test_a_tdms_channel_name_beyond_255_characters_is_refused_naming_the_channel(tmp_path):
    n = 1024
    properties = {"wf_increment": 1.0 / FS_HZ}
    channels = {
        "Force": (np.exp(-np.arange(n) / 5.0), {**properties, "unit_string": "lbf"}),
        "Acceleration" + "a" * 300: (ringing(n), {**properties, "unit_string": "g"}),
    }
    root = make_campaign(tmp_path, BASE_YAML + "configurations:\n  cfg: {files: 'cfg/*.tdms'}\n", {})
    (root / "cfg").mkdir()
    write_tdms(root / "cfg" / "run.tdms", "Impact", channels)
    with pytest.raises(CampaignFormatError) as info:
        read_run(root, "cfg/run.tdms", load_campaign(root))
    assert (
        "channel [1]: name 'Impact/Accelerationaaa" in info.value.problem and "too long" in info.value.problem
    )
    assert len(str(info.value)) < 500


# ------------------------------------------------------------------ 4. samples the analysis cannot square


@pytest.mark.parametrize(("scale", "word"), [(1e160, "beyond ±1e+100"), (1e-160, "below 1e-100")])
def test_samples_beyond_the_float64_range_of_the_analysis_are_refused_naming_the_line(tmp_path, scale, word):
    lines = run_text(n=600, header=True).splitlines()
    response = ringing(600, scale)
    rows = [f"{line.rsplit(chr(9), 1)[0]}\t{value:.6e}" for line, value in zip(lines[2:], response)]
    error = read_error(tmp_path, "\n".join(lines[:2] + rows) + "\n")
    first = (
        int(np.flatnonzero(np.abs(response) > 1e100)[0]) if scale > 1 else int(np.argmax(np.abs(response)))
    )
    assert error.line == 3 + first
    assert error.problem.startswith("response column 3 'Acceleration (g)': ") and word in error.problem


def test_every_response_channel_of_an_ascii_file_is_checked(tmp_path):
    n = 400
    t = np.arange(n) / FS_HZ
    rows = [f"{a:.7f}\t{b:.6e}\t{c:.6e}" for a, b, c in zip(t, ringing(n), ringing(n, 1e160))]
    text = "Sample rate: 2560 Hz\nTime (s)\tacc1 (g)\tacc2 (g)\n" + "\n".join(rows) + "\n"
    yaml_text = (
        BASE_YAML.replace("force: {unit: lbf}\n", "").replace("unit: g}", "unit: g, channels: [acc1, acc2]}")
        + "configurations:\n  cfg: {}\n"
    )
    error = read_error(tmp_path, text, yaml_text)
    assert error.line == 4  # the first sample of a sine is 0; the second is beyond
    assert error.problem.startswith("response column 3 'acc2 (g)': value ")


def test_a_force_beyond_the_range_is_refused_in_a_system_format_naming_the_sample(tmp_path):
    n = 1024
    force = np.exp(-np.arange(n) / 5.0) * 1e200
    properties = {"wf_increment": 1.0 / FS_HZ}
    channels = {
        "Force": (force, {**properties, "unit_string": "lbf"}),
        "Acceleration": (ringing(n), {**properties, "unit_string": "g"}),
    }
    root = make_campaign(tmp_path, BASE_YAML + "configurations:\n  cfg: {files: 'cfg/*.tdms'}\n", {})
    (root / "cfg").mkdir()
    write_tdms(root / "cfg" / "run.tdms", "Impact", channels)
    with pytest.raises(CampaignFormatError) as info:
        read_run(root, "cfg/run.tdms", load_campaign(root))
    assert "channel 'Impact/Force': value 1e+200 is beyond ±1e+100" in info.value.problem
    assert info.value.problem.endswith("(sample 0, 0-based)")


def mode_of(root: Path, paths: list[str], configuration: str = "cfg"):
    settings = AnalysisSettings()
    return identify_configuration_mode(
        root,
        paths,
        configuration=configuration,
        campaign=load_campaign(root),
        mode_search=settings,
        quality_settings=QualitySettings(),
    )


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> Path:
    """A virtual-lab campaign of two configurations, two runs each."""
    from workflow.lab.campaigns import generate_campaign

    campaign = tmp_path_factory.mktemp("lab") / "campaign"
    generate_campaign(
        campaign, seed=5, runs_per_configuration=2, configurations={"no_washer": 1.36, "large_washer": 0.66}
    )
    return campaign


NAMES_LINE = 4
"""Line of the column names in a virtual-lab run file (title, sample rate, pre-trigger, names)."""


def write_scaled(source: Path, target: Path, factor: float) -> None:
    """A copy of a virtual-lab run file with its response column multiplied by ``factor``."""
    lines = source.read_text().splitlines()
    assert lines[NAMES_LINE - 1].startswith("Time (s)")
    rows = []
    for line in lines[NAMES_LINE:]:
        cells = line.split("\t")
        rows.append("\t".join([*cells[:-1], f"{float(cells[-1]) * factor:.9e}"]))
    target.write_text("\n".join(lines[:NAMES_LINE] + rows) + "\n")


def analysis_status(root: Path, path: str, configuration: str, found) -> dict[str, str]:
    """The runs-table row of one run analysed with its configuration's mode ``found``."""
    return analyse_run_file(
        root,
        path,
        configuration=configuration,
        campaign=load_campaign(root),
        mode=found,
        quality_settings=QualitySettings(),
        decay_settings=AnalysisSettings(),
    ).status


def test_a_run_scaled_by_1e160_is_excluded_naming_the_file_and_the_others_give_the_mode(lab, tmp_path):
    root = tmp_path / "campaign"
    shutil.copytree(lab, root)
    write_scaled(root / "no_washer/run02.txt", root / "no_washer/run02.txt", 1e160)
    found = mode_of(root, ["no_washer/run01.txt", "no_washer/run02.txt"], "no_washer")
    assert found.mode is not None and found.mode.n_runs == 1
    assert list(found.skipped_runs) == ["run02"]
    assert found.skipped_runs["run02"][0].startswith(
        f"{root.as_posix()}/no_washer/run02.txt:{NAMES_LINE + 1}: response column 3 'Acceleration (g)': value "
    )
    write_mode(tmp_path / "mode.json", found)  # strict JSON: no NaN, no inf
    assert read_mode(tmp_path / "mode.json").mode.mode_hz == found.mode.mode_hz


def test_a_configuration_whose_every_run_overflows_says_so_and_its_json_is_valid(tmp_path):
    n = 1024
    root = make_campaign(
        tmp_path,
        ONE_CONFIGURATION,
        {f"cfg/run0{i}.txt": run_text(n=n, response=ringing(n, 1e160)) for i in (1, 2)},
    )
    found = mode_of(root, ["cfg/run01.txt", "cfg/run02.txt"])
    assert found.mode is None
    assert found.error.startswith(
        "configuration cfg: first mode not found: every run of the configuration is excluded (2 of 2)"
    )
    # line 3 holds the first sample, 0 (a sine at t = 0); the first beyond 1e100 is on line 4
    assert "cfg/run01.txt:4: response column 3" in found.error and "cfg/run02.txt:4:" in found.error
    write_mode(tmp_path / "mode.json", found)
    json.loads((tmp_path / "mode.json").read_text())


# ------------------------------------------------------------------ 5. units that do not parse


@pytest.mark.parametrize(
    ("old", "new", "role"),
    [
        ("Acceleration (g)", "Acceleration (m/(s^2))", "response"),
        ("Force (lbf)", "Force (lbf", "force"),
        ("Time (s)", "Time (s", "time"),
        ("Acceleration (g)", "Acceleration [g", "response"),
        ("Acceleration (g)", "Acceleration (g) extra", "response"),
    ],
)
def test_a_unit_that_does_not_parse_is_an_error_naming_the_line(tmp_path, old, new, role):
    error = read_error(tmp_path, run_text().replace(old, new))
    assert error.line == 2
    assert error.problem.startswith(f"the unit of the {role} column {new!r} cannot be read")


# ------------------------------------------------------------------ 6. line numbers


def time_fault(n: int, line: int, kind: str, newline: str) -> str:
    """A run of ``n`` samples (header of 2 lines) whose time stamp at ``line`` is wrong."""
    lines = run_text(n=n).splitlines()
    cells = lines[line - 1].split("\t")
    shift = {"jump": 0.5, "spike": 0.5, "back": -0.5}[kind]
    last = len(lines) if kind == "jump" else line
    for number in range(line, last + 1):
        cells = lines[number - 1].split("\t")
        cells[0] = f"{float(cells[0]) + shift:.7f}"
        lines[number - 1] = "\t".join(cells)
    return newline.join(lines) + newline


@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
@pytest.mark.parametrize("kind", ["jump", "spike", "back"])
def test_a_time_fault_is_reported_at_its_own_line(tmp_path, kind, newline):
    error = read_error(tmp_path, time_fault(3000, 1505, kind, newline))
    assert error.line == 1505, str(error)
    words = {"jump": "not uniform", "spike": "out of order", "back": "not increasing"}[kind]
    assert error.problem.startswith(f"time column {words}")


def test_a_time_vector_jump_in_a_system_format_names_its_sample(tmp_path):
    n = 2048
    t = np.arange(n) / FS_HZ
    t[1500:] += 0.5
    root = make_campaign(
        tmp_path,
        BASE_YAML.replace("force: {unit: lbf}\n", "") + "configurations:\n  cfg: {files: 'cfg/*.mat'}\n",
        {},
    )
    (root / "cfg").mkdir()
    write_plain_mat(root / "cfg" / "run.mat", t=t, acc=ringing(n))
    with pytest.raises(CampaignFormatError) as info:
        read_run(root, "cfg/run.mat", load_campaign(root))
    assert "after sample 1499 (0-based)" in info.value.problem


@pytest.mark.parametrize("newline", ["\n", "\r"])
def test_binary_data_is_named_at_its_line_whatever_the_line_ends(tmp_path, newline):
    lines = run_text().splitlines()
    content = (
        newline.join(lines[:9]).encode() + newline.encode() + b"\x00\x01" + newline.join(lines[9:]).encode()
    )
    assert read_error(tmp_path, content).line == 10


# ------------------------------------------------------------------ 7. window beyond the record


def test_a_window_beyond_the_record_is_said_in_the_words_of_the_contract(lab, tmp_path):
    root = tmp_path / "campaign"
    shutil.copytree(lab, root)
    text = (root / "campaign.yaml").read_text()
    (root / "campaign.yaml").write_text(
        text.replace('files: "large_washer/*.txt"', 'files: "large_washer/*.txt", window_s: [5, 6]')
    )
    found = mode_of(root, ["large_washer/run01.txt", "large_washer/run02.txt"], "large_washer")
    expected = (
        f"{root.as_posix()}/large_washer/run01.txt: campaign.yaml configurations.large_washer.window_s [5, 6] s "
        "holds 0 samples of this record, which spans 0 to 3.2 s (8192 samples at 2560 Hz)"
    )
    assert found.mode is None and expected in found.error
    assert "every run of the configuration is excluded (2 of 2)" in found.error
    assert "fewer than 2 samples" not in found.error
    status = analysis_status(root, "large_washer/run01.txt", "large_washer", found)
    assert status["status"] == "excluded" and status["reason"].startswith(expected)
    # the other configuration goes on
    assert mode_of(root, ["no_washer/run01.txt", "no_washer/run02.txt"], "no_washer").mode is not None


@pytest.mark.parametrize(
    ("setting", "line", "key"),
    [
        ("sample_rate_hz: .inf\n", 4, "sample_rate_hz"),
        ("band_hz: [100, .inf]\n", 4, "band_hz.1"),
        ("configurations:\n  cfg: {window_s: [0, .inf]}\n", 5, "configurations.cfg.window_s.1"),
        ("configurations:\n  cfg: {bearing_area_in2: .inf}\n", 5, "configurations.cfg.bearing_area_in2"),
    ],
)
def test_infinities_and_nans_in_campaign_yaml_are_refused_naming_the_key(tmp_path, setting, line, key):
    yaml_text = BASE_YAML + setting + ("" if "configurations" in setting else "configurations:\n  cfg: {}\n")
    error = read_error_yaml(tmp_path, yaml_text)
    assert error.line == line and error.problem.startswith(f"{key}: ")


def test_a_window_ending_at_1e308_s_reaches_the_end_of_the_record(lab):
    from workflow.measured.runs import analysis_window

    record = read_run(lab, "no_washer/run01.txt", load_campaign(lab))
    assert analysis_window(record, (1.0, 1e308)) == (2560, record.n_samples)


# ------------------------------------------------------------------ 8. sample intervals that are not numbers


def test_a_testlab_increment_that_is_not_a_number_is_an_error_naming_the_record(tmp_path):
    n = 1024
    group = lms_export_group(["Time Acc1:+Z"], ringing(n), "g", 1.0 / FS_HZ)
    group["x_values"]["increment"] = "fast"
    yaml_text = (
        BASE_YAML.replace("force: {unit: lbf}\n", "") + "configurations:\n  cfg: {files: 'cfg/*.mat'}\n"
    )
    root = make_campaign(
        tmp_path, yaml_text.replace("name: hostile\n", "name: hostile\nsample_rate_hz: 2560\n"), {}
    )
    (root / "cfg").mkdir()
    write_testlab_mat(root / "cfg" / "run.mat", {"Signal": group})
    with pytest.raises(CampaignFormatError) as info:
        read_run(root, "cfg/run.mat", load_campaign(root))
    assert str(info.value) == (
        f"{root.as_posix()}/cfg/run.mat: variable 'Signal': x_values.increment is 'fast', not a finite number"
    )


def test_a_plain_mat_sample_rate_that_is_not_a_number_is_an_error(tmp_path):
    n = 1024
    yaml_text = (
        BASE_YAML.replace("force: {unit: lbf}\n", "") + "configurations:\n  cfg: {files: 'cfg/*.mat'}\n"
    )
    root = make_campaign(tmp_path, yaml_text, {})
    (root / "cfg").mkdir()
    write_plain_mat(root / "cfg" / "run.mat", acc=ringing(n), fs="fast")
    with pytest.raises(CampaignFormatError, match="variable 'fs' is 'fast', not a positive number"):
        read_run(root, "cfg/run.mat", load_campaign(root))


def test_a_tdms_increment_that_is_not_a_number_is_an_error_naming_the_channel(tmp_path):
    n = 1024
    channels = {"Acceleration": (ringing(n), {"wf_increment": "fast", "unit_string": "g"})}
    yaml_text = (
        BASE_YAML.replace("force: {unit: lbf}\n", "") + "configurations:\n  cfg: {files: 'cfg/*.tdms'}\n"
    )
    root = make_campaign(tmp_path, yaml_text, {})
    (root / "cfg").mkdir()
    write_tdms(root / "cfg" / "run.tdms", "Impact", channels)
    with pytest.raises(
        CampaignFormatError, match="channel 'Impact/Acceleration': wf_increment is 'fast', not a finite"
    ):
        read_run(root, "cfg/run.tdms", load_campaign(root))


# ------------------------------------------------------------------ every file read stays inside


def tdms_campaign(tmp_path: Path) -> Path:
    n = 1024
    channels = {"Acceleration": (ringing(n), {"wf_increment": 1.0 / FS_HZ, "unit_string": "g"})}
    yaml_text = (
        BASE_YAML.replace("force: {unit: lbf}\n", "") + "configurations:\n  cfg: {files: 'cfg/*.tdms'}\n"
    )
    root = make_campaign(tmp_path / "campaign", yaml_text, {})
    (root / "cfg").mkdir()
    write_tdms(root / "cfg" / "run.tdms", "Impact", channels)
    return root


def test_a_tdms_index_file_beside_the_run_is_not_read(tmp_path):
    root = tdms_campaign(tmp_path)
    (tmp_path / "secret").write_text(SECRET)
    (root / "cfg" / "run.tdms_index").symlink_to(tmp_path / "secret")
    record = read_run(root, "cfg/run.tdms", load_campaign(root))
    np.testing.assert_array_equal(record.response, ringing(1024))


@pytest.mark.parametrize("how", ["external link", "external storage"])
def test_a_mat73_file_that_draws_on_another_file_is_refused(tmp_path, how):
    import h5py

    yaml_text = (
        BASE_YAML.replace("force: {unit: lbf}\n", "")
        + "sample_rate_hz: 2560\nconfigurations:\n  cfg: {files: 'cfg/*.mat'}\n"
    )
    root = make_campaign(tmp_path / "campaign", yaml_text, {})
    (root / "cfg").mkdir()
    path = root / "cfg" / "run.mat"
    write_mat73(path, {"acc": ringing(1024)})
    outside = tmp_path / "outside.bin"
    outside.write_bytes(np.arange(1024, dtype=float).tobytes())
    with h5py.File(path, "a") as handle:
        if how == "external link":
            handle["other"] = h5py.ExternalLink(str(outside), "/data")
        else:
            handle.create_dataset("other", shape=(1024,), dtype="<f8", external=[(str(outside), 0, 8192)])
    with pytest.raises(CampaignFormatError, match="'other' .*refused, it would read another file"):
        read_run(root, "cfg/run.mat", load_campaign(root))


# ------------------------------------------------------------------ the real workflow: bad beside good

snakemake = functools.partial(run_snakemake, timeout=900)


def test_bad_runs_are_excluded_by_name_and_the_good_ones_analysed(lab, tmp_path):
    campaign = tmp_path / "campaign"
    shutil.copytree(lab, campaign)
    write_scaled(campaign / "no_washer/run01.txt", campaign / "no_washer/run03.txt", 1e160)
    lines = (campaign / "no_washer/run01.txt").read_text().splitlines()
    lines[NAMES_LINE - 1] = lines[NAMES_LINE - 1].replace("(lbf)", "(lbf")
    (campaign / "no_washer/run04.txt").write_text("\n".join(lines) + "\n")
    (campaign / "no_washer/run05.txt").symlink_to(campaign / "no_washer/run05.txt")
    for path in (campaign / "large_washer").glob("*.txt"):
        write_scaled(path, path, 1e160)
    workdir = tmp_path / "work"
    workdir.mkdir()
    result = snakemake(workdir, "-c2", "results/tables/runs.parquet", "--config", f"campaign={campaign}")
    assert result.returncode == 0, result.stderr[-4000:]
    runs = pd.read_parquet(workdir / "results/tables/runs.parquet").set_index("path")
    assert list(runs.loc[["no_washer/run01.txt", "no_washer/run02.txt"], "status"]) == ["used", "used"]
    assert set(runs.loc[runs["status"] == "excluded"].index) == {
        "no_washer/run03.txt",
        "no_washer/run04.txt",
        "no_washer/run05.txt",
        "large_washer/run01.txt",
        "large_washer/run02.txt",
    }
    reasons = runs["reason"]
    first_row = f":{NAMES_LINE + 1}: response column 3 'Acceleration (g)': value "
    assert f"{campaign.as_posix()}/no_washer/run03.txt{first_row}" in reasons["no_washer/run03.txt"]
    assert "the unit of the force column 'Force (lbf' cannot be read" in reasons["no_washer/run04.txt"]
    assert "a symbolic link loop" in reasons["no_washer/run05.txt"]
    for run in ("run01", "run02"):
        assert f"large_washer/{run}.txt{first_row}" in reasons[f"large_washer/{run}.txt"]
    mode = json.loads((workdir / "results/interim/mode/large_washer.json").read_text())
    assert "every run of the configuration is excluded (2 of 2)" in mode["error"]
    assert "Traceback" not in result.stderr


# ------------------------------------------------------------------ one bad run never takes the others down


def test_a_run_at_another_sample_rate_is_left_out_of_the_mode_search_only(lab, tmp_path):
    root = tmp_path / "campaign"
    shutil.copytree(lab, root)
    text = (root / "campaign.yaml").read_text()
    (root / "campaign.yaml").write_text(text.replace("sample_rate_hz: 2560\n", ""))
    lines = (root / "no_washer/run01.txt").read_text().splitlines()
    assert lines[1] == "Sample rate: 2560 Hz"
    lines[1] = "Sample rate: 5120 Hz"
    rows = [line.split("\t") for line in lines[NAMES_LINE:]]
    faster = ["\t".join([f"{float(cells[0]) / 2:.7f}", *cells[1:]]) for cells in rows]
    # named to come first: the mode search must not take its rate for every run's
    (root / "no_washer/run00.txt").write_text("\n".join(lines[:NAMES_LINE] + faster) + "\n")
    found = mode_of(root, ["no_washer/run00.txt", "no_washer/run01.txt", "no_washer/run02.txt"], "no_washer")
    assert found.mode is not None and found.mode.n_runs == 2 and found.mode.sample_rate_hz == 2560.0
    assert found.mode.mode_hz == pytest.approx(126.0, rel=0.05)
    assert found.skipped_runs == {
        "run00": [
            "no_washer/run00.txt: left out of the mode search only: sample rate 5120 Hz differs from the "
            "2560 Hz of most runs of the configuration"
        ]
    }


def test_a_fault_of_the_analysis_on_one_run_excludes_it_and_the_others_go_on(lab, monkeypatch):
    from workflow.measured import runs as measured_runs

    found = mode_of(lab, ["no_washer/run01.txt", "no_washer/run02.txt"], "no_washer")
    analyse = measured_runs.analyse_run_with_quality

    def fails_on_run02(record, **options):
        if options["run"] == "run02":
            raise IndexError("index 9 is out of bounds")
        return analyse(record, **options)

    monkeypatch.setattr(measured_runs, "analyse_run_with_quality", fails_on_run02)
    statuses = [
        analysis_status(lab, f"no_washer/{run}.txt", "no_washer", found) for run in ("run01", "run02")
    ]
    assert [status["status"] for status in statuses] == ["used", "excluded"]
    assert statuses[1]["reason"] == (
        f"{lab.as_posix()}/no_washer/run02.txt: not analysed: IndexError: index 9 is out of bounds (an error "
        "of the analysis, not a known fault of the file: the job's log has the trace)"
    )


def test_a_fault_of_the_mode_search_is_the_configurations_reason_not_a_crash(lab, monkeypatch):
    from workflow.measured import mode_identification

    def fails(*args, **kwargs):
        raise FloatingPointError("overflow in multiply")

    monkeypatch.setattr(mode_identification, "identify_mode", fails)
    found = mode_of(lab, ["no_washer/run01.txt"], "no_washer")
    assert found.mode is None
    assert found.error.startswith(
        "configuration no_washer: first mode not found: FloatingPointError: overflow in multiply (an error of"
    )

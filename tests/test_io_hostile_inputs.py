"""Inputs that can hurt (issue 17): paths that leave the campaign, configuration names
that leave the working directory, frequencies the records cannot hold, globs that match
nothing, files that are not run files, misleading reader messages, hostile YAML.

Validation and reader cases call the library; the workflow cases run the real
snakemake on small campaigns.
"""

import functools
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import REPO, checksums, run_snakemake
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workflow.io.campaign import load_campaign
from workflow.io.readers.ascii import declared_sample_rate_hz
from workflow.io.records import CampaignFormatError, RunFile
from workflow.io.run_files import list_runs, read_run, scan_campaign
from workflow.measured import quality

FS_HZ = 2560.0
N_SAMPLES = 400

BASE_YAML = """\
name: hostile
response: {quantity: acceleration, unit: g}
force: {unit: lbf}
"""


def run_text(sample_rate_hz=FS_HZ, n=N_SAMPLES, response=None, header=True):
    """A small run file: header with the sample rate, then time, force, response."""
    t = np.arange(n) / sample_rate_hz
    force = 50.0 * np.exp(-(((t - 0.01) / 0.001) ** 2))
    if response is None:
        response = 3.0 * np.exp(-2.0 * t) * np.sin(2 * np.pi * 125.0 * t)
    lines = (
        [f"Sample rate: {sample_rate_hz:g} Hz", "Time (s)\tForce (lbf)\tAcceleration (g)"] if header else []
    )
    lines += [f"{a:.7f}\t{b:.6f}\t{c:.6f}" for a, b, c in zip(t, force, response)]
    return "\n".join(lines) + "\n"


def make_campaign(root: Path, yaml_text: str, files: dict[str, str | bytes]) -> Path:
    root.mkdir(parents=True, exist_ok=True)
    (root / "campaign.yaml").write_text(yaml_text)
    for relative, text in files.items():
        path = root / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(text.encode() if isinstance(text, str) else text)
    return root


def yaml_error(root: Path, yaml_text: str) -> CampaignFormatError:
    make_campaign(root, yaml_text, {})
    with pytest.raises(CampaignFormatError) as info:
        load_campaign(root)
    assert info.value.path.endswith("campaign.yaml")
    return info.value


# ------------------------------------------------------------------ campaign.yaml: paths and names


@pytest.mark.parametrize(
    "glob",
    [
        "../other/*.txt",
        "cfg/../../other/*.txt",
        "..",
        "cfg\\..\\..\\x.txt",
        "/etc/*",
        "~/x/*.txt",
        "C:/x/*.txt",
    ],
)
def test_glob_leaving_the_campaign_is_refused_naming_key_and_line(tmp_path, glob):
    error = yaml_error(tmp_path, BASE_YAML + f"configurations:\n  cfg: {{files: '{glob}'}}\n")
    assert error.line == 5
    assert "configurations.cfg.files" in error.problem


@pytest.mark.parametrize(
    "name", ["../escape", "a/b", "..", ".hidden", "with space", "semi;colon", "x" * 65, "é"]
)
def test_unsafe_configuration_name_is_refused_naming_key_and_line(tmp_path, name):
    error = yaml_error(tmp_path, BASE_YAML + f'configurations:\n  ok: {{}}\n  "{name}": {{}}\n')
    assert error.line == 6
    assert f"configurations.{name}" in error.problem and "not allowed" in error.problem


def test_numeric_configuration_key_is_refused(tmp_path):
    error = yaml_error(tmp_path, BASE_YAML + "configurations:\n  12: {}\n")
    assert error.line == 5 and "configurations.12" in error.problem


# ------------------------------------------------------------------ campaign.yaml: frequencies


def test_mode_outside_its_band_is_refused(tmp_path):
    error = yaml_error(
        tmp_path, BASE_YAML + "mode_hz: 125\nband_hz: [300, 400]\nconfigurations:\n  cfg: {}\n"
    )
    assert error.line == 5
    assert error.problem.startswith("band_hz: [300, 400] Hz does not hold mode_hz 125 Hz")


@pytest.mark.parametrize(
    ("keys", "line", "start"),
    [
        ("band_hz: [1000, 1400]", 4, "band_hz: [1000, 1400] Hz reaches the Nyquist frequency 1280 Hz"),
        ("band_hz: [1300, 1400]", 4, "band_hz: [1300, 1400] Hz reaches the Nyquist frequency 1280 Hz"),
        ("mode_hz: 1500", 4, "mode_hz: 1500 Hz is not below the Nyquist frequency 1280 Hz"),
    ],
)
def test_frequency_at_or_above_nyquist_of_campaign_rate_is_refused(tmp_path, keys, line, start):
    error = yaml_error(tmp_path, BASE_YAML + f"{keys}\nsample_rate_hz: 2560\nconfigurations:\n  cfg: {{}}\n")
    assert error.line == line
    assert error.problem.startswith(start), error.problem


def test_band_above_nyquist_of_the_file_excludes_the_run_naming_key_and_rate_line(tmp_path):
    root = make_campaign(
        tmp_path,
        BASE_YAML + "band_hz: [300, 400]\nconfigurations:\n  cfg: {}\n",
        {"cfg/run01.txt": run_text(500.0)},
    )
    campaign = load_campaign(root)
    assert declared_sample_rate_hz(root, RunFile("cfg", "run01", "cfg/run01.txt"), campaign) == 500.0
    with pytest.raises(CampaignFormatError) as info:
        read_run(root, "cfg/run01.txt", campaign)
    assert info.value.line == 1  # the header line that sets the sample rate
    assert "campaign.yaml band_hz: [300, 400] Hz reaches the Nyquist frequency 250 Hz" in info.value.problem
    assert "header, line 1" in info.value.problem


def test_declared_sample_rate_comes_from_the_time_column_without_a_header(tmp_path):
    root = make_campaign(
        tmp_path,
        BASE_YAML + "configurations:\n  cfg: {}\n",
        {"cfg/run01.txt": run_text(1000.0, header=False)},
    )
    rate_hz = declared_sample_rate_hz(root, RunFile("cfg", "run01", "cfg/run01.txt"), load_campaign(root))
    # Seven printed decimals of a 1 ms step: the rate is exact to well below 1e-6.
    assert rate_hz == pytest.approx(1000.0, rel=1e-6)


# ------------------------------------------------------------------ campaign.yaml: hostile YAML


def alias_bomb(levels: int) -> str:
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    for level in range(1, levels):
        refs = ", ".join([f"*a{level - 1}"] * 10)
        lines.append(f"a{level}: &a{level} [{refs}]")
    return "\n".join(lines) + "\n"


def test_alias_bomb_is_refused_in_under_a_second(tmp_path):
    (tmp_path / "campaign.yaml").write_text(alias_bomb(9) + BASE_YAML + "configurations:\n  cfg: {}\n")
    assert (tmp_path / "campaign.yaml").stat().st_size < 1200
    start = time.perf_counter()
    with pytest.raises(CampaignFormatError, match="aliases .* expand to more than"):
        load_campaign(tmp_path)
    assert time.perf_counter() - start < 1.0


def test_duplicate_key_inside_an_aliased_mapping_is_found_once(tmp_path):
    # 12 levels of a mapping used twice by the next: about 65 000 values expanded (under
    # the limit); each node is visited once and the duplicate key still found.
    lines = ["d0: &d0 {k: 1, k: 2}"]
    lines += [f"d{i}: &d{i} {{p: *d{i - 1}, q: *d{i - 1}}}" for i in range(1, 13)]
    (tmp_path / "campaign.yaml").write_text("\n".join(lines) + "\n")
    start = time.perf_counter()
    with pytest.raises(CampaignFormatError) as info:
        load_campaign(tmp_path)
    assert time.perf_counter() - start < 1.0
    assert info.value.line == 1 and "k: key given twice" in info.value.problem


def test_deep_nesting_is_a_message_not_a_crash(tmp_path):
    (tmp_path / "campaign.yaml").write_text("a: " + "[" * 20000 + "]" * 20000 + "\n")
    with pytest.raises(CampaignFormatError, match="nested too deeply"):
        load_campaign(tmp_path)


def test_ordinary_aliases_still_work(tmp_path):
    root = make_campaign(
        tmp_path,
        BASE_YAML + "configurations:\n  a: &same {bearing_area_in2: 1.0}\n  b: *same\n",
        {"a/r1.txt": run_text(), "b/r1.txt": run_text()},
    )
    campaign = load_campaign(root)
    assert [spec.files for spec in campaign.configurations.values()] == ["a/*.txt", "b/*.txt"]


# ------------------------------------------------------------------ run discovery


def test_links_directories_and_empty_globs_are_listed_as_excluded(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "secret.txt").write_text(run_text())
    (outside / "deep").mkdir()
    (outside / "deep" / "other.txt").write_text(run_text())
    root = make_campaign(
        tmp_path / "campaign",
        BASE_YAML
        + "configurations:\n  cfg: {files: 'cfg/**/*.txt'}\n  viadir: {files: 'cfg/*/*.txt'}\n  none: {}\n",
        {"cfg/run01.txt": run_text(), "cfg/inside_target.txt": run_text()},
    )
    (root / "cfg" / "link_out.txt").symlink_to(outside / "secret.txt")
    (root / "cfg" / "linked_dir").symlink_to(outside / "deep")
    (root / "cfg" / "link_in.txt").symlink_to(root / "cfg" / "inside_target.txt")
    (root / "cfg" / "old.txt").mkdir()
    (root / "cfg" / "broken.txt").symlink_to(root / "cfg" / "missing")
    os.mkfifo(root / "cfg" / "pipe.txt")
    campaign = load_campaign(root)
    runs, excluded = scan_campaign(root, campaign)
    assert [run.path for run in runs] == ["cfg/inside_target.txt", "cfg/link_in.txt", "cfg/run01.txt"]
    assert list_runs(root, campaign) == runs
    reasons = {entry.path: entry.reason for entry in excluded}
    assert set(reasons) == {
        "cfg/link_out.txt",
        "cfg/linked_dir/other.txt",
        "cfg/old.txt",
        "cfg/broken.txt",
        "cfg/pipe.txt",
        "none/*.txt",
    }
    for path in ("cfg/link_out.txt", "cfg/linked_dir/other.txt"):
        assert reasons[path] == f"{root.as_posix()}/{path}: not read: a symbolic link that leads outside " + (
            "the campaign folder (docs/input-safety.md)"
        )
    assert "a directory, not a run file" in reasons["cfg/old.txt"]
    assert (
        "not a regular file" in reasons["cfg/broken.txt"] and "not a regular file" in reasons["cfg/pipe.txt"]
    )
    assert reasons["none/*.txt"].startswith(
        "configurations.none.files: the glob 'none/*.txt' matches no file"
    )
    rows = [entry.status() for entry in excluded]
    assert all(
        row["status"] == "excluded" and row["configuration"] in ("cfg", "viadir", "none") for row in rows
    )
    # The reader refuses the same paths when asked directly.
    for path in ("cfg/link_out.txt", "cfg/linked_dir/other.txt", "cfg/../../outside/secret.txt"):
        with pytest.raises(CampaignFormatError, match="outside the campaign folder"):
            read_run(root, path, campaign)


def test_unreadable_file_is_listed_as_excluded(tmp_path, monkeypatch):
    root = make_campaign(tmp_path, BASE_YAML + "configurations:\n  cfg: {}\n", {"cfg/run01.txt": run_text()})
    campaign = load_campaign(root)
    # Root reads any file whatever its mode bits: the permission check itself is replaced.
    monkeypatch.setattr("workflow.io.path_checks.os.access", lambda path, mode: False)
    runs, excluded = scan_campaign(root, campaign)
    assert runs == [] and len(excluded) == 1
    assert excluded[0].reason.endswith(
        "cfg/run01.txt: not read: permission denied (the file cannot be opened for reading)"
    )


def test_file_without_read_permission_is_excluded_not_a_crash(tmp_path):
    root = make_campaign(tmp_path, BASE_YAML + "configurations:\n  cfg: {}\n", {"cfg/run01.txt": run_text()})
    (root / "cfg/run01.txt").chmod(0)
    code = (
        "import json, sys\n"
        "from workflow.io.campaign import load_campaign\n"
        "from workflow.io.run_files import scan_campaign\n"
        "runs, excluded = scan_campaign(sys.argv[1], load_campaign(sys.argv[1]))\n"
        "print(json.dumps([len(runs), [entry.reason for entry in excluded]]))"
    )
    command = [sys.executable, "-c", code, str(root)]
    if os.geteuid() == 0:
        # Root reads any file through its capabilities to override permissions: drop them,
        # so that the test runs (in CI, as root) instead of skipping.
        command = ["setpriv", "--inh-caps=-all", "--bounding-set=-dac_override,-dac_read_search", *command]
    answer = subprocess.run(
        command, capture_output=True, text=True, check=True, env={**os.environ, "PYTHONPATH": str(REPO)}
    )
    n_runs, reasons = json.loads(answer.stdout)
    assert n_runs == 0 and len(reasons) == 1 and "permission denied" in reasons[0]


def test_open_failure_in_the_reader_is_a_format_error(tmp_path, monkeypatch):
    root = make_campaign(tmp_path, BASE_YAML + "configurations:\n  cfg: {}\n", {"cfg/run01.txt": run_text()})
    campaign = load_campaign(root)

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr("workflow.io.readers.ascii_rows.open", refuse, raising=False)
    with pytest.raises(CampaignFormatError, match="cfg/run01.txt: cannot be read: Permission denied"):
        read_run(root, "cfg/run01.txt", campaign)


# ------------------------------------------------------------------ reader messages


def read_error(tmp_path, content: str | bytes) -> CampaignFormatError:
    root = make_campaign(tmp_path, BASE_YAML + "configurations:\n  cfg: {}\n", {"cfg/run01.txt": content})
    with pytest.raises(CampaignFormatError) as info:
        read_run(root, "cfg/run01.txt", load_campaign(root))
    assert info.value.path.endswith("cfg/run01.txt")
    return info.value


@pytest.mark.parametrize("separator", ["\t", ";", "  "])
def test_decimal_commas_are_named_at_the_first_data_line(tmp_path, separator):
    text = run_text().replace(".", ",").replace("\t", separator)
    error = read_error(tmp_path, text)
    assert error.line == 3  # sample rate, column names, then the first data line
    assert "decimal commas" in error.problem and 'decimal: ","' in error.problem


def test_decimal_commas_after_integer_rows_are_named_where_they_start(tmp_path):
    lines = run_text().splitlines()
    lines[3:] = [line.replace(".", ",") for line in lines[3:]]
    lines[2] = "0\t0\t0"
    error = read_error(tmp_path, "\n".join(lines) + "\n")
    assert error.line == 4 and "decimal commas" in error.problem


@pytest.mark.parametrize(
    ("encoding", "name"),
    [
        ("utf-16", "UTF-16 (little-endian)"),  # with byte-order mark
        ("utf-16-le", "UTF-16 (little-endian)"),
        ("utf-16-be", "UTF-16 (big-endian)"),
        ("utf-32", "UTF-32 (little-endian)"),
    ],
)
def test_wide_encodings_are_named(tmp_path, encoding, name):
    error = read_error(tmp_path, run_text().encode(encoding))
    assert error.problem.startswith(f"text encoded as {name}: run files must be ASCII or UTF-8")


def test_binary_file_is_still_called_binary(tmp_path):
    error = read_error(tmp_path, run_text().encode()[:200] + b"\x00\x01\x02\xff" * 50)
    assert "binary data (NUL byte)" in error.problem


def test_constant_response_is_a_dead_channel_not_clipping():
    def reason(response):
        return quality.check_clipping(response, 0.9999, 3, "g").reason

    assert reason(np.full(1000, 0.25)) == "response is constant (0.25 g) throughout: a dead or stuck channel"
    stuck = 0.25 + 1e-7 * np.sin(np.arange(1000))
    assert "an offset with no ring-down): a dead or stuck channel" in reason(stuck)
    assert "dead or disconnected" in reason(np.zeros(1000))
    flat_top = np.clip(np.sin(np.linspace(0, 40 * np.pi, 4000)), -0.5, 0.5)
    assert reason(flat_top).startswith("response clipped")


# ------------------------------------------------------------------ property: nothing leaves


def _output_templates() -> list[str]:
    """Every path pattern of the rules that a configuration name goes into."""
    text = "\n".join(path.read_text() for path in sorted((REPO / "rules").glob("*.smk")))
    return sorted(set(re.findall(r'"(results/[^"\n]*\{(?:configuration|name)\}[^"\n]*)"', text)))


OUTPUT_TEMPLATES = _output_templates()
PATH_CHARACTERS = st.sampled_from(list("ab*?[]!./\\~-_ ") + ["..", "**", "/", "cfg", "outside", "link"])


@pytest.fixture(scope="module")
def sandbox(tmp_path_factory):
    """A campaign beside an ``outside`` folder of run files, with links leading there."""
    base = tmp_path_factory.mktemp("sandbox")
    outside = base / "outside"
    outside.mkdir()
    (outside / "secret.txt").write_text(run_text())
    root = make_campaign(
        base / "campaign", BASE_YAML + "configurations:\n  cfg: {}\n", {"cfg/run01.txt": run_text()}
    )
    (root / "cfg" / "link.txt").symlink_to(outside / "secret.txt")
    (root / "link").symlink_to(outside)
    return base, root


def test_output_templates_are_found():
    assert "results/interim/mode/{configuration}.json" in OUTPUT_TEMPLATES
    assert len(OUTPUT_TEMPLATES) >= 5


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    name=st.text(min_size=1, max_size=12) | st.lists(PATH_CHARACTERS, min_size=1, max_size=6).map("".join),
    glob=st.lists(PATH_CHARACTERS, min_size=1, max_size=8).map("".join),
)
def test_no_name_or_glob_reads_outside_the_campaign_or_writes_outside_the_workdir(sandbox, name, glob):
    base, root = sandbox
    # JSON strings are YAML flow scalars: any name and glob is written as it is.
    (root / "campaign.yaml").write_text(
        BASE_YAML + f"configurations:\n  {json.dumps(name)}: {{files: {json.dumps(glob)}}}\n"
    )
    try:
        campaign = load_campaign(root)
        runs, _ = scan_campaign(root, campaign)
    except CampaignFormatError:
        return
    root_resolved = root.resolve()
    for run in runs:
        assert (root / run.path).resolve().is_relative_to(root_resolved), run
    workdir = (base / "work").resolve()
    for configuration in campaign.configurations:
        for template in OUTPUT_TEMPLATES:
            output = template.replace("{configuration}", configuration).replace("{name}", configuration)
            assert (workdir / output).resolve().is_relative_to(workdir), output


# ------------------------------------------------------------------ the real workflow

snakemake = functools.partial(run_snakemake, timeout=600)


@pytest.fixture(scope="module")
def lab_campaign(tmp_path_factory):
    from workflow.lab.campaigns import generate_campaign

    base = tmp_path_factory.mktemp("hostile_workflow")
    campaign = base / "campaign"
    generate_campaign(campaign, seed=5, runs_per_configuration=2, configurations={"no_washer": 1.36})
    return campaign


def listing(folder: Path) -> list[str]:
    return sorted(path.relative_to(folder).as_posix() for path in folder.rglob("*"))


def test_workflow_lists_unread_paths_and_empty_globs_in_the_runs_table(lab_campaign, tmp_path):
    campaign = tmp_path / "campaign"
    shutil.copytree(lab_campaign, campaign)
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "run03.txt").write_bytes((campaign / "no_washer/run01.txt").read_bytes())
    (campaign / "no_washer/run03.txt").symlink_to(outside / "run03.txt")
    (campaign / "no_washer/run04.txt").mkdir()
    text = (campaign / "campaign.yaml").read_text()
    (campaign / "campaign.yaml").write_text(text + '  spare: {files: "spare/*.txt"}\n')
    before_raw = checksums(campaign)
    workdir = tmp_path / "work"
    workdir.mkdir()
    before_outside = listing(tmp_path)
    result = snakemake(workdir, "-c2", "results/tables/runs.parquet", "--config", f"campaign={campaign}")
    assert result.returncode == 0, result.stderr[-4000:]
    runs = pd.read_parquet(workdir / "results/tables/runs.parquet").set_index("path")
    assert list(runs.loc[["no_washer/run01.txt", "no_washer/run02.txt"], "status"]) == ["used", "used"]
    assert runs.loc["no_washer/run03.txt", "status"] == "excluded"
    assert "symbolic link that leads outside the campaign folder" in runs.loc["no_washer/run03.txt", "reason"]
    assert "a directory, not a run file" in runs.loc["no_washer/run04.txt", "reason"]
    assert runs.loc["spare/*.txt", "configuration"] == "spare"
    assert runs.loc["spare/*.txt", "reason"].startswith(
        "configurations.spare.files: the glob 'spare/*.txt' matches no file"
    )
    assert "matches no file" in result.stderr  # warned while planning, too
    assert checksums(campaign) == before_raw
    after = [path for path in listing(tmp_path) if not path.startswith("work/")]
    assert after == [path for path in before_outside if not path.startswith("work/")]


def test_strict_workflow_stops_at_an_empty_glob_before_any_job(lab_campaign, tmp_path):
    text = (lab_campaign / "campaign.yaml").read_text()
    campaign = tmp_path / "campaign"
    campaign.mkdir()
    (campaign / "campaign.yaml").write_text(text + '  spare: {files: "spare/*.txt"}\n')
    shutil.copytree(lab_campaign / "no_washer", campaign / "no_washer")
    result = snakemake(tmp_path, "-n", "all", "--config", f"campaign={campaign}", "strict=true")
    assert result.returncode != 0
    output = result.stdout + result.stderr
    assert "strict mode: campaign paths not read" in output
    assert "configurations.spare.files: the glob 'spare/*.txt' matches no file" in output
    assert "Job stats" not in output


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda text: text + '  "../escape": {files: "no_washer/*.txt"}\n',
            "campaign.yaml:9: configurations.../escape: configuration name '../escape' is not allowed",
        ),
        (
            lambda text: text + '  "a/b": {files: "no_washer/*.txt"}\n',
            "campaign.yaml:9: configurations.a/b: configuration name 'a/b' is not allowed",
        ),
        (
            lambda text: text.replace("no_washer/*.txt", "../*/no_washer/*.txt"),
            "campaign.yaml:8: configurations.no_washer.files: Value error, files glob '../*/no_washer/*.txt' "
            "leaves the campaign folder",
        ),
        (
            lambda text: text.replace("mode_hz: 126", "mode_hz: 126\nband_hz: [300, 400]"),
            "campaign.yaml:5: band_hz: [300, 400] Hz does not hold mode_hz 126 Hz",
        ),
        (
            lambda text: text.replace("sample_rate_hz: 2560\n", "").replace(
                "mode_hz: 126", "band_hz: [1200, 1400]"
            ),
            "campaign.yaml: band_hz: [1200, 1400] Hz reaches the Nyquist frequency 1280 Hz of the sample rate "
            "2560 Hz (declared by no_washer/run01.txt)",
        ),
        (
            lambda text: text.replace("sample_rate_hz: 2560\n", "").replace("mode_hz: 126", "mode_hz: 1500"),
            "campaign.yaml: mode_hz: 1500 Hz is not below the Nyquist frequency 1280 Hz",
        ),
    ],
    ids=[
        "dotdot_name",
        "slash_name",
        "dotdot_glob",
        "mode_outside_band",
        "band_above_nyquist",
        "mode_above_nyquist",
    ],
)
def test_hostile_campaign_yaml_stops_before_any_job_and_writes_nothing_outside(
    lab_campaign, tmp_path, edit, message
):
    campaign = tmp_path / "campaign"
    campaign.mkdir()
    (campaign / "campaign.yaml").write_text(edit((lab_campaign / "campaign.yaml").read_text()))
    shutil.copytree(lab_campaign / "no_washer", campaign / "no_washer")
    workdir = tmp_path / "work"
    workdir.mkdir()
    before = listing(tmp_path)
    result = snakemake(workdir, "-c1", "all", "--config", f"campaign={campaign}")
    assert result.returncode != 0
    output = result.stdout + result.stderr
    assert message in output, output[-3000:]
    assert "Job stats" not in output
    assert [p for p in listing(tmp_path) if not p.startswith("work/")] == [
        p for p in before if not p.startswith("work/")
    ]

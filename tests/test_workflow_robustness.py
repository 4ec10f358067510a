"""Robustness of the whole workflow (issue 7), on the real ``snakemake``.

One small virtual-lab campaign carries one bad run per malformed case of
campaign-format.md and per quality check, plus a configuration whose mode lies
outside the search range. It is analysed once (module fixture) and many things
are asserted on that one result: every bad run is an ``excluded`` row of
runs.parquet whose reason names the file, the line where there is one and what
is wrong (by how much, for a quality check); every good run is used and has
segments; tables and figures are all written; raw files are untouched. Separate
short runs check ``strict: true`` and an unknown key in campaign.yaml.
"""

from __future__ import annotations

import functools
import json
import os
import re
import stat
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import CHEAP, checksums, run_snakemake, write_run_with_bad_cell

from workflow.lab.campaign_files import format_run
from workflow.lab.campaigns import generate_campaign
from workflow.lab.settings import PRETRIGGER_SAMPLES, SAMPLE_RATE_HZ

FS_HZ = SAMPLE_RATE_HZ
PRETRIGGER = PRETRIGGER_SAMPLES
HEADER_LINES = 4  # title, sample rate, pre-trigger, column names: data start on line 5
GOOD_CONFIGURATIONS = {"no_washer": 1.36, "small_washer": 0.17}
OFF_MODE = "large_washer"  # readable runs whose mode lies far outside the search range


snakemake = functools.partial(run_snakemake, timeout=600)


def measured_targets(configurations: list[str]) -> list[str]:
    """The measured-data chain's part of ``all``: every table and figure except the
    friction-model fits (minutes per configuration; tested on their own)."""
    return [
        "results/tables/segments.parquet",
        "results/tables/runs.parquet",
        "results/tables/damping_fits.parquet",
        "results/tables/hypotheses.parquet",
        "results/figures/fig09_time_history.png",
        "results/figures/fig13_area_fits.png",
        *[
            f"results/figures/fig{min(10 + i, 12):02d}_damping_{name}.png"
            for i, name in enumerate(configurations)
        ],
        *[f"results/figures/backbone_{name}.png" for name in configurations],
    ]


def data_line(sample: int) -> int:
    """1-based file line of a sample in a virtual-lab run file."""
    return HEADER_LINES + 1 + sample


def read_columns(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    values = np.loadtxt(path, skiprows=HEADER_LINES, delimiter="\t")
    return values[:, 0], values[:, 1], values[:, 2]


def write_columns(path: Path, time_s, force_lbf, response_g) -> None:
    path.write_text(format_run(time_s, force_lbf, response_g))


def replace_cell(lines: list[str], line: int, column: int, text: str) -> list[str]:
    """``lines`` with cell ``column`` (1-based) of file line ``line`` replaced by ``text``."""
    out = list(lines)
    cells = out[line - 1].split("\t")
    cells[column - 1] = text
    out[line - 1] = "\t".join(cells)
    return out


def build_campaign(root: Path) -> tuple[Path, dict[str, dict]]:
    """A campaign with good runs, one bad run per case, and an off-mode configuration.

    Returns the campaign folder and, per bad run (``configuration/run``), what its
    reason must say: ``words`` (exact fragments) and ``line`` (or None).
    """
    campaign = root / "campaign"
    generate_campaign(campaign, seed=11, runs_per_configuration=2, configurations=GOOD_CONFIGURATIONS)
    # A third configuration: campaign.yaml keeps its plotting order (first here, so that
    # the paper's figure 9, drawn from the first configuration, must cope with it).
    yaml_text = (campaign / "campaign.yaml").read_text()
    yaml_text = yaml_text.replace(
        "configurations:\n",
        f'configurations:\n  {OFF_MODE}: {{bearing_area_in2: 0.66, files: "{OFF_MODE}/*.txt"}}\n',
    )
    (campaign / "campaign.yaml").write_text(yaml_text)

    source = campaign / "no_washer" / "run01.txt"
    text = source.read_text()
    lines = text.splitlines()
    time_s, force_lbf, response_g = read_columns(source)
    n = time_s.size
    bad = campaign / "no_washer"
    expected: dict[str, dict] = {}

    def malformed(name: str, new_lines: list[str] | str, line: int | None, *words: str) -> None:
        content = new_lines if isinstance(new_lines, str) else "\n".join(new_lines) + "\n"
        (bad / f"{name}.txt").write_text(content)
        expected[f"no_washer/{name}"] = {"line": line, "words": words}

    # ---------------------------------------------------------------- malformed files
    malformed("bad_cell", replace_cell(lines, 40, 3, "n/a"), 40, "non-numeric cell 'n/a' in column 3")
    ragged = list(lines)
    ragged[999] = ragged[999].rsplit("\t", 1)[0]
    malformed("bad_ragged", ragged, 1000, "ragged row: 2 values, expected 3")
    malformed("bad_nan", replace_cell(lines, 500, 3, "NaN"), 500, "NaN/inf value 'NaN' in column 3")
    malformed("bad_inf", replace_cell(lines, 2001, 2, "-inf"), 2001, "NaN/inf value '-inf' in column 2")
    malformed("bad_empty", "", 1, "the file is empty")
    malformed(
        "bad_header_only",
        lines[:HEADER_LINES],
        HEADER_LINES,
        "no numeric rows: all 4 line(s) are header text",
    )
    mixed = list(lines)
    mixed[299] = mixed[299].replace("\t", ",")
    malformed("bad_delimiters", mixed, 300, "mixed delimiters: comma in a row separated by tab")
    uneven = replace_cell(lines, data_line(3000), 1, f"{time_s[3000] + 0.4 / FS_HZ:.6f}")
    malformed("bad_time_uneven", uneven, data_line(3000), "time column not uniform")
    backwards = list(lines)
    backwards[data_line(700) - 1], backwards[data_line(701) - 1] = (
        backwards[data_line(701) - 1],
        backwards[data_line(700) - 1],
    )
    malformed(
        "bad_time_backwards",
        backwards,
        data_line(700),  # the first line whose time stamp is wrong
        f"time column out of order: {time_s[701]:.9g} s is followed by {time_s[700]:.9g} s on the next line",
    )
    rate = list(lines)
    rate[1] = "Sample rate: 2048 Hz"
    malformed(
        "bad_sample_rate",
        rate,
        2,
        "sample rate 2048 Hz from the header disagrees with 2560 Hz from the campaign.yaml sample_rate_hz",
    )
    malformed(
        "bad_few_samples",
        lines[: HEADER_LINES + 100],
        HEADER_LINES + 100,
        "only 100 samples; a run needs at least 256",
    )

    # ---------------------------------------------------------------- quality checks
    def failing(name: str, force, response, *words: str, n_samples: int = n) -> None:
        write_columns(bad / f"{name}.txt", time_s[:n_samples], force[:n_samples], response[:n_samples])
        expected[f"no_washer/{name}"] = {"line": None, "words": words}

    rail = 0.5 * np.abs(response_g).max()
    clipped = np.clip(response_g, -rail, rail)
    at_rail = int(np.count_nonzero(np.abs(clipped) >= 0.9999 * rail))
    failing(
        "qc_clipped",
        force_lbf,
        clipped,
        f"response clipped: {at_rail} samples within 0.01 % of the peak {rail:.4g} g (limit 3)",
    )

    main_at = int(np.argmax(force_lbf))
    delay = int(round(0.040 * FS_HZ))  # a bounce 40 ms later, at half the force
    double = force_lbf.copy()
    double[main_at + delay - 5 : main_at + delay + 6] += 0.5 * force_lbf[main_at - 5 : main_at + 6]
    second = double[main_at + delay - 5 : main_at + delay + 6].max()
    failing(
        "qc_double_hit",
        double,
        response_g,
        f"double hit: a second force pulse of {second:.3g} lbf "
        f"({second / force_lbf[main_at]:.2f} of the main {force_lbf[main_at]:.3g} lbf pulse) "
        f"{1e3 * delay / FS_HZ:.3g} ms after it (limit 0.30)",
    )

    tiny = force_lbf * (0.4 / force_lbf.max())
    failing("qc_no_hit", tiny, response_g, f"no real hit: peak force {tiny.max():.3g} lbf is below 1 lbf")

    shift = 200  # the hit 200 samples later than the 25-sample pre-trigger says
    late_force = np.r_[np.tile(force_lbf[:PRETRIGGER], shift // PRETRIGGER), force_lbf][:n]
    late_response = np.r_[np.tile(response_g[:PRETRIGGER], shift // PRETRIGGER), response_g][:n]
    first = int(np.flatnonzero(late_force >= 1.0)[0])
    failing(
        "qc_trigger",
        late_force,
        late_response,
        f"trigger: the force first reaches 1 lbf at sample {first}, {first - PRETRIGGER} "
        f"samples after the pre-trigger length {PRETRIGGER} (tolerance 5)",
    )

    short = 300  # readable (>= 256 samples) but under 20 cycles of the mode
    mode_hz = float(re.search(r"mode_hz: (\S+)", yaml_text).group(1))
    failing(
        "qc_short",
        force_lbf,
        response_g,
        f"record too short: {short / FS_HZ:.3g} s holds {short / FS_HZ * mode_hz:.3g} cycles "
        f"of the {mode_hz:.4g} Hz mode (need 20)",
        n_samples=short,
    )

    noise = np.random.default_rng(3).standard_normal(n) * 2.0 * np.abs(response_g).max()
    failing("qc_noisy", force_lbf, response_g + noise, "signal-to-noise ", " dB is below 20 dB")

    # ---------------------------------------------------------------- mode not found
    # Runs of a much stiffer joint: the first mode near 2.3 x mode_hz, far outside
    # the searched mode_hz * (1 -/+ 0.3); only its flank (and noise) lies in range.
    folder = campaign / OFF_MODE
    folder.mkdir()
    stiff_hz = 2.3 * mode_hz
    tau = time_s - (PRETRIGGER + 0.5) / FS_HZ
    for index in range(2):
        rng = np.random.default_rng(100 + index)
        ring = np.where(
            tau >= 0,
            2.0 * np.exp(-2 * np.pi * stiff_hz * 0.003 * tau) * np.sin(2 * np.pi * stiff_hz * tau),
            0.0,
        )
        write_columns(
            folder / f"run{index + 1:02d}.txt", time_s, force_lbf, ring + 1e-3 * rng.standard_normal(n)
        )
        expected[f"{OFF_MODE}/run{index + 1:02d}"] = {
            "line": None,
            "words": (
                f"configuration {OFF_MODE}: first mode not found: no resonance in the search range",
                "the mode lies outside the range",
            ),
        }
    return campaign, expected


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    root = tmp_path_factory.mktemp("robustness")
    campaign, expected = build_campaign(root)
    before = checksums(campaign)
    workdir = root / "work"
    workdir.mkdir()
    targets = measured_targets([OFF_MODE, *GOOD_CONFIGURATIONS])
    result = snakemake(workdir, "-c2", *targets, "--config", f"campaign={campaign}")
    assert result.returncode == 0, result.stderr[-6000:]
    runs = pd.read_parquet(workdir / "results/tables/runs.parquet")
    return campaign, workdir, expected, before, runs, result


def test_every_file_has_one_row(study):
    campaign, _, expected, _, runs, _ = study
    files = sorted(p.relative_to(campaign).with_suffix("").as_posix() for p in campaign.rglob("*.txt"))
    assert sorted(runs["configuration"] + "/" + runs["run"]) == files
    assert set(runs["status"]) == {"used", "excluded"}
    assert (runs["path"] == runs["configuration"] + "/" + runs["run"] + ".txt").all()


@pytest.mark.parametrize(
    "case",
    [
        "bad_cell",
        "bad_ragged",
        "bad_nan",
        "bad_inf",
        "bad_empty",
        "bad_header_only",
        "bad_delimiters",
        "bad_time_uneven",
        "bad_time_backwards",
        "bad_sample_rate",
        "bad_few_samples",
    ],
)
def test_malformed_file_is_excluded_naming_file_line_and_problem(study, case):
    campaign, _, expected, _, runs, _ = study
    row = runs[(runs["configuration"] == "no_washer") & (runs["run"] == case)].iloc[0]
    want = expected[f"no_washer/{case}"]
    assert row["status"] == "excluded"
    # file:line: problem, with the file as the workflow was given it
    prefix = f"{campaign.as_posix()}/no_washer/{case}.txt:{want['line']}: "
    assert row["reason"].startswith(prefix), row["reason"]
    for words in want["words"]:
        assert words in row["reason"], row["reason"]


@pytest.mark.parametrize(
    "case",
    [
        "qc_clipped",
        "qc_double_hit",
        "qc_no_hit",
        "qc_trigger",
        "qc_short",
        "qc_noisy",
    ],
)
def test_failed_quality_check_is_excluded_saying_by_how_much(study, case):
    _, _, expected, _, runs, _ = study
    row = runs[(runs["configuration"] == "no_washer") & (runs["run"] == case)].iloc[0]
    assert row["status"] == "excluded"
    assert row["reason"].startswith(f"no_washer/{case}.txt: "), row["reason"]
    for words in expected[f"no_washer/{case}"]["words"]:
        assert words in row["reason"], row["reason"]


def test_noisy_run_reports_its_signal_to_noise(study):
    _, _, _, _, runs, _ = study
    reason = runs.set_index("run").loc["qc_noisy", "reason"]
    snr_db = float(re.search(r"signal-to-noise (-?[\d.]+) dB is below 20 dB", reason).group(1))
    assert snr_db < 20
    assert re.search(r"\(peak envelope [\d.e+-]+, noise floor [\d.e+-]+\)", reason)


def test_each_bad_run_fails_for_its_own_reason_only(study):
    # A QC case must not also trip an unrelated check (the reason would mislead).
    _, _, _, _, runs, _ = study
    reasons = runs.set_index("run")["reason"]
    assert "double hit" not in reasons["qc_clipped"] and "trigger" not in reasons["qc_clipped"]
    assert "clipped" not in reasons["qc_double_hit"] and "trigger" not in reasons["qc_double_hit"]
    assert reasons["qc_no_hit"].count(";") == 0  # no trigger complaint on top of "no hit"
    assert "record too short" not in reasons["qc_trigger"]


def test_configuration_whose_mode_is_not_found_is_excluded_and_others_go_on(study):
    _, workdir, expected, _, runs, _ = study
    off = runs[runs["configuration"] == OFF_MODE]
    assert len(off) == 2 and (off["status"] == "excluded").all()
    for row in off.itertuples():
        for words in expected[f"{OFF_MODE}/{row.run}"]["words"]:
            assert words in row.reason, row.reason
    modes = pd.read_parquet(workdir / "results/tables/modes.parquet").set_index("configuration")
    assert modes.loc[OFF_MODE, "method"] == "not found"
    assert "no resonance in the search range" in modes.loc[OFF_MODE, "error"]
    for name in GOOD_CONFIGURATIONS:
        assert modes.loc[name, "error"] == ""
        assert 100 < modes.loc[name, "mode_hz"] < 150


def test_good_runs_are_used_with_segments(study):
    _, workdir, _, _, runs, _ = study
    used = runs[runs["status"] == "used"]
    good = {(name, f"run{i:02d}") for name in GOOD_CONFIGURATIONS for i in (1, 2)}
    assert set(zip(used["configuration"], used["run"])) == good
    assert (used["reason"] == "").all()
    excluded = runs[runs["status"] == "excluded"]
    assert (excluded["reason"].str.len() > 20).all()
    segments = pd.read_parquet(workdir / "results/tables/segments.parquet")
    assert set(zip(segments["configuration"], segments["run"])) == good
    assert segments.groupby(["configuration", "run"]).size().min() >= 3
    assert np.isfinite(segments[["t_s", "velocity_amplitude_in_s", "frequency_hz", "zeta"]]).all().all()


def test_tables_and_figures_are_produced(study):
    _, workdir, _, _, _, _ = study
    results = workdir / "results"
    for name in [
        "segments",
        "segments_rejected",
        "runs",
        "modes",
        "damping_fits",
        "damping_curves",
        "hypotheses",
        "area_fits",
    ]:
        assert (results / "tables" / f"{name}.parquet").is_file(), name
    fits = pd.read_parquet(results / "tables/damping_fits.parquet")
    assert set(fits["configuration"]) == set(GOOD_CONFIGURATIONS)
    for name in [
        "fig09_time_history.png",
        f"fig10_damping_{OFF_MODE}.png",
        "fig11_damping_no_washer.png",
        "fig12_damping_small_washer.png",
        "fig13_area_fits.png",
        *[f"backbone_{c}.png" for c in [OFF_MODE, *GOOD_CONFIGURATIONS]],
    ]:
        assert (results / "figures" / name).stat().st_size > 5_000, name


def test_excluded_runs_are_logged(study):
    _, workdir, _, _, runs, _ = study
    log = (workdir / "results/logs/collect_tables.log").read_text()
    assert f"{int((runs['status'] == 'excluded').sum())} excluded" in log
    assert "excluded no_washer/qc_double_hit: no_washer/qc_double_hit.txt: double hit" in log


def test_raw_files_are_unchanged(study):
    campaign, _, _, before, _, _ = study
    assert checksums(campaign) == before


def test_tables_are_readable_like_any_file_the_user_writes(study):
    # Temporary files are created private (0600); the renamed table must not stay so.
    _, workdir, _, _, _, _ = study
    umask = os.umask(0)
    os.umask(umask)
    for path in (workdir / "results/tables").glob("*.parquet"):
        assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask, path.name


# ------------------------------------------------------------------ strict mode


def test_strict_mode_stops_at_a_bad_run_with_its_message(tmp_path):
    campaign = tmp_path / "campaign"
    generate_campaign(campaign, seed=5, runs_per_configuration=1, configurations={"no_washer": 1.36})
    lines = (campaign / "no_washer/run01.txt").read_text().splitlines()
    (campaign / "no_washer/run00.txt").write_text("\n".join(replace_cell(lines, 60, 2, "x1")) + "\n")
    workdir = tmp_path / "work"
    workdir.mkdir()
    result = snakemake(
        workdir, "-c1", *measured_targets(["no_washer"]), "--config", f"campaign={campaign}", "strict=true"
    )
    assert result.returncode != 0
    reason = f"{campaign.as_posix()}/no_washer/run00.txt:60: non-numeric cell 'x1' in column 2"
    assert f"strict mode: run excluded: {reason}" in result.stderr
    assert "Error in rule identify_mode" in result.stderr  # it analyses the first group of runs
    log = (workdir / "results/logs/identify_mode/no_washer.log").read_text()
    assert f"WARNING excluded {reason}" in log
    assert not (workdir / "results/tables/runs.parquet").exists()


# ------------------------------------------------------------------ campaign.yaml errors


def test_unknown_campaign_key_stops_before_any_job(tmp_path):
    campaign = tmp_path / "campaign"
    generate_campaign(campaign, seed=5, runs_per_configuration=1, configurations={"no_washer": 1.36})
    text = (campaign / "campaign.yaml").read_text()
    (campaign / "campaign.yaml").write_text(text.replace("mode_hz:", "mode_freq_hz:"))
    result = snakemake(tmp_path, "-n", "all", "--config", f"campaign={campaign}")
    assert result.returncode != 0
    output = result.stdout + result.stderr
    assert f"cannot read campaign {campaign}" in output
    assert f"{campaign.as_posix()}/campaign.yaml:4: mode_freq_hz: unknown key" in output
    assert "Job stats" not in output  # stopped while the DAG was built


# ------------------------------------------------------------------ per-check quality table


def _qc_table(campaign: Path, path: str) -> tuple[pd.DataFrame, list[str]]:
    from helpers import failed_check_reasons

    from workflow.io.campaign import load_campaign
    from workflow.io.run_files import read_run
    from workflow.measured.quality import QC_COLUMNS, quality_rows
    from workflow.measured.settings import QualitySettings

    meta = load_campaign(campaign)
    record = read_run(campaign, path, meta)
    rows = quality_rows(record, QualitySettings(), mode_hz=meta.mode_hz)
    table = pd.DataFrame(rows, columns=QC_COLUMNS).set_index("check")
    return table, failed_check_reasons(record, QualitySettings(), mode_hz=meta.mode_hz)


@pytest.mark.parametrize(
    "case, check, value",
    [
        ("qc_clipped", "clipping", None),
        ("qc_double_hit", "double_hit", 0.5),
        ("qc_no_hit", "excitation", 0.4),
        ("qc_trigger", "trigger", None),
        ("qc_short", "record_length", 300 / FS_HZ),
    ],
)
def test_quality_table_row_per_check_agrees_with_runs_table(study, case, check, value):
    campaign, _, _, _, runs, _ = study
    table, reasons = _qc_table(campaign, f"no_washer/{case}.txt")
    assert list(table.index) == ["clipping", "excitation", "double_hit", "trigger", "record_length"]
    failed = table[table["applied"] & ~table["passed"]]
    # the table and runs.parquet never disagree: same failed checks, same words
    assert list(failed["reason"]) == reasons
    assert list(failed.index) == [check]
    runs_reason = runs.set_index("run").loc[case, "reason"]
    assert runs_reason == f"no_washer/{case}.txt: {failed.loc[check, 'reason']}"
    measured, threshold = failed.loc[check, "value"], failed.loc[check, "threshold"]
    if check in ("excitation", "record_length"):
        assert measured < threshold  # "at least" checks
    else:
        assert measured > threshold  # "at most" checks
    if check == "double_hit":
        assert measured == pytest.approx(value, abs=0.02)
    elif check == "excitation":
        assert measured == pytest.approx(value, rel=1e-6)
    elif check == "record_length":
        mode_hz = float(re.search(r"mode_hz: (\S+)", (campaign / "campaign.yaml").read_text()).group(1))
        assert measured == pytest.approx(value * mode_hz)
    elif check == "trigger":
        assert measured == pytest.approx(int(re.search(r"(\d+) samples after", runs_reason).group(1)))
    elif check == "clipping":
        assert measured == int(re.search(r"clipped: (\d+) samples", runs_reason).group(1))


def test_quality_table_of_a_good_run_passes_with_margins(study):
    campaign, _, _, _, _, _ = study
    table, reasons = _qc_table(campaign, "no_washer/run01.txt")
    assert reasons == [] and table["applied"].all() and table["passed"].all()
    assert (table["reason"] == "").all()
    assert table.loc["clipping", "value"] <= 3
    assert table.loc["excitation", "value"] > 10  # lbf: a real hammer hit
    assert table.loc["double_hit", "value"] == 0.0
    assert table.loc["trigger", "value"] <= 5
    assert table.loc["record_length", "value"] > 100  # cycles in a 3.2 s record


def test_quality_rows_mark_checks_that_do_not_apply():
    from workflow.io.records import RunRecord
    from workflow.measured.quality import analysis_rows, quality_rows
    from workflow.measured.settings import QualitySettings

    t = np.arange(4096) / FS_HZ
    record = RunRecord(
        path="cfg/run.txt",
        sample_rate_hz=FS_HZ,
        pretrigger_samples=0,
        time_s=None,
        force_lbf=None,
        response=np.exp(-3 * t) * np.sin(2 * np.pi * 120 * t),
        response_quantity="acceleration",
        response_unit="g",
        header={},
        n_samples=t.size,
    )
    rows = {row["check"]: row for row in quality_rows(record, QualitySettings())}
    for check in ("excitation", "double_hit", "trigger", "record_length"):
        assert rows[check]["applied"] is False and rows[check]["passed"] is False
        assert np.isnan(rows[check]["value"]) and rows[check]["reason"] == ""
    assert rows["clipping"]["applied"] and rows["clipping"]["passed"]
    snr, segments = analysis_rows(1.0, 0.2, 2, QualitySettings())
    assert snr["value"] == pytest.approx(13.979, abs=1e-3) and not snr["passed"]
    assert snr["reason"].startswith("signal-to-noise 14 dB is below 20 dB")
    assert segments["value"] == 2 and not segments["passed"]
    assert segments["reason"] == "only 2 usable log-decrement segments (at least 3 needed)"


def test_configuration_with_every_run_excluded_is_listed_in_the_diagnosis(tmp_path):
    # the diagnosis job once failed on such a configuration, and `all` wrote no
    # diagnosis.json for the configurations that were fine
    campaign = tmp_path / "campaign"
    generate_campaign(
        campaign, seed=5, runs_per_configuration=3, configurations={"no_washer": 1.36, "small_washer": 0.17}
    )
    for run in sorted((campaign / "small_washer").glob("*.txt")):
        write_run_with_bad_cell(run, run)
    workdir = tmp_path / "work"
    workdir.mkdir()
    result = snakemake(workdir, "-c2", "all", "--config", f"campaign={campaign}", *CHEAP)
    assert result.returncode == 0, result.stderr[-6000:]
    runs = pd.read_parquet(workdir / "results/tables/runs.parquet")
    assert (runs.loc[runs["configuration"] == "small_washer", "status"] == "excluded").all()
    document = json.loads((workdir / "results/diagnosis.json").read_text())
    assert list(document["configurations"]) == ["no_washer"]
    assert "every run excluded" in document["skipped_configurations"]["small_washer"]
    assert (workdir / "results/figures/discovery_residuals_small_washer.png").stat().st_size > 5_000


def test_a_reader_fault_on_one_file_excludes_that_run_and_names_it(tmp_path, monkeypatch):
    from workflow.io import run_files
    from workflow.measured.runs import read_with_quality

    def faulty(campaign_dir, path, campaign):
        raise OverflowError("cannot convert float infinity to integer")

    monkeypatch.setattr(run_files, "read_run", faulty)
    record, rows = read_with_quality(tmp_path, "cfg/run07.txt", None, None)
    assert record is None and len(rows) == 1 and not rows[0]["passed"]
    assert rows[0]["reason"].startswith(f"{tmp_path.as_posix()}/cfg/run07.txt: not read: OverflowError")

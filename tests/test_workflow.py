"""The real ``snakemake`` on small campaigns: contract outputs, bad runs, re-runs."""

import functools
import re

import matplotlib.text
import numpy as np
import pandas as pd
import pytest
from helpers import checksums, run_snakemake, write_run_with_bad_cell

from workflow.io.tables import column_units
from workflow.io.units import SI, SI_TWIN_COLUMNS
from workflow.lab.campaigns import generate_campaign
from workflow.outputs import figures
from workflow.outputs.readability import readability_problems

snakemake = functools.partial(run_snakemake, timeout=900)


def job_counts(dry_run_output: str) -> dict[str, int]:
    """Rule -> job count from the 'Job stats' table of a dry run."""
    table = dry_run_output.split("Job stats:", 1)[1]
    counts = {}
    for line in table.splitlines()[3:]:
        match = re.match(r"^(\w+)\s+(\d+)$", line.strip())
        if not match:
            break
        counts[match.group(1)] = int(match.group(2))
    return counts


# Two runs per analyse_runs job, so that a configuration has several jobs and the
# corrupted run04 shares its job with the good run03.
GROUPED = "runs_per_job=2"


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    """A 2-configuration x 3-run virtual-lab campaign with one corrupted run, analysed."""
    root = tmp_path_factory.mktemp("study")
    campaign = root / "campaign"
    generate_campaign(
        campaign, seed=7, runs_per_configuration=3, configurations={"no_washer": 1.36, "small_washer": 0.17}
    )
    # line 40 of the file: a cell that is not a number
    write_run_with_bad_cell(campaign / "no_washer" / "run03.txt", campaign / "no_washer" / "run04.txt")
    before = checksums(campaign)
    workdir = root / "work"
    workdir.mkdir()
    result = snakemake(workdir, "-c2", "measured", "--config", f"campaign={campaign}", GROUPED)
    assert result.returncode == 0, result.stderr[-4000:]
    return campaign, workdir, before


def test_segments_table_follows_the_contract(finished_run):
    _, workdir, _ = finished_run
    path = workdir / "results/tables/segments.parquet"
    segments = pd.read_parquet(path)
    for column in [
        "configuration",
        "run",
        "t_s",
        "response_amplitude",
        "velocity_amplitude_in_s",
        "frequency_hz",
        "zeta",
    ]:
        assert column in segments.columns
    units = column_units(path)
    assert units["velocity_amplitude_in_s"] == "in/s"
    assert units["frequency_hz"] == "Hz"
    assert units["t_s"] == "s"
    assert units["response_amplitude"].startswith("g")
    assert set(segments["configuration"]) == {"no_washer", "small_washer"}
    # every used run contributes segments; damping and frequency are physical
    assert segments.groupby("run").size().min() >= 3
    assert segments["zeta"].between(1e-5, 0.05).all()
    assert segments["frequency_hz"].between(100, 150).all()


def test_bad_run_is_listed_with_file_and_line_and_others_complete(finished_run):
    campaign, workdir, _ = finished_run
    runs = pd.read_parquet(workdir / "results/tables/runs.parquet")
    assert len(runs) == 7  # every file found, read or not
    bad = runs[runs["run"] == "run04"].iloc[0]
    assert bad["status"] == "excluded"
    assert "no_washer/run04.txt" in bad["reason"]
    assert ":40:" in bad["reason"] and "1.2.3" in bad["reason"]
    used = runs[runs["status"] == "used"]
    assert len(used) == 6
    assert (used["reason"] == "").all()
    segments = pd.read_parquet(workdir / "results/tables/segments.parquet")
    assert set(zip(segments["configuration"], segments["run"])) == set(
        zip(used["configuration"], used["run"])
    )


def test_tables_do_not_depend_on_how_runs_are_grouped_into_jobs(finished_run, tmp_path):
    campaign, workdir, _ = finished_run
    tables = ["segments", "segments_rejected", "runs", "quality", "modes"]
    targets = [f"results/tables/{name}.parquet" for name in tables]
    result = snakemake(tmp_path, "-c2", *targets, "--config", f"campaign={campaign}", "runs_per_job=1")
    assert result.returncode == 0, result.stderr[-4000:]
    # a job per run: each configuration's first in its identify_mode job
    assert len(list((tmp_path / "results/benchmarks/analyse_runs").rglob("*.tsv"))) == 7 - 2
    for name in tables:
        pd.testing.assert_frame_equal(
            pd.read_parquet(tmp_path / f"results/tables/{name}.parquet"),
            pd.read_parquet(workdir / f"results/tables/{name}.parquet"),
        )


def test_raw_files_are_never_modified(finished_run):
    campaign, _, before = finished_run
    assert checksums(campaign) == before


def test_figures_and_fit_tables_exist(finished_run):
    _, workdir, _ = finished_run
    figures = workdir / "results/figures"
    for name in [
        "fig09_time_history.png",
        "fig10_damping_no_washer.png",
        "fig11_damping_small_washer.png",
        "fig13_area_fits.png",
        "backbone_no_washer.png",
        "backbone_small_washer.png",
    ]:
        assert (figures / name).stat().st_size > 10_000, name
    hypotheses = pd.read_parquet(workdir / "results/tables/hypotheses.parquet")
    assert set(hypotheses["verdict"]) <= {"supported", "contradicted", "inconclusive", "not applicable"}


def test_every_column_named_with_a_unit_carries_it(finished_run):
    # docs/outputs.md: where a column has a unit, the schema carries it
    _, workdir, _ = finished_run
    tables = sorted((workdir / "results/tables").glob("*.parquet"))
    assert len(tables) >= 8
    for path in tables:
        units = column_units(path)
        for name in pd.read_parquet(path).columns:
            if re.search(r"(_hz|_s|_in2|_std)$", name) or name.startswith("zeta"):
                assert name in units, (path.name, name)


def test_nothing_to_do_after_a_complete_run(finished_run):
    campaign, workdir, _ = finished_run
    result = snakemake(workdir, "-n", "-c2", "measured", "--config", f"campaign={campaign}", GROUPED)
    assert result.returncode == 0, result.stderr[-2000:]
    assert "Nothing to be done" in result.stdout + result.stderr


def test_units_switch_redraws_and_reanalyses_nothing(finished_run):
    campaign, workdir, _ = finished_run
    result = snakemake(
        workdir, "-n", "-c2", "measured", "--config", f"campaign={campaign}", GROUPED, "units=si"
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert set(job_counts(result.stdout)) == {"figures_measured", "measured", "total"}


def test_segment_length_change_reruns_only_what_depends_on_it(finished_run):
    campaign, workdir, _ = finished_run
    result = snakemake(
        workdir,
        "-n",
        "-c2",
        "measured",
        "--config",
        f"campaign={campaign}",
        GROUPED,
        "analysis={segment_cycles: 8}",
    )
    assert result.returncode == 0, result.stderr[-2000:]
    counts = job_counts(result.stdout)
    # 4 + 3 runs, two per job; each configuration's first two with its mode search, which
    # runs again (for those runs: it reads them) but finds the same modes
    assert counts["analyse_runs"] == 2 and counts["identify_mode"] == 2
    assert "collect_tables" in counts and "fit_curves" in counts
    # figures 9-13 and the backbones of every configuration in one job
    assert counts["figures_measured"] == 1


def test_config_typo_stops_with_the_key_named(tmp_path):
    result = snakemake(tmp_path, "-n", "all", "--config", "analysis={segment_cylces: 8}")
    assert result.returncode != 0
    output = result.stdout + result.stderr
    assert "command line (--config): analysis.segment_cylces: unknown key" in output
    assert "valid keys here: filter_order" in output and "segment_cycles" in output


def test_missing_campaign_folder_is_said_as_such(tmp_path):
    result = snakemake(tmp_path, "-n", "all", "--config", f"campaign={tmp_path / 'no_such_campaign'}")
    assert result.returncode != 0
    assert f"campaign folder {tmp_path / 'no_such_campaign'} does not exist" in result.stdout + result.stderr


def test_demo_campaign_dry_run_plans_the_whole_study(tmp_path):
    result = snakemake(tmp_path, "-n", "-c2", "all")
    assert result.returncode == 0, result.stderr[-2000:]
    counts = job_counts(result.stdout)
    assert counts["demo_campaign"] == 1
    # 3 configurations x 10 runs, 10 per job: each configuration's runs read once, in the
    # job that finds its modes
    assert counts["identify_mode"] == 3 and "analyse_runs" not in counts
    assert counts["figures_measured"] == 1
    assert counts["report_summary"] == 1  # the report pages and the summary close `all`


def test_runs_table_is_also_a_csv_file(finished_run):
    _, workdir, _ = finished_run
    runs = pd.read_parquet(workdir / "results/tables/runs.parquet")
    as_csv = pd.read_csv(workdir / "results/tables/runs.csv", keep_default_na=False)
    pd.testing.assert_frame_equal(as_csv, runs.astype(str), check_dtype=False)
    assert "excluded" in set(as_csv["status"])


def test_quality_table_has_every_check_of_every_run_and_agrees_with_runs(finished_run):
    _, workdir, _ = finished_run
    quality = pd.read_parquet(workdir / "results/tables/quality.parquet")
    runs = pd.read_parquet(workdir / "results/tables/runs.parquet")
    assert set(zip(quality["configuration"], quality["run"])) == set(zip(runs["configuration"], runs["run"]))
    bad = quality[quality["run"] == "run04"]
    assert list(bad["check"]) == ["read"] and not bad["passed"].iloc[0]
    used = quality[quality["run"] != "run04"]
    # a used run passed every check that applied to it, read and decay checks alike
    assert used.loc[used["applied"], "passed"].all()
    assert {"clipping", "snr", "segments"} <= set(used["check"])
    snr = used[used["check"] == "snr"]
    assert (snr["value"] > snr["threshold"]).all()


SI_TABLES = {
    "segments": ["velocity_amplitude_in_s", "bearing_area_in2"],
    "segments_rejected": ["velocity_amplitude_in_s"],
    "modes": ["bearing_area_in2"],
    "damping_fits": ["bearing_area_in2", "amplitude_low_in_s", "amplitude_high_in_s"],
    "damping_curves": ["velocity_amplitude_in_s", "bearing_area_in2"],
    "area_fits": ["velocity_amplitude_in_s", "bearing_area_in2"],
    "hypotheses": ["amplitude_low_in_s", "amplitude_high_in_s"],
}
"""Table -> its inch-second columns that have an SI twin beside them."""


def _all_text(figure) -> str:
    """Every label, title, tick label, legend entry and note of a figure."""
    return " ".join(text.get_text() for text in figure.findobj(matplotlib.text.Text))


def test_si_units_add_si_columns_and_si_figures_beside_an_unchanged_default(finished_run, tmp_path):
    campaign, default_workdir, _ = finished_run
    result = snakemake(tmp_path, "-c2", "measured", "--config", f"campaign={campaign}", GROUPED, "units=si")
    assert result.returncode == 0, result.stderr[-4000:]
    tables = {}
    for table, columns in SI_TABLES.items():
        path = tmp_path / f"results/tables/{table}.parquet"
        si, default = (
            pd.read_parquet(path),
            pd.read_parquet(default_workdir / f"results/tables/{table}.parquet"),
        )
        twins = {column: SI_TWIN_COLUMNS[column] for column in columns}
        for column, (twin, unit, factor) in twins.items():
            # the same multiplication as the table's: equal to the last bit
            np.testing.assert_array_equal(si[twin].to_numpy(float), si[column].to_numpy(float) * factor)
            assert column_units(path)[twin] == unit, (table, twin)
            assert list(si.columns).index(twin) == list(si.columns).index(column) + 1
        # units are how results are shown: the default run's tables are the same, twins included
        pd.testing.assert_frame_equal(si, default)
        tables[table] = si
    assert tables["segments"]["velocity_amplitude_m_s"].notna().all()

    # the rules draw in SI: the PNGs differ from the default run's, and nothing is hard to read
    for name in (
        "fig09_time_history.png",
        "fig10_damping_no_washer.png",
        "fig13_area_fits.png",
        "backbone_no_washer.png",
    ):
        si_png = (tmp_path / "results/figures" / name).read_bytes()
        assert si_png != (default_workdir / "results/figures" / name).read_bytes(), name
    assert "hard to read" not in (tmp_path / "results/logs/figures_measured.log").read_text()

    # the figure code path on the SI run's tables: SI on every axis, label and note
    segments = tables["segments"]
    mine = segments[segments["configuration"] == "no_washer"]
    curves = tables["damping_curves"]
    drawn = {
        "damping": figures.damping_vs_amplitude(
            mine, title="t", curve=curves[curves["configuration"] == "no_washer"], units=SI
        ),
        "backbone": figures.frequency_vs_amplitude(mine, title="t", units=SI),
        "area": figures.area_fits(curves, tables["area_fits"], title="t", units=SI),
        "loops": figures.friction_loops(
            [(0.5, np.array([-0.5, 0.5]), np.array([-2.0, 2.0]))], title="t", units=SI
        ),
    }
    assert drawn["damping"].axes[0].get_xlabel() == "velocity amplitude (m/s)"
    assert drawn["backbone"].axes[0].get_xlabel() == "velocity amplitude (m/s)"
    first_run = mine[mine["run"] == mine["run"].iloc[0]]
    np.testing.assert_array_equal(
        drawn["damping"].axes[0].lines[0].get_xdata(), first_run["velocity_amplitude_m_s"].to_numpy(float)
    )
    left, right = drawn["area"].axes[:2]
    assert left.get_xlabel() == "velocity amplitude (m/s)" and right.get_xlabel() == "bearing area (m²)"
    loop_axis = drawn["loops"].axes[0]
    assert (
        loop_axis.get_xlabel() == "relative displacement (m)"
        and loop_axis.get_ylabel() == "friction force (N)"
    )
    np.testing.assert_array_equal(loop_axis.lines[0].get_ydata(), np.array([-2.0, 2.0]) * SI.per_lbf)
    for name, figure in drawn.items():
        text = _all_text(figure)
        assert "in/s" not in text and "in²" not in text and "lbf" not in text, name
        assert readability_problems(figure) == [], name

"""workflow.api: one record's table against analytic truth and against the workflow's own
segments for that record; a campaign's results as objects."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import CHEAP

import workflow
from workflow.api import load_results, ring_down_table, run_campaign
from workflow.io.campaign import load_campaign
from workflow.io.run_files import read_run
from workflow.io.units import STANDARD_GRAVITY_IN_S2
from workflow.lab.campaigns import generate_campaign


def _decay(zeta: float, f_hz: float, amplitude_g: float, fs_hz: float = 4000.0, seconds: float = 3.0):
    t_s = np.arange(int(seconds * fs_hz)) / fs_hz
    omega = 2 * np.pi * f_hz
    response = amplitude_g * np.exp(-zeta * omega * t_s) * np.sin(omega * np.sqrt(1 - zeta**2) * t_s)
    return t_s, response + 1e-7 * np.random.default_rng(1).standard_normal(t_s.size), fs_hz


def test_linear_decay_gives_its_damping_frequency_and_velocity_amplitude():
    zeta, f_hz, amplitude_g = 0.004, 80.0, 3.0
    _, response, fs_hz = _decay(zeta, f_hz, amplitude_g)
    table = ring_down_table(response, fs_hz, quantity="acceleration", unit="g")
    assert len(table) >= 10 and table["kept"].all()
    # a linear decay: every segment's damping and frequency are the record's (the chain's
    # own bias is below 1 % of zeta, docs/decay_analysis.md)
    np.testing.assert_allclose(table["zeta"], zeta, rtol=0.01)
    np.testing.assert_allclose(table["frequency_hz"], f_hz * np.sqrt(1 - zeta**2), rtol=1e-4)
    # velocity amplitude = acceleration amplitude / omega, at each segment's centre
    omega = 2 * np.pi * f_hz
    expected = amplitude_g * STANDARD_GRAVITY_IN_S2 * np.exp(-zeta * omega * table["t_s"]) / omega
    np.testing.assert_allclose(table["velocity_amplitude_in_s"], expected, rtol=0.01)
    np.testing.assert_allclose(table["velocity_amplitude_m_s"], 0.0254 * table["velocity_amplitude_in_s"])
    assert table.attrs["band_hz"][0] < f_hz < table.attrs["band_hz"][1]


def test_bad_input_is_said():
    with pytest.raises(ValueError, match="finite 1-D"):
        ring_down_table(np.ones((2, 3)), 1000.0)
    _, response, fs_hz = _decay(0.004, 80.0, 3.0)
    with pytest.raises(ValueError, match="not a unit of acceleration"):
        ring_down_table(response, fs_hz, unit="furlong")


def test_package_reexports_the_api_lazily():
    assert workflow.ring_down_table is ring_down_table and workflow.load_results is load_results


def test_campaign_results_as_objects_match_the_record_table(tmp_path):
    campaign = tmp_path / "campaign"
    generate_campaign(campaign, seed=11, runs_per_configuration=3, configurations={"a": 1.36, "b": 0.17})
    config = dict(entry.split("=", 1) for entry in CHEAP)
    results = run_campaign(campaign, tmp_path / "work", config=config)
    assert set(results.causes) == {"a", "b"} and results.cause == results.diagnosis["cause"]
    assert results.discrepancy("a") == results.diagnosis["configurations"]["a"]["discrepancy"]
    assert {"segments", "runs", "damping_fits", "hypotheses"} <= set(results.tables)
    # one run through the API gives the workflow's segments for it (same chain, same mode band)
    mode = results.tables["modes"].set_index("configuration").loc["a"]
    run = results.runs[(results.runs["configuration"] == "a") & (results.runs["status"] == "used")].iloc[0]
    record = read_run(campaign, run["path"], load_campaign(campaign))
    table = ring_down_table(
        record.response,
        record.sample_rate_hz,
        quantity=record.response_quantity,
        unit=record.response_unit,
        mode_hz=float(mode["mode_hz"]),
        band_hz=(float(mode["band_low_hz"]), float(mode["band_high_hz"])),
    )
    mine = results.segments[
        (results.segments["configuration"] == "a") & (results.segments["run"] == run["run"])
    ]
    assert abs(len(table) - len(mine)) <= 1
    np.testing.assert_allclose(np.median(table["zeta"]), np.median(mine["zeta"]), rtol=0.02)
    assert load_results(tmp_path / "work").cause == results.cause


def test_missing_results_are_said(tmp_path):
    with pytest.raises(FileNotFoundError, match="run the workflow first"):
        load_results(tmp_path)


def test_the_documented_example_runs():
    import doctest

    from helpers import REPO

    failures, tried = doctest.testfile(str(REPO / "docs/python-api.md"), module_relative=False)
    assert tried >= 5 and failures == 0

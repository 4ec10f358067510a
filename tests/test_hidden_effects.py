"""Hidden effects: the virtual lab hides a cause, the measured-data chain and the
discovery must name it.

The cases (effect, size and bearing-area ranges, and the measured chain) are in
:mod:`workflow.lab.hidden_effects` (``LAPJOINT_HIDDEN_SEED`` overrides the base seed).
``bench/hit_rate.py`` runs the same cases over many seeds.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from tests.support.discovery import diagnose_with_details
from workflow.discovery.campaign import diagnose_campaign
from workflow.lab.hidden_effects import CASES, campaign_segments, generate_case


def run_case(cause: str, seed: int, work_dir: Path) -> tuple[dict, dict]:
    """Generate, analyse and diagnose one hidden-effect campaign; (drawn case, diagnosis)."""
    case, out = generate_case(cause, seed, work_dir)
    segments = campaign_segments(out)
    return case, diagnose_campaign(segments, out.name)


BASE_SEED = int(os.environ.get("LAPJOINT_HIDDEN_SEED", "20240"))


@pytest.mark.parametrize("cause", list(CASES))
def test_hidden_effect_is_named(cause, tmp_path):
    case, document = run_case(cause, BASE_SEED, tmp_path)
    assert document["cause"] == cause, (case, document["configurations"])
    configuration = document["configurations"]["joint"]
    assert configuration["cause"] == cause
    gain = configuration["gain"]
    if cause == "none":
        assert gain["ratio"] == 1.0
        assert configuration["extended_model"]["model"] == configuration["baseline"]["model"]
    elif cause != "unknown":
        assert gain["ratio"] < 0.7, gain
    causes = [row["cause"] for row in configuration["ranking"]]
    assert set(causes) == {
        "none",
        "microslip_power_law",
        "quadratic_damping",
        "stiffness_nonlinearity",
        "run_drift",
    }
    scores = [row["score"] for row in configuration["ranking"]]
    assert scores == sorted(scores)


SENSOR_GAIN = 0.7
"""Mode-1 amplitude of the second sensor relative to the accelerometer's: its records are
3 dB lower against the same noise floor. Much lower and an effect that sits a few
scatters above the noise at the first sensor may fall into the second one's noise (at
0.4, 8 dB, the base seed's quadratic damping is still named, but with confidence 0.87
against the accelerometer's 1.00 and a gain ratio of 0.44 against 0.16): a detection
limit, not a contradiction (docs/discovery.md)."""


@pytest.mark.parametrize("cause", list(CASES))
def test_two_sensors_on_one_hidden_effect_give_one_verdict(cause, tmp_path):
    """The same ring-downs recorded by a second sensor (amplitudes scaled by the mode
    shape, its own noise), through the whole measured chain: the same cause, and each
    sensor's gain ratio inside the 5-95 % range of the other's 100 resampled ratios,
    widened by 0.05 (the Monte Carlo error of those quantiles is a few hundredths)."""
    verdicts = []
    for noise_stream, gain in enumerate((1.0, SENSOR_GAIN)):
        _, out = generate_case(cause, BASE_SEED, tmp_path, sensor_gain=gain, noise_stream=noise_stream)
        document, details = diagnose_with_details(campaign_segments(out), out.name)
        ratios = [r["ratio"] for r in details["joint"].resamples]
        verdicts.append((document["configurations"]["joint"], np.quantile(ratios, [0.05, 0.95])))
    (a, band_a), (b, band_b) = verdicts
    assert a["cause"] == b["cause"] == cause, (a["confidence"], b["confidence"])
    margin = 0.05
    assert band_a[0] - margin <= b["gain"]["ratio"] <= band_a[1] + margin, (a["gain"], b["gain"], band_a)
    assert band_b[0] - margin <= a["gain"]["ratio"] <= band_b[1] + margin, (a["gain"], b["gain"], band_b)

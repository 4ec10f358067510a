"""Hidden effects: the virtual lab hides a cause, the measured-data chain and the
discovery must name it.

The cases (effect, size and bearing-area ranges, and the measured chain) are in
:mod:`workflow.lab.hidden_effects` (``LAPJOINT_HIDDEN_SEED`` overrides the base seed).
``bench/hit_rate.py`` runs the same cases over many seeds.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from workflow.discovery.diagnosis import diagnose_campaign
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

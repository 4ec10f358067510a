"""Hidden effects: the virtual lab hides a cause, the measured-data chain and the
discovery must name it (cases in :mod:`workflow.studies.hidden_effects`; one seed per
cause, ``LAPJOINT_HIDDEN_SEED`` overrides it; ``bench/hit_rate.py`` runs many).
"""

from __future__ import annotations

import os

import pytest

from workflow.studies.hidden_effects import CASES, run_case

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

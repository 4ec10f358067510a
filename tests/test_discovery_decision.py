"""The decision rule's margins and corrections, pinned by literals with their evidence, and a
false-alarm test: joints without any hidden effect are named ``none``."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from test_discovery_synthetic import DAHL, FAST, synthetic_segments
from test_lab_hidden_effects import run_case

from workflow.discovery import decision
from workflow.discovery.campaign import diagnose_campaign
from workflow.discovery.decision import decide
from workflow.discovery.heldout import heldout_standard_error
from workflow.discovery.misfit import run_order_trend
from workflow.lab.hidden_effects import campaign_segments, draw_mode1_gain, generate_case
from workflow.models.configuration_data import ConfigurationData


def candidate(ratio: float, residual_significant: bool = False) -> dict:
    # held-out error as a fraction of the baseline's (1.0), and a BIC below its 10
    return {"heldout_error": ratio, "bic": 5.0, "residual_significant": residual_significant}


# On no-effect campaigns (the virtual lab's Dahl joint, seeds 1-13 of test_hidden_effects'
# cases) an eligible extension reaches 0.89-0.99 of the baseline's held-out error, from the
# averaged models' own bias; hidden effects are named with median gain ratios 0.04-0.34
# (README). The margin sits at 0.7 between them: a candidate needs a 30 % lower error.
@pytest.mark.parametrize(
    "ratio, cause",
    [(0.3, "quadratic_damping"), (0.69, "quadratic_damping"), (0.71, "none"), (0.8, "none"), (0.89, "none")],
)
def test_without_a_misfit_only_a_clear_held_out_gain_names_a_cause(ratio, cause):
    assert decide(1.0, 10.0, False, {"quadratic_damping": candidate(ratio)})[0] == cause


@pytest.mark.parametrize(
    "ratio, residual_significant, cause",
    [
        (0.89, False, "quadratic_damping"),  # the baseline fails, the candidate explains the data
        (0.69, True, "quadratic_damping"),  # removes most of the misfit (below 0.7 of it)
        (0.71, True, "unknown"),  # leaves a misfit and removes less
        (0.7, True, "unknown"),  # "below", not at
    ],
)
def test_with_a_baseline_misfit_the_candidate_must_remove_most_of_it(ratio, residual_significant, cause):
    assert decide(1.0, 10.0, True, {"quadratic_damping": candidate(ratio, residual_significant)})[0] == cause
    # the same at another scale of the errors: 1.2 against 2.0 is 0.6 of it
    leaves = {"heldout_error": 2.0 * ratio, "bic": 5.0, "residual_significant": residual_significant}
    assert decide(2.0, 10.0, True, {"quadratic_damping": leaves})[0] == cause


def test_a_cause_is_named_only_below_the_margin_not_at_it():
    # the held-out error must be below 0.7 of the baseline's, at any scale of the errors
    assert decide(1.0, 10.0, False, {"quadratic_damping": candidate(0.7)})[0] == "none"
    baseline = {"heldout_error": 1.2, "bic": 5.0, "residual_significant": False}
    assert decide(2.0, 10.0, False, {"quadratic_damping": baseline})[0] == "quadratic_damping"  # 0.6 of 2.0
    baseline["heldout_error"] = 1.5  # 0.75 of 2.0
    assert decide(2.0, 10.0, False, {"quadratic_damping": baseline})[0] == "none"


# What the verdict page and diagnosis.json say for each branch of the rule (evidence.decision_rule).
REASONS = {
    "envelope": "even at the runs' highest amplitudes the segment envelopes depart from exponential decays "
    "by more than ENVELOPE_DEPARTURE_LIMIT of their decay: a disturbance outside every single-mode model "
    "(e.g. a second mode beating in the band)",
    "none": "no significant misfit of the baseline and no candidate reduces the held-out error below 0.7 "
    "of the baseline's or removes more held-out misfit than the models' accuracy",
    "no_candidate": "the baseline misfit is significant but no candidate lowers the held-out error, pays for "
    "its parameters (BIC, or a run drift's held-out gain across runs or its removal of the run-order trend) "
    "and shows its cause's signature",
    "misfit_left": "the best eligible candidate (quadratic_damping) leaves a significant misfit and cuts the "
    "held-out error only to 0.75 of the baseline's",
    "named_misfit": "baseline misfit significant; quadratic_damping has the lowest held-out error among "
    "candidates that also pay for their parameters",
    "named_gain": "clear held-out gain; quadratic_damping has the lowest held-out error among candidates that "
    "also pay for their parameters",
}


def test_each_branch_of_the_rule_says_why():
    strong, weak = candidate(0.3), candidate(0.8)
    assert decide(1.0, 10.0, True, {"quadratic_damping": strong}, envelope_structure=True) == (
        "unknown",
        REASONS["envelope"],
    )
    assert decide(1.0, 10.0, False, {"quadratic_damping": weak}) == ("none", REASONS["none"])
    # the same small gain in a scatter many times the models' accuracy: more than it removes
    assert decide(1.0, 10.0, False, {"quadratic_damping": {**weak, "beyond_accuracy": True}}) == (
        "quadratic_damping",
        REASONS["named_gain"],
    )
    assert decide(1.0, 10.0, True, {"quadratic_damping": candidate(1.1)}) == (
        "unknown",
        REASONS["no_candidate"],
    )
    leaves = {"heldout_error": 1.5, "bic": 5.0, "residual_significant": True}
    assert decide(2.0, 10.0, True, {"quadratic_damping": leaves}) == ("unknown", REASONS["misfit_left"])
    assert decide(1.0, 10.0, True, {"quadratic_damping": weak}) == (
        "quadratic_damping",
        REASONS["named_misfit"],
    )
    assert decide(1.0, 10.0, False, {"quadratic_damping": strong}) == (
        "quadratic_damping",
        REASONS["named_gain"],
    )


@pytest.mark.parametrize(
    "heldout_error, bic, shows_signature",
    [
        (1.0, 5.0, True),  # no lower held-out error than the baseline's
        (1.2, 5.0, True),
        (0.5, 10.0, True),  # no lower BIC
        (0.5, 12.0, True),
        (0.5, 5.0, False),  # without its cause's signature
    ],
)
def test_a_candidate_must_lower_error_and_bic_and_show_its_signature(heldout_error, bic, shows_signature):
    entry = {"heldout_error": heldout_error, "bic": bic, "residual_significant": False}
    entry["shows_signature"] = shows_signature
    assert decide(1.0, 10.0, True, {"stiffness_nonlinearity": entry}) == ("unknown", REASONS["no_candidate"])


def test_candidates_predicting_equally_well_go_to_the_fewest_parameters():
    # Equal held-out errors: the lower BIC is taken, whichever comes first.
    rich = {"heldout_error": 0.5, "bic": 5.0, "residual_significant": False}
    lean = {"heldout_error": 0.5, "bic": 3.0, "residual_significant": False}
    assert (
        decide(1.0, 10.0, True, {"microslip_power_law": rich, "quadratic_damping": lean})[0]
        == "quadratic_damping"
    )
    assert (
        decide(1.0, 10.0, True, {"quadratic_damping": lean, "microslip_power_law": rich})[0]
        == "quadratic_damping"
    )
    # Squared errors within one standard error of the best's (the one-standard-error rule):
    # 0.52^2 - 0.5^2 = 0.0204, against a standard error of the runs' squares of 0.045.
    lean["heldout_error"] = 0.52
    candidates = {"microslip_power_law": rich, "quadratic_damping": lean}
    assert decide(1.0, 10.0, True, candidates)[0] == "microslip_power_law"  # no spread given: no tie
    squares_only = {"microslip_power_law": np.full(6, 0.25), "quadratic_damping": np.full(6, 0.27)}
    assert decide(1.0, 10.0, True, candidates, unit_squares=squares_only)[0] == "microslip_power_law"
    squares = np.array([0.15, 0.35, 0.15, 0.35, 0.15, 0.35])
    weights = np.ones(6)
    assert heldout_standard_error(squares, weights) == pytest.approx(
        0.1 / np.sqrt(6) * np.sqrt(6 / 5), rel=1e-12
    )
    spread = {"microslip_power_law": squares, "quadratic_damping": squares}
    chosen = decide(1.0, 10.0, True, candidates, unit_squares=spread, unit_weights=weights)[0]
    assert chosen == "quadratic_damping"
    # beyond it the better prediction wins
    lean["heldout_error"] = 0.55  # 0.0525 above
    assert (
        decide(1.0, 10.0, True, candidates, unit_squares=spread, unit_weights=weights)[0]
        == "microslip_power_law"
    )
    # the reach is measured from the best held-out error, whatever the candidates' names
    ahead = {"quadratic_damping": {**rich}, "microslip_power_law": {**lean, "bic": 3.0}}
    assert decide(1.0, 10.0, True, ahead, unit_squares=spread, unit_weights=weights)[0] == "quadratic_damping"


def test_a_run_drift_may_pay_for_its_parameter_by_its_gain_across_held_out_runs():
    # A lower held-out error without a lower BIC: a run drift that predicts held-out runs
    # better beyond their scatter is eligible, any other candidate is not.
    entry = {"heldout_error": 0.5, "bic": 11.0, "residual_significant": False, "gain_across_runs": True}
    assert decide(1.0, 10.0, True, {"run_drift": entry})[0] == "run_drift"
    assert decide(1.0, 10.0, True, {"quadratic_damping": entry}) == ("unknown", REASONS["no_candidate"])
    assert decide(1.0, 10.0, True, {"run_drift": {**entry, "gain_across_runs": False}})[0] == "unknown"
    # or by removing the baseline's significant run-order trend, its own test; a candidate
    # acting along the amplitudes cannot pay that way
    by_trend = {**entry, "gain_across_runs": False, "removes_run_trend": True}
    assert decide(1.0, 10.0, True, {"run_drift": by_trend})[0] == "run_drift"
    assert decide(1.0, 10.0, True, {"quadratic_damping": by_trend})[0] == "unknown"
    # the paired test: every run better by a factor that scatters little passes, a gain in
    # half the runs matched by a loss in the others does not
    weights = np.ones(8)
    critical = decision.paired_critical_value(8)
    better = np.full(8, 2.0) * np.exp(0.1 * np.sin(np.arange(8)))
    assert decision.heldout_gain_t(better, np.ones(8), weights) > critical
    mixed = np.array([2.0, 0.5] * 4)
    assert decision.heldout_gain_t(mixed, np.ones(8), weights) < critical


def test_a_run_drift_that_each_runs_offsets_absorb_in_sample_is_named(tmp_path):
    """A friction limit falling 32 % over eight runs seen by a sensor at x0.097 of the
    accelerometer (bench/hit_rate.py --random-placement, seed 728): each run's fitted
    offsets take up most of the drift in sample, so the drift's BIC is above the
    baseline's, while held out, each run calibrated on its stuck-joint segments, the drift
    predicts every run better (t = 2.9 over the runs against 2.36)."""
    _, out = generate_case("run_drift", 728, tmp_path, mode1_gain=draw_mode1_gain("run_drift", 728))
    configuration = diagnose_campaign(campaign_segments(out), out.name)["configurations"]["joint"]
    drift = configuration["evidence"]["candidates"]["run_drift"]
    assert drift["delta_bic"] > 0 and drift["gain_across_runs"], drift
    assert configuration["cause"] == "run_drift", configuration["evidence"]["candidates"]
    assert configuration["confidence"]["run_drift"] >= 0.9


def test_a_run_drift_that_removes_the_baselines_run_order_trend_is_named(tmp_path):
    """A friction limit falling 50 % over eight runs seen by a sensor at x0.107 (bench/
    hit_rate.py --random-placement, seed 2376): the baseline's run-order trend is
    significant (p = 6e-4 against 0.005) and the drift removes it, predicting held-out runs
    better (0.81 against 0.95 scatter units), but neither its BIC (+0.8) nor its paired
    gain over the runs (t = 1.9) pays for its parameter: without the trend's own test
    the verdict was ``unknown``, 0.99 sure."""
    _, out = generate_case("run_drift", 2376, tmp_path, mode1_gain=draw_mode1_gain("run_drift", 2376))
    configuration = diagnose_campaign(campaign_segments(out), out.name)["configurations"]["joint"]
    evidence = configuration["evidence"]
    drift = evidence["candidates"]["run_drift"]
    assert evidence["run_order_trend"]["significant"], evidence["run_order_trend"]
    assert drift["delta_bic"] > 0 and not drift["gain_across_runs"] and drift["removes_run_trend"], drift
    assert configuration["cause"] == "run_drift", evidence["candidates"]
    assert configuration["confidence"]["run_drift"] >= 0.9


def trend_data(slope_per_run: float) -> tuple[ConfigurationData, dict]:
    """Eight runs whose damping curves shift by ``slope_per_run`` in ln zeta per run, plus
    fixed run-to-run offsets; the same residual at every amplitude of a run."""
    n_runs = 8
    offsets = np.array([0.03, -0.04, 0.02, -0.01, 0.04, -0.03, 0.0, 0.01])
    v = np.tile(np.geomspace(0.1, 3, 30), n_runs)
    run = np.repeat(np.arange(n_runs), 30)
    data = ConfigurationData(
        "c", v, np.full(v.size, 1e-3), np.full(v.size, 100.0), run, [f"r{i}" for i in range(n_runs)], None
    )
    shift = slope_per_run * np.arange(n_runs) + offsets
    return data, {"ln_zeta": shift[run], "rel_f": np.zeros(v.size)}


def test_run_order_trend_is_bonferroni_corrected():
    # A trend whose two-sided p is 0.0075 (an ordinary regression of the runs' shifts on
    # run order, computed here independently) and whose change over the sequence (0.13 in
    # ln zeta) is far above the models' 2 % accuracy: significant at the familywise 1 %
    # alone, but not at its Bonferroni share p < 0.01 / 2 = 0.005.
    data, residuals = trend_data(0.019)
    regression = stats.linregress(np.arange(8.0), residuals["ln_zeta"][::30])  # one value per run
    alone = run_order_trend(data, residuals, n_tests=1)
    corrected = run_order_trend(data, residuals, n_tests=2)
    assert alone["p"] == pytest.approx(regression.pvalue, rel=1e-9)
    assert 0.005 < alone["p"] < 0.01
    assert alone["change_over_sequence"] == pytest.approx(7 * regression.slope, rel=1e-9)
    assert alone["significant"] and not corrected["significant"]
    # a steeper trend (p = 0.0047) passes the corrected limit
    assert run_order_trend(*trend_data(0.021), n_tests=2)["significant"]


def test_the_diagnosis_tests_run_order_at_half_the_familywise_one_percent(monkeypatch):
    # The familywise 1 % is split in two halves: the amplitude bins share one, the run-order
    # test has the other (docs/discovery.md): p < 0.005, i.e. the default alpha 0.01 over 2.
    calls = []

    def recorded(*args, **kwargs):
        calls.append(kwargs)
        return run_order_trend(*args, **kwargs)

    monkeypatch.setattr(decision, "run_order_trend", recorded)
    diagnose_campaign(synthetic_segments("dahl", DAHL, seed=1), "synthetic", settings=FAST)
    assert calls
    assert {call["n_tests"] for call in calls} == {2}
    assert all("alpha" not in call for call in calls)
    assert run_order_trend.__kwdefaults__["alpha"] == 0.01


# The first twelve seeds, not chosen: seed 11's run-drift extension reaches 0.89 of the
# baseline's error with a lower BIC, the closest any came to the margin.
@pytest.mark.parametrize("seed", range(1, 13))
def test_joints_without_a_hidden_effect_are_named_none(seed, tmp_path):
    case, document = run_case("none", seed, tmp_path)
    configuration = document["configurations"]["joint"]
    assert document["cause"] == configuration["cause"] == "none", (
        case,
        configuration["evidence"]["candidates"],
    )
    assert configuration["gain"]["ratio"] == 1.0

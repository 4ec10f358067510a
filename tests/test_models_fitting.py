"""Tests of friction-model fitting (workflow.models.fitting)."""

import numpy as np
import pandas as pd
import pytest

from workflow.measured.decay import analyse_decay
from workflow.measured.settings import AnalysisSettings
from workflow.models.fitting import (
    RingdownFitContext,
    fit_friction_model,
    measurement_scatter,
    model_space,
    simulated_curves,
    simulation_rate_hz,
)
from workflow.models.paper import MIN_SEGMENTS_TO_FIT, configuration_models_document
from workflow.models.ringdown import simulate_ringdown
from workflow.models.settings import ModelSettings

FS, T, BAND = 2560.0, 3.2, (100.0, 150.0)


def synthetic_campaign(seed=1, runs=10):
    """Dahl campaign: ring-downs -> measurement chain -> run-to-run and segment scatter."""
    rng = np.random.default_rng(seed)
    w0 = 2 * np.pi * 125.0
    r, knee, zeta0 = 0.05, 1.0, 0.002
    sigma = r * w0**2
    truth = {"sigma": sigma, "fc": sigma * knee / w0, "omega_rad_s": w0 * np.sqrt(1 - r)}
    truth["zeta0"] = zeta0 * w0 / truth["omega_rad_s"]
    starts = rng.uniform(3.0, 10.0, runs)
    sim = simulate_ringdown(
        "dahl",
        {"sigma": truth["sigma"], "fc": truth["fc"]},
        omega_rad_s=truth["omega_rad_s"],
        zeta0=truth["zeta0"],
        initial_velocity=starts,
        fs_out_hz=FS,
        duration_s=T,
    )
    v, z, f, run, peak = [], [], [], [], []
    for i, x in enumerate(sim["acceleration"]):
        x = x + rng.normal(0.0, 1e-3 * np.abs(x).max(), x.size)  # sensor noise, -60 dB
        kept = analyse_decay(x, FS, BAND, mode_hz=125.0).kept
        fr = kept["frequency_hz"]
        v.append(kept["amplitude"] / (2 * np.pi * fr))
        # 3 % run-to-run and 3 % segment scatter of damping, 2e-4 of frequency per run.
        z.append(kept["zeta"] * np.exp(rng.normal(0, 0.03) + rng.normal(0, 0.03, fr.size)))
        f.append(fr * (1 + rng.normal(0, 2e-4)))
        run += [f"run{i}"] * fr.size
        peak.append(np.abs(x).max() / (2 * np.pi * 125.0))
    return truth, [np.concatenate(a) for a in (v, z, f)] + [np.array(run), np.array(peak)]


@pytest.fixture(scope="module")
def dahl_fit():
    truth, (v, z, f, run, peak) = synthetic_campaign()
    ctx = RingdownFitContext(fs_hz=FS, band_hz=BAND, record_duration_s=T)
    fit = fit_friction_model(
        "dahl", v, z, f, run, peak, ctx, global_samples=64, local_starts=2, max_iterations=20
    )
    return truth, fit, (v, z, f)


def test_dahl_fit_recovers_parameters_within_uncertainty(dahl_fit):
    truth, fit, _ = dahl_fit
    for key in ("sigma", "fc", "zeta0", "omega_rad_s"):
        err = abs(fit.params[key] - truth[key])
        assert err < 3.0 * fit.uncertainties[key], (key, fit.params[key], truth[key])
        # and the uncertainty itself is informative (a few % at most for this campaign)
        assert fit.uncertainties[key] < 0.1 * abs(truth[key])


def test_dahl_fit_residuals_match_injected_scatter(dahl_fit):
    from scipy.stats import chi2

    _, fit, (v, z, f) = dahl_fit
    measured = z > 0  # the fit's segments
    v, z, f = v[measured], z[measured], f[measured]
    np.testing.assert_array_equal(fit.predicted["velocity_amplitude_in_s"], v)
    # In the top fifth of amplitudes the -60 dB sensor noise adds little to the injected
    # scatter: 3 % per run and 3 % per segment in damping (4.2 % rms), 2e-4 per run in
    # frequency. The run part comes from 10 draws, the segment part from about 80: the
    # residuals' rms lies within the 0.1-99.9 % range of those chi-square samples (0.025 to
    # 0.064 in ln zeta, 0.77e-4 to 3.4e-4 in frequency; 0.048 and 1.8e-4 achieved).
    top = v >= np.quantile(v, 0.8)
    n_runs, n_segments = 10, int(top.sum())

    def rms_range(run_sd, segment_sd):
        return [
            np.sqrt(
                run_sd**2 * chi2.ppf(q, n_runs) / n_runs
                + segment_sd**2 * chi2.ppf(q, n_segments) / n_segments
            )
            for q in (0.001, 0.999)
        ]

    low, high = rms_range(0.03, 0.03)
    assert low < np.sqrt(np.mean(np.log(z[top] / fit.predicted["zeta"][top]) ** 2)) < high
    low, high = rms_range(2e-4, 0.0)
    assert low < np.sqrt(np.mean(((f[top] - fit.predicted["frequency_hz"][top]) / f[top]) ** 2)) < high
    assert fit.rms_rel_frequency < 2e-3
    c = fit.curves
    assert np.all(np.diff(c["velocity_amplitude_in_s"]) > 0)
    assert fit.predicted["zeta"].shape == fit.predicted["velocity_amplitude_in_s"].shape


def test_measurement_scatter_recovers_noise_level():
    rng = np.random.default_rng(3)
    v = 10 ** rng.uniform(-2, 1, 800)
    trend = 0.004 * v / (1 + v)
    z = trend * np.exp(rng.normal(0, 0.05, v.size))
    f = 125.0 * (1 - 1e-3 * np.log(v) ** 2) * (1 + rng.normal(0, 1e-4, v.size))
    s_z, s_f = measurement_scatter(v, z, f)
    # 100 points per bin: the rms estimate is good to ~1/sqrt(200) = 7 %; allow 25 %.
    np.testing.assert_allclose(s_z, 0.05, rtol=0.25)
    np.testing.assert_allclose(s_f, 1e-4, rtol=0.25)


def test_lugre_space_maps_to_valid_parameters():
    v = np.array([0.01, 0.1, 1.0, 10.0])
    z = np.array([0.001, 0.003, 0.008, 0.01])
    f = np.array([125.0, 124.8, 124.0, 123.5])
    ctx = RingdownFitContext(fs_hz=FS, band_hz=BAND, record_duration_s=T)
    space = model_space("lugre", v, z, f, ctx)
    rng = np.random.default_rng(0)
    theta = space.lower + rng.random((50, space.lower.size)) * (space.upper - space.lower)
    p = space.to_physical(theta)
    for key in ("sigma0", "alpha0", "v0", "vd", "omega_rad_s", "zeta0"):
        assert np.all(p[key] > 0), key
    assert np.all(p["alpha0"] + p["alpha1"] > 0)
    # the stuck-joint frequency is the first search coordinate
    f0 = np.sqrt(p["omega_rad_s"] ** 2 + p["sigma0"]) / (2 * np.pi)
    np.testing.assert_allclose(f0, theta[:, 0], rtol=1e-12)


# The demo's fitted Dahl and LuGre (no_washer, large_washer), modal units, sensor
# displacement 11.08 in per unit modal coordinate; band of the demo's 125 Hz mode.
DEMO_FITS = [
    ("dahl", {"sigma": 2891.17, "fc": 0.5225, "zeta0": 1.169e-3, "omega_rad_s": 791.065}),
    ("dahl", {"sigma": 2589.84, "fc": 3.5223, "zeta0": 7.48e-4, "omega_rad_s": 773.497}),
    (
        "lugre",
        {
            "sigma0": 6059.11,
            "alpha0": 0.98016,
            "alpha1": 0.48431,
            "v0": 3.37e-4,
            "vd": 0.061472,
            "sigma1": 1.23107,
            "alpha2": 0.031528,
            "zeta0": 2.65e-4,
            "omega_rad_s": 789.282,
        },
    ),
    (
        "lugre",
        {
            "sigma0": 6901.54,
            "alpha0": 4.13763,
            "alpha1": 12.4073,
            "v0": 0.133113,
            "vd": 0.15711,
            "sigma1": 0.733796,
            "alpha2": 0.0,
            "zeta0": 2.95e-4,
            "omega_rad_s": 770.731,
        },
    ),
]


def test_simulation_rate_keeps_the_band_resolved_and_the_demos_rate():
    assert simulation_rate_hz(2560.0, (100.7, 151.0)) == 2560.0  # the demo: unchanged
    assert simulation_rate_hz(12800.0, (100.7, 151.0)) == 2560.0
    assert simulation_rate_hz(51200.0, (121.0, 181.0)) == pytest.approx(51200.0 / 17)
    assert simulation_rate_hz(1024.0, (15.0, 22.4)) == 1024.0 / 2
    for fs, band in ((12800.0, (100.7, 151.0)), (51200.0, (121.0, 181.0)), (3000.0, (400.0, 600.0))):
        assert simulation_rate_hz(fs, band) >= min(fs, 16 * band[1])  # never above the record's


@pytest.mark.parametrize(("model", "params"), DEMO_FITS)
def test_curves_simulated_at_the_reduced_rate_match_the_full_rate(model, params):
    """A 12.8 kHz, 5 s record's fit simulates at 2560 Hz: its curves stay within half the
    averaged models' accuracy in ln zeta (0.01 of 0.02) and a tenth of it in relative
    frequency (1e-5 of 1e-4); measured differences are 1e-4 and 3e-6 at most."""
    band = (100.7, 151.0)
    phys = {key: np.array([value]) for key, value in params.items()}
    curves = {}
    for fs in (12800.0, simulation_rate_hz(12800.0, band)):
        ctx = RingdownFitContext(fs_hz=fs, band_hz=band, record_duration_s=5.0, response_per_modal=11.08)
        curves[fs] = simulated_curves(model, phys, ctx, start_velocity_in_s=8.0, duration_s=5.0)[0]
    full, reduced = curves[12800.0], curves[2560.0]
    v = np.geomspace(0.05, 5.0, 60)
    v = v[
        (v > 1.05 * full["velocity_amplitude_in_s"].min())
        & (v < full["velocity_amplitude_in_s"].max() / 1.05)
    ]
    assert v.size > 30

    def at(curve, key):
        return np.interp(np.log(v), np.log(curve["velocity_amplitude_in_s"]), curve[key])

    d_ln_zeta = np.log(at(reduced, "zeta") / at(full, "zeta"))
    d_rel_f = at(reduced, "frequency_hz") / at(full, "frequency_hz") - 1
    assert np.max(np.abs(d_ln_zeta)) < 0.01
    assert np.max(np.abs(d_rel_f)) < 1e-5


@pytest.mark.parametrize("model", ["dahl", "lugre"])
def test_a_simulated_ring_down_does_not_depend_on_its_batch(model):
    """The fit simulates a Levenberg-Marquardt step's Jacobian apart from its trials
    (only the accepted trial's): that gives the fit of one batched call to the bit
    because each ring-down of a batch is simulated and analysed on its own."""
    sets = [params for name, params in DEMO_FITS if name == model]
    batch = {key: np.array([params[key] for params in sets] * 2) for key in sets[0]}
    batch["zeta0"] = batch["zeta0"] * np.repeat([1.0, 1.5], len(sets))  # four different sets
    ctx = RingdownFitContext(fs_hz=FS, band_hz=(100.7, 151.0), record_duration_s=T, response_per_modal=11.08)
    together = simulated_curves(model, batch, ctx, start_velocity_in_s=8.0, duration_s=T)
    for index, curve in enumerate(together):
        alone = {key: value[index : index + 1] for key, value in batch.items()}
        (single,) = simulated_curves(model, alone, ctx, start_velocity_in_s=8.0, duration_s=T)
        for key in curve:
            assert np.array_equal(curve[key], single[key]), (index, key)
    # and so is the map from search coordinates to the parameters simulated
    v, z, f = np.array([0.05, 0.5, 2.0, 5.0]), np.array([0.001, 0.003, 0.008, 0.01]), np.full(4, 124.0)
    space = model_space(model, v, z, f, ctx)
    theta = space.lower + np.random.default_rng(3).random((7, space.lower.size)) * (space.upper - space.lower)
    mapped = space.to_physical(theta)
    for index in range(theta.shape[0]):
        for key, value in space.to_physical(theta[index : index + 1]).items():
            assert value[0] == mapped[key][index], (index, key)


def test_a_configuration_with_too_few_segments_gets_no_models_and_the_reason():
    segments = pd.DataFrame(
        {
            "configuration": ["few"] * (MIN_SEGMENTS_TO_FIT - 1) + ["many"] * 20,
            "run": "run01",
            "velocity_amplitude_in_s": 1.0,
            "zeta": 0.01,
            "frequency_hz": 125.0,
        }
    )
    document = configuration_models_document(
        segments,
        "few",
        pd.DataFrame(),  # not read: nothing is fitted
        {"few": None, "many": None},
        response_quantity="acceleration",
        analysis=AnalysisSettings(),
        settings=ModelSettings(),
        averaged_params=None,
    )
    assert document["models"] == {}
    assert f"only {MIN_SEGMENTS_TO_FIT - 1} usable segments" in document["skipped"]

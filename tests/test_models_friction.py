"""Tests of the paper's friction models (workflow.models.friction)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workflow.models import paper
from workflow.models.friction import (
    dahl_dissipation_per_cycle,
    dahl_z_rate,
    hysteresis_loop,
    loop_dissipation,
    lugre_force,
    lugre_z_rate,
)

PAPER_DAHL = {"sigma": 2133.4, "fc": 38.0}


def test_dahl_loop_saturates_at_coulomb_force():
    # sigma A / Fc = 2133.4 * 1 / 38 = 56: z reaches Fc/sigma within exp(-56) of a stroke.
    x, f = hysteresis_loop("dahl", PAPER_DAHL, 1.0, points_per_cycle=2000)
    assert np.max(f) == pytest.approx(38.0, rel=1e-9)
    assert np.min(f) == pytest.approx(-38.0, rel=1e-9)
    assert np.all(np.abs(f) <= 38.0 * (1 + 1e-12))


@pytest.mark.parametrize("amplitude_in", [1e-4, 1e-3, 0.02, 0.1, 1.0])
@pytest.mark.parametrize("sigma", [(2 * np.pi) ** 2, 2133.4])
def test_numerical_loop_energy_matches_closed_form(amplitude_in, sigma):
    # RK4 with the step refined against stiffness, spectral loop integral: measured
    # agreement ~1e-9; 1e-7 leaves margin while catching any error in the derivation.
    x, f = hysteresis_loop(
        "dahl", {"sigma": sigma, "fc": 38.0}, amplitude_in, cycles=1, points_per_cycle=2000
    )
    numeric = loop_dissipation(x, f, 2000)
    closed = dahl_dissipation_per_cycle(amplitude_in, sigma, 38.0)
    assert numeric == pytest.approx(closed, rel=1e-7)


def test_closed_form_limits():
    sigma, fc = 2133.4, 38.0
    small = 1e-7  # sigma A / Fc = 5.6e-6: cubic (micro-slip) limit to 1e-11
    assert dahl_dissipation_per_cycle(small, sigma, fc) == pytest.approx(
        4.0 / 3.0 * sigma**2 * small**3 / fc, rel=1e-9
    )
    large = 10.0  # tanh(561) = 1: Coulomb limit 4 Fc A less the elastic correction
    assert dahl_dissipation_per_cycle(large, sigma, fc) == pytest.approx(
        4 * fc * large - 4 * fc**2 / sigma, rel=1e-14
    )


def test_lugre_reduces_to_dahl():
    # g = Fc (alpha1 = 0, alpha0 = Fc), sigma1 = alpha2 = 0, sigma0 = sigma.
    lugre = {
        "sigma0": 2133.4,
        "sigma1": 0.0,
        "alpha0": 38.0,
        "alpha1": 0.0,
        "alpha2": 0.0,
        "v0": 1.0,
        "vd": 1.0,
    }
    z = np.linspace(-0.02, 0.02, 41)[:, None]
    v = np.linspace(-5, 5, 21)[None, :]
    np.testing.assert_allclose(
        lugre_z_rate(z, v, 2133.4, 38.0, 0.0, 1.0), dahl_z_rate(z, v, 2133.4, 38.0), rtol=1e-13, atol=1e-15
    )
    np.testing.assert_allclose(
        lugre_force(z, v, 2133.4, 0.0, 38.0, 0.0, 0.0, 1.0, 1.0), 2133.4 * z + 0 * v, rtol=1e-14
    )
    for amplitude in (0.005, 0.05):
        _, f_d = hysteresis_loop("dahl", PAPER_DAHL, amplitude, points_per_cycle=500)
        _, f_l = hysteresis_loop("lugre", lugre, amplitude, points_per_cycle=500)
        np.testing.assert_allclose(f_l, f_d, rtol=1e-12, atol=1e-12 * 38.0)


def test_lugre_paper_loop_is_dissipative_and_batched():
    # Fig. 8 parameters; alpha2 adds viscous loss, so the loop area exceeds Dahl's.
    p = {
        "sigma0": (2 * np.pi) ** 2,
        "sigma1": 0.008 * np.pi,
        "alpha0": 38.0,
        "alpha1": 19.0,
        "alpha2": 0.008 * np.pi,
        "v0": 1.0,
        "vd": 1.0,
    }
    x, f = hysteresis_loop("lugre", p, 2.0, cycles=4, points_per_cycle=1000)
    assert f.shape == x.shape
    e_lugre = loop_dissipation(x, f, 1000)
    assert e_lugre > dahl_dissipation_per_cycle(2.0, (2 * np.pi) ** 2, 38.0)
    batch = {**p, "alpha2": np.array([0.0, 0.008 * np.pi])}
    _, fb = hysteresis_loop("lugre", batch, 2.0, cycles=4, points_per_cycle=1000)
    assert fb.shape == (2, x.size)
    np.testing.assert_allclose(fb[1], f, rtol=1e-12, atol=1e-12)


def test_a_batch_of_amplitudes_is_each_loop_alone_bit_for_bit():
    # figures 7-8 integrate their five amplitudes as one batch: the same numbers as one
    # call per amplitude where the step is the same (here one step per output sample)
    amplitudes = (0.25, 0.5, 1.0, 2.0, 4.0)
    for model, params in (("dahl", paper.PAPER_DAHL), ("lugre", paper.PAPER_LUGRE)):
        x, f = hysteresis_loop(model, params, np.array(amplitudes), cycles=2, points_per_cycle=500)
        assert x.shape == f.shape == (len(amplitudes), 1001)
        for k, amplitude in enumerate(amplitudes):
            x_alone, f_alone = hysteresis_loop(model, params, amplitude, cycles=2, points_per_cycle=500)
            np.testing.assert_array_equal(x[k], x_alone)
            np.testing.assert_array_equal(f[k], f_alone)


@settings(max_examples=25, deadline=None)
@given(log_sigma=st.floats(0.0, 5.0), log_fc=st.floats(-1.0, 2.0), log_a=st.floats(-4.0, 0.0))
def test_dahl_loop_energy_nonnegative(log_sigma, log_fc, log_a):
    sigma, fc, a = 10.0**log_sigma, 10.0**log_fc, 10.0**log_a
    x, f = hysteresis_loop("dahl", {"sigma": sigma, "fc": fc}, a, cycles=1, points_per_cycle=400)
    # A passive loop dissipates; allow round-off relative to the work scale Fc * A.
    assert loop_dissipation(x, f, 400) >= -1e-9 * fc * a
    assert dahl_dissipation_per_cycle(a, sigma, fc) >= 0.0


@settings(max_examples=15, deadline=None)
@given(ratio=st.floats(0.0, 2.0), alpha2=st.floats(0.0, 1.0), log_a=st.floats(-3.0, 0.0))
def test_lugre_loop_energy_nonnegative(ratio, alpha2, log_a):
    # sigma1 = 0: eq. 5 is then passive (bristle loss plus viscous alpha2 v^2 >= 0).
    p = {
        "sigma0": 2133.4,
        "sigma1": 0.0,
        "alpha0": 38.0,
        "alpha1": 38.0 * ratio,
        "alpha2": alpha2,
        "v0": 1.0,
        "vd": 1.0,
    }
    a = 10.0**log_a
    x, f = hysteresis_loop("lugre", p, a, frequency_hz=125.0, cycles=3, points_per_cycle=400)
    assert loop_dissipation(x, f, 400) >= -1e-9 * 38.0 * a

"""Averaged ring-down models against direct integration and closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workflow.models import friction
from workflow.models.averaged import (
    MODELS,
    CurveGrid,
    gradient_along_grid,
    model_curves,
    model_curves_on_grid,
)
from workflow.models.joint_averages import (
    dahl_averages,
    iwan_averages,
    iwan_cells_averages,
    jenkins_dissipation,
    jenkins_inphase,
    lugre_averages,
    power_stiffness_harmonic_factor,
    threshold_cell_edges,
)


def _loop_averages(model, params, amplitude, frequency_hz=10.0, points=4000):
    """Dissipation and in-phase first harmonic of a directly integrated steady loop."""
    x, force = friction.hysteresis_loop(
        model, params, amplitude, frequency_hz=frequency_hz, cycles=4, points_per_cycle=points
    )
    d = friction.loop_dissipation(x, force, points)
    f = np.asarray(force)[..., -(points + 1) : -1]
    phase = 2 * np.pi * np.arange(points) / points  # x = A sin(phase)
    k1 = 2.0 / points * np.sum(f * np.sin(phase), axis=-1) / amplitude
    return d, k1


@pytest.mark.parametrize("y", [0.05, 0.5, 2.0, 8.0])
def test_dahl_closed_forms_match_direct_integration_of_the_dahl_ode(y):
    sigma, fc = 2133.4, 38.0
    amplitude = y * fc / sigma
    d, k1 = _loop_averages("dahl", {"sigma": sigma, "fc": fc}, amplitude)
    av = dahl_averages(y)
    # the D = 4 Fc A - 4 Fc^2 / sigma tanh(sigma A / Fc), normalised by Fc^2/sigma
    assert av.dissipation == pytest.approx(d / (fc**2 / sigma), rel=2e-3)
    assert av.inphase == pytest.approx(k1 / sigma, rel=2e-3, abs=1e-5)


def test_dahl_small_and_large_amplitude_limits():
    y = np.array([1e-4, 1e-3 * 0.999, 1e-3, 50.0])
    av = dahl_averages(y)
    assert av.dissipation[0] == pytest.approx(4 * y[0] ** 3 / 3, rel=1e-6)
    assert av.dissipation[1] == pytest.approx(av.dissipation[2], rel=1e-2)  # series/exact join
    assert av.dissipation[3] == pytest.approx(4 * (50 - 1), rel=1e-9)  # Coulomb 4 Fc A
    assert av.inphase[0] == pytest.approx(1.0, abs=1e-6)
    # macro-slip: Coulomb friction has no in-phase part; Dahl's decays like y^-3/2
    assert av.inphase[3] == pytest.approx(4 / (50 * np.sqrt(2 * np.pi * 50)), rel=2e-2)


def test_lugre_without_stribeck_or_micro_damping_is_dahl():
    y = np.geomspace(0.01, 100, 25)
    lugre = lugre_averages(y, 1.0, 0.0, 0.0, n_steps=160)
    dahl = dahl_averages(y)
    np.testing.assert_allclose(lugre.dissipation, dahl.dissipation, rtol=1e-6)
    np.testing.assert_allclose(lugre.inphase, dahl.inphase, rtol=1e-4, atol=1e-7)
    np.testing.assert_allclose(lugre.tip_energy, 0.5 * np.tanh(y) ** 2, rtol=1e-6)


@pytest.mark.parametrize("y,velocity_ratio", [(0.5, 0.5), (3.0, 2.0), (10.0, 0.3)])
def test_lugre_steady_cycle_matches_direct_integration(y, velocity_ratio):
    sigma0, alpha0, frequency = 1000.0, 2.0, 10.0
    amplitude = y * alpha0 / sigma0
    v0 = amplitude * 2 * np.pi * frequency / velocity_ratio
    sigma1 = 0.3 * sigma0 / (2 * np.pi * frequency)
    params = {
        "sigma0": sigma0,
        "sigma1": sigma1,
        "alpha0": alpha0,
        "alpha1": 0.7 * alpha0,
        "alpha2": 0.0,
        "v0": v0,
        "vd": v0,
    }
    d, k1 = _loop_averages("lugre", params, amplitude, frequency_hz=frequency)
    av = lugre_averages(y, velocity_ratio, 0.7, sigma1 * 2 * np.pi * frequency / sigma0, n_steps=400)
    assert av.dissipation == pytest.approx(d / (alpha0**2 / sigma0), rel=5e-3)
    assert av.inphase == pytest.approx(k1 / sigma0, rel=5e-3, abs=2e-4)


def _iwan_discrete(x, chi, macro_ratio, n=20000):
    """Sum over many Jenkins elements sampled from the Segalman density."""
    # equal-weight quantiles of the density t^chi on (0, 1)
    t = ((np.arange(n) + 0.5) / n) ** (1.0 / (chi + 1.0))
    weights = np.full(n, 1.0 / (n * (1.0 + macro_ratio)))
    macro = macro_ratio / (1.0 + macro_ratio)
    onsets = np.append(t, 1.0)
    weights = np.append(weights, macro)
    d = np.sum(weights * jenkins_dissipation(x, onsets))
    g = np.sum(weights * np.where(onsets >= x, 1.0, jenkins_inphase(onsets / x)))
    return d, g


@pytest.mark.parametrize("x", [0.03, 0.4, 0.99, 2.5])
@pytest.mark.parametrize("chi", [-0.6, -0.2, 0.3])
def test_iwan_averages_match_a_sum_of_jenkins_elements(x, chi):
    av = iwan_averages(x, chi, 0.4)
    d, g = _iwan_discrete(x, chi, 0.4)
    assert av.dissipation == pytest.approx(d, rel=1e-2)
    assert av.inphase == pytest.approx(g, rel=2e-3)


@given(chi=st.floats(-0.9, 0.4), x=st.floats(1e-3, 0.1))
@settings(max_examples=30, deadline=None)
def test_iwan_micro_slip_power_law(chi, x):
    """Below macro-slip D ~ x^(3 + chi): the damping ratio grows like x^(1 + chi)."""
    d1 = iwan_averages(x, chi, 0.3).dissipation
    d2 = iwan_averages(2 * x, chi, 0.3).dissipation
    assert np.log2(d2 / d1) == pytest.approx(3 + chi, rel=1e-9)


def test_iwan_tip_energy_slope_is_the_derivative_of_the_stored_energy():
    x = np.linspace(0.05, 1.5, 300)
    chi, beta = -0.4, 0.5
    r = (chi + 1) / (1 + beta)
    s = beta / (1 + beta)
    m = np.minimum(x, 1.0)
    # stored energy at the tip: stuck elements x^2/2, slipped ones t^2/2 (at their limit)
    energy = (
        0.5 * x**2 * (r * (1 - m ** (chi + 1)) / (chi + 1) + np.where(x <= 1, s, 0.0))
        + 0.5 * r * m ** (chi + 3) / (chi + 3)
        + np.where(x > 1, 0.5 * s, 0.0)
    )
    slope = iwan_averages(x, chi, beta).tip_energy_slope
    smooth = np.abs(x - 1.0) > 0.02  # the slope jumps at macro-slip onset (x = 1)
    smooth[[0, -1]] = False
    np.testing.assert_allclose(np.gradient(energy, x)[smooth], slope[smooth], rtol=2e-2, atol=1e-4)


def _cells_discrete(x, shares, per_cell=20000):
    """A sum of Jenkins elements with thresholds log-uniform within each cell (midpoint rule in ln t)."""
    edges = threshold_cell_edges(len(shares))
    onsets, weights = [], []
    for k, share in enumerate(shares):
        u = np.linspace(np.log(edges[k]), np.log(edges[k + 1]), per_cell + 1)
        onsets.append(np.exp(0.5 * (u[1:] + u[:-1])))
        weights.append(np.full(per_cell, share / per_cell))
    t, w = np.concatenate(onsets), np.concatenate(weights)
    d = np.sum(w * jenkins_dissipation(x, t))
    g = np.sum(w * np.where(t >= x, 1.0, jenkins_inphase(t / x)))
    stuck = x * np.sum(w[t > x])
    return d, g, stuck


@pytest.mark.parametrize("x", [0.002, 0.05, 0.3, 0.9, 3.0])
def test_threshold_cells_match_a_sum_of_jenkins_elements(x):
    shares = np.array([0.1, 0.35, 0.05, 0.5])
    av = iwan_cells_averages(x, shares)
    d, g, slope = _cells_discrete(x, shares)
    # midpoint rule over 20000 elements a cell: relative error ~ (ln 10 / 4 / 20000)^2
    assert av.dissipation == pytest.approx(d, rel=1e-7, abs=1e-15)
    assert av.inphase == pytest.approx(g, abs=1e-7)
    # the stuck stiffness counts whole elements: one element's weight is 2.5e-5 of the joint
    assert av.tip_energy_slope == pytest.approx(slope, abs=3e-5 * x)


def test_threshold_cells_are_a_stuck_joint_below_and_a_slipped_one_above():
    shares = np.array([0.25, 0.25, 0.5])
    below = iwan_cells_averages(0.5 * threshold_cell_edges(3)[0], shares)
    assert below.dissipation == 0.0 and below.inphase == pytest.approx(1.0)
    above = iwan_cells_averages(1e4, shares)
    # every element slides: in-phase stiffness ~ (16 / 3 pi) sum t^1.5, dissipation ~ 4 x sum t
    assert above.inphase < 1e-4
    assert above.tip_energy_slope == 0.0


def test_threshold_cells_batch_shapes_follow_the_parameters():
    y = np.geomspace(0.01, 2.0, 7)
    shares = np.array([[0.5, 0.5], [0.9, 0.1]])[:, None, :]  # two parameter sets, shape (2, 1, 2)
    av = iwan_cells_averages(y, shares)
    assert av.inphase.shape == (2, 7)
    np.testing.assert_allclose(av.inphase[1], iwan_cells_averages(y, [0.9, 0.1]).inphase, rtol=1e-12)


def test_power_stiffness_harmonic_factor():
    assert power_stiffness_harmonic_factor(2.0) == pytest.approx(0.75)  # cubic spring
    assert power_stiffness_harmonic_factor(0.0) == pytest.approx(1.0)  # linear spring


# ------------------------------------------------------------ direct integration
def _simulate_dahl_oscillator(f_lin, zeta0, beta, v_slip, quadratic, y0, duration=1.5, fs=20000.0, sub=5):
    """RK4 of xi'' + c xi' + k_nj xi + sigma z + c2 xi'|xi'| = 0, Dahl z (phi = psi = 1).

    Returns time, displacement and acceleration sampled at ``fs``.
    """
    w = 2 * np.pi * f_lin
    kappa = beta * w**2
    k_nj, c = w**2 - kappa, 2 * zeta0 * w
    a_s = v_slip / w
    fc = kappa * a_s
    c2 = 3 * np.pi * quadratic * w / 4  # zeta_q = (4 / 3 pi) c2 a = q V

    def rhs(x, v, z):
        acc = -c * v - k_nj * x - kappa * z - c2 * v * abs(v)
        return v, acc, v - kappa * abs(v) * z / fc

    dt, n = 1 / fs / sub, int(duration * fs)
    x, v, z = 0.0, y0 * v_slip, 0.0
    xs, accs = np.empty(n), np.empty(n)
    for i in range(n):
        xs[i], accs[i] = x, rhs(x, v, z)[1]
        for _ in range(sub):
            k1 = rhs(x, v, z)
            k2 = rhs(x + dt / 2 * k1[0], v + dt / 2 * k1[1], z + dt / 2 * k1[2])
            k3 = rhs(x + dt / 2 * k2[0], v + dt / 2 * k2[1], z + dt / 2 * k2[2])
            k4 = rhs(x + dt * k3[0], v + dt * k3[1], z + dt * k3[2])
            x += dt / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            v += dt / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
            z += dt / 6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])
    return np.arange(n) / fs, xs, accs


def _log_decrement(t, x, signal, cycles=10):
    """Fundamental-harmonic amplitude per cycle of ``signal`` (between upward zero
    crossings of x), then zeta, frequency and velocity amplitude per window of cycles."""
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    tc = t[up] - x[up] * (t[up + 1] - t[up]) / (x[up + 1] - x[up])
    amp, mid = [], []
    for k in range(tc.size - 1):
        m = (t >= tc[k]) & (t < tc[k + 1])
        period = tc[k + 1] - tc[k]
        coef = 2 / period * np.sum(signal[m] * np.exp(-2j * np.pi * (t[m] - tc[k]) / period))
        amp.append(abs(coef) * (t[1] - t[0]))
        mid.append(0.5 * (tc[k] + tc[k + 1]))
    amp, mid, periods = np.array(amp), np.array(mid), np.diff(tc)
    rows = []
    for k in range(0, mid.size - cycles, cycles // 2):
        sl = slice(k, k + cycles)
        s = -np.polyfit(mid[sl], np.log(amp[sl]), 1)[0]
        wd = 2 * np.pi / np.mean(periods[sl])
        rows.append((np.exp(np.mean(np.log(amp[sl]))) / wd, s / np.hypot(s, wd), wd / (2 * np.pi)))
    return np.array(rows).T


@pytest.mark.parametrize("beta,quadratic", [(0.08, 0.0), (0.03, 0.002)])
def test_averaged_dahl_model_matches_direct_integration_of_the_ringdown(beta, quadratic):
    """zeta(V) and f(V) of the acceleration envelope agree with the time integration within
    3 % and 0.1 % from deep macro-slip (V = 30 V_s) down to the stuck joint."""
    f_lin, zeta0, v_slip = 125.0, 0.001, 0.8
    t, x, acc = _simulate_dahl_oscillator(f_lin, zeta0, beta, v_slip, quadratic, y0=30)
    velocity, zeta, freq = _log_decrement(t, x, acc)
    params = {
        "f_lin_hz": f_lin,
        "zeta0": zeta0,
        "joint_stiffness_fraction": beta,
        "slip_velocity_in_s": v_slip,
        "quadratic_zeta_per_in_s": max(quadratic, 1e-12),
    }
    model_zeta, model_f = model_curves("dahl_quadratic", params, velocity, response_order=2)
    assert velocity.max() > 10 * v_slip and velocity.min() < 0.2 * v_slip
    np.testing.assert_allclose(model_zeta, zeta, rtol=0.03)
    np.testing.assert_allclose(model_f, freq, rtol=1e-3)


def test_response_order_changes_the_envelope_decay_only_where_frequency_moves():
    params = {"f_lin_hz": 100.0, "zeta0": 1e-3, "joint_stiffness_fraction": 0.1, "slip_velocity_in_s": 1.0}
    v = np.geomspace(0.01, 100, 50)
    z0, _ = model_curves("dahl", params, v, response_order=0)
    z2, _ = model_curves("dahl", params, v, response_order=2)
    # the frequency rises as the amplitude decays (softening joint): the acceleration
    # envelope (omega^2 a) decays more slowly than the displacement's
    assert np.all(z2 <= z0 * (1 + 1e-9))
    assert np.max(1 - z2 / z0) > 0.01
    assert abs(1 - z2[0] / z0[0]) < 1e-3 and abs(1 - z2[-1] / z0[-1]) < 1e-2


@pytest.mark.parametrize("model", ["dahl", "dahl_drift"])
def test_segments_of_records_of_different_quantities_each_read_their_own_envelope(model):
    # accelerometers beside a laser vibrometer and a displacement probe, pooled: each
    # segment's model damping is the one of its own record's quantity, on the same grid
    params = {
        "f_lin_hz": 100.0,
        "zeta0": 1e-3,
        "joint_stiffness_fraction": 0.1,
        "slip_velocity_in_s": 1.0,
        "drift": 0.4,
    }
    rng = np.random.default_rng(3)
    v = np.geomspace(0.02, 50, 60)
    runs = rng.integers(0, 3, v.size)
    orders = rng.permutation(np.resize([2, 1, 0], v.size))
    common = {"run_index": runs, "n_runs": 3, "grid_range": (v.min(), v.max())}
    zeta, frequency_hz = CurveGrid(v, response_order=orders, **common)(model, params)
    for order in (0, 1, 2):
        own_zeta, own_f = CurveGrid(v, response_order=order, **common)(model, params)
        np.testing.assert_array_equal(zeta[orders == order], own_zeta[orders == order])
        np.testing.assert_array_equal(frequency_hz, own_f)
    # one quantity given per segment is the one-quantity grid, to the bit
    np.testing.assert_array_equal(
        CurveGrid(v, response_order=np.full(v.size, 1), **common)(model, params)[0],
        CurveGrid(v, response_order=1, **common)(model, params)[0],
    )
    # and the orders differ where the frequency moves (the softening joint's slip range)
    z0, z2 = (CurveGrid(v, response_order=n, **common)(model, params)[0] for n in (0, 2))
    assert np.max(1 - z2 / z0) > 0.01


def test_drift_model_at_the_middle_run_is_dahl_and_shifts_the_slip_scale():
    params = {"f_lin_hz": 100.0, "zeta0": 1e-3, "joint_stiffness_fraction": 0.05, "slip_velocity_in_s": 1.0}
    v = np.geomspace(0.05, 5, 30)
    runs = np.array([0, 1, 2])
    grid = CurveGrid(np.tile(v, 3), run_index=np.repeat(runs, v.size), n_runs=3)
    z_drift, f_drift = grid("dahl_drift", {**params, "drift": 0.6})
    z_dahl, f_dahl = grid("dahl", params)
    middle = slice(v.size, 2 * v.size)
    np.testing.assert_allclose(z_drift[middle], z_dahl[middle], rtol=1e-12)
    shifted = CurveGrid(v, grid_range=(v.min(), v.max()))(
        "dahl", {**params, "slip_velocity_in_s": 1.0 * (1 + 0.6 * (2 - 1) / 3)}
    )
    np.testing.assert_allclose(z_drift[2 * v.size :], shifted[0], rtol=1e-9)


def test_curve_grid_interpolation_is_accurate():
    params = {
        "f_lin_hz": 100.0,
        "zeta0": 1e-3,
        "joint_stiffness_fraction": 0.05,
        "slip_velocity_in_s": 0.3,
        "chi": -0.4,
        "macro_ratio": 0.2,
    }
    v = np.geomspace(0.01, 10, 333)
    z_fine, f_fine = model_curves_on_grid(MODELS["iwan"], params, v)
    z, f = CurveGrid(v)("iwan", params)
    # the Iwan curve has a kink at macro-slip onset; elsewhere it is smooth
    np.testing.assert_allclose(z, z_fine, rtol=1.5e-2)
    assert np.median(np.abs(z / z_fine - 1)) < 1e-3
    np.testing.assert_allclose(f, f_fine, rtol=5e-5)


def test_stiffness_term_moves_frequency_not_damping():
    params = {
        "f_lin_hz": 100.0,
        "zeta0": 1e-3,
        "joint_stiffness_fraction": 0.01,
        "slip_velocity_in_s": 1.0,
        "reference_velocity_in_s": 1.0,
        "stiffness_exponent": 2.0,
    }
    v = np.append(np.geomspace(0.01, 3, 40), 1.0)
    z0, f0 = model_curves("dahl_stiffness", {**params, "stiffness_shift": 0.0}, v, response_order=0)
    z1, f1 = model_curves("dahl_stiffness", {**params, "stiffness_shift": -0.02}, v, response_order=0)
    i = v.size - 1  # V = reference velocity
    # omega^2 changes by -2 % at the reference amplitude: f by about -1 %
    assert f1[i] / f0[i] - 1 == pytest.approx(-0.01, rel=0.05)
    # a conservative spring changes the damping ratio only through omega and the stored
    # energy: by no more than the (small) stiffness change itself below V_ref
    below = v <= 1.0
    assert np.max(np.abs(z1[below] / z0[below] - 1)) < 0.04


# the demo's grid in ln V (uneven in floating point), and an evenly spaced one (NumPy's other branch)
@pytest.mark.parametrize("coordinate", [np.log(np.geomspace(0.01, 3.0, 48)), 0.25 * np.arange(7.0) - 1.0])
def test_gradient_along_grid_is_numpys_gradient_to_the_bit(coordinate):
    # the fits' residuals rely on it: every fit is unchanged only if each value is
    values = np.random.default_rng(0).standard_normal((5, 3, coordinate.size))
    np.testing.assert_array_equal(
        gradient_along_grid(values, coordinate), np.gradient(values, coordinate, axis=-1)
    )


def _cells_numpy(y, shares):
    """:func:`iwan_cells_averages`'s formulas with NumPy's arrays, ``H`` by ``np.interp``."""
    from workflow.models.joint_averages import _JENKINS_LOG_H, _JENKINS_LOG_TAU

    edges = threshold_cell_edges(shares.shape[-1])
    low, high = edges[:-1], edges[1:]
    x = np.abs(np.asarray(y, dtype=float))[..., None]
    c = shares / np.log(high / low)
    m = np.clip(x, low, high)
    d = np.sum(4.0 * c * (x * (m - low) - 0.5 * (m**2 - low**2)), axis=-1)
    h = np.interp(np.minimum(edges / np.where(x > 0, x, 1.0), 1.0), _JENKINS_LOG_TAU, _JENKINS_LOG_H)
    h_top = np.where(x > 0, h[..., 1:], h[..., :-1])
    stuck = c * np.log(high / m)
    return d, np.sum(c * (h_top - h[..., :-1]) + stuck, axis=-1), x[..., 0] * np.sum(stuck, axis=-1)


def test_threshold_cells_compiled_loop_is_the_array_formulas():
    # amplitudes inside and beyond every cell, on the edges, at 0 and NaN; two parameter sets
    edges = threshold_cell_edges(9)
    y = np.concatenate([np.geomspace(1e-4, 30.0, 400), edges, np.nextafter(edges, 2.0), [0.0]])
    shares = np.random.default_rng(0).dirichlet(np.ones(9), size=(2, 1))
    av = iwan_cells_averages(y, shares)
    for got, expected in zip((av.dissipation, av.inphase, av.tip_energy_slope), _cells_numpy(y, shares)):
        assert got.shape == (2, y.size)
        # the same arithmetic, summed in another order: a few ulps
        np.testing.assert_allclose(got, expected, rtol=1e-13, atol=1e-15)
    nan = iwan_cells_averages(np.array([np.nan]), shares[0, 0])
    assert np.isnan(nan.dissipation).all() and np.isnan(nan.inphase).all()


def test_gradient_along_grid_of_a_quadratic_is_exact_inside():
    # second-order central differences are exact for a quadratic on any spacing;
    # the one-sided ends are off by the curvature times half the end step
    x = np.log(np.geomspace(0.1, 10.0, 30))
    got = gradient_along_grid(3.0 * x**2 - x, x)
    np.testing.assert_allclose(got[1:-1], 6.0 * x[1:-1] - 1.0, rtol=0, atol=1e-12)
    assert got[0] == pytest.approx(6.0 * x[0] - 1.0 + 3.0 * (x[1] - x[0]), abs=1e-12)


def _one_hit_of_cells(shares, noise_ln_zeta=0.005, seed=3):
    """One ring-down of an Iwan joint with threshold cells, anchored at the top of its
    amplitudes (1 in/s), with a small measured scatter."""
    from workflow.models.configuration_data import ConfigurationData

    model = MODELS[f"iwan_cells_{len(shares)}"]
    truth = {"f_lin_hz": 100.0, "zeta0": 0.001, "anchor_velocity_in_s": 1.0}
    truth.update(dict(zip(model.cell_names, shares)))
    v = np.geomspace(0.01, 1.0, 120)
    zeta, frequency_hz = model_curves(model, truth, v)
    rng = np.random.default_rng(seed)
    zeta = zeta * np.exp(noise_ln_zeta * rng.standard_normal(v.size))
    frequency_hz = frequency_hz * (1.0 + 2e-6 * rng.standard_normal(v.size))
    data = ConfigurationData("c", v, zeta, frequency_hz, np.zeros(v.size, int), ["run01"], None)
    return model, truth, data


def test_cells_no_fitted_amplitude_reaches_are_tied_to_the_highest_one_reached():
    from workflow.models.averaged_fit import unseen_cell_ties

    model = MODELS["iwan_cells_5"]
    index = {p.name: i for i, p in enumerate(model.params)}
    fixed = {"anchor_velocity_in_s": 10.0}  # lower edges 0.562, 1, 1.78, 3.16, 5.62 in/s
    assert unseen_cell_ties(model, np.array([0.05, 4.0]), fixed) == [
        (index["stiffness_fraction_cell_5"], index["stiffness_fraction_cell_4"])
    ]
    assert unseen_cell_ties(model, np.array([0.05, 1.5]), fixed) == [
        (index[f"stiffness_fraction_cell_{k}"], index["stiffness_fraction_cell_2"]) for k in (3, 4, 5)
    ]
    assert unseen_cell_ties(model, np.array([0.05, 6.0]), fixed) == []
    assert unseen_cell_ties(MODELS["iwan"], np.array([0.05, 0.5]), fixed) == []


def test_a_fit_below_the_top_cell_predicts_it_from_the_cells_it_sees():
    """One hit's top quarter decade held out leaves the top threshold cell without a segment
    that slips it: its share is not in the data (untied, from a start a thousandth of the
    truth's, the fit takes it to its range's upper edge and misses the top's damping by a
    factor of 10). Tied to the highest cell the fit sees, which for a log-uniform threshold
    density is the truth, the held-out top is predicted from the cells below."""
    from workflow.models.averaged_fit import FitContext, fit_model, to_coords
    from workflow.models.configuration_data import scatter_of

    model, truth, data = _one_hit_of_cells([2e-3] * 4)
    below = data.velocity_in_s < 10**-0.25  # cell 4 holds thresholds 0.562-1 in/s
    start = dict(truth, stiffness_fraction_cell_4=2e-6)
    fit = fit_model(
        model, data, scatter_of(data), FitContext(0.5), mask=below, warm_start=to_coords(model, start)
    )
    top = ~below
    zeta, frequency_hz = model_curves(model, fit.params, data.velocity_in_s[top])
    true_zeta, true_frequency_hz = model_curves(model, truth, data.velocity_in_s[top])
    # the cells below are fitted within the scatter (0.5 % in zeta): the top follows them
    assert np.max(np.abs(np.log(zeta / true_zeta))) < 0.05
    assert np.max(np.abs(frequency_hz / true_frequency_hz - 1.0)) < 1e-4
    assert fit.params["stiffness_fraction_cell_4"] == fit.params["stiffness_fraction_cell_3"]

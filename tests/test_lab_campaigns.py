"""Checks of the virtual lab: file format, determinism, and the truth's physics."""

import json

import numpy as np
import pytest
import yaml

from workflow.io import campaign, run_files
from workflow.lab.campaign_files import truth_path
from workflow.lab.campaigns import generate_campaign, generate_one_hit, generate_sensor_campaigns
from workflow.lab.configurations import (
    ModeTable,
    averaged_mode_response,
    mode_table,
    reference_modal_amplitude,
    run_dahl_coulomb,
    scale_slip_forces,
    setup_configuration,
    truth_curves,
)
from workflow.lab.sensors import Sensor, positions_with_mode1_gain, sensor_at_gain
from workflow.lab.settings import (
    EFFECT_CAUSES,
    REFERENCE_VELOCITY_IN_S,
    SAMPLE_RATE_HZ,
    LabSettings,
    RunPhysics,
    draw_run_physics,
)
from workflow.lab.time_domain import time_domain_mode_response
from workflow.models import contact

SETTINGS = LabSettings()


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("lab") / "demo"
    truth = generate_campaign(out, seed=7, runs_per_configuration=2)
    return out, truth


@pytest.fixture(scope="module")
def no_washer():
    return setup_configuration("no_washer", 1.36, SETTINGS)


def _read(path):
    lines = path.read_text().splitlines()
    header = lines[:4]
    data = np.array([[float(c) for c in line.split("\t")] for line in lines[4:]])
    return header, data


def test_campaign_layout_and_truth_beside(demo):
    out, truth = demo
    meta = yaml.safe_load((out / "campaign.yaml").read_text())
    assert meta["sample_rate_hz"] == 2560 and meta["pretrigger_samples"] == 25
    assert meta["response"] == {"quantity": "acceleration", "unit": "g"}
    assert list(meta["configurations"]) == ["no_washer", "large_washer", "small_washer"]
    assert meta["configurations"]["large_washer"]["bearing_area_in2"] == 0.66
    assert 110 < meta["mode_hz"] < 140
    assert not list(out.glob("*.json"))
    saved = json.loads(truth_path(out).read_text())
    assert truth_path(out).parent == out.parent
    assert saved["expected_cause"] == truth["expected_cause"] == "microslip_power_law"
    assert sorted(p.name for p in (out / "no_washer").iterdir()) == ["run01.txt", "run02.txt"]


def test_run_file_format_trigger_and_quantisation(demo):
    out, _ = demo
    header, data = _read(out / "no_washer" / "run01.txt")
    assert header[1:] == [
        "Sample rate: 2560 Hz",
        "Pre-trigger: 25 samples",
        "Time (s)\tForce (lbf)\tAcceleration (g)",
    ]
    assert data.shape == (8192, 3)
    assert np.allclose(np.diff(data[:, 0]), 1 / 2560, atol=1e-6)  # 6 printed decimals
    force, acc = data[:, 1], data[:, 2]
    assert np.argmax(force >= 1.0) == 25  # trigger sample after 25 pre-trigger samples
    assert np.all(force[:25] < 1.0)
    for values, full_scale in ((acc, 500.0), (force, 500.0)):
        counts = values / (2 * full_scale / 2**24)
        assert np.allclose(counts, np.round(counts), atol=1e-3)
    assert np.max(np.abs(acc)) < 500


def test_campaign_reader_accepts_it(demo):
    out, _ = demo
    meta = campaign.load_campaign(out)
    runs = run_files.list_runs(out, meta)
    assert len(runs) == 6
    record = run_files.read_run(out, runs[0], meta)
    assert record.n_samples == 8192 and record.pretrigger_samples == 25


def test_deterministic_for_a_seed(tmp_path):
    kwargs = dict(seed=11, runs_per_configuration=2, configurations={"beam": None})
    generate_campaign(tmp_path / "a", **kwargs)
    generate_campaign(tmp_path / "b", **kwargs)
    generate_campaign(tmp_path / "c", **{**kwargs, "seed": 12})
    a = (tmp_path / "a" / "beam" / "run02.txt").read_bytes()
    assert a == (tmp_path / "b" / "beam" / "run02.txt").read_bytes()
    assert a != (tmp_path / "c" / "beam" / "run02.txt").read_bytes()
    assert "bearing_area_in2" not in (tmp_path / "a" / "campaign.yaml").read_text()


def test_truth_damping_physics(demo):
    _, truth = demo
    v = np.array(truth["velocity_amplitude_in_s"])
    z = {c: np.array(e["zeta"]) for c, e in truth["configurations"].items()}
    f = np.array(truth["configurations"]["no_washer"]["damped_frequency_hz"])
    low = (v >= 0.01) & (v <= 1.0)
    assert np.all(np.diff(z["no_washer"][low]) > 0)  # damping grows with amplitude
    assert np.all(np.diff(f[low]) < 0)  # frequency falls with amplitude
    # ordered by bearing area where micro-slip matters
    band = (v >= 0.03) & (v <= 1.0)
    assert np.all(z["no_washer"][band] > z["large_washer"][band])
    assert np.all(z["large_washer"][band] >= z["small_washer"][band] - 1e-12)
    # the linear floor is the modal damping
    assert z["small_washer"][0] == pytest.approx(SETTINGS.zeta0, rel=0.01)


def integrate_patch_ringdown(
    xi0, omega0_rad_s, zeta0, slip_per_xi, stiffness_lbf_in, slip_force_lbf, dt_s, n_steps
):
    """Direct time integration of mode 1 with the patch forces: the reference the
    lab's slow flow is checked against.

    ``xi'' + 2 zeta0 w0 xi' + w0^2 xi + sum s (F - k s xi) = 0`` (the stuck
    stiffness is already in ``w0``), central differences, Jenkins forces
    updated from each step's slip increment.  Starts at rest at ``xi0``
    with every patch unloaded-then-stuck at that displacement (virgin loading).

    Returns
    -------
    xi : ndarray, shape (n_steps,)
    """
    s = np.asarray(slip_per_xi, dtype=float).ravel()
    k = np.broadcast_to(stiffness_lbf_in, np.shape(slip_per_xi)).ravel()
    fs = np.broadcast_to(slip_force_lbf, np.shape(slip_per_xi)).ravel()
    force = contact.jenkins_force_update(np.zeros_like(s), s * xi0, k, fs)
    xi = np.empty(n_steps)
    x_prev, x = xi0, xi0
    v = 0.0
    # first step from rest (Taylor)
    acc = -(omega0_rad_s**2) * x - np.dot(s, force - k * s * x)
    x_next = x + 0.5 * dt_s**2 * acc
    xi[0] = x
    for n in range(1, n_steps):
        x_prev, x = x, x_next
        force = contact.jenkins_force_update(force, s * (x - x_prev), k, fs)
        v = (x - x_prev) / dt_s
        acc = -(omega0_rad_s**2) * x - 2 * zeta0 * omega0_rad_s * v - np.dot(s, force - k * s * x)
        # v lags half a step; with >= 200 steps per cycle the damping error is < 1 %
        x_next = 2 * x - x_prev + dt_s**2 * acc
        xi[n] = x
    return xi


def test_slow_flow_matches_direct_integration(no_washer):
    setup, curves = no_washer
    table = mode_table(setup, curves, SETTINGS, "patches", None, None)
    jm = setup.joint_modes
    w0 = setup.omega0_rad_s
    a0 = 3.0 / (abs(jm.mode.accelerometer_participation) * w0)  # 3 in/s
    dt = 2 * np.pi / w0 / 200
    n = int(0.4 / dt)
    xi = integrate_patch_ringdown(
        a0, w0, SETTINGS.zeta0, jm.slip_per_xi, jm.patches.stiffness_lbf_in, jm.patches.slip_force_lbf, dt, n
    )
    t = np.arange(n) * dt
    peaks = np.flatnonzero((xi[1:-1] > xi[:-2]) & (xi[1:-1] >= xi[2:])) + 1
    # parabolic refinement of each peak
    y0, y1, y2 = xi[peaks - 1], xi[peaks], xi[peaks + 1]
    shift = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
    t_peak = t[peaks] + shift * dt
    a_peak = y1 - 0.25 * (y0 - y2) * shift
    a_slow, phase = ModeTable.evolve(table, a0, t_peak)
    # amplitude decay within 2 % over 50 cycles (the slow flow averages the
    # weak nonlinearity; the initial virgin loading differs slightly)
    assert np.allclose(a_peak[5:], a_slow[5:], rtol=0.02)
    # local damping and frequency from the direct run vs the table
    period = np.diff(t_peak)
    zeta_direct = np.log(a_peak[5:-1] / a_peak[6:]) / (2 * np.pi)
    zeta_table, w_table = table.at(a_peak[5:-1])
    assert np.median(zeta_direct / zeta_table) == pytest.approx(1.0, abs=0.05)
    f_direct = 1 / period[5:]
    assert np.median(f_direct / (w_table / (2 * np.pi))) == pytest.approx(1.0, abs=2e-3)


@pytest.mark.parametrize("size", [0.002, 0.005])
def test_quadratic_damping_raises_damping_not_frequency(no_washer, size):
    setup, curves = no_washer
    v = np.logspace(-1, 1, 21)
    base = truth_curves(setup, mode_table(setup, curves, SETTINGS, "dahl", None, None), v)
    quad = truth_curves(setup, mode_table(setup, curves, SETTINGS, "dahl", "quadratic_damping", size), v)
    added = quad[0] - base[0]
    # zeta added grows linearly with amplitude: size at the reference velocity
    # (2 %: the modal amplitude of a velocity differs by the ~1 % frequency shift)
    at_ref = np.interp(np.log(REFERENCE_VELOCITY_IN_S), np.log(v), added)
    assert at_ref == pytest.approx(size, rel=0.02)
    assert np.polyfit(np.log(v), np.log(added), 1)[0] == pytest.approx(1.0, abs=0.02)
    # only the damped frequency's factor sqrt(1 - zeta^2) changes, by < zeta^2 / 2
    assert np.allclose(quad[1], base[1], rtol=0.6 * np.max(quad[0]) ** 2)


@pytest.mark.parametrize("size", [0.005, 0.02])
def test_stiffness_nonlinearity_shifts_frequency_only(no_washer, size):
    setup, curves = no_washer
    v = np.logspace(-1, 1, 21)
    base = truth_curves(setup, mode_table(setup, curves, SETTINGS, "dahl", None, None), v)
    soft = truth_curves(setup, mode_table(setup, curves, SETTINGS, "dahl", "stiffness_nonlinearity", size), v)
    ratio = np.interp(np.log(REFERENCE_VELOCITY_IN_S), np.log(v), soft[1] / base[1])
    assert ratio == pytest.approx(1 - size, abs=0.1 * size)
    assert np.all(np.diff(soft[1] / base[1]) < 0)
    # no dissipation added: damping changes only through omega in zeta's definition
    assert np.allclose(soft[0], base[0], rtol=3 * size)


def test_run_drift_shifts_damping_with_run_order(tmp_path):
    truth = generate_campaign(
        tmp_path / "drift",
        joint="dahl",
        effect="run_drift",
        effect_size=0.3,
        runs_per_configuration=4,
        configurations={"no_washer": 1.36},
    )
    assert truth["expected_cause"] == "run_drift"
    v = np.array(truth["velocity_amplitude_in_s"])
    sel = (v > 0.1) & (v < 3)
    runs = truth["configurations"]["no_washer"]["runs"]
    level = [np.mean(np.array(r["zeta"])[sel]) for r in runs]
    # Fc falls with run order; below Fc/sigma the Dahl damping ~ 1/Fc rises
    assert np.all(np.diff(level) > 0)
    assert level[-1] / level[0] > 1.05


def test_second_mode_appears_in_band(tmp_path):
    truth = generate_campaign(
        tmp_path / "two",
        joint="dahl",
        effect="second_mode",
        effect_size=0.6,
        runs_per_configuration=1,
        configurations={"no_washer": 1.36},
    )
    assert truth["expected_cause"] == "unknown"
    _, data = _read(tmp_path / "two" / "no_washer" / "run01.txt")
    spectrum = np.abs(np.fft.rfft(data[:, 2] * np.hanning(8192)))
    freq = np.fft.rfftfreq(8192, 1 / 2560)
    f1 = truth["configurations"]["no_washer"]["linear_frequency_hz"]
    near = lambda f: spectrum[np.argmin(np.abs(freq - f))]
    # the extra mode's peak is comparable to mode 1's (size 0.6 of its initial amplitude)
    assert near(1.08 * f1) > 0.2 * near(f1)
    with pytest.raises(ValueError, match="patches joint takes an effect in"):
        generate_campaign(tmp_path / "bad", effect="second_mode")


# ------------------------------------------------- run-to-run variability

NO_SPREAD = LabSettings(frequency_spread=0.0, damping_spread=0.0, slip_force_spread=0.0)


def test_demo_settings_default_to_the_lab_spreads():
    from workflow.lab.layout import DemoSettings

    demo = DemoSettings()
    for name in ("frequency_spread", "damping_spread", "slip_force_spread"):
        assert getattr(demo, name) == getattr(SETTINGS, name), name


def test_slip_force_scaling_matches_recomputed_patches(no_washer):
    setup, (a, d, loss) = no_washer
    p = setup.joint_modes.patches
    for factor in (0.9, 1.08):
        d_scaled, loss_scaled = scale_slip_forces(a, d, loss, factor)
        d_exact, loss_exact = contact_describing(setup, a, p.slip_force_lbf * factor)
        v = abs(setup.mode.accelerometer_participation) * setup.omega0_rad_s * a
        sel = (v > 0.01) & (v < 30) & (d_exact > 1e-6 * d_exact.max())
        # linear interpolation on the 1500-point log grid: relative error ~ (d ln a)^2
        assert np.allclose(d_scaled[sel], d_exact[sel], rtol=2e-3)
        assert np.allclose(loss_scaled[sel], loss_exact[sel], rtol=2e-3, atol=1e-9 * setup.omega0_rad_s**2)


def contact_describing(setup, a, slip_force_lbf):
    from workflow.models import contact

    p = setup.joint_modes.patches
    return contact.patch_describing_function(
        a, setup.joint_modes.slip_per_xi, p.stiffness_lbf_in, slip_force_lbf
    )


def test_runs_get_their_own_physics(tmp_path):
    truth = generate_campaign(
        tmp_path / "spread", seed=5, runs_per_configuration=12, joint="dahl", configurations={"beam": 0.8}
    )
    entry = truth["configurations"]["beam"]
    runs = entry["runs"]
    factors = np.array([[r["frequency_factor"], r["zeta0"], r["slip_force_factor"]] for r in runs])
    # drawn, not equal; spreads of the right size (12 draws: sample std within 0.5-1.6 sigma)
    for column, sigma in zip(np.log(factors).T, (3e-4, 0.03, 0.03)):
        assert 0.5 * sigma < np.std(column, ddof=1) < 1.6 * sigma
    v = np.array(truth["velocity_amplitude_in_s"])
    low = np.argmin(np.abs(v - 0.01))  # far below slip: the stuck linear mode
    f_low = np.array([r["damped_frequency_hz"][low] for r in runs])
    assert np.allclose(f_low / entry["damped_frequency_hz"][low], factors[:, 0], rtol=2e-6)
    z_low = np.array([r["zeta"][low] for r in runs])
    # at 0.01 in/s the Dahl joint adds < 0.5 % to the linear damping: each run's own zeta0
    assert np.allclose(z_low, factors[:, 1], rtol=0.005)
    coulomb = np.array([r["dahl_coulomb_modal"] for r in runs])
    assert np.allclose(coulomb / entry["dahl_coulomb_modal"], factors[:, 2], rtol=1e-12)
    # in slip (3 in/s) a weaker joint damps more: the slip force really changes the physics
    high = np.argmin(np.abs(v - 3.0))
    z_high = np.array([r["zeta"][high] for r in runs]) - factors[:, 1]
    assert np.corrcoef(np.log(z_high), np.log(factors[:, 2]))[0, 1] < -0.9


def test_measured_frequencies_follow_the_drawn_ones(tmp_path):
    from workflow.lab.hidden_effects import campaign_segments

    truth = generate_campaign(
        tmp_path / "m", seed=9, runs_per_configuration=6, joint="dahl", configurations={"beam": 0.8}
    )
    segments = campaign_segments(tmp_path / "m")
    runs = truth["configurations"]["beam"]["runs"]
    v = np.array(truth["velocity_amplitude_in_s"])
    measured, drawn = [], []
    for run in runs:
        seg = segments[segments["run"] == run["run"]]
        sel = (seg["velocity_amplitude_in_s"] > 0.1) & (seg["velocity_amplitude_in_s"] < 0.5)
        f_truth = np.interp(
            np.log(seg["velocity_amplitude_in_s"][sel]), np.log(v), np.array(run["damped_frequency_hz"])
        )
        measured.append(np.median(seg["frequency_hz"][sel] / f_truth))
        drawn.append(run["frequency_factor"])
    # each run's measured frequency is its own truth within the measurement's 2e-5
    # scatter (the drawn spread is 3e-4)
    assert np.allclose(measured, 1.0, atol=3e-5)
    assert np.std(drawn) > 5e-5


def test_no_spread_gives_the_same_beam_every_run(tmp_path):
    truth = generate_campaign(
        tmp_path / "same", seed=5, runs_per_configuration=3, configurations={"beam": 1.36}, settings=NO_SPREAD
    )
    entry = truth["configurations"]["beam"]
    for run in entry["runs"]:
        assert run["frequency_factor"] == 1.0 and run["slip_force_factor"] == 1.0
        assert run["zeta0"] == NO_SPREAD.zeta0
        assert run["zeta"] == entry["zeta"] and run["damped_frequency_hz"] == entry["damped_frequency_hz"]


def test_variability_has_no_trend_with_run_order():
    # 400 runs: a trend of even 0.2 sigma over the runs would give a correlation of 0.06;
    # the draws' correlation with run index stays at sampling noise 1/sqrt(400)
    runs = draw_run_physics(SETTINGS, np.random.default_rng(1), 400)
    order = np.arange(400)
    for name in ("frequency_factor", "zeta0", "slip_force_factor"):
        values = np.array([getattr(r, name) for r in runs])
        assert abs(np.corrcoef(order, values)[0, 1]) < 3 / np.sqrt(400), name


# ------------------------------------------------------------ time domain


def _peaks(t, x):
    i = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:])) + 1
    y0, y1, y2 = x[i - 1], x[i], x[i + 1]
    shift = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
    return t[i] + shift * (t[1] - t[0]), y1 - 0.25 * (y0 - y2) * shift


@pytest.mark.parametrize("joint", ["dahl", "patches"])
@pytest.mark.parametrize("peak_force_lbf", [5.0, 40.0])
def test_time_domain_agrees_with_the_averaged_model(no_washer, joint, peak_force_lbf):
    setup, curves = no_washer
    run = RunPhysics(frequency_factor=1.0003, zeta0=0.00085, slip_force_factor=0.97)
    table = mode_table(setup, curves, SETTINGS, joint, None, None, run=run)
    coulomb = run_dahl_coulomb(setup, None, None, 0.0, run.slip_force_factor)
    t = np.arange(8192) / SAMPLE_RATE_HZ
    modal_peak = setup.mode.hammer_participation * peak_force_lbf
    averaged = averaged_mode_response(setup, table, run)(t, modal_peak, 0.8e-3)
    direct = time_domain_mode_response(setup, joint, coulomb, run)(t, modal_peak, 0.8e-3)
    ta, aa = _peaks(t, averaged)
    td, ad = _peaks(t, direct)
    n = min(ta.size, td.size) - 20
    # damping over 20-cycle blocks (0.04-6 in/s): the describing function drops the joint
    # force's higher harmonics, a relative error of order zeta (measured <= 0.5 %)
    block = np.arange(5, n, 20)
    zeta_a = np.log(aa[block] / aa[block + 20]) / (40 * np.pi)
    zeta_d = np.log(ad[block] / ad[block + 20]) / (40 * np.pi)
    assert np.allclose(zeta_d, zeta_a, rtol=0.01)
    f_a = 20 / (ta[block + 20] - ta[block])
    f_d = 20 / (td[block + 20] - td[block])
    # frequency to the measurement's own scatter (2e-5; measured <= 1e-5)
    assert np.allclose(f_d, f_a, rtol=2e-5)
    assert np.allclose(ad[5:n], aa[5:n], rtol=0.01)


def test_time_domain_campaign_and_its_limits(tmp_path):
    truth = generate_campaign(
        tmp_path / "td",
        seed=3,
        runs_per_configuration=2,
        joint="dahl",
        effect="run_drift",
        configurations={"beam": 0.8},
        integrator="time_domain",
    )
    assert truth["integrator"] == "time_domain"
    _, data = _read(tmp_path / "td" / "beam" / "run02.txt")
    assert data.shape == (8192, 3) and np.argmax(data[:, 1] >= 1.0) == 25
    for effect in ("quadratic_damping", "stiffness_nonlinearity"):
        with pytest.raises(ValueError, match="time-domain"):
            generate_campaign(tmp_path / "x", joint="dahl", effect=effect, integrator="time_domain")


# ---------------------------------------------------------------- sensors


def test_sensor_variants_share_the_decay_not_the_noise(tmp_path):
    truths = generate_sensor_campaigns(
        tmp_path,
        {"accelerometer": 1.0, "mid": 0.5},
        seed=4,
        runs_per_configuration=1,
        joint="dahl",
        configurations={"beam": 0.8},
    )
    gains = [
        abs(t["configurations"]["beam"]["channels"]["Acceleration"]["participation"])
        / abs(t["configurations"]["beam"]["accelerometer_participation"])
        for t in truths.values()
    ]
    assert gains == pytest.approx([1.0, 0.5], rel=1e-12)
    _, a = _read(tmp_path / "accelerometer" / "beam" / "run01.txt")
    _, b = _read(tmp_path / "mid" / "beam" / "run01.txt")
    assert np.array_equal(a[:, :2], b[:, :2])  # same hammer hit
    freq = np.fft.rfftfreq(8192, 1 / SAMPLE_RATE_HZ)
    band = (freq > 110) & (freq < 140)
    spectrum_a, spectrum_b = (np.fft.rfft(x[:, 2])[band] for x in (a, b))
    # mode 1 scaled by the gain (the band's noise is 1e-3 of the mode's energy)
    ratio = np.sqrt(np.sum(np.abs(spectrum_b) ** 2) / np.sum(np.abs(spectrum_a) ** 2))
    assert ratio == pytest.approx(0.5, rel=0.01)
    # independent noise: before the hit the records are noise alone, and their difference
    # has the std of two independent noises (sqrt(2) x 0.002 g; 20 samples: +-40 %)
    difference = a[:20, 2] - b[:20, 2]
    assert np.std(difference) == pytest.approx(np.sqrt(2) * SETTINGS.acceleration_noise_g, rel=0.4)
    v = np.array(truths["mid"]["velocity_amplitude_in_s"])
    # the truth is per sensor: the mid sensor's 1 in/s is the accelerometer's 2 in/s
    z_mid = np.interp(np.log(1.0), np.log(v), truths["mid"]["configurations"]["beam"]["zeta"])
    z_acc = np.interp(np.log(2.0), np.log(v), truths["accelerometer"]["configurations"]["beam"]["zeta"])
    assert z_mid == pytest.approx(z_acc, rel=1e-3)


# ------------------------------------------------- two mechanisms at once


@pytest.mark.parametrize("effect, size", [("quadratic_damping", 0.004), ("cubic_stiffness", 0.005)])
def test_combined_truth_adds_the_term_to_the_joint(no_washer, tmp_path, effect, size):
    """On the patches an added term is a second cause, and the averaged model adds exactly
    its analytic share at the reference amplitude: ``zeta += size omega0^2 / omega^2``
    (``4 c2 a / (3 pi)`` in units of the undamped frequency) for the velocity-squared loss,
    ``omega^2 += omega0^2 ((1 + size)^2 - 1)`` for the cubic spring, to the table's linear
    interpolation in ``ln a`` (grid step 0.0115: a power of ``a`` is off by at most
    ``step^2 / 8`` = 1.7e-5 relative)."""
    setup, curves = no_washer
    a_ref = reference_modal_amplitude(setup)
    alone = mode_table(setup, curves, SETTINGS, "patches", None, None).at(a_ref)
    both = mode_table(setup, curves, SETTINGS, "patches", effect, size).at(a_ref)
    w0 = setup.omega0_rad_s
    if effect == "quadratic_damping":
        assert both[1] == pytest.approx(alone[1], rel=1e-12)
        assert both[0] - alone[0] == pytest.approx(size * w0**2 / both[1] ** 2, rel=2e-5)
    else:
        assert both[1] ** 2 - alone[1] ** 2 == pytest.approx(w0**2 * ((1 + size) ** 2 - 1), rel=2e-5)
    truth = generate_campaign(
        tmp_path / "combined",
        seed=5,
        runs_per_configuration=1,
        joint="patches",
        effect=effect,
        effect_size=size,
        configurations={"joint": 1.2},
    )
    cause = EFFECT_CAUSES[effect]
    assert (
        truth["causes"] == ["microslip_power_law", cause] and truth["expected_cause"] == "microslip_power_law"
    )
    with pytest.raises(ValueError, match="patches joint takes an effect"):
        generate_campaign(tmp_path / "bad", joint="patches", effect="run_drift")


def test_cubic_stiffness_is_a_hardening_spring(tmp_path):
    with pytest.raises(ValueError, match="hardening"):
        generate_campaign(tmp_path / "soft", joint="patches", effect="cubic_stiffness", effect_size=-0.01)


def _first_harmonic_envelope(t, acceleration, low_hz=60.0, high_hz=250.0):
    """Envelope of the acceleration's fundamental (an FFT band-pass and its analytic
    signal): what the measured chain's band-pass and Hilbert envelope see; a cubic
    spring's third harmonic, which peak-picking would add, is left out."""
    spectrum = np.fft.fft(acceleration)
    freq = np.fft.fftfreq(t.size, t[1] - t[0])
    return np.abs(np.fft.ifft(np.where((freq > low_hz) & (freq < high_hz), 2 * spectrum, 0)))


@pytest.mark.parametrize("effect, size", [("quadratic_damping", 0.006), ("cubic_stiffness", 0.008)])
def test_time_domain_combination_agrees_with_the_averaged_model(no_washer, effect, size):
    """The patches with the added term in the equation of motion against the averaged
    model, at the hardest hit (40 lbf), on the fundamental's envelope: decay rate over
    20-cycle blocks within 1 % (the describing functions drop higher harmonics, an error
    of order zeta), and the zero-crossing frequency within 1e-4 (terms of order zeta^2
    dropped: the velocity-squared loss brings zeta to 0.0075 in the first block, measured
    9e-5 there; the cubic's second-order Lindstedt term, ``21/256 (4/3 size)^2``, is 5e-6
    at the reference amplitude, growing as a^4)."""
    setup, curves = no_washer
    run = RunPhysics(zeta0=SETTINGS.zeta0)
    table = mode_table(setup, curves, SETTINGS, "patches", effect, size, run=run)
    t = np.arange(8192) / SAMPLE_RATE_HZ
    modal_peak = setup.mode.hammer_participation * 40.0
    averaged = averaged_mode_response(setup, table, run)(t, modal_peak, 0.8e-3)
    direct = time_domain_mode_response(setup, "patches", 0.0, run, effect, size)(t, modal_peak, 0.8e-3)
    period = 1 / setup.mode.frequency_hz
    block = np.arange(0.1, 1.3, 0.1)  # later the record's wrap-around (FFT) ripples the envelope
    rates = []
    for signal in (averaged, direct):
        envelope = np.log(_first_harmonic_envelope(t, signal))
        rates.append(np.interp(block, t, envelope) - np.interp(block + 20 * period, t, envelope))
    assert np.allclose(rates[1], rates[0], rtol=0.01)
    ta, _ = _peaks(t, averaged)
    td, _ = _peaks(t, direct)
    n = min(ta.size, td.size) - 20
    cycles = np.arange(5, n, 20)
    f_a = 20 / (ta[cycles + 20] - ta[cycles])
    f_d = 20 / (td[cycles + 20] - td[cycles])
    if effect == "cubic_stiffness":
        # where the mode is less than 0.3 % above its end frequency: higher, in the first
        # blocks (2 %), the second-order term 15/256 (eps A^2)^2 reaches 2e-4 (measured
        # 3.7e-4 at 2 %, 1.3e-4 at 0.5 %)
        kept = f_a / f_a[-1] - 1 < 0.003
        assert kept.sum() > 0.8 * kept.size
        f_a, f_d = f_a[kept], f_d[kept]
    assert np.allclose(f_d, f_a, rtol=1e-4)


# ------------------------------------------------------- sensor placement


def _band_rms(x, low_hz, high_hz, sample_rate_hz=SAMPLE_RATE_HZ):
    """RMS spectral amplitude of a Hann-windowed record in a band (the window keeps a
    mode's leakage into another mode's band below 1e-4)."""
    spectrum = np.fft.rfft(x * np.hanning(x.size))
    freq = np.fft.rfftfreq(x.size, 1 / sample_rate_hz)
    band = (freq > low_hz) & (freq < high_hz)
    return np.sqrt(np.sum(np.abs(spectrum[band]) ** 2))


@pytest.fixture(scope="module")
def three_sensors(tmp_path_factory, no_washer):
    setup, _ = no_washer
    mode = setup.mode
    near_node = sensor_at_gain(mode, SETTINGS, 0.05, "acc2")
    sensors = (Sensor("acc1"), near_node, Sensor("acc3", 19.0, noise_g=0.004))
    out = tmp_path_factory.mktemp("lab") / "sensors"
    truth = generate_campaign(
        out, seed=9, runs_per_configuration=1, configurations={"no_washer": 1.36}, sensors=sensors
    )
    return out, truth, sensors


def test_each_sensor_sees_every_mode_at_its_own_shape_value(three_sensors, no_washer):
    """One hit, three sensors: the reference accelerometer, one near a node of mode 1
    (x0.05) and one near the far end. Each mode's band amplitude relative to the
    accelerometer's is the ratio of that mode's shape values at the two points (mode 1
    within 1 %: noise and leakage are < 1e-3 of the near-node sensor's mode 1; mode 2
    within 2 %)."""
    out, truth, sensors = three_sensors
    setup, _ = no_washer
    mode = setup.mode
    header, data = _read(out / "no_washer" / "run01.txt")
    assert header[3] == "Time (s)\tForce (lbf)\tacc1 (g)\tacc2 (g)\tacc3 (g)"
    channels = truth["configurations"]["no_washer"]["channels"]
    f1, f2 = mode.frequency_hz, mode.higher_modes[0].frequency_hz
    for column, sensor in enumerate(sensors[1:], start=3):
        x = sensor.position_in
        shape_1 = np.interp(x, mode.x_in, mode.shape_in) / mode.accelerometer_participation
        shape_2 = (
            np.interp(x, mode.x_in, mode.higher_modes[0].shape_in)
            / mode.higher_modes[0].accelerometer_participation
        )
        ratio_1 = _band_rms(data[:, column], f1 - 6, f1 + 6) / _band_rms(data[:, 2], f1 - 6, f1 + 6)
        ratio_2 = _band_rms(data[:, column], f2 - 10, f2 + 10) / _band_rms(data[:, 2], f2 - 10, f2 + 10)
        assert ratio_1 == pytest.approx(abs(shape_1), rel=0.01)
        assert ratio_2 == pytest.approx(abs(shape_2), rel=0.02)
        assert channels[sensor.name]["participation"] / mode.accelerometer_participation == pytest.approx(
            shape_1
        )
    assert abs(channels["acc2"]["participation"] / mode.accelerometer_participation) == pytest.approx(0.05)
    # each sensor its own noise: before the hit, noise alone at each one's floor (25 samples: +-40 %)
    assert np.std(data[:25, 4]) == pytest.approx(0.004, rel=0.4)
    assert np.std(data[:25, 3]) == pytest.approx(0.002, rel=0.4)
    assert abs(np.corrcoef(data[:25, 2], data[:25, 3])[0, 1]) < 0.6


def test_multi_sensor_columns_take_the_input_contracts_roles(three_sensors):
    """Every sensor column is a response by the ASCII reader's column-name rule, and
    campaign.yaml names them under ``response: {channels: [...]}``."""
    from workflow.io.record_rules import column_role

    out, _, sensors = three_sensors
    header, _ = _read(out / "no_washer" / "run01.txt")
    names = header[3].split("\t")
    assert [column_role(name) for name in names] == ["time", "force", "response", "response", "response"]
    meta = yaml.safe_load((out / "campaign.yaml").read_text())
    assert meta["response"] == {"quantity": "acceleration", "unit": "g", "channels": ["acc1", "acc2", "acc3"]}
    assert "mode_hz" in meta and "modes_hz" not in meta
    with pytest.raises(ValueError, match="must contain 'acc'"):
        generate_campaign(out.parent / "bad", sensors=(Sensor("vel1"),))
    with pytest.raises(ValueError, match="off the beam"):
        generate_campaign(out.parent / "bad", sensors=(Sensor("acc", 30.0),))


def test_positions_with_a_mode1_gain(no_washer):
    setup, _ = no_washer
    mode = setup.mode
    for gain in (0.05, 0.5, 1.0, 2.0):
        positions = positions_with_mode1_gain(mode, gain)
        assert positions.size >= 2
        ratios = [
            abs(np.interp(x, mode.x_in, mode.shape_in) / mode.accelerometer_participation) for x in positions
        ]
        assert np.allclose(ratios, gain, rtol=1e-9)
    # the free ends see mode 1 about 3 times the accelerometer: nothing sees it 8 times
    assert positions_with_mode1_gain(mode, 8.0).size == 0


# ---------------------------------------------------- two modes, MAT files


def test_mat_runs_hold_the_ascii_runs_numbers(tmp_path):
    sensors = (Sensor("acc1"), Sensor("acc2", 2.0), Sensor("acc3", 12.0))
    kwargs = dict(seed=13, runs_per_configuration=1, configurations={"hit": None}, sensors=sensors)
    generate_campaign(tmp_path / "txt", **kwargs)
    generate_campaign(tmp_path / "mat", file_format="mat", **kwargs)
    generate_campaign(tmp_path / "mat2", file_format="mat", **kwargs)
    scipy_io = pytest.importorskip("scipy.io")
    mat = scipy_io.loadmat(tmp_path / "mat" / "hit" / "run01.mat")
    _, data = _read(tmp_path / "txt" / "hit" / "run01.txt")
    for column, name in enumerate(["t", "force", "acc1", "acc2", "acc3"]):
        # the ASCII export prints 10 significant digits (time: 6 decimals)
        assert np.allclose(mat[name].ravel(), data[:, column], rtol=1e-9, atol=1e-6 if name == "t" else 1e-12)
    assert (tmp_path / "mat" / "hit" / "run01.mat").read_bytes() == (
        tmp_path / "mat2" / "hit" / "run01.mat"
    ).read_bytes()
    assert 'files: "hit/*.mat"' in (tmp_path / "mat" / "campaign.yaml").read_text()


def test_joint_on_two_modes_writes_a_truth_per_mode(tmp_path):
    out = tmp_path / "two"
    truth = generate_campaign(
        out,
        seed=21,
        runs_per_configuration=2,
        configurations={"joint": 1.36},
        sensors=(Sensor("acc1"), Sensor("acc2", 18.0)),
        nonlinear_modes=2,
    )
    meta = yaml.safe_load((out / "campaign.yaml").read_text())
    assert len(meta["modes_hz"]) == 2 and "mode_hz" not in meta
    mode2 = json.loads(truth_path(out, 2).read_text())
    assert truth["mode"] == 1 and mode2["mode"] == 2
    assert meta["modes_hz"] == [round(truth["mode_hz"]), round(mode2["mode_hz"])]
    assert 300 < mode2["mode_hz"] < 360
    v = np.array(mode2["velocity_amplitude_in_s"])
    curves = mode2["configurations"]["joint"]["channels"]["acc1"]
    zeta, f = np.array(curves["zeta"]), np.array(curves["damped_frequency_hz"])
    # the patches act on mode 2 too: above its linear damping, micro-slip's damping
    # rises and its frequency falls with amplitude
    low, high = np.argmin(np.abs(v - 0.01)), np.argmin(np.abs(v - 3.0))
    assert zeta[low] == pytest.approx(SETTINGS.higher_mode_zeta, rel=1e-3)
    assert zeta[high] > 1.02 * zeta[low] and f[high] < f[low] * (1 - 1e-4)
    assert len(mode2["configurations"]["joint"]["runs"]) == 2
    with pytest.raises(ValueError, match="two modes"):
        generate_campaign(tmp_path / "bad", joint="dahl", nonlinear_modes=2)


def test_one_hit_three_sensor_mat_file(tmp_path):
    """Issue 32's record: one 12.8 kHz, 5 s hit in one MAT 5 file with ``t`` and three
    acceleration variables, campaign.yaml asking for every mode and naming the channels."""
    scipy_io = pytest.importorskip("scipy.io")
    out = tmp_path / "hit"
    generate_one_hit(out)
    assert sorted(p.name for p in (out / "hit").iterdir()) == ["run01.mat"]
    mat = scipy_io.loadmat(out / "hit" / "run01.mat")
    assert {"t", "force", "acc1", "acc2", "acc3"} <= set(mat)
    assert mat["t"].size == 64000 and np.allclose(np.diff(mat["t"].ravel()), 1 / 12800)
    meta = yaml.safe_load((out / "campaign.yaml").read_text())
    assert meta["modes_hz"] == "auto" and meta["sample_rate_hz"] == 12800
    assert meta["response"]["channels"] == ["acc1", "acc2", "acc3"]
    assert truth_path(out, 2).exists()

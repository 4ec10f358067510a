"""Checks of the virtual lab: file format, determinism, and the truth's physics."""

import json

import numpy as np
import pytest
import yaml

from workflow.lab import virtual_lab as vl

SETTINGS = vl.LabSettings()


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("lab") / "demo"
    truth = vl.generate_campaign(out, seed=7, runs_per_configuration=2)
    return out, truth


@pytest.fixture(scope="module")
def no_washer():
    return vl.setup_configuration("no_washer", 1.36, SETTINGS)


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
    saved = json.loads(vl.truth_path(out).read_text())
    assert vl.truth_path(out).parent == out.parent
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
    campaign = pytest.importorskip("workflow.io.campaign")
    out, _ = demo
    meta = campaign.load_campaign(out)
    runs = campaign.list_runs(out, meta)
    assert len(runs) == 6
    record = campaign.read_run(out, runs[0], meta)
    assert record.n_samples == 8192 and record.pretrigger_samples == 25


def test_deterministic_for_a_seed(tmp_path):
    kwargs = dict(seed=11, runs_per_configuration=2, configurations={"beam": None})
    vl.generate_campaign(tmp_path / "a", **kwargs)
    vl.generate_campaign(tmp_path / "b", **kwargs)
    vl.generate_campaign(tmp_path / "c", **{**kwargs, "seed": 12})
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


def test_slow_flow_matches_direct_integration(no_washer):
    setup, curves = no_washer
    table = vl.mode_table(setup, curves, SETTINGS, "patches", None, None)
    jm = setup.joint_modes
    w0 = setup.omega0_rad_s
    a0 = 3.0 / (abs(jm.mode.accelerometer_participation) * w0)  # 3 in/s
    dt = 2 * np.pi / w0 / 200
    n = int(0.4 / dt)
    xi = vl.integrate_patch_ringdown(
        a0, w0, SETTINGS.zeta0, jm.slip_per_xi, jm.patches.stiffness_lbf_in, jm.patches.slip_force_lbf, dt, n
    )
    t = np.arange(n) * dt
    peaks = np.flatnonzero((xi[1:-1] > xi[:-2]) & (xi[1:-1] >= xi[2:])) + 1
    # parabolic refinement of each peak
    y0, y1, y2 = xi[peaks - 1], xi[peaks], xi[peaks + 1]
    shift = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
    t_peak = t[peaks] + shift * dt
    a_peak = y1 - 0.25 * (y0 - y2) * shift
    a_slow, phase = vl.ModeTable.evolve(table, a0, t_peak)
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
    base = vl.truth_curves(setup, vl.mode_table(setup, curves, SETTINGS, "dahl", None, None), v)
    quad = vl.truth_curves(
        setup, vl.mode_table(setup, curves, SETTINGS, "dahl", "quadratic_damping", size), v
    )
    added = quad[0] - base[0]
    # zeta added grows linearly with amplitude: size at the reference velocity
    # (2 %: the modal amplitude of a velocity differs by the ~1 % frequency shift)
    at_ref = np.interp(np.log(vl.REFERENCE_VELOCITY_IN_S), np.log(v), added)
    assert at_ref == pytest.approx(size, rel=0.02)
    assert np.polyfit(np.log(v), np.log(added), 1)[0] == pytest.approx(1.0, abs=0.02)
    # only the damped frequency's factor sqrt(1 - zeta^2) changes, by < zeta^2 / 2
    assert np.allclose(quad[1], base[1], rtol=0.6 * np.max(quad[0]) ** 2)


@pytest.mark.parametrize("size", [0.005, 0.02])
def test_stiffness_nonlinearity_shifts_frequency_only(no_washer, size):
    setup, curves = no_washer
    v = np.logspace(-1, 1, 21)
    base = vl.truth_curves(setup, vl.mode_table(setup, curves, SETTINGS, "dahl", None, None), v)
    soft = vl.truth_curves(
        setup, vl.mode_table(setup, curves, SETTINGS, "dahl", "stiffness_nonlinearity", size), v
    )
    ratio = np.interp(np.log(vl.REFERENCE_VELOCITY_IN_S), np.log(v), soft[1] / base[1])
    assert ratio == pytest.approx(1 - size, abs=0.1 * size)
    assert np.all(np.diff(soft[1] / base[1]) < 0)
    # no dissipation added: damping changes only through omega in zeta's definition
    assert np.allclose(soft[0], base[0], rtol=3 * size)


def test_run_drift_shifts_damping_with_run_order(tmp_path):
    truth = vl.generate_campaign(
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
    truth = vl.generate_campaign(
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
    with pytest.raises(ValueError, match="joint='dahl'"):
        vl.generate_campaign(tmp_path / "bad", effect="second_mode")

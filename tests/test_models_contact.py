"""Checks of the friction contact models against closed forms."""

import numpy as np
import pytest
import scipy.integrate

from workflow.models import contact, friction


def _cycle(amplitude, n=4000):
    theta = np.linspace(0, 2 * np.pi, n + 1)
    return amplitude * np.cos(theta), theta


def _drive_jenkins(x, k, fs):
    force = np.zeros(x.size)
    f = 0.0
    for i in range(1, x.size):
        f = contact.jenkins_force_update(f, x[i] - x[i - 1], k, fs)
        force[i] = f
    return force


@pytest.mark.parametrize("amplitude", [0.5e-4, 2e-4, 1e-3])
def test_jenkins_time_domain_matches_closed_form(amplitude):
    k, fs = 1e6, 50.0  # onset at 5e-5 in
    x, theta = _cycle(amplitude)
    # two cycles: the first reaches the steady loop, the second is measured
    x2 = np.concatenate([x, x[1:]])
    force = _drive_jenkins(x2, k, fs)[x.size - 1 :]
    work = np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(x))
    expected = contact.jenkins_dissipation_per_cycle(amplitude, k, fs)
    # trapezoid loop integration error is far below 0.5 % with 4000 steps
    assert work == pytest.approx(expected, rel=5e-3, abs=1e-6 * fs * amplitude)
    # first-harmonic in-phase stiffness by quadrature
    k_eq = np.trapezoid(force * np.cos(theta), theta) / (np.pi * amplitude)
    assert k_eq == pytest.approx(contact.jenkins_secant_stiffness(amplitude, k, fs), rel=5e-3)


def test_jenkins_closed_form_limits():
    k, fs = 2e6, 10.0
    a = np.logspace(-7, -3, 50)
    d = contact.jenkins_dissipation_per_cycle(a, k, fs)
    assert np.all(d >= 0)
    assert np.all(d[a < fs / k] == 0)
    assert np.all(np.diff(d) >= 0)
    k_eq = contact.jenkins_secant_stiffness(a, k, fs)
    assert np.allclose(k_eq[a < fs / k], k)
    assert np.all(np.diff(k_eq) <= 1e-9 * k)
    # macro-slip: the loop tends to a rectangle, D -> 4 Fs A
    assert d[-1] / (4 * fs * a[-1]) > 0.99


def test_single_uniform_patch_equals_jenkins():
    # patch model with one patch of uniform pressure is exactly one Jenkins element
    s, k, fs = np.array([0.02]), np.array([3e5]), np.array([4.0])
    a = np.logspace(-5, -1, 30)
    d, loss = contact.patch_describing_function(a, s, k, fs)
    assert np.allclose(d, 4 * fs * np.maximum(s * a - fs / k, 0), rtol=1e-12, atol=0)
    assert np.allclose(loss, s**2 * (k - contact.jenkins_secant_stiffness(s * a, k, fs)))


def test_patches_preload_and_pressure():
    params = contact.JointParameters()
    assert params.preload_lbf == pytest.approx(85 / (0.2 * 0.25))
    for area in (1.36, 0.66, 0.17):
        p = contact.contact_patches(area, params)
        assert p.area_in2.sum() == pytest.approx(area, rel=1e-9)
        assert np.sum(p.pressure_psi * p.area_in2) == pytest.approx(params.preload_lbf, rel=1e-9)
        r = np.hypot(p.x_rel_in, p.y_in)
        assert np.all(np.diff(p.pressure_psi[np.argsort(r)]) <= 1e-9)  # decays from the bolt
    # smaller area: higher pressure everywhere, later slip onset
    # (a patch starts to slide at its Coulomb limit over its stuck stiffness)
    patches = [contact.contact_patches(a, params) for a in (1.36, 0.66, 0.17)]
    onset = [np.min(p.slip_force_lbf / p.stiffness_lbf_in) for p in patches]
    assert onset[0] < onset[1] < onset[2]


def dahl_force_update(force, displacement_increment, sigma, coulomb_force):
    """Advance the Dahl force over a monotone displacement increment (exact): the
    time-domain reference for the closed-form dissipation.

    On a branch of constant velocity sign ``d``, ``dF/dx = sigma (1 - d F / Fc)``
    integrates to ``F = d Fc + (F0 - d Fc) exp(-sigma |dx| / Fc)``.
    """
    direction = np.sign(displacement_increment)
    target = direction * coulomb_force
    return target + (force - target) * np.exp(-sigma * np.abs(displacement_increment) / coulomb_force)


def test_dahl_dissipation_formula_by_time_integration():
    sigma, fc = 2133.4, 38.0
    for amplitude in (0.005, 0.02, 0.1):
        # the memory of the start decays as exp(-4 sigma A / Fc) per cycle:
        # 15 cycles make it negligible even for the smallest amplitude
        n = 4000
        x, _ = _cycle(amplitude, n)
        x = np.concatenate([x[:-1]] * 15 + [x[:1]])
        force = np.zeros(x.size)
        for i in range(1, x.size):
            force[i] = dahl_force_update(force[i - 1], x[i] - x[i - 1], sigma, fc)
        last = slice(14 * n, 15 * n + 1)
        work = np.sum(0.5 * (force[last][1:] + force[last][:-1]) * np.diff(x[last]))
        assert work == pytest.approx(friction.dahl_dissipation_per_cycle(amplitude, sigma, fc), rel=2e-3)
        # loop saturates at +-Fc and never exceeds it
        assert np.max(np.abs(force)) <= fc * (1 + 1e-12)
        assert np.max(force[last]) == pytest.approx(fc * np.tanh(sigma * amplitude / fc), rel=1e-3)


def test_dahl_ode_and_secant_stiffness():
    sigma, fc, amplitude, omega = 50.0, 2.0, 0.3, 2 * np.pi

    def rhs(t, z):
        v = -amplitude * omega * np.sin(omega * t)
        return [v - sigma * abs(v) / fc * z[0]]

    t = np.linspace(0, 4, 8001)
    sol = scipy.integrate.solve_ivp(rhs, (0, 4), [0.0], t_eval=t, rtol=1e-10, atol=1e-12, max_step=1e-3)
    f = sigma * sol.y[0]
    last = t >= 3
    theta = omega * t[last]
    k_eq = np.trapezoid(f[last] * np.cos(theta), theta) / (np.pi * amplitude)
    assert k_eq == pytest.approx(contact.dahl_secant_stiffness(amplitude, sigma, fc), rel=2e-3)
    assert np.max(np.abs(f)) < fc
    # small amplitude: the Dahl element is a spring of stiffness sigma
    assert contact.dahl_secant_stiffness(1e-9, sigma, fc) == pytest.approx(sigma, rel=1e-6)


def test_micro_slip_power_law_and_area_ordering():
    params = contact.JointParameters()
    v = np.logspace(-2, 0, 9)  # accelerometer velocity amplitude, in/s
    zeta = {}
    for area in (1.36, 0.66, 0.17):
        jm = contact.joint_first_mode(area, params)
        a = v / (abs(jm.mode.accelerometer_participation) * jm.omega_rad_s)
        d, loss = contact.patch_describing_function(
            a, jm.slip_per_xi, jm.patches.stiffness_lbf_in, jm.patches.slip_force_lbf
        )
        assert np.all(d >= 0) and np.all(loss >= 0)
        zeta[area], omega = contact.equivalent_damping(a, jm.omega_rad_s, 0.0, d, loss)
        if area == 1.36:
            # friction damping grows over two decades with log-log slope below 1
            slope = np.polyfit(np.log(v[2:]), np.log(zeta[area][2:]), 1)[0]
            assert 0.1 < slope < 0.9
            assert np.all(np.diff(zeta[area]) > 0)
            assert np.all(np.diff(omega) < 0)  # frequency loss grows with amplitude
    assert np.all(zeta[1.36] > zeta[0.66]) and np.all(zeta[0.66] >= zeta[0.17])

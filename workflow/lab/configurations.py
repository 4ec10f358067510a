"""Virtual lab configurations: each bearing area's modes, joint curves and averaged mode tables.

The specimen's first mode is nonlinear (joint friction); it is simulated with
the averaged (slow-flow) equations ``da/dt = -zeta(a) omega(a) a``,
``dtheta/dt = omega_d(a)`` using the describing-function damping and
frequency of :mod:`workflow.models.contact`.  These are autonomous, so time and phase
are tabulated once per joint as functions of ``ln a`` (quadrature) and every
run is an interpolation: fast, and accurate for this weak nonlinearity. The contact
patches may carry a second mechanism (a velocity-squared loss, a stiffness term) and
may act on mode 2 as well (:func:`higher_mode_table`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import scipy.optimize

from workflow.lab.layout import PAPER_CONFIGURATIONS
from workflow.lab.pulse import half_sine_response
from workflow.lab.settings import REFERENCE_VELOCITY_IN_S, LabSettings, RunPhysics
from workflow.models import contact, friction, specimen

__all__ = [
    "higher_mode_response",
    "ModeTable",
    "nonlinear_mode_response",
    "JointSetup",
    "setup_configuration",
    "scale_slip_forces",
    "joint_curves",
    "run_dahl_coulomb",
    "mode_table",
    "truth_curves",
    "averaged_mode_response",
    "reference_modal_amplitude",
    "effect_coefficients",
    "ModeResponse",
    "higher_mode_table",
]


# ------------------------------------------------------- nonlinear mode 1


@dataclass(frozen=True)
class ModeTable:
    """Averaged dynamics of the nonlinear mode on a log-amplitude grid.

    ``log_a`` decreasing from the largest amplitude; ``time_s`` is the time to
    decay from ``a_max`` to ``a`` and ``phase_rad`` the phase accumulated meanwhile.
    """

    log_a: np.ndarray
    zeta: np.ndarray
    omega_rad_s: np.ndarray
    time_s: np.ndarray
    phase_rad: np.ndarray

    @classmethod
    def build(cls, amplitude, zeta, omega_rad_s) -> ModeTable:
        order = np.argsort(amplitude)[::-1]
        log_a = np.log(np.asarray(amplitude)[order])
        z, w = np.asarray(zeta)[order], np.asarray(omega_rad_s)[order]
        z = np.minimum(z, 0.5)  # beyond any physical joint; keeps sqrt(1 - z^2) real
        rate = z * w  # -d ln a / dt
        wd = w * np.sqrt(1 - z**2)
        d = -np.diff(log_a)
        time = np.concatenate([[0.0], np.cumsum(0.5 * d * (1 / rate[1:] + 1 / rate[:-1]))])
        phase = np.concatenate([[0.0], np.cumsum(0.5 * d * (wd[1:] / rate[1:] + wd[:-1] / rate[:-1]))])
        return cls(log_a, z, w, time, phase)

    def evolve(self, a0, t_s):
        """Amplitude and phase increment ``t_s`` seconds after amplitude ``a0``.

        Below the grid the decay continues at the smallest amplitude's rate.
        """
        t0 = np.interp(np.log(a0), self.log_a[::-1], self.time_s[::-1])
        p0 = np.interp(np.log(a0), self.log_a[::-1], self.phase_rad[::-1])
        tt = t0 + np.asarray(t_s, dtype=float)
        log_a = np.interp(tt, self.time_s, self.log_a)
        phase = np.interp(tt, self.time_s, self.phase_rad)
        beyond = tt > self.time_s[-1]
        rate = self.zeta[-1] * self.omega_rad_s[-1]
        extra = np.where(beyond, tt - self.time_s[-1], 0.0)
        log_a = log_a - rate * extra
        phase = phase + self.omega_rad_s[-1] * np.sqrt(1 - self.zeta[-1] ** 2) * extra
        return np.exp(log_a), phase - p0

    def at(self, a):
        """Damping ratio and undamped frequency (rad/s) at amplitude ``a``."""
        la = np.log(a)
        return (
            np.interp(la, self.log_a[::-1], self.zeta[::-1]),
            np.interp(la, self.log_a[::-1], self.omega_rad_s[::-1]),
        )


def nonlinear_mode_response(t_s, table: ModeTable, omega0_rad_s, zeta0, modal_peak, duration_s):
    """Modal coordinate acceleration of the nonlinear mode after a half-sine pulse.

    During the pulse (a fraction of a cycle) the mode is linear with its stuck
    properties; afterwards the slow flow from the pulse-end state.
    """
    t = np.asarray(t_s, dtype=float)
    _, _, acc = half_sine_response(t, omega0_rad_s, zeta0, modal_peak, duration_s)
    q1, v1, _ = half_sine_response(np.array([duration_s]), omega0_rad_s, zeta0, modal_peak, duration_s)
    # amplitude and phase at the pulse end, with the amplitude's own frequency
    a0 = np.hypot(q1[0], v1[0] / omega0_rad_s)
    for _ in range(3):
        _, w = table.at(a0)
        a0 = np.hypot(q1[0], v1[0] / w)
    theta0 = np.arctan2(-v1[0] / w, q1[0])
    after = t > duration_s
    a, dphase = table.evolve(a0, t[after] - duration_s)
    zeta, w = table.at(a)
    wd = w * np.sqrt(1 - zeta**2)
    theta = theta0 + dphase
    xi = a * np.cos(theta)
    xi_dot = -a * (wd * np.sin(theta) + zeta * w * np.cos(theta))
    acc = acc.copy()
    acc[after] = -(w**2) * xi - 2 * zeta * w * xi_dot
    return acc


# --------------------------------------------------------- configurations


@dataclass
class JointSetup:
    """One configuration's linear modes and nonlinear first-mode description."""

    name: str
    bearing_area_in2: float | None
    joint_modes: contact.JointModes
    omega0_rad_s: float
    dahl_sigma: float
    dahl_coulomb: float

    @property
    def mode(self) -> specimen.FirstMode:
        return self.joint_modes.mode


def _amplitude_grid(accelerometer_participation, omega0, points):
    """Modal amplitudes spanning 1e-5 .. 300 in/s at the accelerometer."""
    phi = abs(accelerometer_participation)
    return np.logspace(np.log10(1e-5 / (phi * omega0)), np.log10(300.0 / (phi * omega0)), points)


def _patch_curves(setup: JointSetup, a):
    p = setup.joint_modes.patches
    return contact.patch_describing_function(
        a, setup.joint_modes.slip_per_xi, p.stiffness_lbf_in, p.slip_force_lbf
    )


def _dahl_curves(a, sigma, coulomb):
    d = friction.dahl_dissipation_per_cycle(a, sigma, coulomb)
    loss = sigma - contact.dahl_secant_stiffness(a, sigma, coulomb)
    return d, loss


def _fit_dahl(setup: JointSetup, zeta0, patch_d, patch_loss, a):
    """Dahl (modal sigma, Fc) matching the patch model's damping over 0.1-10 in/s.

    Makes the Dahl-joint demo look like the same specimen (same damping level
    and area ordering), with the single-state model's shape. The rest stiffness is
    bounded by the stuck contact's (the patches' stiffness in modal units, 3-4 % of
    ``omega0^2``): a Dahl joint cannot be stiffer than the contact it stands for, and
    where the patches stay in pre-sliding over the fitted range their damping fixes
    only ``sigma^2 / Fc``, so without the bound the fit ends anywhere along that valley
    (at up to 3.5 ``omega0^2`` at 0.7 in^2, a negative stiffness outside the joint,
    and at a point that moved with the machine's floating point).
    """
    phi = abs(setup.mode.accelerometer_participation)
    v = phi * setup.omega0_rad_s * a
    sel = (v > 0.1) & (v < 10.0)
    target, _ = contact.equivalent_damping(a[sel], setup.omega0_rad_s, zeta0, patch_d[sel], patch_loss[sel])

    def residual(log_p):
        sigma, fc = np.exp(log_p)
        d, loss = _dahl_curves(a[sel], sigma, fc)
        z, _ = contact.equivalent_damping(a[sel], setup.omega0_rad_s, zeta0, d, loss)
        return np.log(z) - np.log(target)

    # starting point: sigma a tenth of the stuck contact stiffness, Fc at the
    # modal force of the mid-range amplitude
    s = setup.joint_modes.slip_per_xi
    k = setup.joint_modes.patches.stiffness_lbf_in
    contact_stiffness = float(np.sum(s**2 * k))
    sigma0 = 0.1 * contact_stiffness
    fc0 = sigma0 * np.median(a[sel])
    fit = scipy.optimize.least_squares(
        residual, np.log([sigma0, fc0]), bounds=(np.log([1.0, 1e-9]), np.log([contact_stiffness, 1e6]))
    )
    return tuple(float(x) for x in np.exp(fit.x))


@functools.lru_cache(maxsize=16)
def _configuration_physics(area_in2: float, settings: LabSettings):
    """Modes, describing-function curves and Dahl fit of one bearing area (cached:
    campaigns generated in one process share them)."""
    jm = contact.joint_first_mode(area_in2, settings.joint)
    setup = JointSetup("", area_in2, jm, jm.omega_rad_s, 0.0, 0.0)
    a = _amplitude_grid(jm.mode.accelerometer_participation, setup.omega0_rad_s, settings.amplitude_points)
    d, loss = _patch_curves(setup, a)
    sigma, coulomb = _fit_dahl(setup, settings.zeta0, d, loss, a)
    for array in (a, d, loss):
        array.setflags(write=False)
    return jm, sigma, coulomb, (a, d, loss)


def setup_configuration(name, bearing_area_in2, settings: LabSettings) -> tuple[JointSetup, tuple]:
    """Build a configuration's modes and curves ``(amplitude, dissipation, loss)``.

    A configuration without an area gets the paper's no-washer contact.
    """
    area = bearing_area_in2 if bearing_area_in2 is not None else PAPER_CONFIGURATIONS["no_washer"]
    # the nominal physics does not depend on the run-to-run spreads: one cache entry
    nominal = replace(settings, frequency_spread=0.0, damping_spread=0.0, slip_force_spread=0.0)
    jm, sigma, coulomb, curves = _configuration_physics(float(area), nominal)
    return JointSetup(name, bearing_area_in2, jm, jm.omega_rad_s, sigma, coulomb), curves


def scale_slip_forces(amplitude, dissipation, stiffness_loss, factor):
    """Describing-function curves of a joint whose slip forces are all multiplied by ``factor``.

    Exact for rate-independent joints whose elements slip at a force ``Fs`` over a
    stiffness (Jenkins patches, Dahl): the loop at amplitude ``a`` with ``c Fs`` is the
    loop at ``a / c`` with ``Fs`` scaled by ``c`` in force and displacement, so
    ``D_c(a) = c^2 D(a / c)`` and ``loss_c(a) = loss(a / c)``. Interpolated in
    ``ln a`` on the (fine, logarithmic) amplitude grid.

    Parameters
    ----------
    amplitude : ndarray
        Modal amplitude grid, increasing.
    dissipation : ndarray
        Energy dissipated per cycle at each amplitude (modal units).
    stiffness_loss : ndarray
        Modal stiffness loss at each amplitude (units of omega^2, 1/s^2).
    factor : float
        Slip-force multiplier ``c`` (> 0).

    Returns
    -------
    dissipation, stiffness_loss : ndarray
    """
    if factor == 1.0:
        return dissipation.copy(), stiffness_loss.copy()
    log_a = np.log(amplitude)
    shifted = log_a - np.log(factor)
    return (
        factor**2 * np.interp(shifted, log_a, dissipation),
        np.interp(shifted, log_a, stiffness_loss),
    )


def joint_curves(
    setup: JointSetup,
    patch_curves,
    settings: LabSettings,
    joint,
    effect,
    effect_size,
    run_fraction=0.0,
    slip_force_factor=1.0,
):
    """Dissipation per cycle and stiffness loss of the whole mode-1 joint model.

    ``run_fraction`` in [0, 1] is the run's position in the campaign (drift);
    ``slip_force_factor`` the run's random change of every slip force.
    """
    a, patch_d, patch_loss = patch_curves
    if joint == "patches":
        d, loss = scale_slip_forces(a, patch_d, patch_loss, slip_force_factor)
    else:
        d, loss = _dahl_curves(
            a, setup.dahl_sigma, run_dahl_coulomb(setup, effect, effect_size, run_fraction, slip_force_factor)
        )
    w0 = setup.omega0_rad_s
    a_ref = reference_modal_amplitude(setup)
    quadratic, cubic = effect_coefficients(setup, effect, effect_size)
    if effect == "quadratic_damping":
        # c2 xi'|xi'| dissipates 8/3 c2 w^2 a^3 per cycle: zeta = 4 c2 a / (3 pi)
        d = d + 8.0 / 3.0 * quadratic * w0**2 * a**3
    elif effect == "stiffness_nonlinearity":
        r2 = (a / a_ref) ** 2
        ratio = 1.0 - 2.0 * effect_size * r2 / (1.0 + r2)
        loss = loss + w0**2 * (1.0 - ratio**2)
    elif effect == "cubic_stiffness":
        # k3 xi^3's in-phase first harmonic is 3/4 k3 a^3: omega^2 gains 3/4 k3 a^2
        loss = loss - 0.75 * cubic * a**2
    return d, loss


def reference_modal_amplitude(setup: JointSetup) -> float:
    """Mode 1's modal amplitude at the reference velocity amplitude at the accelerometer."""
    return REFERENCE_VELOCITY_IN_S / (abs(setup.mode.accelerometer_participation) * setup.omega0_rad_s)


def effect_coefficients(setup: JointSetup, effect, effect_size) -> tuple[float, float]:
    """Modal coefficients ``(c2, k3)`` of an added ``c2 xi'|xi'|`` and ``k3 xi^3``.

    ``c2`` (1/in) gives the damping ratio ``effect_size`` at the reference amplitude
    (``zeta = 4 c2 a / (3 pi)``); ``k3`` (1/(in^2 s^2)) changes the frequency by the
    fraction ``effect_size`` there (``omega^2 = omega0^2 + 3/4 k3 a^2``). Zero for the
    effects that are neither.
    """
    w0 = setup.omega0_rad_s
    a_ref = reference_modal_amplitude(setup)
    quadratic = effect_size * 3 * np.pi / (4 * a_ref) if effect == "quadratic_damping" else 0.0
    cubic = (
        4.0 / 3.0 * w0**2 * ((1.0 + effect_size) ** 2 - 1.0) / a_ref**2
        if effect == "cubic_stiffness"
        else 0.0
    )
    return quadratic, cubic


def run_dahl_coulomb(
    setup: JointSetup, effect, effect_size, run_fraction=0.0, slip_force_factor=1.0
) -> float:
    """The Dahl joint's modal friction limit ``Fc`` in one run (drift and random change)."""
    coulomb = setup.dahl_coulomb * slip_force_factor
    if effect == "run_drift":
        coulomb = coulomb * (1.0 - effect_size * run_fraction)
    return coulomb


def mode_table(
    setup, patch_curves, settings, joint, effect, effect_size, run_fraction=0.0, run: RunPhysics | None = None
):
    """Averaged dynamics of one run's mode 1 (``run``: its own frequency, damping and
    slip force; default the configuration's nominal physics)."""
    run = run if run is not None else RunPhysics(zeta0=settings.zeta0)
    a = patch_curves[0]
    d, loss = joint_curves(
        setup, patch_curves, settings, joint, effect, effect_size, run_fraction, run.slip_force_factor
    )
    omega0 = setup.omega0_rad_s * run.frequency_factor
    zeta, omega = contact.equivalent_damping(a, omega0, run.zeta0, d, loss)
    _, cubic = effect_coefficients(setup, effect, effect_size)
    if cubic:
        # Energy balance: a cubic spring's energy at amplitude a grows as
        # (omega^2 + k3 a^2 / 4) a da, not omega^2 a da (omega^2 holds only 3/4 k3 a^2)
        zeta = zeta * omega**2 / (omega**2 + 0.25 * cubic * a**2)
    return ModeTable.build(a, zeta, omega)


def truth_curves(setup: JointSetup, table: ModeTable, velocity_in_s, participation=None):
    """True damping ratio and damped frequency vs velocity amplitude at a sensor.

    ``participation``: the mode's shape at the sensor (default mode 1 at the accelerometer).
    """
    phi = abs(setup.mode.accelerometer_participation if participation is None else participation)
    a_grid = np.exp(table.log_a[::-1])
    v_grid = phi * table.omega_rad_s[::-1] * a_grid
    a = np.exp(np.interp(np.log(velocity_in_s), np.log(v_grid), np.log(a_grid)))
    zeta, w = table.at(a)
    return zeta, w * np.sqrt(1 - zeta**2) / (2 * np.pi)


ModeResponse = Callable[[np.ndarray, float, float], np.ndarray]
"""A nonlinear mode's modal acceleration at times from the pulse start, given the peak
modal force and the pulse duration."""


def averaged_mode_response(setup: JointSetup, table: ModeTable, run: RunPhysics) -> ModeResponse:
    """Mode 1 from the run's averaged table (slow flow)."""
    omega0 = setup.omega0_rad_s * run.frequency_factor

    def response(tau, modal_peak, duration):
        return nonlinear_mode_response(tau, table, omega0, run.zeta0, modal_peak, duration)

    return response


# ------------------------------------------------------- the joint on mode 2


@functools.lru_cache(maxsize=16)
def _higher_mode_patch_curves(area_in2: float, settings: LabSettings, index: int):
    """Amplitude grid and the contact patches' describing function on higher flexible
    mode ``index`` (0 = mode 2), through that mode's own interface slip (cached)."""
    jm, _, _, _ = _configuration_physics(area_in2, settings)
    m = jm.mode.higher_modes[index]
    _, strip = contact.strip_springs(jm.patches)
    slip = m.slip_per_xi[:, strip]
    omega = 2 * np.pi * m.frequency_hz
    a = _amplitude_grid(m.accelerometer_participation, omega, settings.amplitude_points)
    p = jm.patches
    d, loss = contact.patch_describing_function(a, slip, p.stiffness_lbf_in, p.slip_force_lbf)
    for array in (a, d, loss):
        array.setflags(write=False)
    return a, d, loss


def higher_mode_table(setup: JointSetup, settings: LabSettings, index: int, run: RunPhysics | None = None):
    """Averaged dynamics of higher flexible mode ``index`` (0 = mode 2) with the contact
    patches acting through its own slip, linear damping ``higher_mode_zeta``.

    The modes are taken as uncoupled (a modal Iwan joint per mode): each mode's slip
    amplitude is its own, the other modes' slip at other frequencies being left out.
    """
    run = run if run is not None else RunPhysics(zeta0=settings.zeta0)
    area = setup.bearing_area_in2 if setup.bearing_area_in2 is not None else PAPER_CONFIGURATIONS["no_washer"]
    nominal = replace(settings, frequency_spread=0.0, damping_spread=0.0, slip_force_spread=0.0)
    a, patch_d, patch_loss = _higher_mode_patch_curves(float(area), nominal, index)
    d, loss = scale_slip_forces(a, patch_d, patch_loss, run.slip_force_factor)
    omega0 = 2 * np.pi * setup.mode.higher_modes[index].frequency_hz * run.frequency_factor
    zeta, omega = contact.equivalent_damping(a, omega0, settings.higher_mode_zeta, d, loss)
    return ModeTable.build(a, zeta, omega)


def higher_mode_response(setup: JointSetup, settings: LabSettings, index: int, run: RunPhysics):
    table = higher_mode_table(setup, settings, index, run)
    omega0 = 2 * np.pi * setup.mode.higher_modes[index].frequency_hz * run.frequency_factor

    def response(tau, modal_peak, duration):
        return nonlinear_mode_response(tau, table, omega0, settings.higher_mode_zeta, modal_peak, duration)

    return response, table

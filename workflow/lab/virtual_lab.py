"""Virtual lab: simulated impact-hammer ring-down campaigns with known truth.

The specimen's first mode is nonlinear (joint friction); it is simulated with
the averaged (slow-flow) equations ``da/dt = -zeta(a) omega(a) a``,
``dtheta/dt = omega_d(a)`` using the describing-function damping and
frequency of :mod:`workflow.models.contact`.  These are autonomous, so time and phase
are tabulated once per joint as functions of ``ln a`` (quadrature) and every
run is an interpolation: fast, and accurate for this weak nonlinearity.
Higher flexible modes and the two rigid-body suspension modes (bounce and
pitch on the rubber tubing) respond linearly to the hammer pulse.

Runs of a configuration differ as in a real lab (``LabSettings.*_spread``, see
docs/virtual-lab.md): each run draws its own natural frequency, linear modal damping
and joint slip force, at random and independent of run order, and gets its own table.
For test campaigns, ``generate_campaign(integrator="time_domain")`` integrates the
joint's equation of motion in time (contact patches: :func:`patch_mode_response_time_domain`;
Dahl: :func:`workflow.models.ringdown.simulate_ringdown`) instead of the averaged equations, so that the discovery is not tested only on the
model it fits.

Sensors (:class:`Sensor`) stand at points of the beam and see every mode at its own
shape value there, each with its own noise; several sensors are columns of one run file
(or variables of one MAT file). The contact patches may carry a second mechanism (a
velocity-squared loss, a stiffness term) and may act on mode 2 as well.

The campaign folder follows ``campaign-format.md``; the truth is written
beside it as ``<campaign_dir>.truth.json`` (mode 2's as ``<campaign_dir>.mode2.truth.json``),
never inside.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numba
import numpy as np
import scipy.optimize

from workflow.lab.layout import PAPER_CONFIGURATIONS, run_name
from workflow.models import contact, friction, ringdown, specimen

__all__ = [
    "SAMPLE_RATE_HZ",
    "N_SAMPLES",
    "PRETRIGGER_SAMPLES",
    "TRIGGER_LBF",
    "ADC_BITS",
    "ACCELERATION_RANGE_G",
    "FORCE_RANGE_LBF",
    "REFERENCE_VELOCITY_IN_S",
    "EFFECT_CAUSES",
    "DEFAULT_EFFECT_SIZES",
    "EFFECT_SIZE_MEANING",
    "SECOND_MODE_FREQUENCY_RATIO",
    "INTEGRATORS",
    "TIME_DOMAIN_EFFECTS",
    "LabSettings",
    "RunPhysics",
    "draw_run_physics",
    "half_sine_response",
    "ModeTable",
    "nonlinear_mode_response",
    "JointSetup",
    "setup_configuration",
    "scale_slip_forces",
    "joint_curves",
    "run_dahl_coulomb",
    "mode_table",
    "truth_curves",
    "quantise",
    "boxcar_half_sine",
    "half_sine_spectral_factor",
    "dahl_mode_response_time_domain",
    "patch_mode_response_time_domain",
    "simulate_run",
    "averaged_mode_response",
    "time_domain_mode_response",
    "format_run",
    "truth_path",
    "generate_campaign",
    "generate_sensor_campaigns",
]


SAMPLE_RATE_HZ = 2560.0
N_SAMPLES = 8192
PRETRIGGER_SAMPLES = 25
TRIGGER_LBF = 1.0
ADC_BITS = 24
ACCELERATION_RANGE_G = 500.0
FORCE_RANGE_LBF = 500.0
REFERENCE_VELOCITY_IN_S = 3.0
"""Accelerometer velocity amplitude at which effect sizes are defined, in/s."""

EFFECT_CAUSES = {
    None: None,
    "quadratic_damping": "quadratic_damping",
    "stiffness_nonlinearity": "stiffness_nonlinearity",
    "cubic_stiffness": "stiffness_nonlinearity",
    "run_drift": "run_drift",
    "second_mode": "unknown",
}
DEFAULT_EFFECT_SIZES = {
    "quadratic_damping": 0.003,
    "stiffness_nonlinearity": 0.01,
    "cubic_stiffness": 0.005,
    "run_drift": 0.4,
    "second_mode": 0.5,
}
EFFECT_SIZE_MEANING = {
    "quadratic_damping": "damping ratio added by c2 v|v| at the reference velocity amplitude",
    "stiffness_nonlinearity": "fractional frequency drop at the reference velocity amplitude "
    "(saturating contact-opening softening; asymptote twice that)",
    "cubic_stiffness": "fractional frequency rise at the reference velocity amplitude from a "
    "hardening cubic spring k3 xi^3 (softening: stiffness_nonlinearity, which stays bounded)",
    "run_drift": "fractional fall of the Dahl friction limit Fc from the first to the last run",
    "second_mode": "initial acceleration amplitude of a linear mode at 1.08 f1, relative to mode 1",
}
JOINT_EFFECTS = {
    "dahl": tuple(effect for effect in EFFECT_CAUSES if effect),
    "patches": ("quadratic_damping", "stiffness_nonlinearity", "cubic_stiffness"),
}
"""Effects each joint can carry. Added to the Dahl joint (the baseline) an effect is the
one cause; added to the contact patches it is a second mechanism beside micro-slip, and
the truth names both (:func:`true_causes`)."""
SECOND_MODE_FREQUENCY_RATIO = 1.08
INTEGRATORS = ("averaged", "time_domain")
TIME_DOMAIN_EFFECTS = {
    "patches": (None, "quadratic_damping", "cubic_stiffness"),
    "dahl": (None, "run_drift", "second_mode"),
}
"""Effects the time-domain path can add, per joint: the patch integrator carries a
velocity-squared loss ``c2 xi'|xi'|`` and a cubic spring ``k3 xi^3`` in the equation of
motion; the Dahl integrator has the joint and linear modal damping only (no dissipation-free
softening of the saturating kind on either)."""


def true_causes(joint: str, effect: str | None) -> list[str]:
    """The mechanisms a campaign of this joint and added effect holds, the joint's first.

    ``patches`` is micro-slip; the Dahl joint is the baseline (``none`` unless an effect
    is added).
    """
    causes = ["microslip_power_law"] if joint == "patches" else []
    if effect is not None:
        causes.append(EFFECT_CAUSES[effect])
    return causes or ["none"]


@dataclass(frozen=True)
class LabSettings:
    """Instrument and specimen settings of the virtual lab."""

    zeta0: float = 0.0008
    """Linear modal damping of mode 1 (material, suspension, air)."""
    higher_mode_zeta: float = 0.003
    suspension_hz: tuple[float, float] = (2.5, 3.6)
    """Bounce and pitch frequencies on the rubber tubing, Hz."""
    suspension_zeta: float = 0.03
    peak_force_lbf: tuple[float, float] = (5.0, 40.0)
    """Range of hammer peak forces (log-uniform)."""
    pulse_duration_s: tuple[float, float] = (0.5e-3, 1.0e-3)
    acceleration_noise_g: float = 0.002
    force_noise_lbf: float = 0.005
    amplitude_points: int = 1500
    samples_per_run: int = N_SAMPLES
    """Record length (the paper's analyser: 8192); longer only to benchmark scaling."""
    sample_rate_hz: float = SAMPLE_RATE_HZ
    """Sample rate of the records, Hz (the paper's analyser: 2560; higher for the
    high-rate records of bench/bench_workflow.py)."""
    joint: contact.JointParameters = field(default_factory=contact.JointParameters)
    frequency_spread: float = 3e-4
    """Run-to-run relative standard deviation of the natural frequency (temperature:
    aluminium's modulus changes by about -4e-4/K, so f by -2e-4/K; re-hanging the beam
    on its tubing; docs/virtual-lab.md). 0 turns it off."""
    damping_spread: float = 0.03
    """Run-to-run relative standard deviation of the linear modal damping ``zeta0``
    (support and suspension losses after re-hanging; air). 0 turns it off."""
    slip_force_spread: float = 0.03
    """Run-to-run relative standard deviation of every joint slip force (friction
    coefficient and preload of a re-struck, settled contact). 0 turns it off."""


@dataclass(frozen=True)
class RunPhysics:
    """What differs from run to run of one configuration (drawn, not a trend)."""

    frequency_factor: float = 1.0
    """Natural frequency of the stuck-joint mode relative to the configuration's."""
    zeta0: float = LabSettings.zeta0
    """Linear modal damping ratio of this run."""
    slip_force_factor: float = 1.0
    """Every slip force of the joint (patches' limits, Dahl's Fc) relative to nominal."""


def draw_run_physics(settings: LabSettings, rng: np.random.Generator, n_runs: int) -> list[RunPhysics]:
    """Independent run-to-run variations of ``n_runs`` runs.

    Frequency: ``1 + frequency_spread * N(0, 1)``; damping and slip force log-normal
    with log standard deviations ``damping_spread`` and ``slip_force_spread`` (positive,
    median the nominal value). Draws are independent of run order: a trend is the
    ``run_drift`` effect, not this.
    """
    normal = rng.standard_normal((n_runs, 3))
    return [
        RunPhysics(
            frequency_factor=float(1.0 + settings.frequency_spread * f),
            zeta0=float(settings.zeta0 * np.exp(settings.damping_spread * z)),
            slip_force_factor=float(np.exp(settings.slip_force_spread * s)),
        )
        for f, z, s in normal
    ]


# ------------------------------------------------------------ linear modes


def half_sine_response(t_s, omega_rad_s, zeta, peak, duration_s):
    """Response of ``q'' + 2 zeta w q' + w^2 q = f(t)`` to a half-sine pulse.

    ``f = peak sin(pi t / duration)`` for ``0 <= t <= duration``, else 0; the
    oscillator is at rest before ``t = 0``.  Closed form of the Duhamel
    integral with the complex pole ``lam = -zeta w + i w_d``.

    Returns
    -------
    q, q_dot, q_ddot : ndarray
    """
    t = np.asarray(t_s, dtype=float)
    wd = omega_rad_s * np.sqrt(1.0 - zeta**2)
    lam = -zeta * omega_rad_s + 1j * wd
    big_omega = np.pi / duration_s
    tc = np.clip(t, 0.0, duration_s)
    integral = (
        np.exp(-lam * tc) * (-lam * np.sin(big_omega * tc) - big_omega * np.cos(big_omega * tc)) + big_omega
    ) / (lam**2 + big_omega**2)
    z = np.exp(lam * np.clip(t, 0.0, None)) * integral * peak / wd
    q = z.imag
    qd = (lam * z).imag
    force = np.where((t >= 0) & (t <= duration_s), peak * np.sin(big_omega * tc), 0.0)
    qdd = force - 2 * zeta * omega_rad_s * qd - omega_rad_s**2 * q
    started = t >= 0
    return q * started, qd * started, qdd * started


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


# ------------------------------------------------------------------ runs


def quantise(values, full_scale, bits=ADC_BITS):
    """Round to the ADC step ``2 full_scale / 2^bits`` and clip to the range."""
    step = 2.0 * full_scale / 2**bits
    return np.clip(np.round(values / step), -(2 ** (bits - 1)), 2 ** (bits - 1) - 1) * step


def boxcar_half_sine(t_start_s, dt_s, t0_s, peak, duration_s):
    """Mean of a half-sine pulse over each sample interval ``[t, t + dt)``.

    An ideal integrating ADC: the sum of the samples times dt is the impulse.
    """
    big_omega = np.pi / duration_s

    def primitive(t):  # integral of the pulse from t0 to t
        tc = np.clip(t - t0_s, 0.0, duration_s)
        return peak / big_omega * (1.0 - np.cos(big_omega * tc))

    return (primitive(t_start_s + dt_s) - primitive(t_start_s)) / dt_s


def half_sine_spectral_factor(omega_rad_s, duration_s):
    """``|F(omega)| / impulse`` of a half-sine pulse (1 for an ideal impulse).

    After the pulse, a linear oscillator struck by it rings exactly as if struck by an
    impulse this much smaller at the pulse centre (the pulse is symmetric).
    """
    x = omega_rad_s * duration_s / np.pi
    return float(np.cos(0.5 * omega_rad_s * duration_s) / (1.0 - x**2)) if abs(x - 1) > 1e-9 else np.pi / 4


def dahl_mode_response_time_domain(
    t_s, sigma, coulomb, omega0_rad_s, zeta0, modal_peak, duration_s, oversampling=8, steps_per_period=64
):
    """Modal acceleration of mode 1 with a Dahl joint, integrated in time.

    The equation of motion ``xi'' + 2 zeta0 omega0 xi' + (omega0^2 - sigma) xi + F = 0``,
    ``dF/dxi = sigma (1 - F sign(xi') / Fc)`` (the stuck stiffness ``sigma`` is part of
    ``omega0``, as in the averaged tables) is integrated by the compiled Lawson RK4 of
    :func:`workflow.models.ringdown.simulate_ringdown`, from the pulse centre with the
    pulse's impulse at the stuck frequency; during the pulse (a tenth of a cycle) the mode
    responds as the stuck linear oscillator.

    Parameters
    ----------
    t_s : ndarray
        Times from the pulse start, s (uniform).
    sigma : float
        Dahl rest stiffness in modal units, 1/s^2.
    coulomb : float
        Dahl friction limit ``Fc`` in modal units (modal force per unit mass).
    omega0_rad_s : float
        Stuck-joint natural frequency, rad/s.
    zeta0 : float
        Linear modal damping ratio (of ``omega0``).
    modal_peak : float
        Peak modal force of the half-sine pulse (per unit modal mass).
    duration_s : float
        Pulse duration, s.
    oversampling : int
        Integrator output samples per sample of ``t_s``: the pulse centre falls on the
        output grid within ``dt / (2 oversampling)`` (phase error < 0.01 rad at 125 Hz).
    steps_per_period : int
        Minimum integration steps per period (envelope error < 1e-4 at 64,
        bench/bench_integrator.py).

    Returns
    -------
    ndarray
        Modal acceleration at ``t_s``.
    """
    t = np.asarray(t_s, dtype=float)
    if omega0_rad_s**2 <= sigma:
        raise ValueError("the Dahl stiffness sigma must be below omega0^2 (the stuck mode includes it)")
    omega_free = np.sqrt(omega0_rad_s**2 - sigma)
    impulse = 2.0 * modal_peak * duration_s / np.pi
    v0 = impulse * half_sine_spectral_factor(omega0_rad_s, duration_s)
    dt = t[1] - t[0]
    fs_fine = oversampling / dt
    centre = 0.5 * duration_s
    n_fine = int(np.ceil((t[-1] - centre) * fs_fine)) + 2
    out = ringdown.simulate_ringdown(
        "dahl",
        {"sigma": sigma, "fc": coulomb},
        omega_rad_s=omega_free,
        zeta0=zeta0 * omega0_rad_s / omega_free,  # same damping force 2 zeta0 omega0 xi'
        initial_velocity=v0,
        fs_out_hz=fs_fine,
        duration_s=n_fine / fs_fine,
        steps_per_period=steps_per_period,
    )
    acc_fine = out["acceleration"][0]
    _, _, acc = half_sine_response(t, omega0_rad_s, zeta0, modal_peak, duration_s)
    after = t > duration_s
    index = np.round((t[after] - centre) * fs_fine).astype(int)
    acc[after] = acc_fine[np.minimum(index, n_fine - 1)]
    return acc


_FREEZE_MARGIN = 1.05
"""A patch is frozen once the amplitude is this factor below its slip onset (the
energy amplitude ``sqrt(x^2 + (x'/omega0)^2)`` varies within a cycle by the joint's
< 1 % softening)."""


@numba.njit(cache=True, error_model="numpy")
def _patch_ringdown_kernel(
    s, k, fs, onset, stiffness, damping, quadratic, cubic, e00, e01, e10, e11, v0, n_steps, h, acc
):
    """Kick-drift-kick ring-down of ``x'' + damping x' + stiffness x + R = 0`` from
    ``x = 0, x' = v0``, ``R = sum s (f - k s x) + quadratic x'|x'| + cubic x^3`` with
    Jenkins forces ``f``; writes ``acc``.

    Patches sorted by ``onset``. Once the amplitude has fallen below a patch's onset it
    never slips again: stuck, its ``s (f - k s x)`` is constant, so it is summed once
    (``frozen``) and leaves the loop.
    """
    f = np.zeros(s.size)
    x, eta, x_prev = 0.0, v0, 0.0
    n_active = s.size
    frozen = 0.0
    for j in range(n_steps):
        dx = x - x_prev
        remainder = frozen + quadratic * eta * abs(eta) + cubic * x * x * x
        for i in range(n_active):
            trial = f[i] + k[i] * s[i] * dx
            f[i] = min(max(trial, -fs[i]), fs[i])
            remainder += s[i] * (f[i] - k[i] * s[i] * x)
        amplitude = math.sqrt(x * x + eta * eta / stiffness)
        while n_active > 0 and onset[n_active - 1] > _FREEZE_MARGIN * amplitude:
            n_active -= 1
            frozen += s[n_active] * (f[n_active] - k[n_active] * s[n_active] * x)
        x_prev = x
        if j > 0:
            eta -= 0.5 * h * remainder  # second half kick of the previous step
        acc[j] = -stiffness * x - damping * eta - remainder
        eta -= 0.5 * h * remainder
        x, eta = e00 * x + e01 * eta, e10 * x + e11 * eta


def patch_mode_response_time_domain(
    t_s,
    slip_per_xi,
    stiffness_lbf_in,
    slip_force_lbf,
    omega0_rad_s,
    zeta0,
    modal_peak,
    duration_s,
    oversampling=4,
    quadratic=0.0,
    cubic=0.0,
):
    """Modal acceleration of mode 1 with the contact patches, integrated in time.

    ``xi'' + 2 zeta0 omega0 xi' + omega0^2 xi + sum s (f - k s xi) + c2 xi'|xi'| + k3 xi^3
    = 0`` (the stuck patch stiffness is part of ``omega0``), every patch a Jenkins element
    (``f`` clipped at its slip force). The linear oscillator's flow over a step is exact;
    the nonlinear remainder (the patches' part zero while they stick) is applied as two
    half kicks per step (second order, Strang). Starts at the pulse centre with the pulse's impulse at the stuck
    frequency; during the pulse the stuck linear oscillator. Patches whose slip onset lies
    above the initial amplitude never slip and are left out (their remainder is zero).

    Parameters
    ----------
    t_s : ndarray
        Times from the pulse start, s (uniform).
    slip_per_xi, stiffness_lbf_in, slip_force_lbf : ndarray
        Slip per unit modal coordinate (in), tangential stiffness (lbf/in) and slip force
        (lbf) of every patch (broadcast together).
    omega0_rad_s, zeta0, modal_peak, duration_s
        As :func:`dahl_mode_response_time_domain`.
    oversampling : int
        Steps per sample of ``t_s`` (4 at 2560 samples/s: 80 steps per period at 126 Hz;
        8 changes the damping by < 0.03 % and the frequency by < 1e-6, measured).
    quadratic, cubic : float
        ``c2`` (1/in) and ``k3`` (1/(in^2 s^2)) of an added velocity-squared loss and
        cubic spring (:func:`effect_coefficients`); 0 for the joint alone.

    Returns
    -------
    ndarray
        Modal acceleration at ``t_s``.
    """
    t = np.asarray(t_s, dtype=float)
    s, k, fs = (
        np.ascontiguousarray(x, dtype=float).ravel()
        for x in np.broadcast_arrays(np.abs(slip_per_xi), stiffness_lbf_in, slip_force_lbf)
    )
    v0 = 2.0 * modal_peak * duration_s / np.pi * half_sine_spectral_factor(omega0_rad_s, duration_s)
    with np.errstate(divide="ignore"):
        onset = fs / (k * s)  # modal amplitude at which each patch starts slipping
    # sorted by onset; those above the initial amplitude never slip
    order = np.argsort(onset)
    order = order[onset[order] < _FREEZE_MARGIN * v0 / omega0_rad_s]
    dt = t[1] - t[0]
    h = dt / oversampling
    centre = 0.5 * duration_s
    n_steps = int(np.ceil((t[-1] - centre) / h)) + 2
    stiffness, damping = omega0_rad_s**2, 2.0 * zeta0 * omega0_rad_s
    e00, e01, e10, e11 = (float(e) for e in ringdown.oscillator_propagator(stiffness, damping, h))
    acc_fine = np.empty(n_steps)
    _patch_ringdown_kernel(
        s[order],
        k[order],
        fs[order],
        onset[order],
        stiffness,
        damping,
        float(quadratic),
        float(cubic),
        e00,
        e01,
        e10,
        e11,
        v0,
        n_steps,
        h,
        acc_fine,
    )
    _, _, acc = half_sine_response(t, omega0_rad_s, zeta0, modal_peak, duration_s)
    after = t > duration_s
    index = np.round((t[after] - centre) / h).astype(int)
    acc[after] = acc_fine[np.minimum(index, n_steps - 1)]
    return acc


ModeResponse = Callable[[np.ndarray, float, float], np.ndarray]
"""A nonlinear mode's modal acceleration at times from the pulse start, given the peak
modal force and the pulse duration."""


# ---------------------------------------------------------------- sensors


@dataclass(frozen=True)
class Sensor:
    """An accelerometer on the beam, with its own noise."""

    name: str = "Acceleration"
    """Column (or MAT variable) name; contains ``acc``, the input contract's response role."""
    position_in: float | None = None
    """Distance from the beam's left end, in; None: the reference accelerometer's point
    (``SpecimenGeometry.accelerometer_x_in``, the paper's)."""
    noise_g: float | None = None
    """Noise floor (standard deviation) in the sensor's unit, g; None:
    ``LabSettings.acceleration_noise_g``."""


@dataclass(frozen=True)
class SensorView:
    """What one sensor sees of one configuration's modes."""

    mode1_participation: float
    """Mode 1's mass-normalised shape at the sensor, in per unit modal coordinate."""
    higher_participations: tuple[float, ...]
    """The higher flexible modes' shapes at the sensor, same order as ``higher_modes``."""
    position_in: float
    noise_g: float

    def participation(self, mode_index: int) -> float:
        """Shape at the sensor of flexible mode ``mode_index`` (1 = mode 1)."""
        return self.mode1_participation if mode_index == 1 else self.higher_participations[mode_index - 2]


def sensor_view(mode: specimen.FirstMode, settings: LabSettings, sensor: Sensor) -> SensorView:
    """The sensor's view of the modes: each mode at its own shape value at the sensor.

    At the reference accelerometer the FE model's participations; elsewhere every mode's
    deflection line interpolated linearly between FE nodes (1/8 in apart: the error is
    ``h^2 |phi''| / 8``, under 1e-4 of mode 1's largest deflection).
    """
    noise = settings.acceleration_noise_g if sensor.noise_g is None else float(sensor.noise_g)
    geometry = settings.joint.geometry
    if sensor.position_in is None:
        return SensorView(
            mode.accelerometer_participation,
            tuple(m.accelerometer_participation for m in mode.higher_modes),
            geometry.accelerometer_x_in,
            noise,
        )
    x = float(sensor.position_in)
    if not 0.0 <= x <= geometry.total_length_in:
        raise ValueError(
            f"sensor {sensor.name!r} at {x} in is off the beam (0 to {geometry.total_length_in} in)"
        )
    return SensorView(
        float(np.interp(x, mode.x_in, mode.shape_in)),
        tuple(float(np.interp(x, mode.x_in, m.shape_in)) for m in mode.higher_modes),
        x,
        noise,
    )


def mode1_gain(mode: specimen.FirstMode, settings: LabSettings, sensor: Sensor) -> float:
    """Mode 1 at the sensor relative to the reference accelerometer (signed)."""
    return sensor_view(mode, settings, sensor).mode1_participation / mode.accelerometer_participation


def positions_with_mode1_gain(mode: specimen.FirstMode, gain: float) -> np.ndarray:
    """Points of the beam (in, increasing) where mode 1's ``|phi(x) / phi(x_accelerometer)|``
    equals ``gain``; empty where the beam has none (above its free ends' ratio, 3.0 on
    the paper's specimen)."""
    ratio = np.abs(mode.shape_in / mode.accelerometer_participation) - gain
    crossing = np.flatnonzero(np.sign(ratio[:-1]) * np.sign(ratio[1:]) <= 0)
    crossing = crossing[ratio[crossing] != ratio[crossing + 1]]
    x0, x1 = mode.x_in[crossing], mode.x_in[crossing + 1]
    r0, r1 = ratio[crossing], ratio[crossing + 1]
    return np.unique(x0 - r0 * (x1 - x0) / (r1 - r0))


def _check_sensors(sensors) -> tuple[Sensor, ...]:
    sensors = tuple(sensors)
    if not sensors:
        raise ValueError("at least one sensor is needed")
    names = [s.name for s in sensors]
    for name in names:
        if "acc" not in name.lower() or any(c in name for c in "\t\n\r()[],:{}#\"'") or name != name.strip():
            raise ValueError(
                f"sensor name {name!r}: it must contain 'acc' (the response role of campaign-format.md) "
                "and no tab, line break, bracket, comma, colon, brace, quote or '#'"
            )
    if len(set(names)) != len(names):
        raise ValueError(f"sensor names must differ, got {names}")
    return sensors


# ------------------------------------------------------------------ runs


def simulate_run(
    setup: JointSetup,
    mode_response: ModeResponse,
    settings: LabSettings,
    rng,
    second_mode_ratio=0.0,
    *,
    run: RunPhysics | None = None,
    sensors: tuple[SensorView, ...] | None = None,
    noise_rngs=None,
    higher_responses: tuple[ModeResponse | None, ...] = (),
):
    """One triggered record: (time s, force lbf, acceleration g per sensor) and run facts.

    Parameters
    ----------
    mode_response : callable
        Mode 1's modal acceleration (:func:`averaged_mode_response` or
        :func:`time_domain_mode_response`).
    rng : numpy.random.Generator
        The hammer: peak force, pulse duration, trigger phase, force noise.
    run : RunPhysics, optional
        This run's frequency (also of the linear modes, as a temperature change would)
        and damping; default the nominal ones.
    sensors : tuple of SensorView, optional
        Each sensor's view of the modes and its noise floor; default the reference
        accelerometer alone.
    noise_rngs : sequence of numpy.random.Generator, optional
        Each sensor's own noise; default ``rng`` for a single sensor.
    higher_responses : tuple
        Per higher flexible mode (in order), its nonlinear modal acceleration when the
        joint acts on it, else None (or missing): linear.

    Returns
    -------
    time_s : ndarray, shape (n,)
    force_lbf : ndarray, shape (n,)
    acceleration_g : ndarray, shape (n_sensors, n)
    facts : dict
    """
    run = run if run is not None else RunPhysics(zeta0=settings.zeta0)
    if sensors is None:
        sensors = (sensor_view(setup.mode, settings, Sensor()),)
    noise_rngs = noise_rngs if noise_rngs is not None else [rng]
    dt = 1.0 / settings.sample_rate_hz
    lo, hi = settings.peak_force_lbf
    peak = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
    duration = float(rng.uniform(*settings.pulse_duration_s))
    extra = 16
    n = settings.samples_per_run + extra
    t = np.arange(n) * dt
    t0 = (PRETRIGGER_SAMPLES + float(rng.uniform(0.0, 1.0))) * dt
    force = boxcar_half_sine(t, dt, t0, peak, duration)
    force = force + settings.force_noise_lbf * rng.standard_normal(n)
    trigger = int(np.argmax(force >= TRIGGER_LBF))
    mode = setup.mode
    tau = t - t0
    phi_h = mode.hammer_participation
    # modal accelerations, shared by every sensor
    mode1 = mode_response(tau, phi_h * peak, duration)
    higher = []
    for index, m in enumerate(mode.higher_modes):
        response = higher_responses[index] if index < len(higher_responses) else None
        if response is not None:
            higher.append(response(tau, m.hammer_participation * peak, duration))
            continue
        _, _, q = half_sine_response(
            tau,
            2 * np.pi * m.frequency_hz * run.frequency_factor,
            settings.higher_mode_zeta,
            m.hammer_participation * peak,
            duration,
        )
        higher.append(q)
    second = None
    if second_mode_ratio:
        # An extra (e.g. torsional) mode that the beam model lacks: excited like
        # mode 1, seen at each sensor with the chosen amplitude relative to mode 1.
        _, _, second = half_sine_response(
            tau,
            SECOND_MODE_FREQUENCY_RATIO * setup.omega0_rad_s * run.frequency_factor,
            run.zeta0,
            phi_h * peak,
            duration,
        )
    # rigid-body bounce and pitch on the suspension
    lever_ham = settings.joint.geometry.hammer_x_in - mode.centre_of_mass_in

    def suspension(f_hz, gain):
        return half_sine_response(tau, 2 * np.pi * f_hz, settings.suspension_zeta, gain * peak, duration)[2]

    bounce = suspension(settings.suspension_hz[0], 1.0 / mode.total_mass_lbf_s2_in)
    sl = slice(trigger - PRETRIGGER_SAMPLES, trigger - PRETRIGGER_SAMPLES + settings.samples_per_run)
    accelerations = []
    for view, noise_rng in zip(sensors, noise_rngs, strict=True):
        acc = view.mode1_participation * mode1
        for participation, q in zip(view.higher_participations, higher, strict=True):
            acc += participation * q
        if second is not None:
            acc += second_mode_ratio * view.mode1_participation * second
        acc += bounce
        lever = view.position_in - mode.centre_of_mass_in
        acc += suspension(settings.suspension_hz[1], lever * lever_ham / mode.pitch_inertia_lbf_s2_in)
        acc_g = acc / specimen.G_IN_S2 + view.noise_g * noise_rng.standard_normal(n)
        accelerations.append(quantise(acc_g[sl], ACCELERATION_RANGE_G))
    force_q = quantise(force[sl], FORCE_RANGE_LBF)
    facts = {"peak_force_lbf": peak, "pulse_duration_s": duration}
    return np.arange(settings.samples_per_run) * dt, force_q, np.array(accelerations), facts


def averaged_mode_response(setup: JointSetup, table: ModeTable, run: RunPhysics) -> ModeResponse:
    """Mode 1 from the run's averaged table (slow flow)."""
    omega0 = setup.omega0_rad_s * run.frequency_factor

    def response(tau, modal_peak, duration):
        return nonlinear_mode_response(tau, table, omega0, run.zeta0, modal_peak, duration)

    return response


def time_domain_mode_response(
    setup: JointSetup, joint: str, coulomb: float, run: RunPhysics, effect=None, effect_size=None
) -> ModeResponse:
    """Mode 1 with the run's joint (``patches`` or ``dahl`` with friction limit
    ``coulomb``) integrated in time; with the patches, an added ``quadratic_damping`` or
    ``cubic_stiffness`` is a term of the equation of motion."""
    omega0 = setup.omega0_rad_s * run.frequency_factor
    patches = setup.joint_modes.patches
    quadratic, cubic = effect_coefficients(setup, effect, effect_size)

    def response(tau, modal_peak, duration):
        if joint == "patches":
            return patch_mode_response_time_domain(
                tau,
                setup.joint_modes.slip_per_xi,
                patches.stiffness_lbf_in,
                patches.slip_force_lbf * run.slip_force_factor,
                omega0,
                run.zeta0,
                modal_peak,
                duration,
                quadratic=quadratic,
                cubic=cubic,
            )
        return dahl_mode_response_time_domain(
            tau, setup.dahl_sigma, coulomb, omega0, run.zeta0, modal_peak, duration
        )

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


def _higher_mode_response(setup: JointSetup, settings: LabSettings, index: int, run: RunPhysics):
    table = higher_mode_table(setup, settings, index, run)
    omega0 = 2 * np.pi * setup.mode.higher_modes[index].frequency_hz * run.frequency_factor

    def response(tau, modal_peak, duration):
        return nonlinear_mode_response(tau, table, omega0, settings.higher_mode_zeta, modal_peak, duration)

    return response, table


# ------------------------------------------------------------------ files


def format_run(
    time_s, force_lbf, acceleration_g, sample_rate_hz=SAMPLE_RATE_HZ, names=("Acceleration",)
) -> str:
    """The run file text (Dactron-like ASCII export); one acceleration column per name
    (``acceleration_g`` of shape (n,) or (n_sensors, n))."""
    columns = np.atleast_2d(acceleration_g)
    if len(names) != columns.shape[0]:
        raise ValueError(f"{len(names)} column names for {columns.shape[0]} acceleration columns")
    lines = [
        "Virtual lab ASCII export (lapjoint)",
        f"Sample rate: {sample_rate_hz:g} Hz",
        f"Pre-trigger: {PRETRIGGER_SAMPLES} samples",
        "\t".join(["Time (s)", "Force (lbf)", *(f"{name} (g)" for name in names)]),
    ]
    body = np.char.add(np.char.add(np.char.mod("%.6f", time_s), "\t"), np.char.mod("%.10g", force_lbf))
    for column in columns:
        body = np.char.add(np.char.add(body, "\t"), np.char.mod("%.10g", column))
    return "\n".join(lines + body.tolist()) + "\n"


def write_run_mat(path, time_s, force_lbf, acceleration_g, names) -> None:
    """One run as a MATLAB 5 MAT file of plain variables: ``t`` (s), ``force`` (lbf) and
    one acceleration vector (g) per sensor, named as the sensor."""
    import scipy.io

    variables = {"t": np.asarray(time_s), "force": np.asarray(force_lbf)}
    for name, column in zip(names, np.atleast_2d(acceleration_g), strict=True):
        variables[name] = column
    scipy.io.savemat(path, variables, format="5", oned_as="column")
    # the header's text holds the writing time: a fixed one keeps a seed's files identical
    with open(path, "r+b") as f:
        f.write(MAT_HEADER_TEXT.ljust(116))


MAT_HEADER_TEXT = b"MATLAB 5.0 MAT-file, written by the lapjoint virtual lab"


FILE_FORMATS = {"txt": "ASCII export", "mat": "MATLAB 5 MAT, plain variables"}


def _campaign_yaml(name, configurations, modes_hz, sample_rate_hz, channels=None, file_format="txt") -> str:
    lines = [
        f"name: {name}",
        f"sample_rate_hz: {sample_rate_hz:g}",
        f"pretrigger_samples: {PRETRIGGER_SAMPLES}",
    ]
    if modes_hz == "auto":
        lines.append("modes_hz: auto")
    elif len(modes_hz) == 1:
        lines.append(f"mode_hz: {modes_hz[0]:g}")
    else:
        lines.append("modes_hz: [" + ", ".join(f"{f:g}" for f in modes_hz) + "]")
    if channels is None:
        lines.append("response: {quantity: acceleration, unit: g}")
    else:
        lines.append("response: {quantity: acceleration, unit: g, channels: [" + ", ".join(channels) + "]}")
    lines += ["force: {unit: lbf}", "configurations:"]
    for cname, area in configurations.items():
        area_part = f"bearing_area_in2: {area:g}, " if area is not None else ""
        lines.append(f'  {cname}: {{{area_part}files: "{cname}/*.{file_format}"}}')
    return "\n".join(lines) + "\n"


def truth_path(out_dir, mode: int = 1) -> Path:
    """Where the truth JSON of a campaign folder's mode lives (beside it, not inside):
    ``<campaign>.truth.json`` for mode 1, ``<campaign>.mode<k>.truth.json`` for mode k."""
    out = Path(out_dir)
    suffix = ".truth.json" if mode == 1 else f".mode{mode}.truth.json"
    return out.parent / (out.name + suffix)


def generate_campaign(
    out_dir,
    *,
    seed=2004,
    runs_per_configuration=10,
    joint="patches",
    effect=None,
    effect_size=None,
    configurations=None,
    samples_per_run=None,
    settings: LabSettings | None = None,
    integrator="averaged",
    sensors=None,
    noise_stream=0,
    nonlinear_modes=1,
    file_format="txt",
    modes_auto=False,
) -> dict:
    """Write a simulated campaign folder and its truth; return mode 1's truth dict.

    Parameters
    ----------
    out_dir : path
        Campaign folder to create (existing run files in it are overwritten).
    seed : int
        Random seed; the same seed gives byte-identical files.
    runs_per_configuration : int
    joint : {"patches", "dahl"}
        ``patches``: micro-slip contact patches (true cause ``microslip_power_law``);
        ``dahl``: single-state Dahl joint fitted to the same specimen (cause ``none``).
    effect : {None, "quadratic_damping", "stiffness_nonlinearity", "cubic_stiffness", "run_drift", "second_mode"}
        One added effect (``JOINT_EFFECTS``): on the Dahl joint the one cause; on the
        patches (quadratic damping, a stiffness term) a second mechanism beside
        micro-slip, the truth's ``causes`` naming both.
    effect_size : float, optional
        Physical size of the effect (see ``EFFECT_SIZE_MEANING``); default
        ``DEFAULT_EFFECT_SIZES[effect]``.
    configurations : dict, optional
        Name -> bearing area in^2 (or None for a campaign without areas);
        default the paper's three.
    samples_per_run : int, optional
        Samples per record; overrides ``settings.samples_per_run`` (default 8192, as the
        paper's analyser).
    settings : LabSettings, optional
        Instrument, specimen and run-to-run variability (default ``LabSettings()``:
        variability on; ``frequency_spread=0, damping_spread=0, slip_force_spread=0``
        makes every run of a configuration the same beam).
    integrator : {"averaged", "time_domain"}
        ``averaged``: mode 1 from the slow-flow tables (any joint and effect);
        ``time_domain``: the joint's equation of motion integrated in time (effects in
        ``TIME_DOMAIN_EFFECTS[joint]``; about 1 s per patch-joint run).
    sensors : sequence of Sensor, optional
        The accelerometers, each a column of every run file (or a MAT variable), at its
        own point of the beam (every mode at its own shape value there) with its own
        noise; default the reference accelerometer alone. Several sensors: the
        campaign.yaml names them as ``response: {channels: [...]}``.
    noise_stream : int
        Index of the first sensor's noise stream (sensor ``i`` draws from stream
        ``noise_stream + i``): with the same ``seed``, campaigns with different streams
        share the physics and the hammer and differ only in sensor noise.
    nonlinear_modes : {1, 2}
        Flexible modes the joint acts on: 2 gives mode 2 the contact patches too, through
        its own interface slip (``joint="patches"``, no effect, averaged); the
        campaign.yaml lists both modes (``modes_hz``) and mode 2's truth is written to
        ``truth_path(out_dir, 2)``.
    file_format : {"txt", "mat"}
        Run files as ASCII exports or MATLAB 5 MAT files (``t``, ``force``, one variable
        per sensor).
    modes_auto : bool
        campaign.yaml asks for every mode the analysis finds (``modes_hz: auto``) instead
        of listing the simulated ones.
    """
    if joint not in ("patches", "dahl"):
        raise ValueError(f"joint must be 'patches' or 'dahl', got {joint!r}")
    if effect not in EFFECT_CAUSES:
        raise ValueError(
            f"effect must be one of {sorted(k for k in EFFECT_CAUSES if k)} or None, got {effect!r}"
        )
    if effect is not None and effect not in JOINT_EFFECTS[joint]:
        raise ValueError(f"the {joint} joint takes an effect in {JOINT_EFFECTS[joint]}, got {effect!r}")
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
    if integrator == "time_domain" and effect not in TIME_DOMAIN_EFFECTS[joint]:
        raise ValueError(
            f"the time-domain path integrates the {joint} joint: it takes effect in "
            f"{TIME_DOMAIN_EFFECTS[joint]}, got {effect!r}"
        )
    if nonlinear_modes not in (1, 2):
        raise ValueError(f"nonlinear_modes must be 1 or 2, got {nonlinear_modes!r}")
    if nonlinear_modes == 2 and (joint != "patches" or effect is not None or integrator != "averaged"):
        raise ValueError("a joint on two modes is the contact patches alone, averaged")
    if file_format not in FILE_FORMATS:
        raise ValueError(f"file_format must be one of {sorted(FILE_FORMATS)}, got {file_format!r}")
    sensors = _check_sensors(sensors if sensors is not None else (Sensor(),))
    if effect is not None and effect_size is None:
        effect_size = DEFAULT_EFFECT_SIZES[effect]
    if effect == "cubic_stiffness" and not effect_size > 0:
        raise ValueError(
            f"cubic_stiffness is a hardening spring (effect_size > 0), got {effect_size!r}: a softening "
            "cubic loses all stiffness at a finite amplitude; use stiffness_nonlinearity"
        )
    if runs_per_configuration < 1:
        raise ValueError("runs_per_configuration must be at least 1")
    configurations = dict(PAPER_CONFIGURATIONS if configurations is None else configurations)
    settings = settings if settings is not None else LabSettings()
    if samples_per_run is not None:
        settings = replace(settings, samples_per_run=samples_per_run)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    root_seq = np.random.SeedSequence(seed)
    children = root_seq.spawn(len(configurations))
    velocity = np.logspace(-3, 2, 101)
    causes = true_causes(joint, effect)
    names = [s.name for s in sensors]
    truth = {
        "campaign_dir": out.name,
        "seed": seed,
        "joint": joint,
        "effect": effect,
        "effect_size": effect_size,
        "effect_size_meaning": EFFECT_SIZE_MEANING.get(effect),
        "reference_velocity_in_s": REFERENCE_VELOCITY_IN_S,
        "expected_cause": causes[0],
        "causes": causes,
        "integrator": integrator,
        "sensors": [
            {**asdict(s), "noise_stream": noise_stream + i, "column": s.name} for i, s in enumerate(sensors)
        ],
        "lab_settings": {k: v for k, v in asdict(settings).items() if k != "joint"},
        "joint_parameters": {k: v for k, v in asdict(settings.joint).items() if k != "geometry"},
        "preload_lbf": settings.joint.preload_lbf,
        "geometry": asdict(settings.joint.geometry),
        "velocity_amplitude_in_s": velocity.tolist(),
        "configurations": {},
    }
    setups = {}
    for cname, area in configurations.items():
        setups[cname] = setup_configuration(cname, area, settings)
    modes_hz = [float(np.mean([s.mode.frequency_hz for s, _ in setups.values()]))]
    if nonlinear_modes == 2:
        modes_hz.append(float(np.mean([s.mode.higher_modes[0].frequency_hz for s, _ in setups.values()])))
    (out / "campaign.yaml").write_text(
        _campaign_yaml(
            f"virtual-lab-{joint}-{effect or 'baseline'}-{seed}",
            configurations,
            "auto" if modes_auto else [round(f) for f in modes_hz],
            settings.sample_rate_hz,
            channels=names if len(sensors) > 1 else None,
            file_format=file_format,
        )
    )
    mode2_truth = {**truth, "mode": 2, "mode_hz": modes_hz[-1], "causes": causes, "configurations": {}}
    truth["mode"], truth["mode_hz"] = 1, modes_hz[0]
    for (cname, (setup, curves)), child in zip(setups.items(), children):
        folder = out / cname
        folder.mkdir(exist_ok=True)
        for stale in [*folder.glob("run*.txt"), *folder.glob("run*.mat")]:
            stale.unlink()
        hammer_seq, noise_seq, variability_seq = child.spawn(3)
        rng = np.random.default_rng(hammer_seq)
        noise_rngs = [
            np.random.default_rng(s) for s in noise_seq.spawn(noise_stream + len(sensors))[noise_stream:]
        ]
        runs = draw_run_physics(settings, np.random.default_rng(variability_seq), runs_per_configuration)
        views = tuple(sensor_view(setup.mode, settings, s) for s in sensors)
        base_table = mode_table(setup, curves, settings, joint, effect, effect_size)
        mode = setup.mode
        # the truth's curves are against the first sensor's own velocity amplitude
        first_gain = abs(views[0].mode1_participation / mode.accelerometer_participation)
        zeta, fd = truth_curves(setup, base_table, velocity / first_gain)
        entry = {
            "bearing_area_in2": setup.bearing_area_in2,
            "linear_frequency_hz": mode.frequency_hz,
            "node_positions_in": mode.node_positions_in.tolist(),
            "accelerometer_participation": mode.accelerometer_participation,
            "hammer_participation": mode.hammer_participation,
            "higher_modes_hz": [m.frequency_hz for m in mode.higher_modes],
            "dahl_sigma_modal": setup.dahl_sigma,
            "dahl_coulomb_modal": setup.dahl_coulomb,
            "n_patches_per_interface": int(setup.joint_modes.patches.x_rel_in.size),
            "zeta": zeta.tolist(),
            "damped_frequency_hz": fd.tolist(),
            "channels": _channel_truth(setup, base_table, velocity, sensors, views, 1),
            "runs": [],
        }
        mode2_table = higher_mode_table(setup, settings, 0) if nonlinear_modes == 2 else None
        if mode2_table is not None:
            mode2_truth["configurations"][cname] = {
                "bearing_area_in2": setup.bearing_area_in2,
                "linear_frequency_hz": mode.higher_modes[0].frequency_hz,
                "accelerometer_participation": mode.higher_modes[0].accelerometer_participation,
                "hammer_participation": mode.higher_modes[0].hammer_participation,
                "channels": _channel_truth(setup, mode2_table, velocity, sensors, views, 2),
                "runs": [],
            }
        for i, run in enumerate(runs):
            fraction = i / (runs_per_configuration - 1) if runs_per_configuration > 1 else 0.0
            table = mode_table(setup, curves, settings, joint, effect, effect_size, fraction, run)
            coulomb = run_dahl_coulomb(setup, effect, effect_size, fraction, run.slip_force_factor)
            if integrator == "time_domain":
                response = time_domain_mode_response(setup, joint, coulomb, run, effect, effect_size)
            else:
                response = averaged_mode_response(setup, table, run)
            higher_responses = ()
            if mode2_table is not None:
                mode2_response, run_mode2_table = _higher_mode_response(setup, settings, 0, run)
                higher_responses = (mode2_response,)
            ratio = effect_size if effect == "second_mode" else 0.0
            t, f, acc, facts = simulate_run(
                setup,
                response,
                settings,
                rng,
                ratio,
                run=run,
                sensors=views,
                noise_rngs=noise_rngs,
                higher_responses=higher_responses,
            )
            name = run_name(i)
            if file_format == "mat":
                write_run_mat(folder / f"{name}.mat", t, f, acc, names)
            else:
                (folder / f"{name}.txt").write_text(format_run(t, f, acc, settings.sample_rate_hz, names))
            z_run, f_run = truth_curves(setup, table, velocity / first_gain)
            entry["runs"].append(
                {
                    "run": name,
                    **facts,
                    **asdict(run),
                    "linear_frequency_hz": mode.frequency_hz * run.frequency_factor,
                    "dahl_coulomb_modal": coulomb,
                    "zeta": z_run.tolist(),
                    "damped_frequency_hz": f_run.tolist(),
                }
            )
            if mode2_table is not None:
                participation = views[0].participation(2)
                z2, f2 = truth_curves(setup, run_mode2_table, velocity, participation=participation)
                mode2_truth["configurations"][cname]["runs"].append(
                    {"run": name, "zeta": z2.tolist(), "damped_frequency_hz": f2.tolist()}
                )
        truth["configurations"][cname] = entry
    truth_path(out).write_text(json.dumps(truth, indent=1))
    if nonlinear_modes == 2:
        truth_path(out, 2).write_text(json.dumps(mode2_truth, indent=1))
    return truth


def _channel_truth(setup, table, velocity, sensors, views, mode_index) -> dict:
    """Per sensor: the mode's shape at it and the true curves against its own velocity
    amplitude."""
    channels = {}
    for sensor, view in zip(sensors, views, strict=True):
        participation = view.participation(mode_index)
        zeta, fd = truth_curves(setup, table, velocity, participation=participation)
        channels[sensor.name] = {
            "position_in": view.position_in,
            "participation": participation,
            "noise_g": view.noise_g,
            "zeta": zeta.tolist(),
            "damped_frequency_hz": fd.tolist(),
        }
    return channels


def generate_sensor_campaigns(out_root, sensors: Mapping[str, Sensor | float], **campaign_options) -> dict:
    """The same campaign as seen by several sensors: one campaign folder per sensor.

    Every campaign has the same physics, hammer hits and run-to-run variations (same
    ``seed``); each sensor sees every mode at its own shape value and has its own
    independent noise.

    Parameters
    ----------
    out_root : path
        Folder that receives ``<sensor name>/`` campaign folders (truth beside each).
    sensors : mapping of str to Sensor or float
        Sensor name (the campaign folder) -> a :class:`Sensor`, or mode 1's amplitude
        relative to the accelerometer (``|phi(x) / phi(x_accelerometer)|``): the sensor
        is then placed at the point of the first configuration's mode 1 with that ratio
        nearest the accelerometer.
    **campaign_options
        Passed to :func:`generate_campaign` (seed, joint, effect, configurations ...).

    Returns
    -------
    dict
        Sensor name -> truth dict of its campaign.
    """
    root = Path(out_root)
    settings = campaign_options.get("settings") or LabSettings()
    configurations = campaign_options.get("configurations") or PAPER_CONFIGURATIONS
    name, area = next(iter(configurations.items()))
    mode = setup_configuration(name, area, settings)[0].mode
    placed = {}
    for name, sensor in sensors.items():
        if not isinstance(sensor, Sensor):
            sensor = sensor_at_gain(mode, settings, float(sensor))
        placed[name] = sensor
    return {
        name: generate_campaign(root / name, sensors=(sensor,), noise_stream=index, **campaign_options)
        for index, (name, sensor) in enumerate(placed.items())
    }


def sensor_at_gain(
    mode: specimen.FirstMode, settings: LabSettings, gain: float, name="Acceleration"
) -> Sensor:
    """A sensor where mode 1 is ``gain`` times the accelerometer's (the point nearest the
    accelerometer; gain 1 is the accelerometer itself)."""
    if gain == 1.0:
        return Sensor(name)
    positions = positions_with_mode1_gain(mode, gain)
    if positions.size == 0:
        raise ValueError(f"no point of the beam sees mode 1 at {gain:g} times the accelerometer")
    x_acc = settings.joint.geometry.accelerometer_x_in
    return Sensor(name, float(positions[np.argmin(np.abs(positions - x_acc))]))


HIT_SENSOR_GAINS = {"acc1": 1.0, "acc2": 0.05, "acc3": 2.0}
"""The one-hit record's sensors: mode 1 at each relative to the reference accelerometer
(acc2 near a node of mode 1, acc3 towards a free end)."""


def generate_one_hit(
    out_dir, *, seed=7, sample_rate_hz=12800.0, duration_s=5.0, bearing_area_in2=1.36
) -> dict:
    """One hammer hit recorded by three accelerometers, as one MAT 5 file.

    The shape of a real multi-sensor impact test: a campaign of one configuration
    (``hit``) and one run, ``hit/run01.mat`` holding ``t``, ``force`` and ``acc1``-``acc3``
    (``HIT_SENSOR_GAINS``), the joint acting on modes 1 and 2, campaign.yaml asking for
    every mode (``modes_hz: auto``) and every channel. Returns mode 1's truth (mode 2's
    is at ``truth_path(out_dir, 2)``).
    """
    settings = LabSettings(
        sample_rate_hz=sample_rate_hz, samples_per_run=int(round(duration_s * sample_rate_hz))
    )
    mode = setup_configuration("hit", bearing_area_in2, settings)[0].mode
    sensors = tuple(sensor_at_gain(mode, settings, gain, name) for name, gain in HIT_SENSOR_GAINS.items())
    return generate_campaign(
        out_dir,
        seed=seed,
        runs_per_configuration=1,
        configurations={"hit": bearing_area_in2},
        settings=settings,
        sensors=sensors,
        nonlinear_modes=2,
        file_format="mat",
        modes_auto=True,
    )

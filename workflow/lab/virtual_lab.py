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

The campaign folder follows ``campaign-format.md``; the truth is written
beside it as ``<campaign_dir>.truth.json``, never inside.
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
    "run_drift": "run_drift",
    "second_mode": "unknown",
}
DEFAULT_EFFECT_SIZES = {
    "quadratic_damping": 0.003,
    "stiffness_nonlinearity": 0.01,
    "run_drift": 0.4,
    "second_mode": 0.5,
}
EFFECT_SIZE_MEANING = {
    "quadratic_damping": "damping ratio added by c2 v|v| at the reference velocity amplitude",
    "stiffness_nonlinearity": "fractional frequency drop at the reference velocity amplitude "
    "(saturating contact-opening softening; asymptote twice that)",
    "run_drift": "fractional fall of the Dahl friction limit Fc from the first to the last run",
    "second_mode": "initial acceleration amplitude of a linear mode at 1.08 f1, relative to mode 1",
}
SECOND_MODE_FREQUENCY_RATIO = 1.08
INTEGRATORS = ("averaged", "time_domain")
TIME_DOMAIN_EFFECTS = (None, "run_drift", "second_mode")
"""Effects the time-domain path can add (to the Dahl joint): its integrators have the
joints (contact patches, Dahl) and linear modal damping only (no velocity-squared loss,
no dissipation-free softening)."""


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


def _amplitude_grid(mode: specimen.FirstMode, omega0, points):
    """Modal amplitudes spanning 1e-5 .. 300 in/s at the accelerometer."""
    phi = abs(mode.accelerometer_participation)
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
    a = _amplitude_grid(jm.mode, setup.omega0_rad_s, settings.amplitude_points)
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
    a_ref = REFERENCE_VELOCITY_IN_S / (abs(setup.mode.accelerometer_participation) * w0)
    if effect == "quadratic_damping":
        # c2 xi'|xi'| dissipates 8/3 c2 w^2 a^3 per cycle: zeta = 4 c2 a / (3 pi)
        c2 = effect_size * 3 * np.pi / (4 * a_ref)
        d = d + 8.0 / 3.0 * c2 * w0**2 * a**3
    elif effect == "stiffness_nonlinearity":
        r2 = (a / a_ref) ** 2
        ratio = 1.0 - 2.0 * effect_size * r2 / (1.0 + r2)
        loss = loss + w0**2 * (1.0 - ratio**2)
    return d, loss


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
    return ModeTable.build(a, zeta, omega)


def truth_curves(setup: JointSetup, table: ModeTable, velocity_in_s):
    """True damping ratio and damped frequency vs accelerometer velocity amplitude."""
    phi = abs(setup.mode.accelerometer_participation)
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
def _patch_ringdown_kernel(s, k, fs, onset, stiffness, damping, e00, e01, e10, e11, v0, n_steps, h, acc):
    """Kick-drift-kick ring-down of ``x'' + damping x' + stiffness x + R = 0`` from
    ``x = 0, x' = v0``, ``R = sum s (f - k s x)`` with Jenkins forces ``f``; writes ``acc``.

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
        remainder = frozen
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
):
    """Modal acceleration of mode 1 with the contact patches, integrated in time.

    ``xi'' + 2 zeta0 omega0 xi' + omega0^2 xi + sum s (f - k s xi) = 0`` (the stuck patch
    stiffness is part of ``omega0``), every patch a Jenkins element (``f`` clipped at its
    slip force). The linear oscillator's flow over a step is exact; the patches' nonlinear
    remainder, zero while they stick, is applied as two half kicks per step (second
    order, Strang). Starts at the pulse centre with the pulse's impulse at the stuck
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
"""Mode-1 modal acceleration at times from the pulse start, given the peak modal force
and the pulse duration."""


def simulate_run(
    setup: JointSetup,
    mode_response: ModeResponse,
    settings: LabSettings,
    rng,
    second_mode_ratio=0.0,
    *,
    run: RunPhysics | None = None,
    noise_rng=None,
    sensor_gain=1.0,
):
    """One triggered record: (time s, force lbf, acceleration g) and run facts.

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
    noise_rng : numpy.random.Generator, optional
        Accelerometer noise; default ``rng``.
    sensor_gain : float
        Mode 1 (and the added second mode) as seen by this sensor, relative to the
        accelerometer's mode shape; the other modes as at the accelerometer.
    """
    run = run if run is not None else RunPhysics(zeta0=settings.zeta0)
    noise_rng = noise_rng if noise_rng is not None else rng
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
    phi_a = sensor_gain * mode.accelerometer_participation
    acc = phi_a * mode_response(tau, phi_h * peak, duration)
    for m in mode.higher_modes:
        _, _, q = half_sine_response(
            tau,
            2 * np.pi * m.frequency_hz * run.frequency_factor,
            settings.higher_mode_zeta,
            m.hammer_participation * peak,
            duration,
        )
        acc += m.accelerometer_participation * q
    if second_mode_ratio:
        _, _, q = half_sine_response(
            tau,
            SECOND_MODE_FREQUENCY_RATIO * setup.omega0_rad_s * run.frequency_factor,
            run.zeta0,
            phi_h * peak,
            duration,
        )
        # An extra (e.g. torsional) mode that the beam model lacks: excited like
        # mode 1, seen at the accelerometer with the chosen relative amplitude.
        acc += second_mode_ratio * phi_a * q
    # rigid-body bounce and pitch on the suspension
    geo = settings.joint.geometry
    lever_acc = geo.accelerometer_x_in - mode.centre_of_mass_in
    lever_ham = geo.hammer_x_in - mode.centre_of_mass_in
    for f_hz, gain in (
        (settings.suspension_hz[0], 1.0 / mode.total_mass_lbf_s2_in),
        (settings.suspension_hz[1], lever_acc * lever_ham / mode.pitch_inertia_lbf_s2_in),
    ):
        _, _, q = half_sine_response(tau, 2 * np.pi * f_hz, settings.suspension_zeta, gain * peak, duration)
        acc += q
    acc_g = acc / specimen.G_IN_S2 + settings.acceleration_noise_g * noise_rng.standard_normal(n)
    sl = slice(trigger - PRETRIGGER_SAMPLES, trigger - PRETRIGGER_SAMPLES + settings.samples_per_run)
    force_q = quantise(force[sl], FORCE_RANGE_LBF)
    acc_q = quantise(acc_g[sl], ACCELERATION_RANGE_G)
    facts = {"peak_force_lbf": peak, "pulse_duration_s": duration}
    return np.arange(settings.samples_per_run) * dt, force_q, acc_q, facts


def averaged_mode_response(setup: JointSetup, table: ModeTable, run: RunPhysics) -> ModeResponse:
    """Mode 1 from the run's averaged table (slow flow)."""
    omega0 = setup.omega0_rad_s * run.frequency_factor

    def response(tau, modal_peak, duration):
        return nonlinear_mode_response(tau, table, omega0, run.zeta0, modal_peak, duration)

    return response


def time_domain_mode_response(setup: JointSetup, joint: str, coulomb: float, run: RunPhysics) -> ModeResponse:
    """Mode 1 with the run's joint (``patches`` or ``dahl`` with friction limit
    ``coulomb``) integrated in time."""
    omega0 = setup.omega0_rad_s * run.frequency_factor
    patches = setup.joint_modes.patches

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
            )
        return dahl_mode_response_time_domain(
            tau, setup.dahl_sigma, coulomb, omega0, run.zeta0, modal_peak, duration
        )

    return response


def format_run(time_s, force_lbf, acceleration_g, sample_rate_hz=SAMPLE_RATE_HZ) -> str:
    """The run file text (Dactron-like ASCII export)."""
    lines = [
        "Virtual lab ASCII export (lapjoint)",
        f"Sample rate: {sample_rate_hz:g} Hz",
        f"Pre-trigger: {PRETRIGGER_SAMPLES} samples",
        "Time (s)\tForce (lbf)\tAcceleration (g)",
    ]
    body = np.char.add(
        np.char.add(
            np.char.add(np.char.add(np.char.mod("%.6f", time_s), "\t"), np.char.mod("%.10g", force_lbf)), "\t"
        ),
        np.char.mod("%.10g", acceleration_g),
    )
    return "\n".join(lines + body.tolist()) + "\n"


def _campaign_yaml(name, configurations, mode_hz, sample_rate_hz) -> str:
    lines = [
        f"name: {name}",
        f"sample_rate_hz: {sample_rate_hz:g}",
        f"pretrigger_samples: {PRETRIGGER_SAMPLES}",
        f"mode_hz: {mode_hz:g}",
        "response: {quantity: acceleration, unit: g}",
        "force: {unit: lbf}",
        "configurations:",
    ]
    for cname, area in configurations.items():
        area_part = f"bearing_area_in2: {area:g}, " if area is not None else ""
        lines.append(f'  {cname}: {{{area_part}files: "{cname}/*.txt"}}')
    return "\n".join(lines) + "\n"


def truth_path(out_dir) -> Path:
    """Where the truth JSON of a campaign folder lives (beside it, not inside)."""
    out = Path(out_dir)
    return out.parent / (out.name + ".truth.json")


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
    sensor_gain=1.0,
    noise_stream=0,
) -> dict:
    """Write a simulated campaign folder and its truth; return the truth dict.

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
    effect : {None, "quadratic_damping", "stiffness_nonlinearity", "run_drift", "second_mode"}
        One added effect; requires ``joint="dahl"`` (the baseline it departs from).
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
        ``time_domain``: the joint's equation of motion integrated in time (patches or
        Dahl; effects in ``TIME_DOMAIN_EFFECTS``; about 1 s per patch-joint run).
    sensor_gain : float
        Mode 1 as seen by another sensor, relative to the accelerometer's mode shape
        (see :func:`generate_sensor_campaigns`).
    noise_stream : int
        Index of the accelerometer-noise stream: with the same ``seed``, campaigns with
        different streams share the physics and the hammer and differ only in sensor noise.
    """
    if joint not in ("patches", "dahl"):
        raise ValueError(f"joint must be 'patches' or 'dahl', got {joint!r}")
    if effect not in EFFECT_CAUSES:
        raise ValueError(
            f"effect must be one of {sorted(k for k in EFFECT_CAUSES if k)} or None, got {effect!r}"
        )
    if effect is not None and joint != "dahl":
        raise ValueError("an added effect departs from the Dahl baseline: pass joint='dahl'")
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
    if integrator == "time_domain" and effect not in TIME_DOMAIN_EFFECTS:
        raise ValueError(
            "the time-domain path integrates the patch or Dahl joint with linear modal damping: "
            f"it takes effect in {TIME_DOMAIN_EFFECTS}, got {effect!r}"
        )
    if not sensor_gain > 0:
        raise ValueError(f"sensor_gain must be positive, got {sensor_gain!r}")
    if effect is not None and effect_size is None:
        effect_size = DEFAULT_EFFECT_SIZES[effect]
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
    cause = EFFECT_CAUSES[effect] if effect else ("microslip_power_law" if joint == "patches" else "none")
    truth = {
        "campaign_dir": out.name,
        "seed": seed,
        "joint": joint,
        "effect": effect,
        "effect_size": effect_size,
        "effect_size_meaning": EFFECT_SIZE_MEANING.get(effect),
        "reference_velocity_in_s": REFERENCE_VELOCITY_IN_S,
        "expected_cause": cause,
        "integrator": integrator,
        "sensor_gain": sensor_gain,
        "noise_stream": noise_stream,
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
    mode_hz = float(np.mean([s.mode.frequency_hz for s, _ in setups.values()]))
    (out / "campaign.yaml").write_text(
        _campaign_yaml(
            f"virtual-lab-{joint}-{effect or 'baseline'}-{seed}",
            configurations,
            round(mode_hz),
            settings.sample_rate_hz,
        )
    )
    for (cname, (setup, curves)), child in zip(setups.items(), children):
        folder = out / cname
        folder.mkdir(exist_ok=True)
        for stale in folder.glob("run*.txt"):
            stale.unlink()
        hammer_seq, noise_seq, variability_seq = child.spawn(3)
        rng = np.random.default_rng(hammer_seq)
        noise_rng = np.random.default_rng(noise_seq.spawn(noise_stream + 1)[noise_stream])
        runs = draw_run_physics(settings, np.random.default_rng(variability_seq), runs_per_configuration)
        base_table = mode_table(setup, curves, settings, joint, effect, effect_size)
        zeta, fd = truth_curves(setup, base_table, velocity / sensor_gain)
        mode = setup.mode
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
            "runs": [],
        }
        for i, run in enumerate(runs):
            fraction = i / (runs_per_configuration - 1) if runs_per_configuration > 1 else 0.0
            table = mode_table(setup, curves, settings, joint, effect, effect_size, fraction, run)
            coulomb = run_dahl_coulomb(setup, effect, effect_size, fraction, run.slip_force_factor)
            if integrator == "time_domain":
                response = time_domain_mode_response(setup, joint, coulomb, run)
            else:
                response = averaged_mode_response(setup, table, run)
            ratio = effect_size if effect == "second_mode" else 0.0
            t, f, acc, facts = simulate_run(
                setup, response, settings, rng, ratio, run=run, noise_rng=noise_rng, sensor_gain=sensor_gain
            )
            name = run_name(i)
            (folder / f"{name}.txt").write_text(format_run(t, f, acc, settings.sample_rate_hz))
            z_run, f_run = truth_curves(setup, table, velocity / sensor_gain)
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
        truth["configurations"][cname] = entry
    truth_path(out).write_text(json.dumps(truth, indent=1))
    return truth


def generate_sensor_campaigns(out_root, sensor_gains: Mapping[str, float], **campaign_options) -> dict:
    """The same campaign as seen by several sensors: one campaign folder per sensor.

    Every campaign has the same physics, hammer hits and run-to-run variations (same
    ``seed``); mode 1's response is scaled by the sensor's mode-shape ratio to the
    accelerometer, and each sensor has its own independent noise.

    Parameters
    ----------
    out_root : path
        Folder that receives ``<sensor name>/`` campaign folders (truth beside each).
    sensor_gains : mapping of str to float
        Sensor name -> mode-1 amplitude relative to the accelerometer (``phi(x) /
        phi(x_accelerometer)``, positive; e.g. ``{"accelerometer": 1.0, "mid": 0.6}``).
    **campaign_options
        Passed to :func:`generate_campaign` (seed, joint, effect, configurations ...).

    Returns
    -------
    dict
        Sensor name -> truth dict of its campaign.
    """
    root = Path(out_root)
    return {
        name: generate_campaign(root / name, sensor_gain=gain, noise_stream=index, **campaign_options)
        for index, (name, gain) in enumerate(sensor_gains.items())
    }

"""Virtual lab settings: the analyser, the effects a campaign can add, and what
differs from run to run.

Runs of a configuration differ as in a real lab (``LabSettings.*_spread``, see
docs/virtual-lab.md): each run draws its own natural frequency, linear modal damping
and joint slip force, at random and independent of run order.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from workflow.lab.layout import DemoSettings
from workflow.models import contact

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
    "true_causes",
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
    frequency_spread: float = DemoSettings.frequency_spread
    """Run-to-run relative standard deviation of the natural frequency (temperature:
    aluminium's modulus changes by about -4e-4/K, so f by -2e-4/K; re-hanging the beam
    on its tubing; docs/virtual-lab.md). 0 turns it off."""
    damping_spread: float = DemoSettings.damping_spread
    """Run-to-run relative standard deviation of the linear modal damping ``zeta0``
    (support and suspension losses after re-hanging; air). 0 turns it off."""
    slip_force_spread: float = DemoSettings.slip_force_spread
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

    Examples
    --------
    The drawn frequencies scatter by ``frequency_spread`` (the standard deviation of 2000
    draws is within 5 %, three times its own sampling error, of it):

    >>> settings = LabSettings()
    >>> runs = draw_run_physics(settings, np.random.default_rng(0), 2000)
    >>> factors = np.array([run.frequency_factor for run in runs])
    >>> bool(abs(factors.std() / settings.frequency_spread - 1) < 0.05)
    True
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

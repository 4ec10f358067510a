"""One triggered, quantised record of a virtual-lab hammer hit.

Higher flexible modes and the two rigid-body suspension modes (bounce and pitch on the
rubber tubing) respond linearly to the hammer pulse; mode 1 through a given response.
"""

from __future__ import annotations

import numpy as np

from workflow.lab.configurations import JointSetup, ModeResponse
from workflow.lab.pulse import boxcar_half_sine, half_sine_response
from workflow.lab.sensors import Sensor, SensorView, sensor_view
from workflow.lab.settings import (
    ACCELERATION_RANGE_G,
    ADC_BITS,
    FORCE_RANGE_LBF,
    PRETRIGGER_SAMPLES,
    SECOND_MODE_FREQUENCY_RATIO,
    TRIGGER_LBF,
    LabSettings,
    RunPhysics,
)
from workflow.models import specimen

__all__ = [
    "quantise",
    "simulate_run",
]


def quantise(values, full_scale, bits=ADC_BITS):
    """Round to the ADC step ``2 full_scale / 2^bits`` and clip to the range."""
    step = 2.0 * full_scale / 2**bits
    return np.clip(np.round(values / step), -(2 ** (bits - 1)), 2 ** (bits - 1) - 1) * step


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
        Mode 1's modal acceleration (:func:`workflow.lab.configurations.averaged_mode_response` or
        :func:`workflow.lab.time_domain.time_domain_mode_response`).
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

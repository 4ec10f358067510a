"""Virtual lab sensors: accelerometers at points of the beam, each with its own noise.

A sensor sees every mode at its own shape value at its point; several sensors are
columns of one run file (or variables of one MAT file).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workflow.lab.settings import LabSettings
from workflow.models import specimen

__all__ = [
    "Sensor",
    "SensorView",
    "sensor_view",
    "mode1_gain",
    "positions_with_mode1_gain",
    "sensor_at_gain",
]


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

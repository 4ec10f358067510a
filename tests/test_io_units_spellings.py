"""workflow.io.units beyond the canonical spellings: spaces and ``**`` in unit names, units
it does not know, its error messages, and single-precision input (what a system format may
store) converted in double precision. Expected values are the unit definitions."""

import math

import numpy as np
import pytest

from workflow.io.units import (
    factor_to_internal,
    known_units,
    normalize_unit,
    response_quantity_of,
    to_internal,
    velocity_amplitude_in_s,
)

G_IN_S2 = 9.80665 / 0.0254  # standard gravity in in/s^2, both exact


@pytest.mark.parametrize(
    "written, canonical",
    [
        ("m / s ^ 2", "m/s^2"),
        (" in / s ", "in/s"),
        ("m/s**2", "m/s^2"),
        ("in / s**2", "in/s^2"),
        ("m/s²", "m/s^2"),
    ],
)
def test_spaces_and_powers_in_a_unit_are_read(written, canonical):
    assert normalize_unit(written) == canonical


def test_an_unknown_unit_comes_back_without_its_spaces_for_the_caller_to_report():
    assert normalize_unit(" furlong / fortnight ") == "furlong/fortnight"


def test_errors_list_what_is_accepted():
    with pytest.raises(ValueError, match=r"expected one of acceleration, velocity, displacement, force$"):
        known_units("torque")
    with pytest.raises(ValueError, match=r"expected one of acceleration, velocity, displacement, force$"):
        factor_to_internal("torque", "N m")
    with pytest.raises(ValueError, match=r"unit 'kg' is not a unit of force; expected one of lbf, N$"):
        factor_to_internal("force", "kg")
    with pytest.raises(ValueError, match=r"expected one of acceleration, velocity, displacement$"):
        velocity_amplitude_in_s(1.0, "jerk", "m/s^3", 100.0)


def test_single_precision_input_is_converted_in_double_precision():
    # A float32 record (TDMS, MAT) must not keep float32 through the conversion: its
    # rounding (6e-8) would show in every value.
    values = np.array([0.1, 1.7, -3.3], dtype=np.float32)
    converted = to_internal(values, "acceleration", "g")
    assert converted.dtype == np.float64
    np.testing.assert_array_equal(converted, values.astype(np.float64) * G_IN_S2)
    frequency_hz = np.array([130.1, 97.3], dtype=np.float32)
    velocity = velocity_amplitude_in_s(1.0, "acceleration", "g", frequency_hz)
    expected = G_IN_S2 / (2 * math.pi * frequency_hz.astype(np.float64))
    np.testing.assert_allclose(velocity, expected, rtol=1e-14)


@pytest.mark.parametrize(
    "written, quantity, inches_per_unit",
    [
        ("mm/s", "velocity", 1.0 / 25.4),
        ("MM/S", "velocity", 1.0 / 25.4),
        ("mm/s²", "acceleration", 1.0 / 25.4),
        ("mm/s/s", "acceleration", 1.0 / 25.4),
        ("mm", "displacement", 1.0 / 25.4),
        ("µm", "displacement", 1e-3 / 25.4),
        ("μm", "displacement", 1e-3 / 25.4),
        ("um", "displacement", 1e-3 / 25.4),
    ],
)
def test_millimetre_and_micrometre_units_of_lasers_and_probes_are_read(written, quantity, inches_per_unit):
    # 1 in = 25.4 mm exactly
    unit = normalize_unit(written)
    assert response_quantity_of(unit) == quantity
    assert factor_to_internal(quantity, unit) == pytest.approx(inches_per_unit, rel=1e-15)

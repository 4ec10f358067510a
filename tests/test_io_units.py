"""Unit conversion to in, in/s, in/s^2 and lbf."""

import math

import numpy as np
import pytest

from workflow.io import units


def test_standard_gravity_is_exact_in_inches():
    assert units.STANDARD_GRAVITY_IN_S2 == 9.80665 / 0.0254
    assert units.STANDARD_GRAVITY_IN_S2 == pytest.approx(386.0886, abs=1e-4)


@pytest.mark.parametrize(
    ("quantity", "unit", "value", "expected"),
    [
        ("acceleration", "g", 1.0, 9.80665 / 0.0254),
        ("acceleration", "m/s^2", 0.0254, 1.0),
        ("acceleration", "in/s^2", 3.5, 3.5),
        ("velocity", "m/s", 0.0254, 1.0),
        ("velocity", "in/s", 2.0, 2.0),
        ("displacement", "m", 0.0254, 1.0),
        ("displacement", "in", 0.25, 0.25),
        ("force", "lbf", 7.0, 7.0),
        ("force", "N", 4.4482216152605, 1.0),
    ],
)
def test_to_internal_every_documented_unit(quantity, unit, value, expected):
    assert units.to_internal([value], quantity, unit)[0] == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    ("spelling", "canonical"),
    [("m/s2", "m/s^2"), ("m/s²", "m/s^2"), ("G", "g"), ("lb", "lbf"), ("n", "N"), ("M/S", "m/s")],
)
def test_unit_spellings_from_exports_are_understood(spelling, canonical):
    assert units.normalize_unit(spelling) == canonical


@pytest.mark.parametrize(
    ("quantity", "unit", "named"),
    [("acceleration", "m/s", "'m/s'"), ("force", "kg", "'kg'"), ("jerk", "m/s^3", "'jerk'")],
)
def test_unknown_combination_is_named(quantity, unit, named):
    with pytest.raises(ValueError, match=named):
        units.to_internal([1.0], quantity, unit)


def test_velocity_amplitude_from_each_quantity():
    f_hz = 125.0
    omega = 2 * math.pi * f_hz
    # A harmonic of velocity amplitude 2 in/s has acceleration 2*w and displacement 2/w.
    assert units.velocity_amplitude_in_s(2.0 * omega, "acceleration", "in/s^2", f_hz) == pytest.approx(2.0)
    assert units.velocity_amplitude_in_s(2.0, "velocity", "in/s", f_hz) == pytest.approx(2.0)
    assert units.velocity_amplitude_in_s(2.0 / omega, "displacement", "in", f_hz) == pytest.approx(2.0)
    one_g = units.velocity_amplitude_in_s(1.0, "acceleration", "g", f_hz)
    assert one_g == pytest.approx(386.08858 / omega, rel=1e-6)


def test_velocity_amplitude_broadcasts_frequency():
    amplitude = np.array([1.0, 1.0])
    out = units.velocity_amplitude_in_s(amplitude, "displacement", "m", np.array([1.0, 2.0]))
    assert out[1] == pytest.approx(2 * out[0])
    assert out[0] == pytest.approx(2 * math.pi / 0.0254)


def test_velocity_amplitude_rejects_force_and_bad_frequency():
    with pytest.raises(ValueError, match="'force'"):
        units.velocity_amplitude_in_s(1.0, "force", "lbf", 10.0)
    with pytest.raises(ValueError, match="positive"):
        units.velocity_amplitude_in_s(1.0, "acceleration", "g", 0.0)


@pytest.mark.parametrize(
    ("quantity", "unit", "si_per_unit", "si_label"),
    [
        # g is 9.80665 m/s^2 by definition (CGPM 1901); the inch is 0.0254 m exactly (1959).
        ("acceleration", "g", 9.80665, "m/s²"),
        ("acceleration", "in/s^2", 0.0254, "m/s²"),
        ("acceleration", "m/s^2", 1.0, "m/s²"),
        ("velocity", "in/s", 0.0254, "m/s"),
        ("velocity", "m/s", 1.0, "m/s"),
        ("displacement", "in", 0.0254, "m"),
        ("displacement", "m", 1.0, "m"),
    ],
)
def test_response_shown_in_si_and_in_its_own_unit(quantity, unit, si_per_unit, si_label):
    """Under SI a recorded response is shown in m/s², m/s or m by the exact definitions;
    under inch-second it keeps the campaign's own values and unit."""
    recorded = [-2.5, 0.0, 1.0, 3.0e4]
    shown, label = units.response_in_units(recorded, quantity, unit, units.SI)
    np.testing.assert_allclose(shown, np.array(recorded) * si_per_unit, rtol=1e-14, atol=0.0)
    assert label == si_label
    # whole numbers, as an integer export would hold them, still come back as float64
    whole = [-2, 0, 1, 30000]
    kept, kept_label = units.response_in_units(whole, quantity, unit, units.INCH_SECOND)
    assert kept.dtype == np.float64 and kept.tolist() == whole and kept_label == unit

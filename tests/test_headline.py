"""The result block's wording (geofrac/headline.py): units where declared, signed differences."""

import math

from geofrac.headline import band, numbers, quantity, versus, versus_vector


def test_a_value_carries_its_unit_only_when_declared():
    assert quantity(34.2189, "mm") == "34.22 mm"
    assert quantity(34.2189) == "34.22"
    assert quantity(-0.0) == "0"
    assert numbers([0.0, 40.25], "m") == "[0, 40.25] m" and numbers([1.5, -2.0]) == "[1.5, -2]"


def test_the_difference_is_value_minus_reference_absolute_and_relative():
    assert versus(34.0, 40.0, "mm") == "difference -6 mm, -15 %"
    assert versus(0.1003, 0.1) == "difference +0.0003, +0.3 %"
    assert "no relative" in versus(1.0, 0.0)
    text = versus_vector([3.0, 4.0], [0.0, 8.0], "m")
    assert text == f"|difference| {math.hypot(3.0, 4.0):.3g} m, {100 * 5 / 8:.3g} %"


def test_a_band_says_inside_or_the_difference_from_its_nearer_end():
    assert band(34.2, 30.0, 40.0, unit="mm") == "inside"
    assert band(29.85, 30.0, 40.0, unit="mm") == "below: difference -0.15 mm, -0.5 % from 30 mm"
    assert band(44.0, 30.0, 40.0).startswith("above: difference +4, +10 %")

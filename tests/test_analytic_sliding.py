"""The ramped sliding closed forms (geofrac/analytic_sliding.py) against direct integration."""

import math

import numpy as np
import pytest

from geofrac.analytic_sliding import incline_acceleration, ramped_motion, stop_distance


def _integrate(a, t_end, ramp, v0, n=200_000):
    """Trapezoidal integration of x'' = a min(1, t / ramp), x(0) = 0, x'(0) = v0."""
    t = np.linspace(0.0, t_end, n + 1)
    acc = a * np.minimum(1.0, t / ramp) if ramp > 0 else np.full_like(t, a)
    v = v0 + np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * np.diff(t))])
    x = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    return x, v, t


@pytest.mark.parametrize(("t_end", "ramp"), [(0.05, 0.1), (3.0, 0.1), (1.0, 0.0)])
def test_the_ramped_motion_is_the_integral_of_the_ramped_acceleration(t_end, ramp):
    a = incline_acceleration(30.0, 0.3)
    x, v, _ = _integrate(a, t_end, ramp, 0.5)
    got = ramped_motion(a, t_end, ramp=ramp, v0=0.5)
    assert got == pytest.approx((x[-1], v[-1]), rel=1e-8)


def test_incline_acceleration_is_g_sin_minus_mu_cos():
    assert incline_acceleration(30.0, 0.3) == pytest.approx(10 * (0.5 - 0.3 * math.sqrt(3) / 2))
    assert incline_acceleration(30.0, 0.7) < 0  # mu > tan 30: decelerates


@pytest.mark.parametrize("ramp", [0.0, 0.1, 2.0])
def test_the_stop_distance_is_where_the_integrated_velocity_vanishes(ramp):
    a = incline_acceleration(30.0, 0.7)  # -1.062
    x, v, _ = _integrate(a, 4.0, ramp, 1.0, n=400_000)
    stop = int(np.argmax(v <= 0))
    assert stop_distance(1.0, a, ramp=ramp) == pytest.approx(x[stop], rel=1e-5)
    if ramp == 0.0:
        assert stop_distance(1.0, a) == pytest.approx(1.0 / (2 * -a))  # 0.4707


def test_a_block_that_never_stops_is_refused():
    with pytest.raises(ValueError, match="a < 0"):
        stop_distance(1.0, 0.5)

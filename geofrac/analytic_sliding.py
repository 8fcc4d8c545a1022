"""A rigid block sliding on a plane under Coulomb friction, gravity ramped: closed forms.

Pure arithmetic. A block on a plane inclined at θ with friction coefficient μ, under
gravity g switched on linearly over ``ramp`` seconds (``[gravity] ramp``: the factor
min(1, t / ramp)), moves along the plane with the acceleration A f(t), f = min(1, t / ramp):

- sliding downhill: A = g (sin θ − μ cos θ) (μ < tan θ: it accelerates);
- launched downhill at v₀ with μ > tan θ: A = −g (μ cos θ − sin θ) until it stops, and it
  stays (the friction holds it).

Integrating f once and twice (F₁, F₂ below) gives the velocity v₀ + A F₁(t) and the
displacement v₀ t + A F₂(t). Without a ramp they are the textbook v₀ + A t and
v₀ t + A t² / 2, and the launched block stops after v₀² / (2 |A|).
"""

from __future__ import annotations

import math

__all__ = ["incline_acceleration", "ramped_motion", "stop_distance"]


def incline_acceleration(theta_deg: float, mu: float, *, g: float = 10.0) -> float:
    """The sliding block's acceleration along the plane, g (sin θ − μ cos θ) (downhill +).

    Negative when μ > tan θ: the deceleration of a block launched downhill.
    """
    th = math.radians(theta_deg)
    return g * (math.sin(th) - mu * math.cos(th))


def _f1(t: float, ramp: float) -> float:
    """∫₀ᵗ min(1, s / ramp) ds."""
    if ramp <= 0:
        return t
    return t * t / (2 * ramp) if t <= ramp else t - ramp / 2


def _f2(t: float, ramp: float) -> float:
    """∫₀ᵗ ∫₀ˢ min(1, r / ramp) dr ds."""
    if ramp <= 0:
        return t * t / 2
    return t**3 / (6 * ramp) if t <= ramp else t * t / 2 - ramp * t / 2 + ramp * ramp / 6


def ramped_motion(a: float, t: float, *, ramp: float = 0.0, v0: float = 0.0) -> tuple[float, float]:
    """(displacement, velocity) at ``t`` of a block accelerating at a min(1, t / ramp).

    For a decelerating block (``a`` < 0 < ``v0``) only until it stops (:func:`stop_distance`).
    """
    return v0 * t + a * _f2(t, ramp), v0 + a * _f1(t, ramp)


def stop_distance(v0: float, a: float, *, ramp: float = 0.0) -> float:
    """Where a block launched at ``v0`` > 0 and decelerated at a min(1, t / ramp) stops.

    Raises:
        ValueError: ``a`` >= 0 (it never stops) or ``v0`` <= 0.
    """
    if a >= 0 or v0 <= 0:
        raise ValueError(f"stop_distance: needs v0 > 0 and a < 0, got v0={v0}, a={a}")
    need = v0 / -a  # the stop time solves F₁(t) = v₀ / |a|
    if ramp > 0 and need <= ramp / 2:
        t = math.sqrt(2 * ramp * need)  # stops during the ramp
    else:
        t = need + (ramp / 2 if ramp > 0 else 0.0)
    return ramped_motion(a, t, ramp=ramp, v0=v0)[0]

"""The wording of a run's result block: a value with its unit, its difference from a reference.

``geofrac run`` ends with a ``result:`` block (:func:`geofrac.pipeline.report`): each
method and each declared effect gives its headline numbers through these helpers, so
every line says a number the same way. A unit is the scene's ``[units]`` entry
(:meth:`geofrac.model.scene.Units.of`); an empty unit prints nothing (the scene did not
declare it).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["band", "numbers", "quantity", "versus", "versus_vector"]


def quantity(value: float, unit: str = "", digits: int = 4) -> str:
    """``value`` to ``digits`` significant digits, followed by ``unit`` when declared."""
    text = f"{value + 0.0:.{digits}g}"  # + 0.0 turns -0 into 0
    return f"{text} {unit}" if unit else text


def numbers(values: Sequence[float], unit: str = "", digits: int = 10) -> str:
    """``[a, b, c]`` to ``digits`` significant digits, followed by ``unit`` when declared."""
    text = "[" + ", ".join(f"{v + 0.0:.{digits}g}" for v in values) + "]"
    return f"{text} {unit}" if unit else text


def _relative(difference: float, reference: float) -> str:
    if reference == 0.0:
        return "reference 0: no relative difference"
    return f"{100.0 * difference / abs(reference):+.3g} %"


def versus(value: float, reference: float, unit: str = "") -> str:
    """``"difference +4.2 mm, +14 %"``: ``value - reference``, absolute and relative."""
    difference = value - reference
    text = f"{difference + 0.0:+.3g}" + (f" {unit}" if unit else "")
    return f"difference {text}, {_relative(difference, reference)}"


def versus_vector(value: Sequence[float], reference: Sequence[float], unit: str = "") -> str:
    """``"|difference| 2.6e-4 mm, 6.5e-4 %"``: the Euclidean norm of ``value - reference``.

    The relative part is over the reference's norm.
    """
    gap = math.dist(value, reference)
    norm = math.hypot(*reference)
    relative = "" if norm == 0.0 else f", {100.0 * gap / norm:.3g} %"
    return f"|difference| {quantity(gap, unit, 3)}{relative}"


def band(value: float, low: float, high: float, *, unit: str = "") -> str:
    """Where ``value`` lies against the band [low, high].

    ``"inside"``, or the difference from the nearer end, absolute and relative
    (``"above by 2 mm, +5 %"``).
    """
    if low <= value <= high:
        return "inside"
    edge = low if value < low else high
    where = "below" if value < low else "above"
    return f"{where}: {versus(value, edge, unit)} from {quantity(edge, unit)}"

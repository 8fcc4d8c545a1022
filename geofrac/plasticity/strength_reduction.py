"""Shear strength reduction: the reduced law and the bisection on the trial factor.

Pure python (no solver): :func:`reduce_strength` divides c, tan φ and tan ψ (and the
tension cut-off) by a trial factor F (Griffiths and Lane (1999); Dawson, Roth and
Drescher (1999)); :func:`bisect_factor` brackets the factor of safety between a stable
and a failed trial and halves the bracket to a stated tolerance. The solver that decides
whether a trial is stable is the caller's (:mod:`geofrac.fem.strength_reduction`).
See docs/plasticity.md, "Factor of safety by strength reduction".
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

__all__ = ["Bracket", "bisect_factor", "reduce_strength", "trial_factor", "trials_left"]


def _reduced_angle(angle: float, factor: float) -> float:
    """atan(tan(angle)/factor) in degrees."""
    return math.degrees(math.atan(math.tan(math.radians(angle)) / factor))


def reduce_strength[L](law: L, factor: float) -> L:
    """The law with c/F, atan(tan φ/F), atan(tan ψ/F) (and T/F for a tension cut-off).

    Any dataclass law with ``cohesion``, ``friction_angle`` and ``dilatancy_angle``
    (:class:`geofrac.plasticity.MohrCoulomb`, :class:`geofrac.plasticity.DruckerPrager`);
    the elasticity is kept. ψ is reduced like φ so that ψ <= φ holds at every F (ψ = 0,
    Griffiths and Lane's choice, stays 0). The cut-off T <= c cot φ stays within its
    bound since c cot φ is unchanged by the reduction.
    """
    if not factor > 0:
        raise ValueError(f"strength reduction: the trial factor must be > 0, got {factor}")
    changes: dict[str, Any] = {
        "cohesion": law.cohesion / factor,  # type: ignore[attr-defined]
        "friction_angle": _reduced_angle(law.friction_angle, factor),  # type: ignore[attr-defined]
        "dilatancy_angle": _reduced_angle(law.dilatancy_angle, factor),  # type: ignore[attr-defined]
    }
    if getattr(law, "tension", None) is not None:
        changes["tension"] = law.tension / factor  # type: ignore[attr-defined]
    return replace(law, **changes)  # type: ignore[type-var]


def trial_factor(law: Any, reduced: Any) -> float:
    """The factor F of ``reduced = reduce_strength(law, F)``, from the two laws.

    tan φ / tan φ_F when φ > 0, else c / c_F (a law has φ > 0 or c > 0): what a problem
    factory that receives only the reduced rock law needs to reduce other strengths (the
    joints' c and μ) by the same F. Exact to round-off (relative 1e-15).

    Raises:
        ValueError: neither φ nor c of ``law`` is positive.
    """
    if law.friction_angle > 0:
        tan = math.tan(math.radians(law.friction_angle))
        return tan / math.tan(math.radians(reduced.friction_angle))
    if law.cohesion > 0:
        return float(law.cohesion / reduced.cohesion)
    raise ValueError("strength reduction: a law with neither friction nor cohesion")


@dataclass
class Bracket:
    """The factor of safety between a stable and a failed trial factor.

    Attributes:
        stable: the largest trial factor found stable.
        failed: the smallest trial factor found failed.
        trials: every (factor, stable) tried, in order.
    """

    stable: float
    failed: float
    trials: list[tuple[float, bool]] = field(default_factory=list)

    @property
    def factor_of_safety(self) -> float:
        """The middle of the bracket (within half its width of the true threshold)."""
        return 0.5 * (self.stable + self.failed)

    @property
    def width(self) -> float:
        """The width failed − stable."""
        return self.failed - self.stable


def trials_left(
    tried: list[tuple[float, bool]], *, low: float, high: float, tolerance: float
) -> int:
    """How many more trials :func:`bisect_factor` needs after ``tried`` (an estimate).

    Exact once a stable and a failed factor are known: the halvings of the bracket
    [largest stable, smallest failed] until its width is <= ``tolerance``. Before that,
    the missing end(s) of [``low``, ``high``] count one trial each, assuming no move of
    the bracket (a moved bracket adds its moves).
    """
    stable = [f for f, ok in tried if ok]
    failed = [f for f, ok in tried if not ok]
    lo = max(stable) if stable else low
    hi = min(failed) if failed else max(high, lo)
    if not failed and stable and max(stable) >= high:  # moved up: the next end is 2 x
        hi = 2.0 * max(stable)
    if not stable and failed and min(failed) <= low:  # moved down: the next end is / 2
        lo = 0.5 * min(failed)
    count = int(not stable) + int(not failed)
    width = hi - lo
    while width > tolerance:
        width *= 0.5
        count += 1
    return count


def bisect_factor(
    is_stable: Callable[[float], bool],
    *,
    low: float,
    high: float,
    tolerance: float,
    max_expansions: int = 4,
) -> Bracket:
    """Bisection on F between a stable and a failed trial until failed − stable <= tolerance.

    ``low`` must be stable and ``high`` failed; when ``low`` fails (``high`` holds) the
    bracket is moved down (up) by halving ``low`` (doubling ``high``) up to
    ``max_expansions`` times, and a bracket still not found raises ``ValueError``. Every
    factor calls ``is_stable`` once (the expensive solve), in the order of ``trials``.
    Assumes one threshold (stable below, failed above).
    """
    if not 0 < low < high or not tolerance > 0:
        raise ValueError(
            f"strength reduction: needs 0 < low < high and tolerance > 0, got low = {low}, "
            f"high = {high}, tolerance = {tolerance}"
        )
    trials: list[tuple[float, bool]] = []
    known: dict[float, bool] = {}

    def trial(factor: float) -> bool:
        if factor not in known:  # a bracket moved down already knows its new high
            known[factor] = bool(is_stable(factor))
            trials.append((factor, known[factor]))
        return known[factor]

    for _ in range(max_expansions + 1):
        if trial(low):
            break
        high, low = low, low / 2
    else:
        raise ValueError(f"strength reduction: no stable trial factor down to {2 * low:.4g}")
    for _ in range(max_expansions + 1):
        if not trial(high):
            break
        low, high = high, high * 2
    else:
        raise ValueError(f"strength reduction: no failed trial factor up to {high / 2:.4g}")
    while high - low > tolerance:
        mid = 0.5 * (low + high)
        if trial(mid):
            low = mid
        else:
            high = mid
    return Bracket(low, high, trials)

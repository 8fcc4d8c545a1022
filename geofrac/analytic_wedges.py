"""Two-wedge limit equilibrium of a layer sliding on a kinked slip surface: closed forms.

Pure arithmetic (2D, per metre of width). A layer resting on two planes (an upper one
dipping at α₁ downhill and a lower one rising at α₂ toward the toe) cannot move as one
rigid body: it moves as two wedges, an *upper* one sliding down the upper plane and a
*lower* one pushed up the lower plane, separated by an interface through the kink on
which the layer itself must shear. The bases carry Coulomb friction μ (the bed), the
interface the soil's friction angle φ (c = 0). At limit every surface mobilises its full
friction; the upper wedge then *needs* an interface force P_req to be held and the lower
wedge can *supply* at most P_cap before it moves. The layer stands when P_req ≤ P_cap.

With φ_b = atan μ and an interface leaning ω from the vertical, the force polygons give
(the textbook method of wedges; ω = 0 is the vertical interface):

- P_req = W₁ sin(α₁ − φ_b) cos φ / cos(α₁ − φ_b − φ − ω),
- P_cap = W₂ sin(α₂ + φ_b) cos φ / cos(α₂ + φ_b + φ + ω) (unbounded once the cosine ≤ 0).

:func:`wedge_forces` solves the same equilibrium as vectors (each wedge's two unknowns,
its base normal force and the interface's normal force, from its two equations of force
balance), with the interface's shear direction taken from the wedges' relative motion
instead of assumed, and :func:`threshold_angle` finds the friction angle
at which P_req = P_cap. Moments are not balanced (the method of wedges); a mechanism with
other interfaces gives its own threshold, and the layer is stable only above the largest
of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["WedgeForces", "threshold_angle", "wedge_forces"]


@dataclass(frozen=True)
class WedgeForces:
    """The interface force the upper wedge needs and the one the lower wedge can supply.

    Attributes:
        required: P_req, the interface's normal force that holds the upper wedge at limit
            (force per metre of width; ≤ 0: the upper wedge stands on its own base).
        capacity: P_cap, the largest normal force the lower wedge resists before it moves
            (``math.inf``: it cannot be pushed along its base whatever the force).
    """

    required: float
    capacity: float

    @property
    def stable(self) -> bool:
        """Whether the layer stands: P_req ≤ P_cap."""
        return self.required <= self.capacity


def _unit(angle_deg: float) -> np.ndarray:
    a = math.radians(angle_deg)
    return np.array([math.cos(a), math.sin(a)])


def wedge_forces(
    w_upper: float,
    w_lower: float,
    *,
    alpha_upper: float,
    alpha_lower: float,
    mu: float,
    phi: float,
    omega: float = 0.0,
) -> WedgeForces:
    """The two wedges' interface forces at limit, for any interface through the kink.

    Args:
        w_upper: weight of the upper wedge (per metre of width), > 0.
        w_lower: weight of the lower wedge, > 0.
        alpha_upper: dip of the upper plane, degrees, downhill toward +x (0 < α₁ < 90).
        alpha_lower: rise of the lower plane toward +x, degrees (0 ≤ α₂ < 90).
        mu: Coulomb friction coefficient of both bases, ≥ 0.
        phi: the soil's friction angle on the interface, degrees in [0, 90).
        omega: the interface's inclination from the vertical, degrees in (−90, 90); > 0
            leans its top toward the toe (+x).

    Returns:
        The required and the supplied interface force (see :class:`WedgeForces`).

    Raises:
        ValueError: on a weight ≤ 0 or an angle outside its range.
    """
    if not (w_upper > 0 and w_lower > 0):
        raise ValueError("wedge weights must be > 0")
    if not (0 < alpha_upper < 90 and 0 <= alpha_lower < 90 and 0 <= phi < 90):
        raise ValueError(
            "angles out of range: need 0 < alpha_upper < 90, 0 <= alpha_lower < 90, 0 <= phi < 90"
        )
    if not -90 < omega < 90 or mu < 0:
        raise ValueError("need -90 < omega < 90 and mu >= 0")
    d1 = _unit(-alpha_upper)  # motion of the upper wedge: down its plane
    d2 = _unit(alpha_lower)  # motion of the lower wedge: up its plane
    n1 = np.array([-d1[1], d1[0]])  # base normals, pointing into the wedges (up)
    n2 = np.array([-d2[1], d2[0]])
    t = _unit(90.0 - omega)  # interface tangent, pointing up
    n = np.array([-t[1], t[0]])  # interface normal, from the lower wedge into the upper (−x side)
    # kinematics: the normal velocities agree across the interface; the upper wedge's
    # velocity relative to the lower one lies along t, and the shear on the upper wedge
    # opposes it
    lam = float(d1 @ n) / float(d2 @ n)
    slip = float((d1 - lam * d2) @ t)
    shear = -math.copysign(1.0, slip) * t if slip != 0.0 else np.zeros(2)
    dirn = n + math.tan(math.radians(phi)) * shear  # interface force on the upper wedge per unit P
    g = np.array([0.0, -1.0])
    # upper wedge: W₁ g + N₁ (n1 − μ d1) + P dirn = 0
    a_up = np.column_stack([n1 - mu * d1, dirn])
    n_up, p_req = np.linalg.solve(a_up, -w_upper * g)
    # lower wedge: W₂ g + N₂ (n2 − μ d2) − P dirn = 0
    a_lo = np.column_stack([n2 - mu * d2, -dirn])
    n_lo, p_cap = np.linalg.solve(a_lo, -w_lower * g)
    if p_cap < 0 or n_lo < 0:
        p_cap = math.inf  # no push along the base can reach the limit: the lower wedge locks
    del n_up
    return WedgeForces(float(p_req), float(p_cap))


def threshold_angle(
    w_upper: float,
    w_lower: float,
    *,
    alpha_upper: float,
    alpha_lower: float,
    mu: float,
    omega: float = 0.0,
    tol: float = 1e-6,
) -> float:
    """The smallest soil friction angle (degrees) at which the two wedges stand.

    Bisection on φ in [0, 90) of P_req(φ) ≤ P_cap(φ) (both monotonic in φ: more friction
    on the interface helps both wedges); 0 when the layer stands without interface
    friction (the bed alone holds it).

    Args:
        w_upper: weight of the upper wedge, as :func:`wedge_forces`.
        w_lower: weight of the lower wedge.
        alpha_upper: dip of the upper plane, degrees.
        alpha_lower: rise of the lower plane, degrees.
        mu: Coulomb friction coefficient of the bases.
        omega: the interface's inclination from the vertical, degrees.
        tol: bisection tolerance in degrees.
    """

    def stable(phi: float) -> bool:
        return wedge_forces(
            w_upper,
            w_lower,
            alpha_upper=alpha_upper,
            alpha_lower=alpha_lower,
            mu=mu,
            phi=phi,
            omega=omega,
        ).stable

    if stable(0.0):
        return 0.0
    lo, hi = 0.0, 89.999
    if not stable(hi):
        return math.inf
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if stable(mid):
            hi = mid
        else:
            lo = mid
    return hi

"""Coulomb joint law of zero-thickness interface springs (pure numpy, vectorised over pairs).

A joint's two faces are tied node to node by a normal and a shear spring (Goodman,
Taylor and Brekke (1968) type interface, lumped at the nodes). For a pair with the
relative displacement (jump) δ = u⁺ − u⁻ split into the opening δₙ = δ·n (positive when
the faces separate) and the sliding δₛ = δ·t, and the plastic slip s (the only history):

    σₙ = kₙ min(δₙ, 0)                         (tension positive; no tensile strength)
    τ* = kₛ (δₛ − s)                            (elastic trial)
    τ_max = c − μ σₙ  (>= c: σₙ <= 0)           (Coulomb with cohesion)
    τ = τ*  if |τ*| <= τ_max (stick), else  τ = sign(τ*) τ_max, s ← δₛ − τ/kₛ (slip).

It is Mohr-Coulomb with a tension cut-off at σₙ = 0 in (σₙ, τ) space, returned with
non-associated slip (zero dilatancy: slip never opens the joint) and an associated
cut-off whose opening is reversible (no history: a joint that opened closes again where
it was): an open pair (δₙ > 0) carries no normal traction and shear up to c (the corner
(0, ±c) of the Coulomb line with the cut-off, so that the traction is continuous in δ);
a cohesionless open pair carries nothing. The strength reduction divides c and μ by the
trial factor (:meth:`JointStrength.reduced`), as the rock's c and tan φ.

Consistent tangent, per pair, d(σₙ, τ)/d(δₙ, δₛ) = [[kₙ χ, 0], [−μ kₙ χ sign(τ*) ς, kₛ (1 − ς)]]
with χ = 1 where closed (δₙ <= 0; the closed branch at δₙ = 0, so that a fresh joint
has its stiffness) and ς = 1 where slipping. Not symmetric where slipping (ψ = 0).
See docs/plasticity.md, "Joints in the strength reduction".

In 3D (:func:`coulomb_joint_3d`) the sliding and the slip are vectors in the joint's plane
(two components in a tangent frame t₁, t₂) and the shear is returned radially: with the
trial τ* = kₛ (δₛ − s) and e = τ*/|τ*|, slip where |τ*| > τ_max gives τ = τ_max e and
s ← δₛ − τ/kₛ; the tangent is dτ/dδₛ = kₛ (τ_max/|τ*|) (I − e eᵀ), dτ/dδₙ = −μ kₙ χ e. The
slip keeps the trial's direction (isotropic friction), so the law is the same in any
tangent frame, and with one tangent component it is :func:`coulomb_joint`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "CLOSED",
    "OPEN",
    "SLIP",
    "JointReturn",
    "JointStrength",
    "coulomb_joint",
    "coulomb_joint_3d",
]

#: State of a pair: closed and sticking.
CLOSED = 0
#: Closed (or at the cut-off corner) and slipping.
SLIP = 1
#: Open (δₙ > 0) and sticking (|τ| < c).
OPEN = 2


@dataclass(frozen=True)
class JointStrength:
    """Coulomb strength of a joint: cohesion c (stress) and friction coefficient μ = tan φ.

    Raises:
        ValueError: c < 0 or μ < 0 (or not finite).
    """

    cohesion: float
    friction: float

    def __post_init__(self) -> None:  # noqa: D105
        for name in ("cohesion", "friction"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"joint {name} must be finite and >= 0, got {value}")

    def reduced(self, factor: float) -> JointStrength:
        """c/F and μ/F (strength reduction with the trial factor F > 0)."""
        if not factor > 0:
            raise ValueError(f"strength reduction: the trial factor must be > 0, got {factor}")
        return JointStrength(self.cohesion / factor, self.friction / factor)


@dataclass
class JointReturn:
    """The joint law at n pairs.

    Attributes:
        normal: σₙ, shape=(n,) (<= 0).
        shear: τ, shape=(n,).
        slip: the plastic slip after the return, shape=(n,).
        state: :data:`CLOSED`, :data:`SLIP` or :data:`OPEN` (an open pair that slips is
            SLIP), shape=(n,).
        tangent: d(σₙ, τ)/d(δₙ, δₛ), shape=(n, 2, 2).
    """

    normal: np.ndarray
    shear: np.ndarray
    slip: np.ndarray
    state: np.ndarray
    tangent: np.ndarray


def _per_pair(n: int, *values: np.ndarray | float) -> list[np.ndarray]:
    """Each scalar or per-pair value as an array of shape=(n,)."""
    return [np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in values]


def coulomb_joint(
    opening: np.ndarray,
    sliding: np.ndarray,
    slip: np.ndarray,
    *,
    kn: np.ndarray | float,
    ks: np.ndarray | float,
    cohesion: np.ndarray | float,
    friction: np.ndarray | float,
) -> JointReturn:
    """Return-map n pairs from their jump and their converged slip (module docstring).

    Args:
        opening: δₙ, shape=(n,).
        sliding: δₛ, shape=(n,).
        slip: the converged plastic slip s, shape=(n,).
        kn: normal stiffness (stress/length), scalar or shape=(n,), > 0.
        ks: shear stiffness, scalar or shape=(n,), > 0.
        cohesion: c, scalar or shape=(n,).
        friction: μ, scalar or shape=(n,).
    """
    d_n = np.asarray(opening, dtype=float)
    n = d_n.shape[0]
    kn_a, ks_a, mu, c = _per_pair(n, kn, ks, friction, cohesion)
    closed = d_n <= 0.0
    normal = np.where(closed, kn_a * d_n, 0.0)
    trial = ks_a * (np.asarray(sliding, dtype=float) - slip)
    limit = c - mu * normal
    slipping = np.abs(trial) > limit
    sign = np.sign(trial)
    shear = np.where(slipping, sign * limit, trial)
    new_slip = np.where(slipping, sliding - shear / ks_a, slip)
    state = np.where(slipping, SLIP, np.where(closed, CLOSED, OPEN))
    tangent = np.zeros((n, 2, 2))
    tangent[:, 0, 0] = np.where(closed, kn_a, 0.0)
    tangent[:, 1, 0] = np.where(slipping & closed, -mu * kn_a * sign, 0.0)
    tangent[:, 1, 1] = np.where(slipping, 0.0, ks_a)
    return JointReturn(normal, shear, new_slip, state.astype(np.int8), tangent)


def coulomb_joint_3d(
    opening: np.ndarray,
    sliding: np.ndarray,
    slip: np.ndarray,
    *,
    kn: np.ndarray | float,
    ks: np.ndarray | float,
    cohesion: np.ndarray | float,
    friction: np.ndarray | float,
) -> JointReturn:
    """Return-map n pairs of a 3D joint: the shear returned radially in the joint's plane.

    Args:
        opening: δₙ, shape=(n,).
        sliding: δₛ in the tangent frame, shape=(n, 2).
        slip: the converged plastic slip s in that frame, shape=(n, 2).
        kn: normal stiffness (stress/length), scalar or shape=(n,), > 0.
        ks: shear stiffness, scalar or shape=(n,), > 0.
        cohesion: c, scalar or shape=(n,).
        friction: μ, scalar or shape=(n,).

    Returns:
        normal σₙ shape=(n,), shear τ shape=(n, 2), slip shape=(n, 2), state shape=(n,)
        (an open pair is :data:`SLIP` only when it has a cohesion to slip against),
        tangent d(σₙ, τ₁, τ₂)/d(δₙ, δₛ₁, δₛ₂) shape=(n, 3, 3).
    """
    d_n = np.asarray(opening, dtype=float)
    n = d_n.shape[0]
    d_s = np.asarray(sliding, dtype=float).reshape(n, 2)
    kn_a, ks_a, mu, c = _per_pair(n, kn, ks, friction, cohesion)
    closed = d_n <= 0.0
    normal = np.where(closed, kn_a * d_n, 0.0)
    trial = ks_a[:, None] * (d_s - np.asarray(slip, dtype=float).reshape(n, 2))
    size = np.linalg.norm(trial, axis=1)
    limit = c - mu * normal
    slipping = size > limit
    e = np.zeros((n, 2))
    np.divide(trial, size[:, None], out=e, where=size[:, None] > 0)
    shear = np.where(slipping[:, None], limit[:, None] * e, trial)
    new_slip = np.where(slipping[:, None], d_s - shear / ks_a[:, None], slip)
    # an open cohesionless pair has nothing to slip against (τ_max = 0): OPEN, whatever
    # round-off its shear trial carries (the decision is on c, an input, not on a jump)
    sliding_state = slipping & (closed | (c > 0))
    state = np.where(sliding_state, SLIP, np.where(closed, CLOSED, OPEN))
    tangent = np.zeros((n, 3, 3))
    tangent[:, 0, 0] = np.where(closed, kn_a, 0.0)
    tangent[:, 1:, 0] = np.where(
        (slipping & closed)[:, None], -mu[:, None] * kn_a[:, None] * e, 0.0
    )
    ratio = np.zeros(n)
    np.divide(limit, size, out=ratio, where=slipping)
    scale = np.where(slipping, ks_a * ratio, ks_a)
    proj = np.eye(2)[None] - np.where(slipping[:, None, None], e[:, :, None] * e[:, None, :], 0.0)
    tangent[:, 1:, 1:] = scale[:, None, None] * proj
    return JointReturn(normal, shear, new_slip, state.astype(np.int8), tangent)

"""Coulomb friction on grid nodes of a boundary (seed eqs. 4.44-4.47).

A node of the boundary is in contact when its motion pushes into the boundary
(a_i · n_i > 0, eq. 4.44, with n_i the unit normal pointing out of the body, into the
boundary). Then the normal component is removed (4.47) and the tangential one is slowed
by the Coulomb friction μ |a_i · n_i| (4.46), at most to rest: the seed's "μ' = μ while
the node slides, μ' = |a_t| / (a · n) while it sticks" (4.45) is the same cap. We apply it
to the grid velocity after the step's update, v* = v + a Δt, in impulse form (the
normal velocity change Δv_n = v*·n > 0 times μ bounds the tangential change), which is
(4.44-4.47) multiplied by Δt; nodes moving away from the boundary are free.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Friction", "apply_friction", "friction"]


@dataclass(frozen=True)
class Friction:
    """Boundary nodes with their outward normals and a friction coefficient.

    Attributes:
        nodes: flat grid node ids, shape=(k,).
        normals: unit normals out of the body, shape=(k, dim).
        mu: Coulomb friction coefficient μ >= 0 (the seed: 0.1).
    """

    nodes: np.ndarray
    normals: np.ndarray
    mu: float


def friction(nodes: np.ndarray, normals: np.ndarray, mu: float) -> Friction:
    """Validated :class:`Friction` (normals normalised)."""
    nodes = np.asarray(nodes, dtype=np.int64).reshape(-1)
    n = np.asarray(normals, dtype=float).reshape(len(nodes), -1)
    length = np.linalg.norm(n, axis=1)
    if np.any(length == 0):
        raise ValueError("friction: every normal must be non-zero")
    if not mu >= 0:
        raise ValueError(f"friction: mu must be >= 0, got {mu}")
    return Friction(nodes, n / length[:, None], float(mu))


def apply_friction(v: np.ndarray, fr: Friction, sliding_only: bool = False) -> np.ndarray:
    """Contact and Coulomb friction on the trial grid velocities (in place and returned).

    Args:
        v: trial nodal velocities v* = v + a Δt, shape=(num_nodes, dim).
        fr: the boundary.
        sliding_only: only remove the normal approach (no friction): for the velocity
            rebuilt from particle momentum after the friction was applied once.

    Returns:
        ``v``, changed on the nodes in contact.
    """
    vn = np.einsum("ka,ka->k", v[fr.nodes], fr.normals)
    contact = vn > 0.0  # moving into the boundary (4.44)
    if not np.any(contact):
        return v
    ids, n, dvn = fr.nodes[contact], fr.normals[contact], vn[contact]
    vt = v[ids] - dvn[:, None] * n  # tangential part
    if not sliding_only and fr.mu > 0:
        speed = np.linalg.norm(vt, axis=1)
        slow = np.minimum(fr.mu * dvn, speed)  # (4.45)-(4.46): at most to rest
        scale = np.where(speed > 0, 1.0 - slow / np.where(speed > 0, speed, 1.0), 0.0)
        vt = vt * scale[:, None]
    v[ids] = vt  # (4.47): no normal velocity into the boundary
    return v

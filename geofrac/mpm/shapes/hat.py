"""The linear hat of point particles (``mpm``; Edo (2016), eqs. 4.26, 4.28-4.29).

The particle is a point (χ_p = δ(x − x_p) V_p, eq. 4.26), so φ_ip = N_i(x_p), the linear
hat of the two nodes of its cell per direction. At a cell boundary the particle belongs to
the cell on its upper side (its gradients are that cell's), so a particle on a node still
carries forces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geofrac.mpm.grid import Grid
from geofrac.mpm.shapes.base import Shape, Weights

__all__ = ["HAT", "Hat", "hat_1d"]


def hat_1d(s: np.ndarray, L: float) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 4.28-4.29 for the two nodes of the particle's cell.

    Args:
        s: the particle's position in its cell, 0 <= s < L, shape=(n,).
        L: cell size.

    Returns:
        φ and dφ/dx for the lower and upper node, each shape=(n, 2).
    """
    phi = np.stack([1.0 - s / L, s / L], axis=1)
    dphi = np.broadcast_to(np.array([-1.0 / L, 1.0 / L]), phi.shape).copy()
    return phi, dphi


@dataclass(frozen=True)
class Hat(Shape):
    """Point particles with the linear hat: two nodes per direction, no particle domain."""

    def nodes_per_direction(self, spacing: float, lp: np.ndarray | None) -> int:
        """Two: the nodes of the particle's cell."""
        return 2

    def per_direction(
        self, g: Grid, x: np.ndarray, lp: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`Shape.per_direction` (``lp`` is not read)."""
        L = g.spacing
        n, dim = x.shape
        start = np.floor((x - g.origin) / L).astype(np.int64)
        start = np.clip(start, 0, np.asarray(g.cells) - 1)  # the upper boundary's cell
        s = x - (g.origin + L * start)
        idx = start[:, :, None] + np.arange(2)
        phi, dphi = hat_1d(s.ravel(), L)
        return idx, phi.reshape(n, dim, 2), dphi.reshape(n, dim, 2)

    def fill_compiled(self, g: Grid, x: np.ndarray, lp: np.ndarray | None, *, out: Weights) -> bool:
        """:func:`geofrac.mpm.kernels.weights_hat` (a point inside the grid never fails)."""
        from geofrac.mpm import kernels

        shape = np.asarray(g.shape, dtype=np.int64)
        origin = np.ascontiguousarray(g.origin, dtype=float)
        kernels.weights_hat(x, origin, g.spacing, shape, out.nodes, out.phi, out.grad)
        return True


#: The point-particle MPM of Edo (2016).
HAT = Hat("mpm", "linear hat of point particles (eqs. 4.28-4.29)")

"""The quadratic B-spline (``bspline2``; not in Edo (2016)).

N(r) = 3/4 − (r/L)² for |r| < L/2 and (3/2 − |r|/L)²/2 for L/2 ≤ |r| < 3L/2 of the node
distance r (support 1.5 cells each side, three nodes per direction). Its gradient is
continuous, so a particle crossing a cell boundary changes no force abruptly (the
cell-crossing error of ``mpm``); docs/mpm_energy.md. N <= 3/4 and |N'| <= 1/L, within
the bounds every shape keeps (:attr:`Shape.phi_bound`, :attr:`Shape.grad_bound`).

To add another shape (a cubic B-spline, say) copy this module: a :class:`Shape` subclass
with its 1D weights, then one line in :data:`geofrac.mpm.shapes.REGISTRY`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geofrac.mpm.grid import Grid
from geofrac.mpm.shapes.base import Shape, Weights

__all__ = ["BSPLINE2", "QuadraticBSpline", "bspline2_1d"]


def bspline2_1d(r: np.ndarray, L: float) -> tuple[np.ndarray, np.ndarray]:
    """The quadratic B-spline N(r) and dN/dx for r = x_p − x_i, each the shape of r."""
    a = np.abs(r) / L
    sign = np.sign(r)
    phi = np.where(a < 0.5, 0.75 - a**2, np.where(a < 1.5, 0.5 * (1.5 - a) ** 2, 0.0))
    dphi = np.where(a < 0.5, -2 * a, np.where(a < 1.5, -(1.5 - a), 0.0)) * sign / L
    return phi, dphi


@dataclass(frozen=True)
class QuadraticBSpline(Shape):
    """Point particles with the quadratic B-spline: three nodes per direction."""

    def reach(self, spacing: float) -> float:
        """Half a cell: the three nodes around the particle must exist."""
        return 0.5 * spacing

    def nodes_per_direction(self, spacing: float, lp: np.ndarray | None) -> int:
        """Three: the nearest node and its neighbours."""
        return 3

    def per_direction(
        self, g: Grid, x: np.ndarray, lp: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`Shape.per_direction` (``lp`` is not read)."""
        L = g.spacing
        start = np.floor((x - g.origin) / L + 0.5).astype(np.int64) - 1
        idx = start[:, :, None] + np.arange(3)
        r = x[:, :, None] - (g.origin[:, None] + L * idx)
        phi, dphi = bspline2_1d(r, L)
        return idx, phi, dphi

    def fill_compiled(self, g: Grid, x: np.ndarray, lp: np.ndarray | None, *, out: Weights) -> bool:
        """:func:`geofrac.mpm.kernels.weights_bspline2`."""
        from geofrac.mpm import kernels

        shape = np.asarray(g.shape, dtype=np.int64)
        origin = np.ascontiguousarray(g.origin, dtype=float)
        return kernels.weights_bspline2(x, origin, g.spacing, shape, out.nodes, out.phi, out.grad)


#: The quadratic B-spline.
BSPLINE2 = QuadraticBSpline(
    "bspline2", "quadratic B-spline, support 1.5 cells each side (not in Edo (2016))"
)
